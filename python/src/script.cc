// The script interpreter (script/interpreter.h, README "Scripts") from Python: run script
// files or lines, read back what they built (the FFD object's state, its pose graph, the
// synthesis problem, the last run's trajectory), with the same FILE:LINE errors.
#include "support.h"

#include <map>
#include <sstream>

#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"
#include "wobble/core/limits.h"
#include "wobble/script/interpreter.h"
#ifdef WOBBLE_PYTHON_RENDER
#include "pipelines/mesh_io.h"
#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#endif

namespace wobble::python {
namespace {

// An interpreter with the stream it prints to. Ctrl-C: the progress callback (every few dozen
// steps of a run) asks Python for signals and turns one into the interpreter's own stop
// (core/interrupt.h), so runs end as they do on the command line.
class PyInterpreter {
 public:
  explicit PyInterpreter(bool echo) : interp_(out_), echo_(echo) {
    interp_.SetProgress([](double, double) {
      if (PyErr_CheckSignals() != 0) {
        PyErr_Clear();
        RequestInterrupt();
      }
    });
#ifdef WOBBLE_PYTHON_RENDER
    // what `wobble run` installs: a 3D object's mesh read by VTK, and `render` drawn by the
    // one render driver (pictures need an X display; vtp and disp are written without one)
    interp_.SetMeshReader(pipelines::ReadSurfaceMesh);
    interp_.SetRenderHook([this](const script::RenderRequest& r) { RenderRuns(r); });
    interp_.SetSceneRenderHook([this](const script::SceneRenderRequest& r) { return RenderScene(r); });
#endif
  }
  void RunFile(const std::string& path) {
    Guarded([&] { interp_.RunFile(path); });
  }
  void Run(const std::string& text, const std::string& name, const std::string& dir) {
    Guarded([&] {
      std::istringstream in(text);
      interp_.RunStream(in, name, dir);
    });
  }
  // What the script printed since the last call.
  std::string TakeOutput() {
    std::string text = out_.str();
    out_.str("");
    return text;
  }
  script::Interpreter& interp() { return interp_; }

 private:
#ifdef WOBBLE_PYTHON_RENDER
  // `render DIR [WHAT]` of the object's runs (default frames,filmstrip,charts, as wobble run).
  void RenderRuns(const script::RenderRequest& r) {
    namespace pl = pipelines;
    const record::Trajectory& run = *r.trajectory;
    pl::RenderOutputs out;
    out.folder = r.dir;
    out.name = run.bodies().empty() ? "run" : run.bodies()[0].name;
    out.view.title = out.name;
    out.t_end = run.time(run.size() - 1);
    // the NAME=VALUE options, as `wobble run` applies them (scene/render_options.h)
    std::map<std::string, std::string> options;
    for (const auto& [name, value] : r.options) options[name] = value;  // a later one wins
    try {
      pl::ApplyRenderSettings(scene::ParseRenderOptions(options), &out);
    } catch (const scene::RenderOptionError& e) {
      throw InputError(e.option + "=: " + e.what());
    }
    std::vector<std::string> words;
    std::istringstream in(r.what.empty() ? "frames,filmstrip,charts" : r.what);
    for (std::string w; std::getline(in, w, ',');)
      if (!w.empty()) words.push_back(w);
    const std::string error = pl::SetOutputs(words, &out);
    if (!error.empty()) throw InputError(error);
    if (!pl::HasDisplay()) {
      std::string skipped;
      for (const std::string& w : pl::KeepWithoutDisplay(&out)) skipped += (skipped.empty() ? "" : ",") + w;
      if (!skipped.empty()) out_ << "no X display: " << skipped << " skipped (run under xvfb-run -a)\n";
      if (!pl::WritesAnything(out)) return;
    }
    World world = pl::WorldFor(run, r.world);
    for (const pl::RenderReport::File& f : pl::RenderTrajectory(world, run, pl::SceneSpec{}, out).files)
      out_ << "  " << f.Line() << "\n";
  }
  // `render DIR [WHAT]` of a Witkin & Welch scene.
  std::vector<std::string> RenderScene(const script::SceneRenderRequest& r) {
    namespace pl = pipelines;
    pl::RenderOutputs out = pl::SceneRenderOutputs(r.folder, r.name, r.drawing.azimuth, r.drawing.elevation);
    pl::SetOutputs(r.what, &out);  // the words were checked by the script's reader
    if (out.mp4 || out.webp) out.fps = r.fps;  // a video at the recorded rate; else every sample is a frame
    if (!pl::HasDisplay() && !pl::KeepWithoutDisplay(&out).empty())
      out_ << "no X display: the pictures and videos are skipped (run under xvfb-run -a)\n";
    if (!pl::WritesAnything(out)) return {};
    World world = pl::WorldFor(*r.recorded, r.world);
    std::vector<std::string> lines;
    for (const pl::RenderReport::File& f :
         pl::RenderTrajectory(world, *r.recorded, pl::SceneSpecOf(r.drawing.drawings, r.drawing.anchors), out).files)
      lines.push_back(f.Line());
    return lines;
  }
#endif

