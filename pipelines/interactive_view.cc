#include "pipelines/interactive_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <vtkCallbackCommand.h>
#include <vtkCamera.h>
#include <vtkChartXY.h>
#include <vtkContextActor.h>
#include <vtkContextScene.h>
#include <vtkImageData.h>
#include <vtkInteractorEventRecorder.h>
#include <vtkInteractorStyleImage.h>
#include <vtkObjectFactory.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSliderRepresentation2D.h>
#include <vtkSliderWidget.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

#include "pipelines/charts.h"
#include "pipelines/energy_charts.h"
#include "wobble/control/controllers.h"
#include "wobble/control/pulls.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/scene/script_writer.h"

namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

namespace {

// Window layout, fractions of the window (see the header).
constexpr double kPanelTop = 0.22;   // the sliders live below this
constexpr double kSceneRight = 0.62;  // the charts live right of this

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

// A horizontal slider in normalized display coordinates of the window. Sizes are given here in
// pixels: vtkSliderRepresentation2D (9.1, as measured on screen at 800x500) takes lengths along
// the slider as fractions of the window's width, and widths across it as fractions of about
// 0.21 of the window's width whatever the slider's length; the text heights are its own
// fractions, kept fixed.
Ptr<vtkSliderRepresentation2D> MakeSliderRep(double x0, double x1, double y, double lo, double hi, double value,
                                             const std::string& title, int window_width) {
  auto rep = Ptr<vtkSliderRepresentation2D>::New();
  rep->GetPoint1Coordinate()->SetCoordinateSystemToNormalizedDisplay();
  rep->GetPoint1Coordinate()->SetValue(x0, y);
  rep->GetPoint2Coordinate()->SetCoordinateSystemToNormalizedDisplay();
  rep->GetPoint2Coordinate()->SetValue(x1, y);
  rep->SetMinimumValue(lo);
  rep->SetMaximumValue(hi);
  rep->SetValue(value);
  rep->SetTitleText(title.c_str());
  rep->SetLabelFormat("%.3g");
  const double across_unit = std::max(1.0, 0.21 * window_width);  // pixels
  auto along = [&](double pixels) { return std::clamp(pixels / std::max(1, window_width), 0.001, 0.99); };
  auto across = [&](double pixels) { return std::clamp(pixels / across_unit, 0.001, 0.99); };
  rep->SetSliderLength(along(12));
  rep->SetSliderWidth(across(20));
  rep->SetTubeWidth(across(6));
  rep->SetEndCapLength(along(4));
  rep->SetEndCapWidth(across(20));
  rep->SetTitleHeight(0.09);
  rep->SetLabelHeight(0.08);
  rep->GetTubeProperty()->SetColor(0.35, 0.35, 0.4);
  rep->GetSliderProperty()->SetColor(0.85, 0.2, 0.15);
  rep->GetCapProperty()->SetColor(0.3, 0.3, 0.3);
  rep->GetSelectedProperty()->SetColor(0.2, 0.6, 0.2);
  for (vtkTextProperty* t : {rep->GetTitleProperty(), rep->GetLabelProperty()}) {
    t->SetColor(0, 0, 0);
    t->ShadowOff();
    t->BoldOff();
  }
  return rep;
}

}  // namespace

