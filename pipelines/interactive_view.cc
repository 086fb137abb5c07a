#include "pipelines/interactive_view.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkSliderWidget.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>

#include "pipelines/interactive_view_impl.h"

namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

namespace {

constexpr double kPickRadius = 30.0;  // pixels

int NumMassPoints(const World& w, int b) {
  switch (w.kind(b)) {
    case BodyKind::kLinear: return w.linear_model(b).num_points();
    case BodyKind::kFfd: break;
  }
  return w.dim(b) == 3 ? w.body<3>(b).num_points() : w.body<2>(b).num_points();
}

}  // namespace

// ---------------------------------------------------------------- Impl

bool InteractiveView::Impl::StepWorld() {
  if (stopped) return false;
  std::string why;
  try {
    if (in_keys && world->time() >= keys_end - 0.5 * world->options().dt) HandOverFromKeys();
    if (scene->Step()) {
      ++session_steps;
      ++pacer.stats.steps;
      return true;
    }
    why = world->status().message;
  } catch (const std::exception& e) {  // a behaviour that cannot act stops the run
    why = e.what();
  }
  playing = false;
  stopped = true;
  message = "simulation stopped: " + why;
  std::cerr << "wobble view: " << message << std::endl;
  return false;
}

void InteractiveView::Impl::HandOverFromKeys() {
  in_keys = false;
  scene->EndRun();  // the object takes the keys' last state and time (§4.10.1)
  if (character) {
    key_steps = session_steps;
    BeginSessionRun(scene::RunKind::kSimulate);
  } else {
    scene->BeginRun(scene::RunKind::kSimulate, false);
    world = scene->run_world();
  }
  view->SetWorld(world);
}

void InteractiveView::Impl::Advance(double duration) {
  pacer.Advance(duration, world->options().dt, [&] { return world->time(); }, [&] { return StepWorld(); });
}

// The bodies now with room around them to move by their own size every way (a pendulum
// let go from the horizontal swings through a circle of its length about its pivot).
void InteractiveView::Impl::FrameScene() {
  if (character) return FrameBody();
  const Eigen::AlignedBox3d b = SceneBounds(*world, spec);
  const double size = std::max(1e-6, b.sizes().maxCoeff());
  if (IsFlat(*world)) {
    Eigen::AlignedBox2d box(b.min().head<2>(), b.max().head<2>());
    box.extend(box.min() - Eigen::Vector2d::Constant(size));
    box.extend(box.max() + Eigen::Vector2d::Constant(size));
    view->FrameBox(box, 0.02);
  } else {
    Eigen::AlignedBox3d box = b;
    box.extend(box.min() - Eigen::Vector3d::Constant(0.5 * size));
    box.extend(box.max() + Eigen::Vector3d::Constant(0.5 * size));
    view->FrameBox3d(box, 0.02);
  }
}

Eigen::VectorXd InteractiveView::Impl::DisplayToWorldAt(double x, double y, double z_display, int dim) const {
  vtkRenderer* r = view->renderer();
  r->SetDisplayPoint(x, y, z_display);
  r->DisplayToWorld();
  double w[4];
  r->GetWorldPoint(w);
  const double h = std::abs(w[3]) > 1e-300 ? w[3] : 1.0;
  Eigen::VectorXd p(dim);
  for (int i = 0; i < dim; ++i) p[i] = w[i] / h;
  return p;
}

void InteractiveView::Impl::UpdateDragLine() {
  auto points = Ptr<vtkPoints>::New();
  auto lines = Ptr<vtkCellArray>::New();
  if (constraint_pull) {
    const Eigen::Vector3d a = To3(world->PointPosition(constraint_pull->point())), c = To3(constraint_pull->aim());
    points->InsertNextPoint(a.data());
    points->InsertNextPoint(c.data());
    const vtkIdType ids[2] = {0, 1};
    lines->InsertNextCell(2, ids);
  }
  drag_line->SetPoints(points);
  drag_line->SetLines(lines);
  drag_line->Modified();
}

void InteractiveView::Impl::UpdateStatus() { status->SetInput(self->StatusLine().c_str()); }

void InteractiveView::Impl::RequireCharacter(const char* what) const {
  if (!character) throw std::logic_error(std::string(what) + ": only in a character session (an FFD object), not in a scene");
}

// ---------------------------------------------------------------- the view

