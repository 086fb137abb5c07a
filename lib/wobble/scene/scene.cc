#include "wobble/scene/scene.h"

#include "wobble/record/trajectory_csv.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace wobble::scene {

// A run going on: the world it steps, and for the FFD object's runs the recorder that keeps
// every step (and integrates the control energy).
struct Scene::Run {
  RunKind kind = RunKind::kSimulate;
  bool object = false;  // a run of the FFD object (not of the scene's world)
  World* world = nullptr;
  double start_time = 0.0;
  long steps = 0;                                  // taken
  std::shared_ptr<record::Recorder> recorder;      // the object's runs that keep their steps
  std::shared_ptr<control::PoseGraphController> graph;  // while a pose graph drives the object
};

// The behaviour Sequencer as a controller of the scene's world: before every step the current
// behaviour acts (W&W §4: it may switch constraints or give impulses), then the names it
// made are no longer promised.
class Scene::Behaviours : public Controller {
 public:
  explicit Behaviours(Scene& scene) : scene_(scene) {}
  void BeforeStep(World& world) override {
    control::BehaviourContext ctx{&world, &scene_.constraints_};
    scene_.sequencer_.BeforeStep(ctx, scene_.log_);
    if (scene_.promised_.empty()) return;
    for (const auto& kv : scene_.constraints_) scene_.promised_.erase(kv.first);
  }

 private:
  Scene& scene_;
};

Scene::Scene() {
  // the thesis' interpreter integrates with the explicit scheme; appendix C's dt = 0.1 with its
  // mode damping (c/m_eff Δt > 2) is beyond that scheme's stability, so scenes default to
  // implicit Euler (`set integrator thesis` switches back)
  options_.integrator = Integrator::kImplicitEuler;
  options_.dt = 0.01;
}

Scene::~Scene() = default;

template <int Dim> WorldOptions Scene::ObjectWorldOptions(const BodyModelN<Dim>& body) const {
  WorldOptions o = options_;
  if constexpr (Dim == 3) o.params.ground_plane = GroundPlaneOf(options_.params.ground);
  o.params.springs.clear();
  if (springs_.enabled)
    for (Spring sp : springs_.list) {
      sp.body = 0;
      AttachSpring(body, &sp);
      o.params.springs.push_back(sp);
    }
  return o;
}
template WorldOptions Scene::ObjectWorldOptions(const BodyModelN<2>&) const;
template WorldOptions Scene::ObjectWorldOptions(const BodyModelN<3>&) const;

SimulationSetup Scene::CurrentSetup() const {
  SimulationSetup setup;
  setup.body = object_.Body<2>();
  if (!setup.body) return setup;
  setup.world = ObjectWorldOptions(*setup.body);
  setup.q = object_.q();
  setup.qd = object_.qd();
  setup.time = time_;
  setup.end = end_;
  if (control_.enabled) setup.graph = control_.graph;
  setup.object_path = object_.path();
  setup.mode_paths = object_.mode_paths();
  return setup;
}

// ---------------------------------------------------------------- the Witkin & Welch scene

World& Scene::world() {
  if (!world_) {
    WorldOptions o;
    o.params = options_.params;
    o.dt = options_.dt;
    world_ = std::make_unique<World>(o);
    world_->AddController(std::make_shared<Behaviours>(*this));
  }
  return *world_;
}

int Scene::AddLinearBody(const std::string& name, std::shared_ptr<const LinearBodyModel> model,
                         const AffineMaterial& material, const Eigen::VectorXd& at, LinearDrawing drawing) {
  if (bodies_.count(name)) throw std::invalid_argument("a body named '" + name + "' exists already");
  World& w = world();
  const int dim = model->dim(), n = model->basis_size();
  const int b = w.AddLinearBody(model, material);
  w.SetLinearState(b, model->PlacedState(Eigen::MatrixXd::Identity(dim, dim), at), Eigen::MatrixXd::Zero(dim, n));
  bodies_[name] = b;
  drawings_.resize(w.num_bodies());
  drawings_[b] = std::move(drawing);
  return b;
}

namespace {
// The object as a body of `w` at the object's state: its q holds a 3D orientation as the
// rotation vector, which SetCoordinates reads (in 2D it is the state itself).
int AddObjectTo(const FfdObject& object, World& w) {
  const int b = object.dim() == 3 ? w.AddBody(object.Body<3>()) : w.AddBody(object.Body<2>());
  w.SetCoordinates(b, object.q(), object.qd());
  return b;
}
}  // namespace