struct InteractiveView::Impl {
  InteractiveView* self = nullptr;
  ViewerScene scene;
  ViewerOptions options;
  std::unique_ptr<World> world, scrub_world;
  std::unique_ptr<SceneView> view;
  Ptr<vtkRenderWindowInteractor> interactor;
  Ptr<vtkRenderer> panel_renderer;
  Ptr<vtkTextActor> status;
  // charts
  Ptr<vtkRenderer> energy_renderer, cond_renderer;
  Ptr<vtkChartXY> energy_chart, cond_chart;
  std::unique_ptr<RunRecorder> recorder;
  // sliders
  std::vector<Ptr<vtkSliderWidget>> mode_sliders;
  Ptr<vtkSliderWidget> time_slider;
  std::vector<Ptr<vtkCallbackCommand>> callbacks;
  // what can be pulled: mass points and drawing samples, by lattice coordinates
  std::vector<Eigen::Vector2d> pickable;
  // state of the session
  bool playing = true, scrubbing = false, graph_drives = false;
  double speed = 1.0;
  // what drives the world, as its controllers: the pose graph until a slider moves, the
  // sliders (which also log every change of the targets for the session script), the mouse
  std::shared_ptr<control::PoseGraphController> graph;
  std::shared_ptr<control::ModeTargetController> sliders;
  std::shared_ptr<control::SpringPull> pull;
  Eigen::VectorXd slider_targets;  // kept over a restart
  long session_steps = 0;
  int drags = 0;
  long first_drag_step = -1;
  std::vector<Eigen::VectorXd> recorded_poses;
  std::vector<double> recorded_durations;
  double last_pose_time = 0.0;
  struct Recorded {
    double t;
    Eigen::VectorXd q, qd;
  };
  std::vector<Recorded> history;
  long scrub_frame = -1;
  std::string message;  // one line shown under the status (saved files, trouble)
  FramePacer pacer;  // frame clock, the simulated time asked for, measurements
  bool initialized = false;

  void NewWorld() {
    world = std::make_unique<World>(scene.world);
    world->AddBody(scene.body);
    world->SetState(0, scene.q0, scene.qd0);
    world->SetModeTargets(0, slider_targets);
    graph.reset();
    if (graph_drives) {  // PoseAt(n dt) with n the steps since the start, as a script's run
      graph = std::make_shared<control::PoseGraphController>(*world, 0, scene.graph);
      world->AddController(graph);
    }
    sliders = std::make_shared<control::ModeTargetController>(*world, 0);  // after the graph: logs its switches
    world->AddController(sliders);
    pull.reset();
    pacer.SetGoal(0.0);
    session_steps = 0;
    drags = 0;
    first_drag_step = -1;
    recorded_poses.clear();
    recorded_durations.clear();
    last_pose_time = 0.0;
    history.clear();
    recorder = std::make_unique<RunRecorder>(0);
    if (view) view->SetWorld(world.get());
    scrubbing = false;
  }

  bool StepWorld() {
    if (!world->Step()) {
      playing = false;
      message = "simulation stopped: " + world->status().message + " (r restarts)";
      std::cerr << "wobble view: " << message << std::endl;
      return false;
    }
    ++session_steps;
    ++pacer.stats.steps;
    return true;
  }

  void Advance(double duration) {
    pacer.Advance(duration, scene.world.dt, [&] { return world->time(); }, [&] { return StepWorld(); });
  }

  void RecordFrame() {
    if (history.size() >= size_t(std::max(1L, options.max_history))) history.erase(history.begin());
    history.push_back({world->time(), world->state(0).q, world->state(0).qd});
    recorder->Sample(*world);
  }

  void UpdateTimeSlider() {
    auto* rep = vtkSliderRepresentation2D::SafeDownCast(time_slider->GetRepresentation());
    const double last = double(std::max<size_t>(1, history.size()) - 1);
    rep->SetMinimumValue(0.0);
    rep->SetMaximumValue(std::max(1.0, last));
    rep->SetValue(scrubbing ? double(scrub_frame) : last);
  }

  // The charts show the last kChartWindow seconds: redrawing the whole of a long session
  // every few frames would slow the window down as it goes.
  static constexpr double kChartWindow = 30.0;
  static void Trim(ChartSpec* spec) {
    for (ChartSeries& s : spec->series) {
      if (s.x.empty()) continue;
      const double from = s.x.back() - kChartWindow;
      const size_t first = size_t(std::lower_bound(s.x.begin(), s.x.end(), from) - s.x.begin());
      s.x.erase(s.x.begin(), s.x.begin() + long(first));
      s.y.erase(s.y.begin(), s.y.begin() + long(first));
    }
    if (!spec->series.empty() && !spec->series[0].x.empty()) {
      const double from = spec->series[0].x.front();
      spec->markers.erase(std::remove_if(spec->markers.begin(), spec->markers.end(), [&](double m) { return m < from; }),
                          spec->markers.end());
    }
  }
  void UpdateCharts() {
    if (!options.charts || recorder->time().size() < 2) return;  // a line needs two points
    ChartSpec energy = recorder->EnergyChart("energy");
    ChartSpec cond = recorder->ConditionChart("cond2(M)");
    Trim(&energy);
    Trim(&cond);
    FillChart(energy_chart, energy);
    FillChart(cond_chart, cond);
  }

