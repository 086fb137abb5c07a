#include "view.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <vector>

#include <vtkImageData.h>

#include "pipelines/exports.h"
#include "wobble/formats/atomic_file.h"
#include "pipelines/interactive_view.h"
#include "pipelines/mesh_io.h"
#include "pipelines/scene_view.h"
#include "wobble/script/interpreter.h"

namespace wobble::app {
namespace {

namespace pl = wobble::pipelines;
namespace fs = std::filesystem;

bool IsScript(const std::string& path) { return fs::path(path).extension() == ".wob"; }

std::string FirstWord(const std::string& line) {
  std::istringstream words(line.substr(0, line.find('#')));
  std::string first;
  words >> first;
  return first;
}

// Runs the script in the interpreter up to (not including) its first `simul` or `keyframe`:
// the viewer plays that run live (at_keyframe: the keys first, then the simulation). The stop:
// which script ran (this one or its saved result, below) and its line (0: the whole script).
struct ScriptStop {
  std::string path;
  int line = 0;
  bool at_keyframe = false;
};

// A synthesis script anneals (or runs CMA-ES on) its pose graph first, which takes minutes; the
// viewer does that again only when asked (`anneal`). Otherwise, when the script `save`s its
// result after the search and an earlier `wobble run` wrote that file, the viewer opens the
// saved script (the annealed pose graph) in its place; without one it skips the search and that
// `save` (which would write an unsearched graph where the result belongs) and says so.
ScriptStop RunScriptSetup(script::Interpreter* interp, const std::string& path, bool anneal) {
  const std::string kind = formats::NonRegularKind(path);
  if (!kind.empty()) throw UsageError(path + ": is " + kind + ", not a regular file");
  std::ifstream in(path);
  if (!in) throw UsageError(path + ": cannot open the script");
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  const auto search = std::find_if(lines.begin(), lines.end(), [](const std::string& l) {
    const std::string w = FirstWord(l);
    return w == "anneal" || w == "cmaes";
  });
  bool skip_search = false;
  if (!anneal && search != lines.end()) {
    const auto save = std::find_if(search, lines.end(), [](const std::string& l) { return FirstWord(l) == "save"; });
    std::istringstream words(save == lines.end() ? "" : save->substr(0, save->find('#')));
    std::string word, saved;
    words >> word >> saved;
    if (!saved.empty() && fs::is_regular_file(saved)) {
      std::cout << "wobble view: " << path << " searches its pose graph (" << FirstWord(*search)
                << "); the viewer opens the result an earlier run saved, " << saved << " (--anneal searches again)\n";
      return RunScriptSetup(interp, saved, true);
    }
    skip_search = true;
    std::cout << "wobble view: " << path << ": " << FirstWord(*search) << " skipped, the pose graph as written"
              << (saved.empty() ? "" : " (`wobble run " + path + "` saves the searched one to " + saved + ")")
              << "; --anneal searches here\n";
  }
  const std::string dir = fs::path(path).parent_path().string();
  for (int number = 1; number <= int(lines.size()); ++number) {
    const std::string& line = lines[size_t(number - 1)];
    const std::string first = FirstWord(line);
    if (first == "simul" || first == "keyframe") return {path, number, first == "keyframe"};
    if (skip_search && (first == "anneal" || first == "cmaes" || first == "save")) continue;
    if (!interp->RunLine(line, path, number, dir)) return {path, number, false};  // quit
  }
  return {path, 0, false};
}

int ParseSide(const std::string& text, int* w, int* h) {
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", w, &x, h, &extra) != 3 || (x != 'x' && x != 'X') || *w < 320 ||
      *h < 240 || *w > 8192 || *h > 8192)
    throw UsageError("--size: expected WIDTHxHEIGHT of at least 320x240, such as 1280x720, got '" + text + "'");
  return 0;
}

// --report-fps: frames drawn per second, steps per frame, and whether the simulation kept up.
void ReportFps(const pl::ViewerStats& s, const ViewArgs& a, double dt) {
  const double fps = s.wall > 0 ? double(s.frames - 1) / s.wall : 0.0;
  const double ratio = s.playing_wall > 0 ? s.simulated / s.playing_wall : 0.0;
  std::printf("frames drawn: %ld in %.3f s wall: %.1f frames/s\n", s.frames, s.wall, fps);
  std::printf("simulation steps: %ld, %.2f per drawn frame (dt %g s)\n", s.steps,
              s.playing_frames ? double(s.steps) / double(s.playing_frames) : 0.0, dt);
  if (a.fixed_frame_time)
    std::printf("simulated %.3f s in %.3f s of wall time (--fixed-frame-time: each frame advances speed/fps, so "
                "this is no real-time measurement)\n", s.simulated, s.playing_wall);
  else
    std::printf("simulated %.3f s in %.3f s of wall time playing at speed %g: %.3f x real time (%s)\n", s.simulated,
                s.playing_wall, a.speed, ratio, ratio >= 0.98 * a.speed ? "keeps up" : "falls behind");
}

pl::ViewerOptions MakeViewerOptions(const ViewArgs& a, int width, int height) {
  pl::ViewerOptions vo;
  vo.width = width;
  vo.height = height;
  vo.fps = a.fps;
  vo.speed = a.speed;
  vo.fixed_frame_time = a.fixed_frame_time;
  vo.charts = !a.no_charts;
  vo.start_playing = !a.paused;
  vo.slider_range = a.slider_range;
  vo.drag_stiffness = a.drag_stiffness;
  vo.session_path = a.session;
  return vo;
}

}  // namespace

