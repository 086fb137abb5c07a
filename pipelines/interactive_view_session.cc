#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <stdexcept>

#include <vtkCallbackCommand.h>
#include <vtkChartXY.h>
#include <vtkContextActor.h>
#include <vtkContextScene.h>
#include <vtkProperty2D.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSliderRepresentation2D.h>
#include <vtkSliderWidget.h>
#include <vtkTextProperty.h>

#include "pipelines/charts.h"
#include "pipelines/interactive_view_impl.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/scene/script_writer.h"

// What a character session adds to InteractiveView (interactive_view.h): the mode sliders,
// the live charts, the recorded frames and the time slider, restart, poses and the session
// script.
namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

namespace {

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

// The charts show the last kChartWindow seconds: redrawing the whole of a long session every
// few frames would slow the window down as it goes.
constexpr double kChartWindow = 30.0;

void Trim(ChartSpec* spec) {
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

}  // namespace

// ---------------------------------------------------------------- Impl

// The object's run from the setup: the scene's run (its pose graph included) without a record
// of every step, the sliders' controller behind the pose graph so that it logs its switches.
void InteractiveView::Impl::StartSession() {
  if (scene->running()) scene->EndRun();
  scene->object().SetState(setup.q, setup.qd);
  scene->set_time(setup.time);
  in_keys = options.keys_first && scene->control().keys.Duration() > 0.0;
  keys_end = setup.time + (in_keys ? scene->control().keys.Duration() : 0.0);
  BeginSessionRun(in_keys ? scene::RunKind::kKeyframes : scene::RunKind::kSimulate);
  stopped = false;
  pacer.SetGoal(world->time());
  session_steps = 0;
  key_steps = 0;
  drags = 0;
  first_drag_step = -1;
  recorded_poses.clear();
  recorded_durations.clear();
  last_pose_time = world->time();
  history.clear();
  recorder = std::make_unique<RunRecorder>(0);
  if (view) view->SetWorld(world);
  scrubbing = false;
}

void InteractiveView::Impl::BuildSessionPanels() {
  scrub_world = std::make_unique<World>(setup.world);
  scrub_world->AddBody(setup.body);
  vtkRenderWindow* window = view->window();
  // the panel of sliders along the bottom
  panel_renderer = Ptr<vtkRenderer>::New();
  panel_renderer->SetViewport(0.0, 0.0, 1.0, kSessionPanelTop);
  panel_renderer->SetBackground(0.93, 0.93, 0.93);
  panel_renderer->InteractiveOff();
  window->AddRenderer(panel_renderer);

  // the live charts at the right
  if (options.charts) {
    auto add_chart = [&](double y0, double y1, Ptr<vtkRenderer>* renderer, Ptr<vtkChartXY>* chart) {
      *renderer = Ptr<vtkRenderer>::New();
      (*renderer)->SetViewport(kSessionSceneRight, y0, 1.0, y1);
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
    add_chart(0.5 + 0.5 * kSessionPanelTop, 1.0, &energy_renderer, &energy_chart);
    add_chart(kSessionPanelTop, 0.5 + 0.5 * kSessionPanelTop, &cond_renderer, &cond_chart);
  }

  auto add_slider = [&](Ptr<vtkSliderRepresentation2D> rep, void (*fn)(vtkObject*, unsigned long, void*, void*),
                        void* data) {
    auto w = Ptr<vtkSliderWidget>::New();
    w->SetInteractor(interactor);
    w->SetRepresentation(rep);
    w->SetAnimationModeToJump();  // a click on the tube puts the slider there
    w->SetCurrentRenderer(panel_renderer);
    w->SetDefaultRenderer(panel_renderer);
    auto cb = Ptr<vtkCallbackCommand>::New();
    cb->SetCallback(fn);
    cb->SetClientData(data);
    w->AddObserver(vtkCommand::InteractionEvent, cb);
    callbacks.push_back(cb);
    w->EnabledOn();
    return w;
  };
  // one slider per mode: its PD target
  const int D = setup.body->num_modes();
  const double width = 0.96 / std::max(1, D);
  for (int d = 0; d < D; ++d) {
    const std::string& name = setup.body->modes()[d].name;
    auto rep = MakeSliderRep(0.02 + d * width + 0.01, 0.02 + (d + 1) * width - 0.02, 0.15, -options.slider_range,
                             options.slider_range, 0.0, "target " + (name.empty() ? std::to_string(d + 1) : name),
                             options.width);
    // the mode index rides in the callback's client data as an integer beside the view
    auto* data = new std::pair<InteractiveView*, int>(self, d);
    auto w = add_slider(
        rep,
        [](vtkObject* caller, unsigned long, void* client, void*) {
          auto* pd = static_cast<std::pair<InteractiveView*, int>*>(client);
          auto* widget = static_cast<vtkSliderWidget*>(caller);
          const double v = static_cast<vtkSliderRepresentation*>(widget->GetRepresentation())->GetValue();
          pd->first->SetModeTarget(pd->second, v);
        },
        data);
    mode_sliders.push_back(w);
    // freed with the widget's callback: tie its life to the callback command
    callbacks.back()->SetClientDataDeleteCallback([](void* p) { delete static_cast<std::pair<InteractiveView*, int>*>(p); });
  }
  // the time slider: the recorded frames
  time_slider = add_slider(MakeSliderRep(0.02, 0.98, 0.05, 0.0, 1.0, 0.0, "recorded frame", options.width),
                           [](vtkObject* caller, unsigned long, void* client, void*) {
                             auto* view = static_cast<InteractiveView*>(client);
                             auto* widget = static_cast<vtkSliderWidget*>(caller);
                             const double v =
                                 static_cast<vtkSliderRepresentation*>(widget->GetRepresentation())->GetValue();
                             view->ScrubTo(std::lround(v));
                           },
                           self);

  // what can be pulled: every mass point and every drawing sample
  for (int k = 0; k < setup.body->num_points(); ++k) pickable.push_back(setup.body->lattice_coords(k));
  {
    auto shape = Ptr<ShapeSource>::New();
    shape->SetWorld(world);
    shape->SetSamplesPerSegment(std::max(1, options.shape_samples / 4));
    shape->Update();  // fills the samples' lattice coordinates
    for (const Eigen::Vector2d& st : shape->SampleLatticeCoords()) pickable.push_back(st);
  }
  RecordFrame();
  UpdateTimeSlider();
  UpdateCharts();
}

void InteractiveView::Impl::BeginSessionRun(scene::RunKind kind) {
  scene->BeginRun(kind, /*keep_steps=*/false);
  world = scene->run_world();
  if (!graph_drives) scene->StopPoseGraph();
  world->SetModeTargets(0, slider_targets);
  sliders = std::make_shared<control::ModeTargetController>(*world, 0);
  world->AddController(sliders);
  spring_pull.reset();  // a pull acts on the run's world
}

void InteractiveView::Impl::RecordFrame() {
  if (history.size() >= size_t(std::max(1L, options.max_history))) history.erase(history.begin());
  history.push_back({world->time(), world->q(0), world->qd(0)});
  recorder->Sample(*world);
}

void InteractiveView::Impl::UpdateTimeSlider() {
  auto* rep = vtkSliderRepresentation2D::SafeDownCast(time_slider->GetRepresentation());
  const double last = double(std::max<size_t>(1, history.size()) - 1);
  rep->SetMinimumValue(0.0);
  rep->SetMaximumValue(std::max(1.0, last));
  rep->SetValue(scrubbing ? double(scrub_frame) : last);
}

// While the pose graph drives, the mode sliders show its targets as they change (its smoothed
// switches included); moving one hands control to the sliders (SetModeTarget). Setting a
// representation's value fires no interaction callback.
void InteractiveView::Impl::ShowGraphTargets() {
  if (!graph_drives) return;
  const Eigen::VectorXd& targets = sliders->targets();
  for (size_t d = 0; d < mode_sliders.size() && Eigen::Index(d) < targets.size(); ++d) {
    auto* rep = static_cast<vtkSliderRepresentation*>(mode_sliders[d]->GetRepresentation());
    if (rep->GetValue() != targets[Eigen::Index(d)]) rep->SetValue(targets[Eigen::Index(d)]);
  }
}

void InteractiveView::Impl::UpdateCharts() {
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
void InteractiveView::Impl::FrameBody() {
  const World& w = scrubbing ? *scrub_world : *world;
  Eigen::AlignedBox2d box = BodyBounds<2>(w, 0);
  const double size = box.sizes().maxCoeff();
  const Ground& g = setup.world.params.ground;
  if (g.enabled && std::abs(std::cos(g.slope)) > 1e-6) {
    const double x = box.center().x();
    const double ground_y = g.point.y() + std::tan(g.slope) * (x - g.point.x());
    if (ground_y < box.min().y() && ground_y > box.min().y() - 4.0 * size) box.extend(Eigen::Vector2d(x, ground_y));
  }
  box.extend(box.min() - Eigen::Vector2d(size, 0.4 * size));
  box.extend(box.max() + Eigen::Vector2d(size, 0.8 * size));
  view->FrameBox(box);
}

std::string InteractiveView::Impl::SessionStatus() const {
  std::string s;
  if (scrubbing && scrub_frame >= 0) {
    const Recorded& r = history[size_t(scrub_frame)];
    s = "recorded frame " + std::to_string(scrub_frame) + ": t = " + Fmt("%.3f s", r.t) + "   (space: back to live)";
  } else {
    const Energies e = world->ComputeEnergies(0);
    s = "t = " + Fmt("%.3f s", world->time()) + "   E = " + Fmt("%.5g", e.total()) + " (kin " + Fmt("%.3g", e.kinetic) +
        ")\n" + (playing ? "playing" : "paused") + "   speed x" + Fmt("%g", speed);
    // measured rates only on the wall clock's runs: fixed-time runs draw the same pixels every time
    if (!options.fixed_frame_time && pacer.stats.playing_wall > 0 && pacer.stats.playing_frames > 1)
      s += "   " + Fmt("%.1f frames/s", (pacer.stats.playing_frames - 1) / pacer.stats.playing_wall) + ", " +
           Fmt("%.1f steps/frame", double(pacer.stats.steps) / double(std::max(1L, pacer.stats.playing_frames)));
    if (spring_pull) s += "   pulling";
  }
  if (!message.empty()) s += "\n" + message + (stopped ? " (r restarts)" : "");
  s += "\nh: keys";
  return s;
}

bool InteractiveView::Impl::BeginSpringPull(int x, int y) {
  if (scrubbing) self->SetPlaying(true);  // pulling acts on the live world
  double best = 30.0 * 30.0;
  int pick = -1;
  for (size_t i = 0; i < pickable.size(); ++i) {
    const Eigen::Vector3d d = self->WorldToDisplay(WorldPositionOf(*world, 0, pickable[i])) - Eigen::Vector3d(x, y, 0);
    if (d.head<2>().squaredNorm() < best) {
      best = d.head<2>().squaredNorm();
      pick = int(i);
    }
  }
  if (pick < 0) return false;
  // a spring of about 1 Hz for the whole body, half critically damped: stiff enough to lift it
  // (its weight needs a stretch of g / (2 pi)^2 = 0.25 length units), soft enough that a quick
  // move of the cursor does not fling it
  const double mass = setup.body->moments().m;
  const double k = options.drag_stiffness > 0 ? options.drag_stiffness : mass * std::pow(2.0 * M_PI * 1.0, 2);
  const double c = options.drag_damping > 0 ? options.drag_damping : std::sqrt(k * mass);
  Spring sp;
  sp.body = 0;
  sp.lattice_coords << pickable[size_t(pick)], 0.0;  // the view's character is 2D
  sp.anchor << self->DisplayToWorld(x, y), 0.0;
  sp.stiffness = k;
  sp.damping = c;
  spring_pull = std::make_shared<control::SpringPull>(*world, sp);
  world->AddController(spring_pull);
  if (drags++ == 0) first_drag_step = session_steps;
  return true;
}

// ---------------------------------------------------------------- the session's API

void InteractiveView::Restart() {
  Impl& m = *impl_;
  m.RequireCharacter("Restart");
  m.graph_drives = !m.setup.graph.empty() && m.graph_drives;
  m.StartSession();
  m.message = "restarted";
  m.RecordFrame();
  m.UpdateTimeSlider();
  m.UpdateCharts();
}

void InteractiveView::RecordPose() {
  Impl& m = *impl_;
  m.RequireCharacter("RecordPose");
  const int D = m.setup.body->num_modes();
  if (D == 0) return;
  const double t = m.world->time();
  // the pose is held from the last record (or the start) until now; at least one step
  m.recorded_poses.push_back(m.world->q(0).tail(D));
  m.recorded_durations.push_back(std::max(t - m.last_pose_time, m.setup.world.dt));
  m.last_pose_time = t;
  m.message = "recorded pose " + std::to_string(m.recorded_poses.size());
}

namespace {
scene::SessionRecord SessionStart(const scene::SimulationSetup& setup) {
  scene::SessionRecord r;
  r.object_path = setup.object_path;
  r.mode_paths = setup.mode_paths;
  r.body = setup.body.get();
  r.world = setup.world;
  r.q0 = setup.q;
  r.qd0 = setup.qd;
  r.t0 = setup.time;
  return r;
}
}  // namespace

std::string InteractiveView::SessionScriptText() const {
  const Impl& m = *impl_;
  m.RequireCharacter("SessionScriptText");
  scene::SessionRecord r = SessionStart(m.setup);
  r.segments = m.sliders->segments();
  r.steps = m.session_steps;
  r.drags = m.drags;
  r.first_drag_step = m.first_drag_step;
  if (m.options.keys_first && m.scene->control().keys.Duration() > 0.0) {  // the session began with the keys
    r.keys = m.scene->control().keys;
    r.hold = m.scene->control().hold;
    r.key_steps = m.in_keys ? m.session_steps : m.key_steps;
  }
  return scene::SessionScript(r);
}

std::vector<std::string> InteractiveView::SaveSession(const std::string& path) {
  const Impl& m = *impl_;
  m.RequireCharacter("SaveSession");
  std::vector<std::string> written;
  formats::WriteTextAtomically(path, SessionScriptText());
  written.push_back(path);
  if (!m.recorded_poses.empty()) {
    std::filesystem::path p(path);
    const std::string poses = (p.parent_path() / (p.stem().string() + "_poses.wob")).string();
    formats::WriteTextAtomically(poses, scene::PoseGraphScript(SessionStart(m.setup), m.recorded_poses, m.recorded_durations));
    written.push_back(poses);
  }
  return written;
}

void InteractiveView::ScrubTo(long frame) {
  Impl& m = *impl_;
  m.RequireCharacter("ScrubTo");
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
  m.RequireCharacter("SetModeTarget");
  if (mode < 0 || mode >= m.slider_targets.size()) throw std::out_of_range("SetModeTarget: no such mode");
  if (!std::isfinite(target)) throw std::invalid_argument("SetModeTarget: the target must be finite");
  if (m.graph_drives) {  // the user takes over from the pose graph
    m.scene->StopPoseGraph();
    m.graph_drives = false;
  }
  Eigen::VectorXd t = m.sliders->targets();
  t[mode] = target;
  m.sliders->Set(t);
  m.slider_targets = t;
  auto* rep = static_cast<vtkSliderRepresentation*>(m.mode_sliders[size_t(mode)]->GetRepresentation());
  if (rep->GetValue() != target) rep->SetValue(target);
}

const Eigen::VectorXd& InteractiveView::mode_targets() const {
  impl_->RequireCharacter("mode_targets");
  return impl_->sliders->targets();
}
long InteractiveView::num_recorded_frames() const { return long(impl_->history.size()); }
long InteractiveView::session_steps() const { return impl_->session_steps; }
vtkSliderWidget* InteractiveView::mode_slider(int mode) { return impl_->mode_sliders.at(size_t(mode)); }
vtkSliderWidget* InteractiveView::time_slider() { return impl_->time_slider; }

}  // namespace wobble::pipelines
