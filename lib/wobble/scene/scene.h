// The scene runtime: what a script builds and runs, shared by the interpreter (wobble/script),
// the viewer (`wobble view`) and the CLI. A scene holds
//   - the world parameters of every run (dt, integrator, gravity, ground: the script's `set`);
//   - the FFD object of the thesis (FfdObject: object file, modes, codamA, placement, state),
//     its springs (Fig. 4.4) and how it is driven: a pose graph (chapter 5) or keyframes
//     (§4.10.1);
//   - the Witkin & Welch scene: one World of linear (and FFD) bodies with named bodies,
//     points and places, named constraints, paths and the behaviour Sequencer (W&W §3, §4);
//   - what the runs recorded (record::Trajectory).
//
// Runs. What `simul` steps is the scene's world once it has a body, otherwise a world made
// for the run from the FFD object (a new one each run: the object may have changed since).
// Whatever drives a run is a World controller, called inside World::Step: the pose graph
// (control::PoseGraphController), the keys (control::KeyframeController), the behaviours (the
// scene's Sequencer); the recorder is record::Recorder. A run is begun, stepped and ended
// (BeginRun, Step, EndRun: the viewer steps one step at a time), or run whole (Simulate,
// Keyframe). Both ways give the same trajectory.
//
// Usage (tests/scene_test.cc, Scene.HelloTable):
//   scene::Scene s;
//   s.object().Load("data/table.obj");
//   s.object().LoadModes({"data/table_modes.def"});
//   s.control().graph.poses = {...};  s.control().graph.durations = {...};
//   const scene::RunReport r = s.Simulate(3.0);  // or BeginRun(); Step() ...; EndRun();
//   if (!r.ok()) report(r.status.message);
//   const record::Trajectory& run = *s.last_object_run();  // every step of that run
#pragma once

#include <Eigen/Core>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "wobble/body/linear_shapes.h"
#include "wobble/control/behaviours.h"
#include "wobble/control/control.h"
#include "wobble/control/controllers.h"
#include "wobble/control/paths.h"
#include "wobble/core/limits.h"
#include "wobble/record/trajectory.h"
#include "wobble/scene/ffd_object.h"
#include "wobble/world/world.h"

namespace wobble::scene {

// How the FFD object is driven: what the script's `pose`, `key`, `hold`, `set control`,
// `set cyclic`, `set switch_width` and `set interp` fill in.
struct ObjectControl {
  control::PoseGraph graph;    // drives the active modes while `enabled` (chapter 5)
  bool enabled = true;
  double switch_width = 0.0;   // > 0: smoothed switches (control::SmoothPoseTargets)
  // A spacetime fit's targets (`spacetime`), modes × steps from the start of every run; while
  // not empty it drives the modes in place of the pose graph.
  Eigen::MatrixXd schedule;
  control::Keyframes keys;     // what Keyframe() plays (§4.10.1)
  control::HeldPoint hold;     // held in place while keyframing
};

// The FFD object's springs (Fig. 4.4): each from a lattice point to a world point, in the
// object's dimension (a 2D spring's z entries are 0), as a script gives them; the body's b0
// and B are filled in for each run (ObjectWorldOptions).
struct ObjectSprings {
  std::vector<Spring> list;
  bool enabled = true;
};

// What the FFD object's next simulation starts from, for clients that step a World of their
// own: the body (codamA included), the world options with the springs, the state, the span,
// the pose graph (empty when control is off) and the files the object was loaded from.
struct SimulationSetup {
  std::shared_ptr<const BodyModel> body;  // null before an object is loaded
  WorldOptions world;
  Eigen::VectorXd q, qd;
  double time = 0.0, end = 0.0;
  control::PoseGraph graph;
  std::string object_path;              // absolute
  std::vector<std::string> mode_paths;  // absolute, in load order
};

// What draws the Witkin & Welch scene: each body's drawing (linear bodies; FFD bodies draw
// their own shape), the named points and places, and the 3D camera (degrees).
struct SceneDrawing {
  std::vector<LinearDrawing> drawings;  // per body
  std::vector<control::Anchor> anchors;
  double azimuth = 30.0, elevation = 20.0;
};

enum class RunKind {
  kSimulate,   // what `simul` steps
  kKeyframes,  // the FFD object's keys, then the hand-over of q and q̇ (§4.10.1)
};

// Called after every step of a run with the step (1-based), the run's length and the world.
using StepCallback = std::function<void(long step, long steps, const World& world)>;

struct RunReport {
  long steps = 0;      // the run's length; fewer were taken when it stopped
  WorldStatus status;  // ok, or where and why the world stopped
  bool ok() const { return status.ok(); }
};

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // ---- parameters ----
  // dt, integrator, gravity and the ground of every run (the object's springs are below).
  // The scene's world takes dt, gravity and the ground at every BeginRun, and the integrator
  // once a script chose one (ChooseIntegrator): until then it steps with thesis, the
  // velocity-first Euler Witkin & Welch's scenes were made with, while the object's runs
  // default to implicit Euler (Scene()).
  WorldOptions& options() { return options_; }
  const WorldOptions& options() const { return options_; }
  void ChooseIntegrator(Integrator integrator) {
    options_.integrator = integrator;
    integrator_chosen_ = true;
  }
  // What one run may take (core/limits.h): Simulate and Keyframe refuse a run of more steps
  // than limits().max_steps, or one whose record would take the records kept (every object
  // run someone still holds, and the scene's `record`) past limits().max_record_mb.
  Limits& limits() { return limits_; }
  const Limits& limits() const { return limits_; }
  // The FFD object's clock: where its next run starts (a run leaves it at its end), and the
  // end `simul` without a duration runs to.
  double time() const { return time_; }
  void set_time(double t) { time_ = t; }
  double end() const { return end_; }
  void set_end(double t) { end_ = t; }