  template <class F> void Guarded(F&& f) {
    ClearInterrupt();
    try {
      f();
    } catch (...) {
      Flush();
      ClearInterrupt();
      throw;
    }
    Flush();
  }
  void Flush() {
    if (echo_) py::print(TakeOutput(), py::arg("end") = "");
  }
  std::ostringstream out_;
  script::Interpreter interp_;
  bool echo_;
};

}  // namespace

void BindScript(py::module_& m) {
  py::class_<PyInterpreter>(m, "Interpreter",
                            "The script interpreter of the thesis (§4.10.2, appendix C) and every wobble\n"
                            "command (README, 'Scripts'). Errors: ParseError naming FILE:LINE;\n"
                            "SimulationStopped when a run stops. echo: print what scripts print.")
      .def(py::init<bool>(), py::arg("echo") = false)
      .def("run_file", &PyInterpreter::RunFile, py::arg("path"),
           "Runs a script file; paths in it are relative to its folder.")
      .def("run", &PyInterpreter::Run, py::arg("text"), py::arg("name") = "<python>", py::arg("dir") = ".",
           "Runs script lines; `name` is used in errors, `dir` for input paths.")
      .def("take_output", &PyInterpreter::TakeOutput, "What the scripts printed since the last call.")
      .def_property_readonly("body",
                             [](PyInterpreter& p) -> py::object {
                               const auto& object = p.interp().scene().object();
                               return object.dim() == 3 ? WrapBody(object.Body<3>()) : WrapBody(object.Body<2>());
                             },
                             "the FFD object's body, a BodyModel of dim 2 or 3 (None before load_obj)")
      .def_property_readonly("q", [](PyInterpreter& p) { return Eigen::VectorXd(p.interp().q()); })
      .def_property_readonly("qd", [](PyInterpreter& p) { return Eigen::VectorXd(p.interp().qd()); })
      .def_property_readonly("time", [](PyInterpreter& p) { return p.interp().time(); })
      .def_property_readonly("control_energy", [](PyInterpreter& p) { return p.interp().control_energy(); })
      .def_property_readonly("pose_graph", [](PyInterpreter& p) { return p.interp().pose_graph(); })
      .def_property_readonly("world_options", [](PyInterpreter& p) { return p.interp().world_options(); })
      .def_property(
          "max_steps", [](PyInterpreter& p) { return p.interp().scene().limits().max_steps; },
          [](PyInterpreter& p, long v) {
            p.interp().scene().limits().max_steps = CheckedCount(double(v), 1, kMaxStepsLimit, "max_steps");
          },
          "the longest run a command may take (steps)")
      .def_property(
          "max_record_mb", [](PyInterpreter& p) { return p.interp().scene().limits().max_record_mb; },
          [](PyInterpreter& p, double v) {
            if (!(v > 0)) throw InputError("max_record_mb must be > 0");
            p.interp().scene().limits().max_record_mb = v;
          },
          "the memory the records of a script may take (MiB)")
      .def("synthesis_problem", [](PyInterpreter& p) { return p.interp().SynthesisProblem(); },
           "The problem `anneal` would solve now (body, world, start state, steps, cost).")
      .def_property_readonly(
          "last_run",
          [](PyInterpreter& p) -> py::object {
            auto t = p.interp().scene().last_object_run();
            if (!t) return py::none();
            return py::cast(std::make_shared<record::Trajectory>(*t));  // a copy: the scene's may grow
          },
          "a copy of the Trajectory of the FFD object's last simul or keyframe (None before one)")
      .def_property_readonly(
          "scene_record",
          [](PyInterpreter& p) -> py::object {
            auto t = p.interp().scene().recorded();
            if (!t) return py::none();
            return py::cast(std::make_shared<record::Trajectory>(*t));
          },
          "a copy of the Witkin & Welch scene's frames (`record FPS`; every body, prefixed NAME.), None\n"
          "before `record`. (A script's `render` needs the command line's renderer: from Python, use\n"
          "wobble.render on last_run.)")
      .def_property_readonly("last_anneal", [](PyInterpreter& p) { return p.interp().last_anneal(); },
                             "the last anneal's or cmaes' AnnealResult (None before one)")
      .def("replay_script", [](PyInterpreter& p) { return p.interp().ReplayScript(); },
           "The script that rebuilds the current setup and replays it.")
      .def_static("help", &script::Interpreter::Help, "Every command's usage and help, and the parameters.");
}

}  // namespace wobble::python