int Scene::AddObjectBody(const std::string& name) {
  if (bodies_.count(name)) throw std::invalid_argument("a body named '" + name + "' exists already");
  if (!object_.loaded()) throw std::logic_error("AddObjectBody: no FFD object is loaded");
  World& w = world();
  const int b = AddObjectTo(object_, w);
  bodies_[name] = b;
  drawings_.resize(w.num_bodies());
  return b;
}

void Scene::AddAnchor(control::Anchor anchor) {
  if (anchors_.count(anchor.name)) throw std::invalid_argument("a point or place named '" + anchor.name + "' exists already");
  const std::string name = anchor.name;
  anchors_[name] = std::move(anchor);
}

Eigen::VectorXd Scene::Point(const std::string& name) const {
  if (!world_ || !anchors_.count(name)) throw std::out_of_range("no scene point '" + name + "'");
  return anchors_.at(name).Position(*world_);
}

int Scene::Constraint(const std::string& name) const {
  const auto it = constraints_.find(name);
  return !world_ || it == constraints_.end() || !world_->exists(it->second) ? -1 : it->second;
}

void Scene::SetCamera(double azimuth, double elevation) {
  azimuth_ = azimuth;
  elevation_ = elevation;
}

SceneDrawing Scene::Drawing() const {
  SceneDrawing d;
  d.drawings = drawings_;
  for (const auto& [name, a] : anchors_) d.anchors.push_back(a);
  d.azimuth = azimuth_;
  d.elevation = elevation_;
  return d;
}

void Scene::Record(double fps) {
  record_fps_ = fps;
  World& w = world();
  recorder_.reset();
  if (fps > 0) {
    if (!recorded_ || recorded_->num_bodies() != w.num_bodies()) recorded_ = std::make_shared<record::Trajectory>(w);
    recorder_ = std::make_shared<record::Recorder>(recorded_, fps, w.time());
  }
  w.SetRecorder(recorder_);
}

// ---------------------------------------------------------------- runs

void Scene::BeginRun(RunKind kind, bool keep_steps) {
  if (run_) throw std::logic_error("BeginRun: a run is going on (EndRun first)");
  if (kind == RunKind::kKeyframes || !has_bodies()) {
    BeginObjectRun(kind, keep_steps);
    return;
  }
  World& w = *world_;
  // the scene's parameters as they are now apply to its world
  WorldOptions& o = w.mutable_options();
  o.dt = options_.dt;
  o.integrator = integrator_chosen_ ? options_.integrator : Integrator::kThesis;
  o.params.gravity_on = options_.params.gravity_on;
  o.params.ground = options_.params.ground;
  // 3D bodies stand on the plane of the same ground, set now; a terrain is 2D only, so it is
  // refused (GroundPlaneOf) only when a 3D body would stand on it
  bool on_plane = false;
  for (int b = 0; b < w.num_bodies(); ++b)
    on_plane = on_plane || (w.dim(b) == 3 && w.ground_contact(b));
  if (on_plane || !options_.params.ground.terrain) o.params.ground_plane = GroundPlaneOf(options_.params.ground);
  o.params.gravity = options_.params.gravity;
  if (record_fps_ > 0 && recorded_->num_bodies() != w.num_bodies()) Record(record_fps_);
  if (recorder_) recorder_->Start(w);
  run_ = std::make_unique<Run>();
  run_->world = run_world_ = &w;
  run_->start_time = w.time();
}

void Scene::BeginObjectRun(RunKind kind, bool keep_steps) {
  if (!object_.loaded()) throw std::logic_error("BeginRun: no FFD object is loaded");
  std::unique_ptr<World> w;
  // the 3D object stands on the plane of the ground line (GroundPlaneOf), under the same gravity
  w = std::make_unique<World>(object_.dim() == 3 ? ObjectWorldOptions(*object_.Body<3>())
                                                 : ObjectWorldOptions(*object_.Body<2>()));
  AddObjectTo(object_, *w);
  w->SetTime(time_);
  auto run = std::make_unique<Run>();
  run->kind = kind;
  run->object = true;
  run->start_time = time_;
  if (keep_steps) {
    run->recorder = std::make_shared<record::Recorder>(std::make_shared<record::Trajectory>(*w));
    run->recorder->set_control_energy(energy_);
  }
  if (kind == RunKind::kKeyframes) {
    w->AddController(std::make_shared<control::KeyframeController>(*w, 0, control_.keys, control_.hold));
  } else if (control_.enabled && control_.schedule.cols() > 0) {
    w->AddController(std::make_shared<control::TargetScheduleController>(*w, 0, control_.schedule));
  } else if (control_.enabled && !control_.graph.empty()) {
    // the pose graph cycles from its first pose at the start of every run (chapter 5)
    run->graph = std::make_shared<control::PoseGraphController>(*w, 0, control_.graph, control_.switch_width);
    w->AddController(run->graph);
    if (run->recorder) run->recorder->SetPoseSource(run->graph);
  }
  if (run->recorder) {
    w->SetRecorder(run->recorder);
    run->recorder->Start(*w);
  }
  object_world_ = std::move(w);
  run->world = run_world_ = object_world_.get();
  run_ = std::move(run);
}

