// The command interpreter of Faloutsos 1995 (§4.10.2, appendix C), extended to everything
// wobble does: objects, modes, PD control, pose graphs, keyframes, springs, outputs, motion
// synthesis and Witkin & Welch scenes. README.md ("Scripts") documents every command and
// parameter; the command table (commands.cc: name, usage, one-line help, handler) is the one
// list the interpreter runs, `help` prints and unknown words are matched against.
//
// The interpreter parses and reports; what a script builds and runs is a scene::Scene (the
// runtime the viewer and the CLI share): every `simul` and `keyframe` is a run of it, driven
// by World controllers and recorded by record::Recorder.
//
// A script is line-based: `#` starts a comment, words are separated by white space. Every
// error is a formats::ParseError naming the script, the line and what was expected; a
// simulation that stops on numerical trouble raises SimulationStopped (same prefix, plus the
// world's status). Input files named in a script are found relative to the script's folder;
// output files relative to the working directory.
#pragma once

#include <functional>
#include <iosfwd>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "wobble/core/errors.h"
#include "wobble/formats/parse_error.h"
#include "wobble/record/trajectory.h"
#include "wobble/scene/scene.h"
#include "wobble/synth/anneal.h"

namespace wobble::script {

// A simulation run by the script stopped (non-finite state, runaway penetration, ...).
class SimulationStopped : public NumericalStop {
 public:
  using NumericalStop::NumericalStop;
};

// What `render DIR [WHAT]` asks the CLI to draw of the FFD object: every run since the object
// was loaded (or `clear track`) as one trajectory on the object with every mode those runs
// used (scene::MergeRuns), in the world the runs had.
struct RenderRequest {
  std::string dir;   // output folder
  std::string what;  // comma list (frames, filmstrip, charts, vtp, exr, disp); empty: the default
  // NAME=VALUE words: the options of `wobble render` by name (scene/render_options.h), in order
  std::vector<std::pair<std::string, std::string>> options;
  std::shared_ptr<const record::Trajectory> trajectory;  // one FFD body
  WorldOptions world;  // ground, gravity, springs, dt
};

// What `render` asks the CLI to draw of a Witkin & Welch scene: the frames `record` kept, how
// to draw its bodies, and what to write where. Returns the paths written; throws
// std::runtime_error on failure.
struct SceneRenderRequest {
  std::string folder, name;
  // what to write, words of kSceneRenderWords (pipelines::SetOutputs reads them)
  std::vector<std::string> what{"frames", "filmstrip", "vtp"};
  double fps = 0.0;  // the rate the frames were recorded at (`record FPS`): a video's frame rate
  scene::SceneDrawing drawing;
  std::shared_ptr<const record::Trajectory> recorded;  // the scene's bodies
  WorldOptions world;  // the scene world's: ground, gravity, dt
};
// The words a scene's `render DIR WHAT` takes: pictures, the .vtp series, videos, glTF, the web page
inline const std::vector<std::string> kSceneRenderWords{"frames", "filmstrip", "vtp", "mp4", "webp", "gltf", "web"};

struct CommandInfo {
  std::string name, usage, summary;
};

struct State;  // internal/interpreter_internal.h

class Interpreter {
 public:
  // Messages (results of print, summaries of runs, behaviour messages) go to `out`.
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

  // Called during runs with the fraction done and the time (a progress bar).
  void SetProgress(std::function<void(double, double)> progress);
  // Called after `anneal` or `cmaes` wrote its cost history to csv_path (anneal_csv/cmaes_csv):
  // the CLI draws the cost against iteration (Fig. 5.4/5.5) beside it. lib draws nothing.
  using HistoryHook = std::function<void(const std::string& csv_path, const std::string& optimiser,
                                         const std::vector<synth::IterationRecord>& history)>;
  void SetHistoryHook(HistoryHook hook);
  // `render` draws a script's runs through hooks the CLI installs (pipelines/, VTK); lib draws
  // nothing, and without the hook `render` is an error. One command, two kinds of run: with a
  // Witkin & Welch scene (`linear`, ...) it draws the scene's recorded frames (SceneRenderHook),
  // otherwise the FFD object's runs (RenderHook). Hooks report trouble by throwing.
  using RenderHook = std::function<void(const RenderRequest& request)>;
  using SceneRenderHook = std::function<std::vector<std::string>(const SceneRenderRequest&)>;
  void SetRenderHook(RenderHook hook);
  void SetSceneRenderHook(SceneRenderHook hook);
  // Reads the mesh a 3D object file names (`mesh FILE`): lib has no VTK, so the CLI installs
  // pipelines::ReadSurfaceMesh; without it such a file is refused with a message.
  void SetMeshReader(formats::MeshReader reader);

  // The command table's names, usages and one-line helps, and the names `set` accepts.
  static const std::vector<CommandInfo>& Commands();
  static const std::vector<std::string>& Parameters();
  // What `help` prints: every command's usage and help, and the parameters.
  static std::string Help();
  // The known word nearest to `word` by edit distance, or "" when none is close.
  static std::string Nearest(const std::string& word, const std::vector<std::string>& known);

  // What the script built and ran (the viewer steps it further).
  scene::Scene& scene();
  const scene::Scene& scene() const;
  // The FFD object's body and state, for tests and the CLI (body: nullptr until loaded).
  const BodyModel* body() const;
  const Eigen::VectorXd& q() const;
  const Eigen::VectorXd& qd() const;
  double time() const;
  double control_energy() const;
  const control::PoseGraph& pose_graph() const;
  const WorldOptions& world_options() const;
  // Summary of the last anneal or cmaes (empty before one ran).
  const std::optional<synth::AnnealResult>& last_anneal() const;
  // The synthesis problem `anneal` would solve now (after an anneal: from the state its trials
  // started from), for tests and gait measurements.
  synth::Problem SynthesisProblem() const;
  // The script that rebuilds the current setup (object, modes, parameters, state, pose graph)
  // and replays it with `simul` (scene::ReplayScript).
  std::string ReplayScript() const;

 private:
  std::unique_ptr<State> state_;
};

}  // namespace wobble::script
