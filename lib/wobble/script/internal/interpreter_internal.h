// Internal to the script interpreter: its state beside the scene, the line context every error
// names, the command and parameter tables, the word parsers, and the handlers of the
// commands (one file per area: object_commands.cc, scene_commands.cc, synthesis_commands.cc,
// parameters.cc). Not part of the public API.
#pragma once

#include <cmath>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"
#include "wobble/scene/object_runs.h"
#include "wobble/scene/scene.h"
#include "wobble/script/interpreter.h"

namespace wobble::script {

using Words = std::vector<std::string>;

// Where a line came from, and the usage of its command: every error names them.
struct Context {
  std::string file;
  int line = 0;
  std::string dir;
  std::string usage;
  [[noreturn]] void Fail(const std::string& message) const { throw formats::ParseError(file, line, message); }
  // "expected 'USAGE'" unless the line has from `min` to `max` words (the command included).
  void ExpectWords(const Words& w, size_t min, size_t max) const {
    if (w.size() < min || w.size() > max) Fail("expected '" + usage + "'");
  }
};

// Everything the interpreter keeps besides the scene: the language's own settings, the
// synthesis options, what `output` and `render` collect, the hooks.
struct State {
  explicit State(std::ostream& o) : out(o) {}
  std::ostream& out;
  scene::Scene scene;
  bool quit = false;  // `quit` was run
  bool debug = false;  // print q after every step
  double spring_stiffness = 1000.0, spring_damping = 0.0;  // of `spring` without K, C
  std::function<void(double, double)> progress;

  // synthesis
  synth::AnnealOptions anneal_options;
  synth::CostFunction cost;
  long trial_steps = 1200;
  std::string anneal_csv, cmaes_csv;
  int restarts = 1;     // independent anneals/cmaes from seed, seed + 1, ...; the best is kept
  double sigma0 = 0.1;  // CMA-ES initial step, a fraction of each variable's range
  std::optional<synth::AnnealResult> anneal;
  Eigen::VectorXd anneal_start_q, anneal_start_qd;  // the trials' start state