  // What the body will sweep is unknown: show it with room around it, and the ground under it
  // when the ground is within a few body sizes below.
  void FrameBody() {
    const World& w = scrubbing ? *scrub_world : *world;
    Eigen::AlignedBox2d box = BodyBounds(w, 0);
    const double size = box.sizes().maxCoeff();
    const Ground& g = scene.world.params.ground;
    if (g.enabled && std::abs(std::cos(g.slope)) > 1e-6) {
      const double x = box.center().x();
      const double ground_y = g.point.y() + std::tan(g.slope) * (x - g.point.x());
      if (ground_y < box.min().y() && ground_y > box.min().y() - 4.0 * size) box.extend(Eigen::Vector2d(x, ground_y));
    }
    box.extend(box.min() - Eigen::Vector2d(size, 0.4 * size));
    box.extend(box.max() + Eigen::Vector2d(size, 0.8 * size));
    view->FrameBox(box);
  }

  void UpdateStatus() {
    status->SetInput(self->StatusLine().c_str());
  }
};

InteractiveView::InteractiveView(ViewerScene scene, ViewerOptions options) : impl_(new Impl) {
  if (!HasDisplay())
    throw std::runtime_error("wobble view needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run it "
                             "on a desktop, or headless under xvfb-run -a -s \"-screen 0 1280x1024x24\"");
  if (!scene.body) throw std::invalid_argument("InteractiveView: no body");
  if (scene.q0.size() != scene.body->num_q() || scene.qd0.size() != scene.body->num_q())
    throw std::invalid_argument("InteractiveView: the start state does not fit the body");
  if (!(options.fps > 0 && options.fps <= 1000)) throw std::invalid_argument("fps must be in (0, 1000]");
  if (!(options.speed > 0 && std::isfinite(options.speed))) throw std::invalid_argument("speed must be positive");
  if (!(options.slider_range > 0 && std::isfinite(options.slider_range)))
    throw std::invalid_argument("the slider range must be positive");
  Impl& m = *impl_;
  m.self = this;
  m.scene = std::move(scene);
  m.options = options;
  m.speed = options.speed;
  m.playing = options.start_playing;
  m.graph_drives = !m.scene.graph.empty();
  if (m.graph_drives) {
    const std::string invalid = m.scene.graph.Validate(int(control::ActiveModes(*m.scene.body).size()));
    if (!invalid.empty()) throw std::invalid_argument("pose graph: " + invalid);
  }
  const int D = m.scene.body->num_modes();
  m.slider_targets = Eigen::VectorXd::Zero(D);
  m.NewWorld();
  m.scrub_world = std::make_unique<World>(m.scene.world);
  m.scrub_world->AddBody(m.scene.body);

  // the scene: the offscreen renderer's SceneView, on screen in the top-left part
  SceneOptions so;
  so.width = options.width;
  so.height = options.height;
  so.offscreen = false;
  so.viewport[0] = 0.0;
  so.viewport[1] = kPanelTop;
  so.viewport[2] = options.charts ? kSceneRight : 1.0;
  so.viewport[3] = 1.0;
  so.overlay = false;  // the viewer's own status text says more (and the scrubbed time)
  so.shape_samples = options.shape_samples;
  m.view = std::make_unique<SceneView>(m.world.get(), so);
  vtkRenderWindow* window = m.view->window();
  window->SetWindowName("wobble view");
  m.FrameBody();
  m.status = Ptr<vtkTextActor>::New();
  m.status->GetTextProperty()->SetColor(0, 0, 0);
  m.status->GetTextProperty()->SetFontSize(14);
  m.status->GetTextProperty()->SetFontFamilyToCourier();
  m.status->GetTextProperty()->SetVerticalJustificationToTop();
  m.status->SetDisplayPosition(8, options.height - 8);
  m.view->renderer()->AddActor2D(m.status);

  // the panel of sliders along the bottom
  m.panel_renderer = Ptr<vtkRenderer>::New();
  m.panel_renderer->SetViewport(0.0, 0.0, 1.0, kPanelTop);
  m.panel_renderer->SetBackground(0.93, 0.93, 0.93);
  m.panel_renderer->InteractiveOff();
  window->AddRenderer(m.panel_renderer);

  // the live charts at the right
  if (options.charts) {
    auto add_chart = [&](double y0, double y1, Ptr<vtkRenderer>* renderer, Ptr<vtkChartXY>* chart) {
      *renderer = Ptr<vtkRenderer>::New();
      (*renderer)->SetViewport(kSceneRight, y0, 1.0, y1);
      (*renderer)->SetBackground(1.0, 1.0, 1.0);
      (*renderer)->InteractiveOff();
      window->AddRenderer(*renderer);
      *chart = Ptr<vtkChartXY>::New();
      auto scene2d = Ptr<vtkContextScene>::New();
      scene2d->AddItem(*chart);
      auto actor = Ptr<vtkContextActor>::New();
      actor->SetScene(scene2d);
      (*renderer)->AddActor(actor);
      scene2d->SetRenderer(*renderer);
    };
    add_chart(0.5 + 0.5 * kPanelTop, 1.0, &m.energy_renderer, &m.energy_chart);
    add_chart(kPanelTop, 0.5 + 0.5 * kPanelTop, &m.cond_renderer, &m.cond_chart);
  }

  m.interactor = Ptr<vtkRenderWindowInteractor>::New();
  m.interactor->SetRenderWindow(window);
  AttachViewerStyle(m.interactor, this);

  auto add_slider = [&](Ptr<vtkSliderRepresentation2D> rep, void (*fn)(vtkObject*, unsigned long, void*, void*),
                        void* data) {
    auto w = Ptr<vtkSliderWidget>::New();
    w->SetInteractor(m.interactor);
    w->SetRepresentation(rep);
    w->SetAnimationModeToJump();  // a click on the tube puts the slider there
    w->SetCurrentRenderer(m.panel_renderer);
    w->SetDefaultRenderer(m.panel_renderer);
    auto cb = Ptr<vtkCallbackCommand>::New();
    cb->SetCallback(fn);
    cb->SetClientData(data);
    w->AddObserver(vtkCommand::InteractionEvent, cb);
    m.callbacks.push_back(cb);
    w->EnabledOn();
    return w;
  };
  // one slider per mode: its PD target
  const double width = 0.96 / std::max(1, D);
  for (int d = 0; d < D; ++d) {
    const std::string& name = m.scene.body->modes()[d].name;
    auto rep = MakeSliderRep(0.02 + d * width + 0.01, 0.02 + (d + 1) * width - 0.02, 0.15, -options.slider_range,
                             options.slider_range, 0.0, "target " + (name.empty() ? std::to_string(d + 1) : name),
                             options.width);
    // the mode index rides in the callback's client data as an integer beside `this`
    auto* data = new std::pair<InteractiveView*, int>(this, d);
    auto w = add_slider(
        rep,
        [](vtkObject* caller, unsigned long, void* client, void*) {
          auto* pd = static_cast<std::pair<InteractiveView*, int>*>(client);
          auto* widget = static_cast<vtkSliderWidget*>(caller);
          const double v = static_cast<vtkSliderRepresentation*>(widget->GetRepresentation())->GetValue();
          pd->first->SetModeTarget(pd->second, v);
        },
        data);
    m.mode_sliders.push_back(w);
    // freed with the widget's callback: tie its life to the callback command
    m.callbacks.back()->SetClientDataDeleteCallback([](void* p) { delete static_cast<std::pair<InteractiveView*, int>*>(p); });
  }
  // the time slider: the recorded frames
  m.time_slider = add_slider(MakeSliderRep(0.02, 0.98, 0.05, 0.0, 1.0, 0.0, "recorded frame", options.width),
                             [](vtkObject* caller, unsigned long, void* client, void*) {
                               auto* view = static_cast<InteractiveView*>(client);
                               auto* widget = static_cast<vtkSliderWidget*>(caller);
                               const double v =
                                   static_cast<vtkSliderRepresentation*>(widget->GetRepresentation())->GetValue();
                               view->ScrubTo(std::lround(v));
                             },
                             this);

  // what can be pulled: every mass point and every drawing sample
  for (int k = 0; k < m.scene.body->num_points(); ++k) m.pickable.push_back(m.scene.body->lattice_coords(k));
  {
    auto shape = Ptr<ShapeSource>::New();
    shape->SetWorld(m.world.get());
    shape->SetSamplesPerSegment(std::max(1, options.shape_samples / 4));
    shape->Update();  // fills the samples' lattice coordinates
    for (const Eigen::Vector2d& st : shape->SampleLatticeCoords()) m.pickable.push_back(st);
  }
  m.RecordFrame();
  m.UpdateTimeSlider();
  m.UpdateStatus();
  m.UpdateCharts();
}

