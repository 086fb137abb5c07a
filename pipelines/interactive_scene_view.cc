#include "pipelines/interactive_scene_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <stdexcept>

#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkImageData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderWindow.h>
#include <vtkRenderWindowInteractor.h>
#include <vtkRenderer.h>
#include <vtkTextActor.h>
#include <vtkTextProperty.h>
#include <vtkWindowToImageFilter.h>

#include "wobble/control/pulls.h"

namespace wobble::pipelines {

template <class T> using Ptr = vtkSmartPointer<T>;

namespace {

constexpr double kPickRadius = 30.0;  // pixels


int NumMassPoints(const World& w, int b) {
  return w.kind(b) == BodyKind::kLinear ? w.linear_model(b).num_points() : w.body(b).num_points();
}

Eigen::Vector3d To3(const Eigen::VectorXd& p) {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  x.head(std::min<Eigen::Index>(3, p.size())) = p.head(std::min<Eigen::Index>(3, p.size()));
  return x;
}

}  // namespace

struct InteractiveSceneView::Impl {
  InteractiveSceneView* self = nullptr;
  InteractiveSceneInput input;
  ViewerOptions options;
  std::unique_ptr<SceneView> view;
  Ptr<vtkRenderWindowInteractor> interactor;
  Ptr<vtkTextActor> status;
  // the drag: the line from the point to the cursor, drawn with the anchors
  Ptr<vtkPolyData> drag_line;
  Ptr<vtkActor> drag_actor;
  std::shared_ptr<control::ConstraintPull> pull;  // the world's controller while dragging
  bool playing = true;
  double speed = 1.0;
  std::string message;
  FramePacer pacer;  // frame clock, the simulated time asked for, measurements
  bool initialized = false;

  World& world() { return *input.world; }

  bool StepWorld() {
    try {
      input.step();
    } catch (const std::exception& e) {
      playing = false;
      message = std::string("stopped: ") + e.what();
      std::cerr << "wobble view: " << message << std::endl;
      return false;
    }
    ++pacer.stats.steps;
    return true;
  }

  void Advance(double duration) {
    pacer.Advance(duration, world().options().dt, [&] { return world().time(); }, [&] { return StepWorld(); });
  }