InteractiveView::InteractiveView(scene::Scene& scene, ViewerOptions options) : impl_(new Impl) {
  if (!HasDisplay())
    throw std::runtime_error("wobble view needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run it "
                             "on a desktop, or headless under xvfb-run -a -s \"-screen 0 1280x1024x24\"");
  if (!(options.fps > 0 && options.fps <= 1000)) throw std::invalid_argument("fps must be in (0, 1000]");
  if (!(options.speed > 0 && std::isfinite(options.speed))) throw std::invalid_argument("speed must be positive");
  if (!(options.slider_range > 0 && std::isfinite(options.slider_range)))
    throw std::invalid_argument("the slider range must be positive");
  if (!scene.has_bodies() && !scene.object().loaded())
    throw std::invalid_argument("InteractiveView: the scene has no bodies and no FFD object");
  Impl& m = *impl_;
  m.self = this;
  m.scene = &scene;
  m.options = options;
  m.speed = options.speed;
  m.playing = options.start_playing;
  m.object3 = !scene.has_bodies() && scene.object().dim() == 3;
  m.character = !scene.has_bodies() && !m.object3;
  const scene::SceneDrawing drawing = scene.Drawing();
  if (m.character) {
    m.setup = scene.CurrentSetup();
    m.graph_drives = !m.setup.graph.empty();
    m.slider_targets = Eigen::VectorXd::Zero(m.setup.body->num_modes());
    m.StartSession();
  } else {
    m.spec = SceneSpecOf(drawing.drawings, drawing.anchors);
    if (m.object3) {
      // the 3D object's own runs, as `keyframe` and `simul` make them: its keys first when asked,
      // then its simulation (pose graph and springs included); no record of every step
      m.in_keys = options.keys_first && scene.control().keys.Duration() > 0.0;
      m.keys_end = scene.time() + (m.in_keys ? scene.control().keys.Duration() : 0.0);
      scene.BeginRun(m.in_keys ? scene::RunKind::kKeyframes : scene::RunKind::kSimulate, false);
    } else {
      scene.BeginRun();
    }
    m.world = scene.run_world();
    m.pacer.SetGoal(m.world->time());
  }

  // render's drawing path, on screen; a character session leaves room for its panels
  SceneOptions so;
  so.width = options.width;
  so.height = options.height;
  so.offscreen = false;
  so.shape_samples = options.shape_samples;
  if (m.character) {
    so.viewport[0] = 0.0;
    so.viewport[1] = kSessionPanelTop;
    so.viewport[2] = options.charts ? kSessionSceneRight : 1.0;
    so.viewport[3] = 1.0;
    so.overlay = false;  // the status text says more (and the scrubbed time)
  } else {
    so.point_size = 5.0;
    so.azimuth = drawing.azimuth;
    so.elevation = drawing.elevation;
  }
  m.view = std::make_unique<SceneView>(m.world, so, m.spec);
  m.view->window()->SetWindowName("wobble view");
  m.FrameScene();

  m.drag_line = Ptr<vtkPolyData>::New();
  auto mapper = Ptr<vtkPolyDataMapper>::New();
  mapper->SetInputData(m.drag_line);
  m.drag_actor = Ptr<vtkActor>::New();
  m.drag_actor->SetMapper(mapper);
  m.drag_actor->GetProperty()->SetColor(0.1, 0.55, 0.2);  // the anchors' green
  m.drag_actor->GetProperty()->SetLineWidth(2.0f);
  m.drag_actor->GetProperty()->SetLighting(false);
  m.drag_actor->SetPosition(0, 0, IsFlat(*m.world) ? 4.0 : 0.0);
  m.view->renderer()->AddActor(m.drag_actor);
  m.UpdateDragLine();

  m.status = Ptr<vtkTextActor>::New();
  m.status->GetTextProperty()->SetColor(0, 0, 0);
  m.status->GetTextProperty()->SetFontSize(14);
  m.status->GetTextProperty()->SetFontFamilyToCourier();
  if (m.character) {
    m.status->GetTextProperty()->SetVerticalJustificationToTop();
    m.status->SetDisplayPosition(8, options.height - 8);
  } else {
    m.status->SetDisplayPosition(8, 8);
  }
  m.view->renderer()->AddActor2D(m.status);

  m.interactor = Ptr<vtkRenderWindowInteractor>::New();
  m.interactor->SetRenderWindow(m.view->window());
  AttachViewerStyle(m.interactor, this);
  if (m.character) m.BuildSessionPanels();
  m.UpdateStatus();
}

InteractiveView::~InteractiveView() {
  Impl& m = *impl_;
  // widgets first: their callbacks point at this view
  for (auto& w : m.mode_sliders) w->EnabledOff();
  if (m.time_slider) m.time_slider->EnabledOff();
  try {
    EndDrag();
    if (m.scene->running()) m.scene->EndRun();  // the object (or scene) goes on from here
  } catch (const std::exception& e) {
    std::cerr << "wobble view: " << e.what() << std::endl;
  }
}