  // output and render: the FFD object's runs (each every step) since `output` / since the
  // object was loaded or `clear track`
  std::string output_path;
  int output_every = 1;
  scene::ObjectRuns output_runs, track;
  Interpreter::HistoryHook history_hook;
  Interpreter::RenderHook render_hook;
  formats::MeshReader mesh_reader;  // a 3D object file's `mesh` line (VTK's readers, from the app)
  Interpreter::SceneRenderHook scene_render_hook;
};

using Handler = void (*)(State& s, const Words& w, const Context& ctx);
struct Command {
  const char* name;
  const char* usage;
  const char* help;
  Handler run;
};
// The command table (commands.cc), in the order `help` lists it.
const std::vector<Command>& CommandTable();

// A `set` value being parsed: its name, its text, and the line it came from.
struct Value {
  const std::string& name;
  const std::string& text;
  const Context& ctx;
  double Number() const;
  double NonNegative() const;
  double Positive() const;
  int Whole(int min) const;
  bool Boolean() const;
};
struct Parameter {
  const char* name;
  void (*set)(State& s, const Value& v);
};
// The parameters of `set` (parameters.cc), in the order `help` lists them.
const std::vector<Parameter>& ParameterTable();

// ---- handlers ----
// "COMMAND needs an object" unless the FFD object is loaded.
void RequireObject(const State& s, const Context& ctx, const std::string& command);
// What a run reports after its steps: the progress every 64 steps and, for the FFD object's
// runs with `set debug T`, q after every step. Null when neither is wanted.
scene::StepCallback StepObserver(State& s, bool object);
// object_commands.cc: the FFD object, its control, its runs and what they record
void LoadObj(State& s, const Words& w, const Context& ctx);
void LoadDef(State& s, const Words& w, const Context& ctx);
void Trans(State& s, const Words& w, const Context& ctx);
void Set(State& s, const Words& w, const Context& ctx);  // parameters.cc
void Assign(State& s, const Words& w, const Context& ctx);
void Mode(State& s, const Words& w, const Context& ctx);
void SetVec(State& s, const Words& w, const Context& ctx);
void Simul(State& s, const Words& w, const Context& ctx);  // the scene's once it has a body
void Pose(State& s, const Words& w, const Context& ctx);
void Key(State& s, const Words& w, const Context& ctx);
void Hold(State& s, const Words& w, const Context& ctx);
void Keyframe(State& s, const Words& w, const Context& ctx);
void SpringCommand(State& s, const Words& w, const Context& ctx);
void Clear(State& s, const Words& w, const Context& ctx);
void TerrainCommand(State& s, const Words& w, const Context& ctx);      // ground_commands.cc
void TerrainFaceCommand(State& s, const Words& w, const Context& ctx);
void HeightfieldCommand(State& s, const Words& w, const Context& ctx);
void HeightfieldRegionCommand(State& s, const Words& w, const Context& ctx);
void Output(State& s, const Words& w, const Context& ctx);
void Schedule(State& s, const Words& w, const Context& ctx);
void Print(State& s, const Words& w, const Context& ctx);   // the scene's once it has a body
void Render(State& s, const Words& w, const Context& ctx);  // the scene's once it has a body
void Echo(State& s, const Words& w, const Context& ctx);
void Help(State& s, const Words& w, const Context& ctx);
void Quit(State& s, const Words& w, const Context& ctx);
// synthesis_commands.cc
void Anneal(State& s, const Words& w, const Context& ctx);
void Cmaes(State& s, const Words& w, const Context& ctx);
void Gait(State& s, const Words& w, const Context& ctx);
void Save(State& s, const Words& w, const Context& ctx);
// The FFD object's synthesis problem now, of `steps` steps per trial.
synth::Problem MakeProblem(const State& s, long steps);
// The problem of the last anneal (or cmaes): its trials' start state, trial_steps long.
synth::Problem SynthesisProblem(const State& s);
// The `save` script (scene::ReplayScript of the scene; after an anneal, of its trials).
// `save`'s script; with a schedule_path, the `schedule` line of the target schedule written there
std::string ReplayScript(const State& s, const std::string& schedule_path = "", const std::string& heightfield_path = "");
// scene_commands.cc: Witkin & Welch bodies, points, constraints, paths and behaviours
void Linear(State& s, const Words& w, const Context& ctx);
void Ffd(State& s, const Words& w, const Context& ctx);
void PointCommand(State& s, const Words& w, const Context& ctx);
void Place(State& s, const Words& w, const Context& ctx);
void Nail(State& s, const Words& w, const Context& ctx);
void Attach(State& s, const Words& w, const Context& ctx);
void PathCommand(State& s, const Words& w, const Context& ctx);
void TrajectoryCommand(State& s, const Words& w, const Context& ctx);
void ImpulseCommand(State& s, const Words& w, const Context& ctx);
void ChaseOrGrab(State& s, const Words& w, const Context& ctx);
void ConnectCommand(State& s, const Words& w, const Context& ctx);
void ReleaseCommand(State& s, const Words& w, const Context& ctx);
void OnOff(State& s, const Words& w, const Context& ctx);
void WaitCommand(State& s, const Words& w, const Context& ctx);
void WaitForCommand(State& s, const Words& w, const Context& ctx);
void RecordCommand(State& s, const Words& w, const Context& ctx);
void SceneSimul(State& s, const Words& w, const Context& ctx);
void ScenePrint(State& s, const Words& w, const Context& ctx);
void SceneRender(State& s, const Words& w, const Context& ctx);

// ---- word parsers ----
namespace script_detail {

// Shortest round-trip form of a number, as every message prints it.
inline std::string Num(double v) { return formats::FormatDouble(v); }

inline double Number(const std::string& word, const std::string& what, const Context& ctx) {
  double v;
  if (!formats::detail::ParseNumber(word, &v) || !std::isfinite(v))
    ctx.Fail("expected " + what + " (a finite number), got '" + word + "'");
  return v;
}

inline double NonNegative(const std::string& word, const std::string& what, const Context& ctx) {
  const double v = Number(word, what, ctx);
  if (v < 0) ctx.Fail("expected a non-negative " + what + ", got " + word);
  return v;
}

inline double Positive(const std::string& word, const std::string& what, const Context& ctx) {
  const double v = Number(word, what, ctx);
  if (!(v > 0)) ctx.Fail("expected a positive " + what + ", got " + word);
  return v;
}

inline std::string Resolve(const std::string& path, const std::string& dir) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || dir.empty()) return path;
  return (std::filesystem::path(dir) / p).string();
}

// "; did you mean 'X'?" for the known word nearest to `word`, or "".
inline std::string DidYouMean(const std::string& word, const std::vector<std::string>& known) {
  const std::string near = Interpreter::Nearest(word, known);
  return near.empty() ? "" : "; did you mean '" + near + "'?";
}

}  // namespace script_detail
}  // namespace wobble::script