CLI::App* AddViewCommand(CLI::App* app, ViewArgs* a) {
  CLI::App* cmd = app->add_subcommand("view", "Interactive viewer: simulate live, pull points, set mode targets, "
                                              "record poses, save the session as a script");
  cmd->add_option("scene", a->scene, "An object file (with --modes) or a script (.wob)")->type_name("SCENE_OR_SCRIPT");
  cmd->add_option("--object", a->object, "Object file (instead of the positional SCENE)")->type_name("FILE");
  cmd->add_option("--modes", a->modes, "Deformation files of the object; the modes of all files, in order")
      ->delimiter(',')
      ->type_name("FILE[,FILE...]");
  cmd->add_option("--q", a->q, StateFlagHelp("object files; a script uses set_vec"))->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, VelocityFlagHelp("object files"))->type_name("\"NUMS\"");
  cmd->add_option("--integrator", a->integrator, IntegratorFlagHelp() + " (object files)")
      ->capture_default_str()
      ->type_name("NAME");
  cmd->add_option("--dt", a->dt, "Time step (object files)")->capture_default_str();
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--size", a->size, "Window size")->capture_default_str()->type_name("WxH");
  cmd->add_option("--fps", a->fps, "Frames per second the timer asks for")->capture_default_str();
  cmd->add_option("--speed", a->speed, "Simulated seconds per second of wall time (keys + and -)")
      ->capture_default_str();
  cmd->add_flag("--paused", a->paused, "Start paused (space plays)");
  cmd->add_flag("--fixed-frame-time", a->fixed_frame_time,
                "Every frame advances speed/fps of simulated time, whatever the wall clock (reproducible runs)");
  cmd->add_flag("--no-charts", a->no_charts, "No live charts (the scene takes the whole width)");
  cmd->add_option("--frames", a->frames, "Quit after drawing this many frames (0: run until closed)")
      ->capture_default_str();
  cmd->add_option("--play-events", a->play_events,
                  "Play recorded interactor events (vtkInteractorEventRecorder format; TimerEvent lines draw "
                  "frames), then quit unless --frames asks for more")
      ->type_name("FILE");
  cmd->add_option("--screenshot", a->screenshot, "Write the window as PNG when the viewer ends")->type_name("PNG");
  cmd->add_option("--session", a->session, "Where the key w writes the session script")->capture_default_str()
      ->type_name("FILE");
  cmd->add_option("--save-session", a->save_session, "Write the session script here when the viewer ends")
      ->type_name("FILE");
  cmd->add_flag("--report-fps", a->report_fps, "Print frames drawn per second and steps per frame at the end");
  cmd->add_option("--slider-range", a->slider_range, "Mode target sliders span -R..R")->capture_default_str();
  cmd->add_flag("--anneal", a->anneal,
                "A synthesis script: run its anneal (or cmaes) here; by default the viewer opens the result an earlier "
                "`wobble run` saved (the script's `save FILE` after the search), or plays the pose graph as written");
  cmd->add_option("--drag-stiffness", a->drag_stiffness, "Stiffness of the mouse spring (0: automatic, ~1 Hz)")
      ->capture_default_str();
  cmd->footer(
      "Examples:\n"
      "  wobble view data/table.obj --modes data/table_modes.def --q \"0 50 0 0 0 0 0\"\n"
      "  wobble view data/bounding_table.wob\n"
      "  wobble view data/fig2_triple_pendulum.wob   (a Witkin & Welch scene: drag = trajectory constraint, a anchors)\n"
      "Keys: space play/pause, n step, r restart, +/- speed, s l m g p toggle shape/lattice/points/ground/springs,\n"
      "k record pose, w write session, Left/Right scrub, h help, q quit. Left mouse pulls a point.");
  return cmd;
}

