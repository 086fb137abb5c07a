#include "run.h"

#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>

#include "progress.h"
#include "cli_common.h"
#include "wobble/core/distribute.h"
#include "wobble/formats/line_reader.h"
#include "wobble/script/interpreter.h"
#include "wobble/script/variables.h"

#ifdef WOBBLE_HAVE_PIPELINES
#include "pipelines/charts.h"
#include "pipelines/mesh_io.h"
#include "pipelines/scene_view.h"
#include "script_render.h"
#endif

namespace wobble::app {

CLI::App* AddRunCommand(CLI::App* app, RunArgs* a) {
  CLI::App* cmd = app->add_subcommand("run", "Run a command script (appendix C); no script on a terminal: a prompt");
  cmd->add_option("script", a->script, "Script file (see README: Scripts)")->type_name("SCRIPT");
  AddLimitFlags(cmd, &a->limits);
  cmd->add_option("--param", a->params, "NAME=VALUE for the script's ${NAME} words (as a sweep case gives them)")
      ->type_name("NAME=VALUE");
  cmd->add_option("--object", a->object, "Object file loaded before the script (appendix C's script loads none)")
      ->type_name("FILE");
  cmd->footer(
      "Examples:\n"
      "  wobble run data/appendix_c.wob --object data/pot.obj\n"
      "  wobble run data/bounding_table.wob\n"
      "  wobble run --object data/table.obj      (interactive: 'help' lists the commands)");
  return cmd;
}

namespace {

// Fig. 5.4/5.5: cost against iteration, as FILE.png beside the optimiser's FILE.csv.
void PlotCostHistory(const std::string& csv_path, const std::string& optimiser,
                     const std::vector<synth::IterationRecord>& history) {
#ifdef WOBBLE_HAVE_PIPELINES
  if (!IsOutputRank()) return;  // under mpirun rank 0 draws
  if (!pipelines::HasDisplay()) {
    std::cout << "no X display: cost chart skipped (run under xvfb-run -a)\n";
    return;
  }
  pipelines::ChartSpec spec;
  spec.title = "cost against iteration: " + optimiser + " (Fig. 5.4/5.5)";
  spec.x_title = "iteration";
  spec.y_title = "cost";
  spec.log_y = true;
  spec.integer_x = true;
  pipelines::ChartSeries current, best;
  current.name = "current controller";
  best.name = "best so far";
  for (const synth::IterationRecord& r : history) {
    current.x.push_back(r.iteration);
    current.y.push_back(r.current);
    best.x.push_back(r.iteration);
    best.y.push_back(r.best);
  }
  spec.series = {current, best};
  const std::string png = std::filesystem::path(csv_path).replace_extension(".png").string();
  pipelines::WriteChart(spec, png, "");
  std::cout << "wrote " << png << "\n";
#else
  (void)csv_path, (void)optimiser, (void)history;
#endif
}

// `render DIR [WHAT]`: a script's recorded runs through the same driver as `wobble render`, the
// states replayed instead of simulated. Without a display only vtp and disp can be written.
void RenderRecordedRuns(const script::RenderRequest& r) {
#ifdef WOBBLE_HAVE_PIPELINES
  if (!IsOutputRank()) return;
  RenderScriptRuns(r);
#else
  (void)r;
  throw std::runtime_error("this wobble was built without pipelines/ (VTK): it cannot render");
#endif
}

// `render DIR` in a script: the recorded Witkin & Welch scene as frames, filmstrip and .pvd.
std::vector<std::string> RenderScene(const script::SceneRenderRequest& r) {
#ifdef WOBBLE_HAVE_PIPELINES
  if (!IsOutputRank()) return {};
  return RenderScriptScene(r);
#else
  (void)r;
  throw std::runtime_error("this wobble was built without pipelines/ (VTK): nothing can be drawn");
#endif
}

// The script with its ${NAME} words filled (script/variables.h), input paths relative to it.
void RunScriptFile(script::Interpreter& interp, const std::string& path, const std::vector<std::string>& params) {
  std::map<std::string, std::string> values;
  for (const std::string& spec : params) {
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0) throw UsageError("--param: expected NAME=VALUE, got '" + spec + "'");
    values[spec.substr(0, eq)] = spec.substr(eq + 1);
  }
  const std::string text = formats::detail::WithFile(path, [](std::istream& in) {
    std::ostringstream all;
    all << in.rdbuf();
    return all.str();
  });
  const std::set<std::string> used = script::VariablesUsed(text, path);
  for (const auto& [name, value] : values)
    if (!used.count(name)) throw UsageError("--param " + name + ": " + path + " has no ${" + name + "}");
  std::istringstream in(script::ExpandVariables(text, values, path));
  interp.RunStream(in, path, std::filesystem::path(path).parent_path().string());
}

}  // namespace

int RunScript(const RunArgs& a) {
  CheckLimitFlags(a.limits);
  script::Interpreter interp(std::cout);
  interp.scene().limits() = a.limits;
  interp.SetHistoryHook(PlotCostHistory);
  interp.SetRenderHook(RenderRecordedRuns);
#ifdef WOBBLE_HAVE_PIPELINES
  interp.SetMeshReader(pipelines::ReadSurfaceMesh);  // a 3D object file's `mesh` line
#endif
  interp.SetSceneRenderHook(RenderScene);
  Progress progress(isatty(STDERR_FILENO) == 1);
  interp.SetProgress([&](double fraction, double t) {
    progress.Update(fraction, t);
    if (fraction >= 1.0) {
      progress.Finish();
      progress = Progress(isatty(STDERR_FILENO) == 1);
    }
  });
  if (!a.object.empty()) interp.LoadObject(a.object);
  if (!a.script.empty()) {
    try {
      RunScriptFile(interp, a.script, a.params);
    } catch (const script::SimulationStopped& e) {
      progress.Finish();
      std::cerr << e.what() << std::endl;
      return kExitSimStopped;
    }
    return kExitOk;
  }
  // commands from stdin: a prompt on a terminal, a plain script otherwise
  const bool interactive = isatty(STDIN_FILENO) == 1;
  if (!interactive) {
    try {
      interp.RunStream(std::cin, "<stdin>", "");
    } catch (const script::SimulationStopped& e) {
      std::cerr << e.what() << std::endl;
      return kExitSimStopped;
    }
    return kExitOk;
  }
  std::cout << "wobble interactive: 'help' lists the commands, 'quit' leaves.\n";
  std::string line;
  for (int number = 1;; ++number) {
    std::cout << "wobble> " << std::flush;
    if (!std::getline(std::cin, line)) break;
    try {
      if (!interp.RunLine(line, "<prompt>", number, "")) break;
    } catch (const std::exception& e) {
      // at a prompt a mistake is reported and the session goes on
      progress.Finish();
      std::cerr << e.what() << std::endl;
    }
  }
  return kExitOk;
}

}  // namespace wobble::app