  // ---- the FFD object and what drives it ----
  FfdObject& object() { return object_; }
  const FfdObject& object() const { return object_; }
  ObjectSprings& springs() { return springs_; }
  const ObjectSprings& springs() const { return springs_; }
  ObjectControl& control() { return control_; }
  const ObjectControl& control() const { return control_; }
  // The control energy of the object's runs (control/control.h), summed until reset.
  control::ControlEnergy& control_energy() { return energy_; }
  const control::ControlEnergy& control_energy() const { return energy_; }
  // The world of the object's runs: options() with the springs (when enabled) on `body`, body
  // 0 of that world; a 3D body stands on the ground line's plane (GroundPlaneOf).
  template <int Dim> WorldOptions ObjectWorldOptions(const BodyModelN<Dim>& body) const;
  SimulationSetup CurrentSetup() const;

  // ---- the Witkin & Welch scene ----
  // Its world, made at first use from options() (dt, gravity, ground, feedback_rate).
  World& world();
  const World* world_if_made() const { return world_.get(); }  // null until first use
  bool has_bodies() const { return world_ && world_->num_bodies() > 0; }
  // Bodies by name; std::invalid_argument when the name is taken. A linear body starts at
  // rest at `at`; the FFD object joins with its state now (`ffd NAME`).
  int AddLinearBody(const std::string& name, std::shared_ptr<const LinearBodyModel> model,
                    const AffineMaterial& material, const Eigen::VectorXd& at, LinearDrawing drawing);
  int AddObjectBody(const std::string& name);
  const std::map<std::string, int>& bodies() const { return bodies_; }
  // Named points and places (`point`, `place`); std::invalid_argument when the name is taken.
  void AddAnchor(control::Anchor anchor);
  const std::map<std::string, control::Anchor>& anchors() const { return anchors_; }
  // The position of a named point or place now; std::out_of_range for an unknown name.
  Eigen::VectorXd Point(const std::string& name) const;
  // Named constraints, made at once (`nail`, `attach`) or by behaviours. Constraint(): the id
  // of a name, or -1 (unknown or removed).
  control::ConstraintNames& constraints() { return constraints_; }
  const control::ConstraintNames& constraints() const { return constraints_; }
  int Constraint(const std::string& name) const;
  // The names queued behaviours will give the constraints they make (a name is promised
  // until the behaviour makes it).
  std::set<std::string>& promised() { return promised_; }
  std::map<std::string, std::shared_ptr<const control::KeyframeSpline>>& paths() { return paths_; }
  control::Sequencer& sequencer() { return sequencer_; }
  // Where behaviour messages ("t = 1.2: chase ...") go (none by default).
  void SetLog(std::function<void(const std::string&)> log) { log_ = std::move(log); }
  // The 3D camera of `render` and the viewer (degrees).
  void SetCamera(double azimuth, double elevation);
  double azimuth() const { return azimuth_; }
  double elevation() const { return elevation_; }
  SceneDrawing Drawing() const;
  // `record FPS`: the scene's state FPS times per simulated second from now on (0: stop).
  // The frames of the scene's bodies at the time: bodies added later start a new recording.
  void Record(double fps);
  double record_fps() const { return record_fps_; }  // 0: not recording
  // The frames recorded (null before `record`).
  std::shared_ptr<const record::Trajectory> recorded() const { return recorded_; }