InteractiveView::~InteractiveView() {
  // widgets first: their callbacks point at this view
  for (auto& w : impl_->mode_sliders) w->EnabledOff();
  if (impl_->time_slider) impl_->time_slider->EnabledOff();
}

ViewerScene ViewerScene::FromScript(const scene::SimulationSetup& setup) {
  ViewerScene scene;
  scene.body = setup.body;
  scene.world = setup.world;
  scene.q0 = setup.q;
  scene.qd0 = setup.qd;
  scene.t0 = setup.time;
  scene.graph = setup.graph;
  scene.object_path = setup.object_path;
  scene.mode_paths = setup.mode_paths;
  return scene;
}

void InteractiveView::Run(long max_frames, const std::string& events_file, bool keep_open) {
  Impl& m = *impl_;
  m.pacer.max_frames = max_frames;
  Initialize();
  RunViewerLoop(m.interactor, m.options.fps, m.pacer, events_file, keep_open);
}

void InteractiveView::Initialize() {
  Impl& m = *impl_;
  if (m.initialized) return;
  m.initialized = true;
  m.interactor->Initialize();
  m.view->Render();
}

void InteractiveView::Frame() {
  Impl& m = *impl_;
  const double frame_time = m.pacer.BeginFrame(m.options.fps, m.options.fixed_frame_time);
  if (m.playing && !m.scrubbing) {
    const double before = m.world->time();
    m.Advance(m.speed * frame_time);
    m.pacer.Played(m.world->time() - before);
    m.RecordFrame();
  }
  m.UpdateTimeSlider();
  if (m.options.chart_every > 0 && m.pacer.stats.frames % m.options.chart_every == 0) m.UpdateCharts();
  m.UpdateStatus();
  m.view->Render();
  if (m.pacer.EndFrame()) m.interactor->TerminateApp();
}

