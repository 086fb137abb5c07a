// The command interpreter of Faloutsos 1995 (§4.10.2, appendix C), extended to everything
// wobble does: objects, modes, PD control, pose graphs, keyframes, springs, outputs and motion
// synthesis. README.md ("Scripts") documents every command and parameter; Commands() below is
// the list the interpreter checks against (and suggests from).
//
// A script is line-based: `#` starts a comment, words are separated by white space. Every
// error is an formats::ParseError naming the script, the line and what was expected; a simulation
// that stops on numerical trouble raises SimulationStopped (same prefix, plus the world's
// status). Input files named in a script are found relative to the script's folder; output
// files relative to the working directory.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/world/world.h"
#include "wobble/control/behaviours.h"
#include "wobble/control/control.h"
#include "wobble/record/scene_recording.h"
#include "wobble/world/world.h"
#include "wobble/formats/parse_error.h"
#include "wobble/synth/anneal.h"

namespace wobble::script {

// A simulation run by the script stopped (non-finite state, runaway penetration, ...).
class SimulationStopped : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One recorded state of a script's runs (keyframed or simulated), for `render`.
struct TrackState {
  double t = 0;
  Eigen::VectorXd q, qd, targets;  // targets: PD targets γ0 (empty: all 0)
};

// What `render DIR [WHAT]` asks the CLI to draw: every state of the runs since the object was
// loaded (or `clear track`), in the coordinates of `body`, whose modes are every mode those runs
// used (a mode absent from a run's set has amplitude and rate 0 there).
struct RenderRequest {
  std::string dir;   // output folder
  std::string what;  // comma list (frames, filmstrip, charts, vtp, exr, disp); empty: the default
  std::shared_ptr<const BodyModel> body;
  WorldOptions world;  // ground, gravity, springs, dt
  std::vector<TrackState> states;
};

struct CommandInfo {
  std::string name, usage, summary;
};

// What `render` hands to the CLI (lib draws nothing): the scene of Witkin & Welch bodies, the
// frames recorded by `record`, and what to write where. The hook may change the world's state
// (the interpreter restores it afterwards) and returns the paths it wrote; it throws
// std::runtime_error on failure.
struct SceneRenderRequest {
  std::string folder, name;
  bool frames = true, filmstrip = true, vtp = true;
  double azimuth = 30.0, elevation = 20.0;  // 3D camera, degrees
  World* world = nullptr;
  const std::vector<LinearDrawing>* drawings = nullptr;  // per body
  std::vector<control::Anchor> anchors;                   // named points, drawn as dots
  const std::vector<record::SceneFrame>* recorded = nullptr;
};
using SceneRenderHook = std::function<std::vector<std::string>(const SceneRenderRequest&)>;

class Interpreter {
 public:
  // Messages (results of print, summaries of runs) go to `out`.
  explicit Interpreter(std::ostream& out);
  ~Interpreter();

  // Runs a whole script file; input paths in it are relative to its folder.
  void RunFile(const std::string& path);
  // Runs lines from a stream; `name` is used in errors, `dir` for input paths.
  void RunStream(std::istream& in, const std::string& name, const std::string& dir);
  // Runs one line (interactive use). Returns false for `quit`.
  bool RunLine(const std::string& line, const std::string& name, int line_number, const std::string& dir);

  // Loads an object before the script (the CLI's --object), as `load_obj` would.
  void LoadObject(const std::string& path);

  // Called during simulations with the fraction done and the time (a progress bar).
  void SetProgress(std::function<void(double, double)> progress) { progress_ = std::move(progress); }
  // Called after `anneal` or `cmaes` wrote its cost history to csv_path (anneal_csv/cmaes_csv):
  // the CLI draws the cost against iteration (Fig. 5.4/5.5) beside it. lib draws nothing.
  using HistoryHook = std::function<void(const std::string& csv_path, const std::string& optimiser,
                                         const std::vector<synth::IterationRecord>& history)>;
  void SetHistoryHook(HistoryHook hook) { history_hook_ = std::move(hook); }
  // `render` draws a script's runs through hooks the CLI installs (pipelines/, VTK); lib draws
  // nothing, and without the hook `render` is an error. One command, two kinds of run: with a
  // Witkin & Welch scene (`linear`, ...) it draws the scene's recorded frames (SceneRenderHook),
  // otherwise the FFD object's runs (RenderHook). Hooks report trouble by throwing.
  using RenderHook = std::function<void(const RenderRequest& request)>;
  void SetRenderHook(RenderHook hook) { render_hook_ = std::move(hook); }
  void SetSceneRenderHook(SceneRenderHook hook) { scene_render_hook_ = std::move(hook); }

  static const std::vector<CommandInfo>& Commands();
  static const std::vector<std::string>& Parameters();  // names `set` accepts
  // The known word nearest to `word` by edit distance, or "" when none is close.
  static std::string Nearest(const std::string& word, const std::vector<std::string>& known);

  // State, for tests and the CLI.
  const BodyModel* body();  // nullptr until an object and modes are loaded
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }
  double time() const { return time_; }
  double control_energy() const { return energy_.consumed; }
  const control::PoseGraph& pose_graph() const { return graph_; }
  const WorldOptions& world_options() const { return world_; }
  // Summary of the last anneal or cmaes (empty before one ran).
  const std::optional<synth::AnnealResult>& last_anneal() const { return anneal_; }
  // The synthesis problem `anneal` would solve now (after an anneal: from the state its trials
  // started from), for tests and gait measurements.
  synth::Problem SynthesisProblem();
  // The script that rebuilds the current setup (object, modes, parameters, state, pose graph)
  // and replays it with `simul`.
  std::string ReplayScript() const;