  // ---- runs ----
  // Starts a run. Throws std::invalid_argument when the pose graph or the keys do not fit the
  // object's body, std::logic_error when there is nothing to run or a run is going on.
  // keep_steps false: an FFD object's run keeps no record of its steps (last_object_run() is
  // left as it was; the viewer's live runs, which can go on for hours, keep their own frames).
  void BeginRun(RunKind kind = RunKind::kSimulate, bool keep_steps = true);
  // One step of the run; false when the world stopped (its status()). Throws
  // control::BehaviourError when a behaviour cannot act.
  bool Step();
  // Ends the run: the FFD object takes its last state, its clock the run's end, and the run is
  // kept (last_object_run()); in the scene, behaviours due at the end time act now.
  void EndRun();
  bool running() const { return bool(run_); }
  // Ends the pose graph's drive of the current run: the targets stay as they are (the
  // viewer's sliders take over). No-op when no pose graph drives it.
  void StopPoseGraph();
  // The world of the current or the last run (nullptr before the first).
  World* run_world() { return run_world_; }
  // A run of round(duration/dt) steps / of the keys: BeginRun, Step, EndRun.
  RunReport Simulate(double duration, const StepCallback& on_step = nullptr);
  RunReport Keyframe(const StepCallback& on_step = nullptr);
  // Every state of the FFD object's last run (null before one).
  std::shared_ptr<const record::Trajectory> last_object_run() const { return last_object_run_; }

 private:
  struct Run;
  class Behaviours;  // the Sequencer as the scene world's controller
  void BeginObjectRun(RunKind kind, bool keep_steps);
  // EndRun's work; an exception during a run skips the behaviours due at its end.
  void Finish(bool act_due_behaviours);
  RunReport Advance(long steps, const StepCallback& on_step);
  // The steps of a run of `duration` within the limits (LimitExceeded otherwise).
  long CheckedRun(double duration, bool object_run) const;
  // The doubles the records still held take: the object runs (weak: whoever keeps them) and
  // the scene's record.
  double KeptRecordValues() const;

  WorldOptions options_;
  bool integrator_chosen_ = false;  // the scene's world takes options_.integrator
  Limits limits_;
  double time_ = 0.0, end_ = 10.0;
  FfdObject object_;
  ObjectSprings springs_;
  ObjectControl control_;
  control::ControlEnergy energy_;

  std::unique_ptr<World> world_;  // the Witkin & Welch scene
  std::vector<LinearDrawing> drawings_;
  std::map<std::string, int> bodies_;
  std::map<std::string, control::Anchor> anchors_;
  control::ConstraintNames constraints_;
  std::set<std::string> promised_;
  std::map<std::string, std::shared_ptr<const control::KeyframeSpline>> paths_;
  control::Sequencer sequencer_;
  std::function<void(const std::string&)> log_;
  double azimuth_ = 30.0, elevation_ = 20.0;
  double record_fps_ = 0.0;
  std::shared_ptr<record::Trajectory> recorded_;
  std::shared_ptr<record::Recorder> recorder_;  // the scene world's, while recording

  std::unique_ptr<Run> run_;
  std::unique_ptr<World> object_world_;  // the FFD object's last run
  World* run_world_ = nullptr;
  std::shared_ptr<const record::Trajectory> last_object_run_;
  std::vector<std::weak_ptr<const record::Trajectory>> object_runs_;  // every kept run, while held
};

}  // namespace wobble::scene