bool InteractiveView::HandleKey(const std::string& k) {
  Impl& m = *impl_;
  if (k == "space") SetPlaying(!m.playing || m.scrubbing);
  else if (k == "n") StepOnce();
  else if (k == "r") Restart();
  else if (k == "+" || k == "=") SetSpeed(m.speed * 2.0);
  else if (k == "-") SetSpeed(m.speed / 2.0);
  else if (k == "0") {
    for (int d = 0; d < m.slider_targets.size(); ++d) SetModeTarget(d, 0.0);
  } else if (k == "s") ToggleLayer(SceneLayer::kShape);
  else if (k == "l") ToggleLayer(SceneLayer::kLattice);
  else if (k == "m") ToggleLayer(SceneLayer::kPoints);
  else if (k == "g") ToggleLayer(SceneLayer::kGround);
  else if (k == "p") ToggleLayer(SceneLayer::kSprings);
  else if (k == "c") {
    m.FrameBody();
  } else if (k == "k") RecordPose();
  else if (k == "w") {
    try {
      const std::vector<std::string> files = SaveSession(m.options.session_path);
      m.message = "wrote " + files.front() + (files.size() > 1 ? " and " + files.back() : "");
      std::cout << "wobble view: " << m.message << std::endl;
    } catch (const std::exception& e) {
      m.message = std::string("save failed: ") + e.what();
      std::cerr << "wobble view: " << m.message << std::endl;
    }
  } else if (k == "Left" || k == "Right") {
    const long last = long(m.history.size()) - 1;
    const long at = m.scrubbing ? m.scrub_frame : last;
    ScrubTo(std::clamp(at + (k == "Left" ? -1L : 1L), 0L, last));
  } else if (k == "h") {
    std::cout << "wobble view keys: space play/pause, n step, r restart, +/- speed, 0 targets to zero, s shape, "
                 "l lattice, m mass points, g ground, p springs, c recentre, k record pose, w write session, "
                 "Left/Right scrub, q quit\n"
              << std::flush;
  } else if (k == "q" || k == "Escape") m.interactor->TerminateApp();
  else return false;
  m.UpdateStatus();
  m.view->Render();
  return true;
}