int RunView(const ViewArgs& a) {
  // every value first, then the display, then the files
  RequirePositive(a.fps, "--fps");
  RequirePositive(a.speed, "--speed");
  RequirePositive(a.slider_range, "--slider-range");
  RequireNonNegative(a.drag_stiffness, "--drag-stiffness");
  if (a.frames < 0) throw UsageError("--frames must be >= 0");
  int width = 0, height = 0;
  ParseSide(a.size, &width, &height);
  if (a.scene.empty() && a.object.empty()) throw UsageError("view: give an object file (with --modes) or a script");
  if (!a.scene.empty() && !a.object.empty() && !IsScript(a.scene))
    throw UsageError("view: give the object either as SCENE or with --object, not both");
  if (!a.play_events.empty() && !fs::exists(a.play_events)) throw UsageError("--play-events: no file " + a.play_events);
  if (!pl::HasDisplay())
    throw UsageError("view needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run it on a desktop,\n"
                     "or headless: xvfb-run -a -s \"-screen 0 1280x1024x24\" wobble view ... --frames N");

  // the scene runtime the viewer runs: a script's (up to its first run), or an object file's
  script::Interpreter interp(std::cout);
  scene::Scene object_scene;
  scene::Scene* scene = &object_scene;
  const bool script = !a.scene.empty() && IsScript(a.scene);
  bool keys_first = false;
  if (script) {
    if (!a.q.empty() || !a.qdot.empty() || !a.modes.empty())
      throw UsageError("view: --q, --qdot and --modes apply to object files; a script sets them itself");
    if (!a.object.empty()) interp.LoadObject(a.object);
    const ScriptStop stop = RunScriptSetup(&interp, a.scene, a.anneal);
    keys_first = stop.at_keyframe;
    scene = &interp.scene();
    if (!scene->has_bodies() && !scene->object().loaded())
      throw UsageError(a.scene + ": the script loads no object (load_obj FILE, or --object FILE)");
    if (stop.line > 0)
      std::cout << "wobble view: " << stop.path << " ran up to line " << stop.line << "; the viewer "
                << (scene->has_bodies() ? "steps its scene" : keys_first ? "plays its keys, then simulates on" : "plays its simulation")
                << " from there\n";
  } else {
    BodyFiles files;
    files.object = a.object.empty() ? a.scene : a.object;
    files.modes = a.modes;
    RequirePositive(a.dt, "--dt");
    // read and checked here (file, line, sizes), then loaded into the scene as a script would
    const StartingWorld start = LoadStartingWorld(files, a.q, a.qdot, a.world, ParseIntegratorFlag(a.integrator), a.dt);
    object_scene.options() = start.options;
    object_scene.object().Load(files.object, pl::ReadSurfaceMesh);
    object_scene.object().LoadModes(files.modes);
    object_scene.object().SetState(start.q0, start.qd0);
  }
  // a 3D object is drawn as a scene (the camera orbits with [ and ], a drag pulls a mass point)
  // and runs as `keyframe` and `simul` run it; the character session's sliders, charts and
  // session script are 2D only so far
  const bool object3 = !scene->has_bodies() && scene->object().dim() == 3;
  if (!a.save_session.empty() && (scene->has_bodies() || object3))
    throw UsageError("--save-session: sessions are saved for 2D FFD objects, not for scenes or 3D objects");

  pl::ViewerOptions options = MakeViewerOptions(a, width, height);
  options.keys_first = keys_first;
  pl::InteractiveView view(*scene, options);
  view.Run(a.frames, a.play_events, a.frames > 0);

  if (!a.screenshot.empty()) pl::WritePng(a.screenshot, view.Capture());
  if (!a.save_session.empty())
    for (const std::string& f : view.SaveSession(a.save_session)) std::cout << "wrote " << f << "\n";
  if (a.report_fps) ReportFps(view.stats(), a, view.world().options().dt);
  if (view.character() || object3) {
    const Eigen::VectorXd q = view.world().coordinates(0);  // 3D: rotation vector, as the script's q
    std::printf("t = %.6g, q =", view.time());
    for (int i = 0; i < q.size(); ++i) std::printf(" %.17g", q[i]);
    std::printf("\n");
  } else {
    std::printf("t = %.6g, largest constraint violation %.3g\n", view.time(), view.world().MaxViolation());
  }
  if (view.stopped()) {
    std::cerr << "wobble: " << view.message() << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace wobble::app