  // What `simul` would run now, for clients that step a World themselves (`wobble view`):
  // the body (codamA included in the active modes' damping), the world options with the
  // script's springs (when `set spring` is on), the state, the time and the pose graph (empty
  // when `set control F`), and the files it was loaded from. body is null before load_obj.
  struct SimulationSetup {
    std::shared_ptr<const BodyModel> body;
    WorldOptions world;
    Eigen::VectorXd q, qd;
    double time = 0.0, end = 0.0;
    control::PoseGraph graph;
    std::string object_path;              // absolute
    std::vector<std::string> mode_paths;  // absolute, in load order
  };
  SimulationSetup CurrentSetup();

  // The Witkin & Welch scene (`linear`, `nail`, `grab`, ...): nullptr until a linear body is
  // made. Its bodies, named points and constraints, for tests and the CLI.
  const World* scene() const;
  // Position of a named point or place (`point`, `place`); throws std::out_of_range.
  Eigen::VectorXd ScenePoint(const std::string& name) const;
  // The constraint id of a name (`nail`, `attach`, `connect`, ...), or -1.
  int SceneConstraint(const std::string& name) const;
  const std::vector<record::SceneFrame>& recorded_frames() const;
  // For clients that step the scene themselves (`wobble view`): one step as `simul` takes it
  // (the script's dt, gravity and ground; the queued behaviours act, then the world steps;
  // behaviour messages go to `out`). Throws SimulationStopped when the world stops,
  // control::BehaviourError when a behaviour cannot act, std::logic_error without a scene.
  void StepScene();
  // The scene's world, for such clients to add their own constraints (a mouse drag); nullptr
  // without a scene.
  World* mutable_scene();
  // What `render` draws of the scene: world, drawings, named points and camera angles (no
  // folder, no recorded frames). std::logic_error without a scene.
  SceneRenderRequest SceneDrawing();

 private:
  struct Context;
  struct Scene;  // script_scene.cc
  void Execute(const std::vector<std::string>& words, const Context& ctx);
  // The scene commands; false when `words` is not one of them (or a simul/print that belongs
  // to the FFD object because no scene exists).
  bool ExecuteScene(const std::vector<std::string>& words, const Context& ctx);
  // `set` of a scene parameter; false when the name is not one.
  bool SetSceneParameter(const std::string& name, const std::string& value, const Context& ctx);
  // The script's dt, gravity and ground onto the scene's world (before stepping it).
  void SyncSceneOptions();
  // One step of the scene: behaviours (may throw control::BehaviourError), then the world.
  // False when the world stopped.
  bool SceneStep(const std::function<void(const std::string&)>& log);
  Scene& EnsureScene();
  void Set(const std::vector<std::string>& words, const Context& ctx);
  void RequireBody(const Context& ctx, const std::string& command);
  int ModeIndex(const std::string& word, const Context& ctx);
  void Simulate(double duration, const Context& ctx);
  void RunKeyframes(const Context& ctx);
  void RecordRow(const World& world, double t, int pose);
  void FlushOutput(const Context& ctx);
  void ClearOutputRows();
  std::vector<std::vector<double>> OutputRows() const;
  void RecordTrack(const World& world, double t);
  RenderRequest MakeRenderRequest() const;  // rows_ with one column per output_modes_
  void Invalidate() { body_.reset(); }
  std::shared_ptr<const BodyModel> BuildBody();
  synth::Problem MakeProblem(long steps);
  WorldOptions MakeWorldOptions() const;

  std::ostream& out_;
  std::function<void(double, double)> progress_;

  // what was loaded
  std::optional<BodyDef> object_;
  std::string object_path_;
  std::vector<std::string> def_paths_;
  std::vector<DeformationMode> modes_;
  std::shared_ptr<const BodyModel> body_;  // built lazily from object_, modes_ and codamA

  // parameters
  WorldOptions world_;
  bool springs_on_ = true;
  std::vector<Spring> springs_;
  double spring_stiffness_ = 1000.0, spring_damping_ = 0.0;
  double codam_active_ = 0.0;
  bool debug_ = false;
  double time_ = 0.0, end_ = 10.0;
  Eigen::Vector3d placement_ = Eigen::Vector3d::Zero();  // trans x y θ

  // state
  Eigen::VectorXd q_, qd_;
  control::ControlEnergy energy_;

  // control
  control::PoseGraph graph_;
  bool control_on_ = true;
  double switch_width_ = 0.0;  // > 0: simul switches poses smoothly (control::SmoothPoseTargets)
  control::Keyframes keys_;
  control::HeldPoint hold_;

  // synthesis
  synth::AnnealOptions anneal_options_;
  synth::CostFunction cost_;
  HistoryHook history_hook_;
  RenderHook render_hook_;
  std::unique_ptr<Scene> scene_;
  long trial_steps_ = 1200;
  std::string anneal_csv_, cmaes_csv_;
  double sigma0_ = 0.1;  // CMA-ES initial step, a fraction of each variable's range
  std::optional<synth::AnnealResult> anneal_;
  Eigen::VectorXd anneal_start_q_, anneal_start_qd_;  // the trials' start state

  // output
  std::string output_path_;
  int output_every_ = 1;
  long output_counter_ = 0;
  std::vector<std::vector<double>> rows_;  // t, q, q̇, energies... of the mode set of that run
  std::vector<std::string> output_modes_;  // every mode recorded since `output`, first seen first
  std::vector<std::vector<int>> slot_sets_;  // column (index into output_modes_) of each mode
  std::vector<int> row_slot_set_;          // per row: its entry in slot_sets_

  // render
  SceneRenderHook scene_render_hook_;
  struct TrackEntry {
    std::shared_ptr<const BodyModel> body;  // the mode set of that run
    TrackState state;
  };
  std::vector<TrackEntry> track_;
};

}  // namespace wobble::script