void InteractiveView::SetPlaying(bool playing) {
  Impl& m = *impl_;
  if (playing && m.scrubbing) {
    // back to the live world where it was; scrubbing only looked
    m.scrubbing = false;
    m.view->SetWorld(m.world.get());
  }
  m.playing = playing;
}
bool InteractiveView::playing() const { return impl_->playing && !impl_->scrubbing; }

void InteractiveView::StepOnce() {
  Impl& m = *impl_;
  SetPlaying(false);
  if (m.scrubbing) {
    m.scrubbing = false;
    m.view->SetWorld(m.world.get());
  }
  if (m.StepWorld()) {
    m.pacer.SetGoal(m.world->time());
    m.RecordFrame();
  }
}

void InteractiveView::Restart() {
  Impl& m = *impl_;
  m.graph_drives = !m.scene.graph.empty() && m.graph_drives;
  m.NewWorld();
  m.message = "restarted";
  m.RecordFrame();
  m.UpdateTimeSlider();
  m.UpdateCharts();
}

void InteractiveView::SetSpeed(double speed) { impl_->speed = std::clamp(speed, 1.0 / 64.0, 64.0); }
double InteractiveView::speed() const { return impl_->speed; }

void InteractiveView::ToggleLayer(SceneLayer layer) { impl_->view->SetLayerVisible(layer, !impl_->view->LayerVisible(layer)); }
bool InteractiveView::LayerVisible(SceneLayer layer) const { return impl_->view->LayerVisible(layer); }

void InteractiveView::RecordPose() {
  Impl& m = *impl_;
  const int D = m.scene.body->num_modes();
  if (D == 0) return;
  const double t = m.world->time();
  // the pose is held from the last record (or the start) until now; at least one step
  m.recorded_poses.push_back(m.world->state(0).q.tail(D));
  m.recorded_durations.push_back(std::max(t - m.last_pose_time, m.scene.world.dt));
  m.last_pose_time = t;
  m.message = "recorded pose " + std::to_string(m.recorded_poses.size());
}

std::string InteractiveView::SessionScriptText() const {
  const Impl& m = *impl_;
  scene::SessionRecord r;
  r.object_path = m.scene.object_path;
  r.mode_paths = m.scene.mode_paths;
  r.body = m.scene.body.get();
  r.world = m.scene.world;
  r.q0 = m.scene.q0;
  r.qd0 = m.scene.qd0;
  r.t0 = m.scene.t0;
  r.segments = m.sliders->segments();
  r.steps = m.session_steps;
  r.drags = m.drags;
  r.first_drag_step = m.first_drag_step;
  return scene::SessionScript(r);
}