  // The bodies now with room around them to move by their own size every way (a pendulum
  // let go from the horizontal swings through a circle of its length about its pivot).
  void FrameScene() {
    const Eigen::AlignedBox3d b = SceneBounds(world(), input.spec);
    const double size = std::max(1e-6, b.sizes().maxCoeff());
    if (IsFlat(world())) {
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

  Eigen::VectorXd DisplayToWorld(double x, double y, double z_display, int dim) const {
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

  void UpdateDragLine() {
    auto points = Ptr<vtkPoints>::New();
    auto lines = Ptr<vtkCellArray>::New();
    if (pull) {
      const Eigen::Vector3d a = To3(world().PointPosition(pull->point())), c = To3(pull->aim());
      points->InsertNextPoint(a.data());
      points->InsertNextPoint(c.data());
      const vtkIdType ids[2] = {0, 1};
      lines->InsertNextCell(2, ids);
    }
    drag_line->SetPoints(points);
    drag_line->SetLines(lines);
    drag_line->Modified();
  }

  void UpdateStatus() { status->SetInput(self->StatusLine().c_str()); }
};

InteractiveSceneView::InteractiveSceneView(InteractiveSceneInput input, ViewerOptions options) : impl_(new Impl) {
  if (!HasDisplay())
    throw std::runtime_error("wobble view needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run it "
                             "on a desktop, or headless under xvfb-run -a -s \"-screen 0 1280x1024x24\"");
  if (!input.world || input.world->num_bodies() == 0) throw std::invalid_argument("InteractiveSceneView: no bodies");
  if (!input.step) throw std::invalid_argument("InteractiveSceneView: no step function");
  if (!(options.fps > 0 && options.fps <= 1000)) throw std::invalid_argument("fps must be in (0, 1000]");
  if (!(options.speed > 0 && std::isfinite(options.speed))) throw std::invalid_argument("speed must be positive");
  Impl& m = *impl_;
  m.self = this;
  m.input = std::move(input);
  m.options = options;
  m.speed = options.speed;
  m.playing = options.start_playing;
  m.pacer.SetGoal(m.world().time());

  // render's drawing path (trajectory_render.h's view options), on screen
  SceneOptions so;
  so.width = options.width;
  so.height = options.height;
  so.offscreen = false;
  so.point_size = 5.0;
  so.shape_samples = options.shape_samples;
  so.azimuth = m.input.azimuth;
  so.elevation = m.input.elevation;
  m.view = std::make_unique<SceneView>(m.input.world, so, m.input.spec);
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
  m.drag_actor->SetPosition(0, 0, IsFlat(m.world()) ? 4.0 : 0.0);
  m.view->renderer()->AddActor(m.drag_actor);
  m.UpdateDragLine();

  m.status = Ptr<vtkTextActor>::New();
  m.status->GetTextProperty()->SetColor(0, 0, 0);
  m.status->GetTextProperty()->SetFontSize(14);
  m.status->GetTextProperty()->SetFontFamilyToCourier();
  m.status->SetDisplayPosition(8, 8);
  m.view->renderer()->AddActor2D(m.status);
  m.UpdateStatus();

  m.interactor = Ptr<vtkRenderWindowInteractor>::New();
  m.interactor->SetRenderWindow(m.view->window());
  AttachViewerStyle(m.interactor, this);
}

InteractiveSceneView::~InteractiveSceneView() {
  EndDrag();
}

void InteractiveSceneView::Run(long max_frames, const std::string& events_file, bool keep_open) {
  Impl& m = *impl_;
  m.pacer.max_frames = max_frames;
  Initialize();
  RunViewerLoop(m.interactor, m.options.fps, m.pacer, events_file, keep_open);
}

void InteractiveSceneView::Initialize() {
  Impl& m = *impl_;
  if (m.initialized) return;
  m.initialized = true;
  m.interactor->Initialize();
  m.view->Render();
}

void InteractiveSceneView::Frame() {
  Impl& m = *impl_;
  const double frame_time = m.pacer.BeginFrame(m.options.fps, m.options.fixed_frame_time);
  if (m.playing) {
    const double before = m.world().time();
    m.Advance(m.speed * frame_time);
    m.pacer.Played(m.world().time() - before);
  }
  m.UpdateDragLine();
  m.UpdateStatus();
  m.view->Render();
  if (m.pacer.EndFrame()) m.interactor->TerminateApp();
}

bool InteractiveSceneView::HandleKey(const std::string& k) {
  Impl& m = *impl_;
  if (k == "space") SetPlaying(!m.playing);
  else if (k == "n") StepOnce();
  else if (k == "+" || k == "=") SetSpeed(m.speed * 2.0);
  else if (k == "-") SetSpeed(m.speed / 2.0);
  else if (k == "a") ToggleLayer(SceneLayer::kAnchors);
  else if (k == "l") ToggleLayer(SceneLayer::kLattice);
  else if (k == "m") ToggleLayer(SceneLayer::kPoints);
  else if (k == "s") ToggleLayer(SceneLayer::kShape);
  else if (k == "c") m.FrameScene();
  else if (k == "h") {
    std::cout << "wobble view keys (scene): space play/pause, n step, +/- speed, a anchors and drag constraint, "
                 "l control boxes, m mass points, s shapes, c recentre, q quit; left mouse drags a point\n"
              << std::flush;
  } else if (k == "q" || k == "Escape") m.interactor->TerminateApp();
  else return false;
  m.UpdateStatus();
  m.view->Render();
  return true;
}

void InteractiveSceneView::SetPlaying(bool playing) { impl_->playing = playing; }
bool InteractiveSceneView::playing() const { return impl_->playing; }

void InteractiveSceneView::StepOnce() {
  Impl& m = *impl_;
  m.playing = false;
  if (m.StepWorld()) m.pacer.SetGoal(m.world().time());
  m.UpdateDragLine();
}

void InteractiveSceneView::SetSpeed(double speed) { impl_->speed = std::clamp(speed, 1.0 / 64.0, 64.0); }
double InteractiveSceneView::speed() const { return impl_->speed; }

void InteractiveSceneView::ToggleLayer(SceneLayer layer) {
  Impl& m = *impl_;
  // a layer the scene does not draw (no named points) still toggles the drag line
  const bool show = !LayerVisible(layer);
  m.view->SetLayerVisible(layer, show);
  if (layer == SceneLayer::kAnchors) m.drag_actor->SetVisibility(show);
}
bool InteractiveSceneView::LayerVisible(SceneLayer layer) const {
  if (layer == SceneLayer::kAnchors) return impl_->drag_actor->GetVisibility() != 0;
  return impl_->view->LayerVisible(layer);
}

Eigen::Vector3d InteractiveSceneView::WorldToDisplay(const Eigen::VectorXd& p) const {
  vtkRenderer* r = impl_->view->renderer();
  const Eigen::Vector3d x = To3(p);
  r->SetWorldPoint(x[0], x[1], x[2], 1.0);
  r->WorldToDisplay();
  double d[3];
  r->GetDisplayPoint(d);
  return Eigen::Vector3d(d[0], d[1], d[2]);
}

bool InteractiveSceneView::BeginDrag(int x, int y) {
  Impl& m = *impl_;
  EndDrag();
  World& w = m.world();
  // candidates: named points of bodies first (a tie goes to them), then every mass point
  std::vector<MaterialPoint> candidates;
  for (const AnchorSource::Anchor& a : m.input.spec.anchors)
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
  m.pull = std::make_shared<control::ConstraintPull>(w, *pick, kDragTime);
  w.AddController(m.pull);
  DragTo(x, y);
  return true;
}

void InteractiveSceneView::DragTo(int x, int y) {
  Impl& m = *impl_;
  if (!m.pull) return;
  const Eigen::VectorXd now = m.world().PointPosition(m.pull->point());
  // the cursor on the plane through the point that faces the camera; the next step's start takes it
  m.pull->Aim(m.DisplayToWorld(x, y, WorldToDisplay(now)[2], int(now.size())));
  m.UpdateDragLine();
}

void InteractiveSceneView::EndDrag() {
  Impl& m = *impl_;
  if (!m.pull) return;
  m.pull->Release(m.world());
  m.world().RemoveController(m.pull.get());
  m.pull.reset();
  m.UpdateDragLine();
}

std::optional<MaterialPoint> InteractiveSceneView::dragged_point() const {
  if (!impl_->pull) return std::nullopt;
  return impl_->pull->point();
}
int InteractiveSceneView::drag_constraint() const { return impl_->pull ? impl_->pull->constraint() : -1; }
Eigen::VectorXd InteractiveSceneView::drag_target() const { return impl_->pull ? impl_->pull->aim() : Eigen::VectorXd(); }

const World& InteractiveSceneView::world() const { return *impl_->input.world; }
double InteractiveSceneView::time() const { return impl_->input.world->time(); }
const ViewerStats& InteractiveSceneView::stats() const { return impl_->pacer.stats; }
const std::string& InteractiveSceneView::message() const { return impl_->message; }

std::string InteractiveSceneView::StatusLine() const {
  const Impl& m = *impl_;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s x%g   largest constraint violation %.2g%s", m.playing ? "playing" : "paused",
                m.speed, m.input.world->MaxViolation(), m.pull ? "   dragging" : "");
  return std::string(buf) + (m.message.empty() ? "" : "\n" + m.message);
}

vtkRenderWindow* InteractiveSceneView::window() { return impl_->view->window(); }
vtkRenderWindowInteractor* InteractiveSceneView::interactor() { return impl_->interactor; }
SceneView& InteractiveSceneView::scene() { return *impl_->view; }
// An on-screen window's back buffer is undefined after the swap: draw again and read it (as
// InteractiveView does), not SceneView::Capture's read-back of an offscreen render.
vtkSmartPointer<vtkImageData> InteractiveSceneView::Capture() { return CaptureWindow(window()); }

}  // namespace wobble::pipelines