bool InteractiveView::character() const { return impl_->character; }

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
    if (m.character) m.RecordFrame();
  }
  if (m.character) {
    m.UpdateTimeSlider();
    m.ShowGraphTargets();
    if (m.options.chart_every > 0 && m.pacer.stats.frames % m.options.chart_every == 0) m.UpdateCharts();
  }
  m.UpdateDragLine();
  m.UpdateStatus();
  m.view->Render();
  if (m.pacer.EndFrame()) m.interactor->TerminateApp();
}

bool InteractiveView::HandleKey(const std::string& k) {
  Impl& m = *impl_;
  const bool c = m.character;
  if (k == "space") SetPlaying(!m.playing || m.scrubbing);
  else if (k == "n") StepOnce();
  else if (k == "+" || k == "=") SetSpeed(m.speed * 2.0);
  else if (k == "-") SetSpeed(m.speed / 2.0);
  else if (k == "s") ToggleLayer(SceneLayer::kShape);
  else if (k == "l") ToggleLayer(SceneLayer::kLattice);
  else if (k == "m") ToggleLayer(SceneLayer::kPoints);
  else if (k == "g") ToggleLayer(SceneLayer::kGround);
  else if (k == "p") ToggleLayer(SceneLayer::kSprings);
  else if (k == "a") ToggleLayer(SceneLayer::kAnchors);
  else if (k == "c") m.FrameScene();
  else if ((k == "[" || k == "]") && !IsFlat(*m.world)) {  // orbit the 3D camera about its focal point
    m.view->renderer()->GetActiveCamera()->Azimuth(k == "[" ? -15.0 : 15.0);
    m.view->renderer()->ResetCameraClippingRange();
  }
  else if (c && k == "r") Restart();
  else if (c && k == "0") {
    for (int d = 0; d < m.slider_targets.size(); ++d) SetModeTarget(d, 0.0);
  } else if (c && k == "k") RecordPose();
  else if (c && k == "w") {
    try {
      const std::vector<std::string> files = SaveSession(m.options.session_path);
      m.message = "wrote " + files.front() + (files.size() > 1 ? " and " + files.back() : "");
      std::cout << "wobble view: " << m.message << std::endl;
    } catch (const std::exception& e) {
      m.message = std::string("save failed: ") + e.what();
      std::cerr << "wobble view: " << m.message << std::endl;
    }
  } else if (c && (k == "Left" || k == "Right")) {
    const long last = long(m.history.size()) - 1;
    const long at = m.scrubbing ? m.scrub_frame : last;
    ScrubTo(std::clamp(at + (k == "Left" ? -1L : 1L), 0L, last));
  } else if (k == "h") {
    std::cout << "wobble view keys: space play/pause, n step, +/- speed, s shapes, l lattice (control boxes), "
                 "m mass points, g ground, p springs and constraints, a named points, c recentre, [ ] orbit (3D), "
                 "q quit"
              << (c ? "; r restart, 0 targets to zero, k record pose, w write session, Left/Right scrub" : "")
              << "; the left mouse button pulls a point\n"
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
    m.view->SetWorld(m.world);
  }
  m.playing = playing;
}
bool InteractiveView::playing() const { return impl_->playing && !impl_->scrubbing; }

void InteractiveView::StepOnce() {
  Impl& m = *impl_;
  SetPlaying(false);
  if (m.scrubbing) {
    m.scrubbing = false;
    m.view->SetWorld(m.world);
  }
  if (m.StepWorld()) {
    m.pacer.SetGoal(m.world->time());
    if (m.character) m.RecordFrame();
  }
  m.UpdateDragLine();
}

void InteractiveView::SetSpeed(double speed) { impl_->speed = std::clamp(speed, 1.0 / 64.0, 64.0); }
double InteractiveView::speed() const { return impl_->speed; }

void InteractiveView::ToggleLayer(SceneLayer layer) {
  Impl& m = *impl_;
  // a layer the scene does not draw (no named points) still toggles the drag line
  const bool show = !LayerVisible(layer);
  m.view->SetLayerVisible(layer, show);
  if (layer == SceneLayer::kAnchors) m.drag_actor->SetVisibility(show);
}
bool InteractiveView::LayerVisible(SceneLayer layer) const {
  if (layer == SceneLayer::kAnchors) return impl_->drag_actor->GetVisibility() != 0;
  return impl_->view->LayerVisible(layer);
}