std::vector<std::string> InteractiveView::SaveSession(const std::string& path) {
  const Impl& m = *impl_;
  std::vector<std::string> written;
  formats::WriteTextAtomically(path, SessionScriptText());
  written.push_back(path);
  if (!m.recorded_poses.empty()) {
    scene::SessionRecord r;
    r.object_path = m.scene.object_path;
    r.mode_paths = m.scene.mode_paths;
    r.body = m.scene.body.get();
    r.world = m.scene.world;
    r.q0 = m.scene.q0;
    r.qd0 = m.scene.qd0;
    r.t0 = m.scene.t0;
    std::filesystem::path p(path);
    const std::string poses = (p.parent_path() / (p.stem().string() + "_poses.wob")).string();
    formats::WriteTextAtomically(poses, scene::PoseGraphScript(r, m.recorded_poses, m.recorded_durations));
    written.push_back(poses);
  }
  return written;
}

void InteractiveView::ScrubTo(long frame) {
  Impl& m = *impl_;
  if (m.history.empty()) return;
  frame = std::clamp(frame, 0L, long(m.history.size()) - 1);
  m.playing = false;
  m.scrubbing = true;
  m.scrub_frame = frame;
  const Impl::Recorded& r = m.history[size_t(frame)];
  m.scrub_world->SetState(0, r.q, r.qd);
  m.view->SetWorld(m.scrub_world.get());
  m.UpdateTimeSlider();
  m.UpdateStatus();
  m.view->Render();
}

void InteractiveView::SetModeTarget(int mode, double target) {
  Impl& m = *impl_;
  if (mode < 0 || mode >= m.slider_targets.size()) throw std::out_of_range("SetModeTarget: no such mode");
  if (!std::isfinite(target)) throw std::invalid_argument("SetModeTarget: the target must be finite");
  if (m.graph) {  // the user takes over from the pose graph
    m.world->RemoveController(m.graph.get());
    m.graph.reset();
  }
  m.graph_drives = false;
  Eigen::VectorXd t = m.sliders->targets();
  t[mode] = target;
  m.sliders->Set(t);
  m.slider_targets = t;
  auto* rep = static_cast<vtkSliderRepresentation*>(m.mode_sliders[size_t(mode)]->GetRepresentation());
  if (rep->GetValue() != target) rep->SetValue(target);
}
const Eigen::VectorXd& InteractiveView::mode_targets() const { return impl_->sliders->targets(); }

bool InteractiveView::BeginDrag(int x, int y) {
  Impl& m = *impl_;
  if (m.scrubbing) SetPlaying(true);  // pulling acts on the live world
  const World& w = *m.world;
  double best = 30.0 * 30.0;
  int pick = -1;
  for (size_t i = 0; i < m.pickable.size(); ++i) {
    const Eigen::Vector2d d = WorldToDisplay(WorldPositionOf(w, 0, m.pickable[i])) - Eigen::Vector2d(x, y);
    if (d.squaredNorm() < best) {
      best = d.squaredNorm();
      pick = int(i);
    }
  }
  if (pick < 0) return false;
  // a spring of about 1 Hz for the whole body, half critically damped: stiff enough to lift it
  // (its weight needs a stretch of g / (2 pi)^2 = 0.25 length units), soft enough that a quick
  // move of the cursor does not fling it
  const double mass = m.scene.body->moments().m;
  const double k = m.options.drag_stiffness > 0 ? m.options.drag_stiffness : mass * std::pow(2.0 * M_PI * 1.0, 2);
  const double c = m.options.drag_damping > 0 ? m.options.drag_damping : std::sqrt(k * mass);
  Spring sp;
  sp.body = 0;
  sp.lattice_coords = m.pickable[size_t(pick)];
  sp.anchor = DisplayToWorld(x, y);
  sp.stiffness = k;
  sp.damping = c;
  EndDrag();
  m.pull = std::make_shared<control::SpringPull>(*m.world, sp);
  m.world->AddController(m.pull);
  if (m.drags++ == 0) m.first_drag_step = m.session_steps;
  return true;
}

