#include "render.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "wobble/formats/csv.h"
#include "progress.h"

namespace wobble::app {
namespace {

namespace pl = wobble::pipelines;


std::set<std::string> ParseWhat(const std::string& text) {
  const std::vector<std::string> words = ListWords(text);
  pl::RenderOutputs probe;
  const std::string error = pl::SetOutputs(words, &probe);
  if (!error.empty()) throw UsageError("--what: " + error);
  return {words.begin(), words.end()};
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

}  // namespace

CLI::App* AddRenderCommand(CLI::App* app, const std::string& name, const std::string& description,
                           const std::string& default_what, RenderArgs* a) {
  CLI::App* cmd = app->add_subcommand(name, description);
  AddBodyFlags(cmd, &a->files);
  cmd->add_option("--q", a->q, StateFlagHelp("default: at rest at the origin"))->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, VelocityFlagHelp("default: zeros"))->type_name("\"NUMS\"");
  cmd->add_option("--integrator", a->integrator, IntegratorFlagHelp())
      ->capture_default_str()
      ->type_name("NAME");
  cmd->add_option("--dt", a->dt, "Time step")->capture_default_str();
  cmd->add_option("--duration", a->duration, "Simulated time")->capture_default_str();
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--out", a->out, "Output folder")->required()->type_name("DIR");
  AddLimitFlags(cmd, &a->limits);
  cmd->add_option("--what", a->what,
                  "What to write, comma separated: frames, filmstrip, charts, vtp, exr, disp, mp4 (NAME.mp4: H.264 "
                  "video), webp (NAME.webp: animated, loops), gltf (NAME.glb: "
                  "the bodies with a morph target per mode, for Blender or three.js), web (web/index.html: a page "
                  "playing the .glb, opened from the disk; implies gltf) (default: " +
                      default_what + ")")
      ->type_name("LIST");
  for (const scene::RenderOptionInfo& o : scene::RenderOptionTable()) {
    const std::string name = o.name;
    const std::string help = o.help + (o.default_value.empty() || o.flag ? "" : " [" + o.default_value + "]");
    if (o.flag)
      cmd->add_flag_callback("--" + name, [a, name] { a->picture[name] = "on"; }, help);
    else
      cmd->add_option_function<std::string>("--" + name, [a, name](const std::string& v) { a->picture[name] = v; }, help)
          ->type_name(o.value_name);
  }
  return cmd;
}

int RunRender(const RenderArgs& a, const std::string& default_what) {
  // check every value before reading files or simulating
  const Integrator integrator = ParseIntegratorFlag(a.integrator);
  RequirePositive(a.dt, "--dt");
  RequireNonNegative(a.duration, "--duration");
  const RenderRequest request = ParseRenderRequest(a, default_what);
  if (!(a.duration * request.settings.fps <= 1e6))
    throw UsageError("--duration * --fps asks for more than a million frames");
  CheckRenderRequest(request, a.out);

  // the body in its world, simulated from (q0, q̇0) into a trajectory of every step
  const StartingWorld setup = LoadStartingWorld(a.files, a.q, a.qdot, a.world, integrator, a.dt);
  World world = setup.MakeWorld();
  auto run = std::make_shared<record::Trajectory>(world);
  CheckRunLimits(a.duration, a.dt, 1, int(run->Columns().size()), a.limits);
  auto recorder = std::make_shared<record::Recorder>(run);
  world.SetRecorder(recorder);
  recorder->Start(world);
  Progress progress(isatty(STDERR_FILENO) == 1);
  const bool ok = world.RunUntil(a.duration + 0.5 * a.dt, [&](const World& w) {
    progress.Update(a.duration > 0 ? w.time() / a.duration : 1.0, w.time());
  });
  progress.Finish();

  World start = setup.MakeWorld();  // the run is drawn from its start, ground contacts as they were
  RenderRun(a, request, start, *run, a.duration);
  if (!ok) {
    std::cerr << "wobble: simulation stopped: " << world.status().message << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

RenderRequest ParseRenderRequest(const RenderArgs& a, const std::string& default_what, OptionSpelling spelling) {
  RenderRequest r;
  try {
    r.settings = scene::ParseRenderOptions(a.picture);
  } catch (const scene::RenderOptionError& e) {
    if (spelling == OptionSpelling::kScript) throw std::invalid_argument(e.option + "=: " + e.what());
    throw UsageError("--" + e.option + ": " + e.what());
  }
  r.what = ParseWhat(a.what.empty() ? default_what : a.what);
  return r;
}

void CheckRenderRequest(const RenderRequest& r, const std::string& out) {
  if (!pl::NeedingDisplay({r.what.begin(), r.what.end()}).empty() && !pl::HasDisplay())
    throw UsageError("rendering needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run under\n"
                     "  xvfb-run -a -s \"-screen 0 1280x1024x24\" wobble ...\n"
                     "or ask only for --what vtp,disp,gltf,web");
  CheckOutputFolder(out);
}

void RenderRun(const RenderArgs& a, const RenderRequest& request, World& world, const record::Trajectory& run,
               double t_end) {
  if (run.empty()) throw std::invalid_argument("nothing was recorded: no frames to render");
  const std::string name = run.bodies().empty() ? "run" : run.bodies()[0].name;
  pl::RenderOutputs out;
  out.folder = a.out;
  out.name = name;  // the .pvd's stem and the pictures' title
  pl::SetOutputs(std::vector<std::string>(request.what.begin(), request.what.end()), &out);  // checked by ParseWhat
  pl::ApplyRenderSettings(request.settings, &out);
  out.view.title = name;
  out.t_end = t_end;
  Progress progress(isatty(STDERR_FILENO) == 1, "t");
  out.progress = [&](double fraction, double t) { progress.Update(fraction, t); };
  const auto start = std::chrono::steady_clock::now();
  const pl::RenderReport report = pl::RenderTrajectory(world, run, pl::SceneSpec{}, out);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.Finish();
  std::cout << name << ": " << report.frames << " frames at " << Num(out.fps) << " fps over "
            << Num(run.time(run.size() - 1)) << " s, " << Num(wall) << " s wall ("
            << (wall > 0 ? Num(report.frames / wall) : std::string("-")) << " frames/s).\n";
  for (const pl::RenderReport::File& f : report.files) std::cout << "  " << f.Line() << "\n";
  bool ffd = false;
  for (const record::BodyInfo& b : run.bodies()) ffd = ffd || b.kind == BodyKind::kFfd;
  if (out.disp && !ffd) std::cout << "  no displacement images: they are drawn for FFD bodies only\n";
  std::cout << std::flush;
}

}  // namespace wobble::app