bool InteractiveView::BeginDrag(int x, int y) {
  Impl& m = *impl_;
  EndDrag();
  if (m.character) return m.BeginSpringPull(x, y);
  if (m.in_keys) return false;  // a keyframed body is placed, not pulled
  World& w = *m.world;
  // candidates: named points of bodies first (a tie goes to them), then every mass point
  std::vector<MaterialPoint> candidates;
  for (const AnchorSource::Anchor& a : m.spec.anchors)
    if (a.point.body >= 0) candidates.push_back(a.point);
  for (int b = 0; b < w.num_bodies(); ++b)
    for (int k = 0; k < NumMassPoints(w, b); ++k) candidates.push_back(MassPointOf(b, k));
  double best = kPickRadius;
  std::optional<MaterialPoint> pick;
  for (const MaterialPoint& p : candidates) {
    const Eigen::Vector3d d = WorldToDisplay(w.PointPosition(p));
    const double dist = std::hypot(d[0] - x, d[1] - y);
    if (dist < best) {
      best = dist;
      pick = p;
    }
  }
  if (!pick) return false;
  m.constraint_pull = std::make_shared<control::ConstraintPull>(w, *pick, kDragTime);
  w.AddController(m.constraint_pull);
  DragTo(x, y);
  return true;
}

void InteractiveView::DragTo(int x, int y) {
  Impl& m = *impl_;
  if (m.spring_pull) m.spring_pull->Aim(*m.world, DisplayToWorld(x, y));
  if (!m.constraint_pull) return;
  const Eigen::VectorXd now = m.world->PointPosition(m.constraint_pull->point());
  // the cursor on the plane through the point that faces the camera; the next step's start takes it
  m.constraint_pull->Aim(m.DisplayToWorldAt(x, y, WorldToDisplay(now)[2], int(now.size())));
  m.UpdateDragLine();
}

void InteractiveView::EndDrag() {
  Impl& m = *impl_;
  if (m.spring_pull) {
    m.spring_pull->Release(*m.world);
    m.world->RemoveController(m.spring_pull.get());
    m.spring_pull.reset();
  }
  if (m.constraint_pull) {
    m.constraint_pull->Release(*m.world);
    m.world->RemoveController(m.constraint_pull.get());
    m.constraint_pull.reset();
    m.UpdateDragLine();
  }
}

std::optional<MaterialPoint> InteractiveView::dragged_point() const {
  const Impl& m = *impl_;
  if (m.spring_pull) return At(0, Eigen::VectorXd(m.spring_pull->lattice_coords().head<2>()));  // a 2D character
  if (m.constraint_pull) return m.constraint_pull->point();
  return std::nullopt;
}
int InteractiveView::drag_constraint() const {
  return impl_->constraint_pull ? impl_->constraint_pull->constraint() : -1;
}
Eigen::VectorXd InteractiveView::drag_target() const {
  const Impl& m = *impl_;
  if (m.spring_pull) return m.spring_pull->anchor().head<2>();
  if (m.constraint_pull) return m.constraint_pull->aim();
  return Eigen::VectorXd();
}

const World& InteractiveView::world() const { return *impl_->world; }
double InteractiveView::time() const { return impl_->world->time(); }
const ViewerStats& InteractiveView::stats() const { return impl_->pacer.stats; }
const std::string& InteractiveView::message() const { return impl_->message; }
bool InteractiveView::stopped() const { return impl_->stopped; }

std::string InteractiveView::StatusLine() const {
  const Impl& m = *impl_;
  if (m.character) return m.SessionStatus();
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s x%g   t %.2f%s   largest constraint violation %.2g%s",
                m.playing ? "playing" : "paused", m.speed, m.world->time(), m.in_keys ? " (keys)" : "",
                m.world->MaxViolation(), m.constraint_pull ? "   dragging" : "");
  return std::string(buf) + (m.message.empty() ? "" : "\n" + m.message);
}

Eigen::Vector3d InteractiveView::WorldToDisplay(const Eigen::VectorXd& p) const {
  vtkRenderer* r = impl_->view->renderer();
  const Eigen::Vector3d x = To3(p);
  r->SetWorldPoint(x[0], x[1], x[2], 1.0);
  r->WorldToDisplay();
  double d[3];
  r->GetDisplayPoint(d);
  return Eigen::Vector3d(d[0], d[1], d[2]);
}

Eigen::Vector2d InteractiveView::DisplayToWorld(double x, double y) const {
  const Eigen::VectorXd p = impl_->DisplayToWorldAt(x, y, 0.0, 2);
  return {p[0], p[1]};
}

vtkRenderWindow* InteractiveView::window() { return impl_->view->window(); }
vtkRenderWindowInteractor* InteractiveView::interactor() { return impl_->interactor; }
SceneView& InteractiveView::view() { return *impl_->view; }

// An on-screen window's back buffer is undefined after the swap: draw again and read it, not
// SceneView::Capture's read-back of an offscreen render.
vtkSmartPointer<vtkImageData> InteractiveView::Capture() { return CaptureWindow(window()); }

}  // namespace wobble::pipelines