void InteractiveView::DragTo(int x, int y) {
  if (impl_->pull) impl_->pull->Aim(*impl_->world, DisplayToWorld(x, y));
}

void InteractiveView::EndDrag() {
  Impl& m = *impl_;
  if (!m.pull) return;
  m.pull->Release(*m.world);
  m.world->RemoveController(m.pull.get());
  m.pull.reset();
}

std::optional<Eigen::Vector2d> InteractiveView::dragged_point() const {
  if (!impl_->pull) return std::nullopt;
  return impl_->pull->lattice_coords();
}

const World& InteractiveView::world() const { return *impl_->world; }
double InteractiveView::time() const { return impl_->scene.t0 + impl_->world->time(); }
long InteractiveView::num_recorded_frames() const { return long(impl_->history.size()); }
long InteractiveView::session_steps() const { return impl_->session_steps; }
const ViewerStats& InteractiveView::stats() const { return impl_->pacer.stats; }

std::string InteractiveView::StatusLine() const {
  const Impl& m = *impl_;
  std::string s;
  if (m.scrubbing && m.scrub_frame >= 0) {
    const Impl::Recorded& r = m.history[size_t(m.scrub_frame)];
    s = "recorded frame " + std::to_string(m.scrub_frame) + ": t = " + Fmt("%.3f s", m.scene.t0 + r.t) +
        "   (space: back to live)";
  } else {
    const Energies e = m.world->ComputeEnergies(0);
    s = "t = " + Fmt("%.3f s", time()) + "   E = " + Fmt("%.5g", e.total()) + " (kin " + Fmt("%.3g", e.kinetic) +
        ")\n" + (m.playing ? "playing" : "paused") + "   speed x" + Fmt("%g", m.speed);
    // measured rates only on the wall clock's runs: fixed-time runs draw the same pixels every time
    if (!m.options.fixed_frame_time && m.pacer.stats.playing_wall > 0 && m.pacer.stats.playing_frames > 1)
      s += "   " + Fmt("%.1f frames/s", (m.pacer.stats.playing_frames - 1) / m.pacer.stats.playing_wall) + ", " +
           Fmt("%.1f steps/frame", double(m.pacer.stats.steps) / double(std::max(1L, m.pacer.stats.playing_frames)));
    if (m.pull) s += "   pulling";
  }
  if (!m.message.empty()) s += "\n" + m.message;
  s += "\nh: keys";
  return s;
}

Eigen::Vector2d InteractiveView::DisplayToWorld(double x, double y) const {
  vtkRenderer* r = impl_->view->renderer();
  r->SetDisplayPoint(x, y, 0.0);
  r->DisplayToWorld();
  const double* w = r->GetWorldPoint();
  const double h = w[3] != 0.0 ? w[3] : 1.0;
  return {w[0] / h, w[1] / h};
}

Eigen::Vector2d InteractiveView::WorldToDisplay(const Eigen::Vector2d& p) const {
  vtkRenderer* r = impl_->view->renderer();
  r->SetWorldPoint(p.x(), p.y(), 0.0, 1.0);
  r->WorldToDisplay();
  const double* d = r->GetDisplayPoint();
  return {d[0], d[1]};
}

vtkRenderWindow* InteractiveView::window() { return impl_->view->window(); }
vtkRenderWindowInteractor* InteractiveView::interactor() { return impl_->interactor; }
vtkSliderWidget* InteractiveView::mode_slider(int mode) { return impl_->mode_sliders.at(size_t(mode)); }
vtkSliderWidget* InteractiveView::time_slider() { return impl_->time_slider; }
SceneView& InteractiveView::scene() { return *impl_->view; }

vtkSmartPointer<vtkImageData> InteractiveView::Capture() { return CaptureWindow(window()); }

}  // namespace wobble::pipelines