void Scene::StopPoseGraph() {
  if (!run_ || !run_->graph) return;
  run_->world->RemoveController(run_->graph.get());
  run_->graph.reset();
}

bool Scene::Step() {
  if (!run_) throw std::logic_error("Step: no run (BeginRun first)");
  if (!run_->world->Step()) return false;
  ++run_->steps;
  return true;
}

void Scene::EndRun() { Finish(true); }

void Scene::Finish(bool act_due_behaviours) {
  if (!run_) throw std::logic_error("EndRun: no run");
  const std::unique_ptr<Run> run = std::move(run_);  // ended, even when a behaviour throws below
  World& w = *run->world;
  if (!run->object) {
    time_ = w.time();
    // behaviours due at the end time act now (a Connect at a chase's contact time at the end)
    if (act_due_behaviours && run->steps > 0 && w.status().ok()) Behaviours(*this).BeforeStep(w);
    return;
  }
  // the hand-over: the object goes on from the run's last state
  object_.SetState(w.coordinates(0), w.qd(0));
  time_ = run->kind == RunKind::kKeyframes ? run->start_time + control_.keys.Duration() : w.time();
  if (run->recorder) {
    energy_ = run->recorder->control_energy();
    last_object_run_ = run->recorder->trajectory();
    object_runs_.erase(std::remove_if(object_runs_.begin(), object_runs_.end(),
                                      [](const auto& weak) { return weak.expired(); }),
                       object_runs_.end());
    object_runs_.push_back(last_object_run_);
  }
}

RunReport Scene::Advance(long steps, const StepCallback& on_step) {
  // every step is kept: room for them at once (up to a million; beyond, it grows)
  if (run_->recorder) run_->recorder->trajectory()->reserve(int(std::min(steps, 1000000L)) + 1);
  try {
    for (long n = 1; n <= steps; ++n) {
      if (InterruptRequested()) run_->world->ThrowInterrupted();  // the run ends where it is
      if (!Step()) break;
      if (on_step) on_step(n, steps, *run_->world);
    }
  } catch (...) {
    Finish(false);
    throw;
  }
  RunReport report;
  report.steps = steps;
  report.status = run_->world->status();
  Finish(true);
  return report;
}

double Scene::KeptRecordValues() const {
  double values = recorded_ ? double(recorded_->size()) * double(recorded_->Columns().size()) : 0.0;
  for (const auto& weak : object_runs_)
    if (const auto run = weak.lock()) values += double(run->size()) * double(run->Columns().size());
  return values;
}

long Scene::CheckedRun(double duration, bool object_run) const {
  const std::string hint = "raise it with `set max_steps N` in a script, or --max-steps N";
  const long steps = RunSteps(duration, options_.dt, limits_, hint);
  // the samples this run adds: every step of an object run, the frames of the scene's record
  double rows = 0.0, width = 0.0;
  if (object_run && object_.loaded()) {
    rows = double(steps) + 1.0;
    const record::BodyInfo info =
        object_.dim() == 3 ? record::DescribeFfdBody(object_.Body<3>()) : record::DescribeFfdBody(object_.Body<2>());
    width = double(record::Trajectory({info}).Columns().size());
  } else if (recorded_ && record_fps_ > 0) {
    rows = std::min(double(steps), duration * record_fps_) + 1.0;
    width = double(recorded_->Columns().size());
  }
  CheckRecordSize(KeptRecordValues() + rows * width, limits_,
                  "raise it with `set max_record_mb N` in a script or --max-record-mb N, or keep fewer "
                  "runs (`clear track`)");
  return steps;
}

RunReport Scene::Simulate(double duration, const StepCallback& on_step) {
  const long steps = CheckedRun(duration, !has_bodies());
  BeginRun(RunKind::kSimulate);
  return Advance(steps, on_step);
}

RunReport Scene::Keyframe(const StepCallback& on_step) {
  const long steps = CheckedRun(control_.keys.Duration(), true);
  BeginRun(RunKind::kKeyframes);
  return Advance(steps, on_step);
}

}  // namespace wobble::scene
