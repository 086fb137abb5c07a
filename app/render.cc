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
#include <tuple>

#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "wobble/formats/csv.h"
#include "progress.h"

namespace wobble::app {
namespace {

namespace pl = wobble::pipelines;


struct Size {
  int w = 0, h = 0;
};

Size ParseSize(const std::string& text, const std::string& flag) {
  Size s;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.w, &x, &s.h, &extra) != 3 || (x != 'x' && x != 'X'))
    throw UsageError(flag + ": expected WIDTHxHEIGHT such as 640x480, got '" + text + "'");
  if (s.w < 16 || s.h < 16 || s.w > 8192 || s.h > 8192)
    throw UsageError(flag + ": each side must be between 16 and 8192 pixels, got '" + text + "'");
  return s;
}

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
  cmd->add_option("--q", a->q, "Initial q = \"tx ty theta g1 ..\" (default: at rest at the origin)")->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, "Initial q-dot, same layout (default: zeros)")->type_name("\"NUMS\"");
  cmd->add_option("--integrator", a->integrator, "thesis | symplectic | rk4 | implicit | variational")
      ->capture_default_str()
      ->type_name("NAME");
  cmd->add_option("--dt", a->dt, "Time step")->capture_default_str();
  cmd->add_option("--duration", a->duration, "Simulated time")->capture_default_str();
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--out", a->out, "Output folder")->required()->type_name("DIR");
  AddLimitFlags(cmd, &a->limits);
  cmd->add_option("--what", a->what,
                  "What to write, comma separated: frames, filmstrip, charts, vtp, exr, disp (default: " +
                      default_what + ")")
      ->type_name("LIST");
  cmd->add_option("--size", a->size, "Frame size (PNG and EXR frames)")->capture_default_str()->type_name("WxH");
  cmd->add_option("--fps", a->fps, "Frames per simulated second")->capture_default_str();
  cmd->add_option("--color-by", a->color_by,
                  "Colour mass points by mass | velocity | applied_force | in_contact, or lattice points by "
                  "displacement")
      ->type_name("ARRAY");
  cmd->add_option("--shape-samples", a->shape_samples, "Samples per drawing segment (the shape is drawn finer "
                                                       "than the mass points)")
      ->capture_default_str();
  cmd->add_option("--filmstrip", a->filmstrip_times, "Times of the filmstrip's panels (default: 6 evenly spaced)")
      ->type_name("\"T T ..\"");
  cmd->add_option("--filmstrip-size", a->filmstrip_size, "Size of one filmstrip panel")
      ->capture_default_str()
      ->type_name("WxH");
  cmd->add_option("--filmstrip-columns", a->filmstrip_columns, "Panels per filmstrip row (0: one row)")
      ->capture_default_str();
  cmd->add_option("--filmstrip-cycle", a->filmstrip_cycle,
                  "Gaits: the panels sample cycle K of the pose graph (0 the first) at PANELS equal steps (6) and "
                  "its end, each labelled with its active pose (in place of --filmstrip)")
      ->type_name("\"K [PANELS]\"");
  cmd->add_option("--disp-size", a->disp_size, "Size of the displacement image (default: 256 wide, lattice aspect)")
      ->type_name("WxH");
  cmd->add_option("--chart-size", a->chart_size, "Size of the charts")->capture_default_str()->type_name("WxH");
  cmd->add_option("--azimuth", a->azimuth, "3D: the camera's angle about +y, degrees from +z towards +x")
      ->capture_default_str();
  cmd->add_option("--elevation", a->elevation, "3D: the camera's angle above the ground plane, degrees")
      ->capture_default_str();
  cmd->add_option("--orbit", a->orbit, "3D: the camera orbits the motion at this many degrees per simulated second")
      ->capture_default_str();
  cmd->add_option("--camera", a->camera, "whole (frame the whole run, standing still) or follow (the body, smoothed, "
                                        "the ground under it in view; 3D: a cube about it from --azimuth, --elevation)")
      ->capture_default_str();
  cmd->add_option("--style", a->style, "diagnostic (lattice, mass points, shape) or clean (the character: filled, "
                                      "anti-aliased, no lattice or points)")
      ->capture_default_str();
  cmd->add_flag("--exr-terrain", a->exr_terrain,
                "EXR frames: write the rest of the picture (terrain or ground, springs, trails) as its own layer "
                "terrain.R,G,B,A too (the characters' R,G,B,A are always written)");
  cmd->add_option("--trail", a->trail, "Trace points given by lattice coordinates \"s t s t ..\" in the frames")
      ->type_name("\"S T ..\"");
  return cmd;
}

int RunRender(const RenderArgs& a, const std::string& default_what) {
  // check every value before reading files or simulating
  const Integrator integrator = ParseIntegratorFlag(a.integrator);
  RequirePositive(a.dt, "--dt");
  RequireNonNegative(a.duration, "--duration");
  RequirePositive(a.fps, "--fps");
  if (!(a.duration * a.fps <= 1e6)) throw UsageError("--duration * --fps asks for more than a million frames");
  CheckRenderOptions(a, default_what);

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
  RenderRun(a, default_what, start, *run, a.duration);
  if (!ok) {
    std::cerr << "wobble: simulation stopped: " << world.status().message << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

// --filmstrip-cycle "K [PANELS]": (K, PANELS), (-1, 6) when not given.
std::pair<int, int> FilmstripCycleOf(const RenderArgs& a) {
  if (a.filmstrip_cycle.empty()) return {-1, 6};
  const std::vector<double> v = ParseNumbers(a.filmstrip_cycle, "--filmstrip-cycle");
  const bool whole = std::all_of(v.begin(), v.end(), [](double x) { return x == std::floor(x); });
  if (v.empty() || v.size() > 2 || !whole || v[0] < 0 || v[0] > 1e6 || (v.size() == 2 && (v[1] < 1 || v[1] > 100)))
    throw UsageError("--filmstrip-cycle: expected a cycle K >= 0 and optionally 1 to 100 panels, got '" +
                     a.filmstrip_cycle + "'");
  if (!a.filmstrip_times.empty()) throw UsageError("--filmstrip-cycle and --filmstrip both place the panels: give one");
  return {int(v[0]), v.size() == 2 ? int(v[1]) : 6};
}

void CheckRenderOptions(const RenderArgs& a, const std::string& default_what) {
  RequirePositive(a.fps, "--fps");
  if (a.shape_samples < 1 || a.shape_samples > 10000) throw UsageError("--shape-samples must be between 1 and 10000");
  const std::set<std::string> what = ParseWhat(a.what.empty() ? default_what : a.what);
  ParseSize(a.size, "--size");
  ParseSize(a.filmstrip_size, "--filmstrip-size");
  ParseSize(a.chart_size, "--chart-size");
  ParseNumbers(a.filmstrip_times, "--filmstrip");
  FilmstripCycleOf(a);
  if (ParseNumbers(a.trail, "--trail").size() % 2) throw UsageError("--trail: lattice coordinates come in pairs s t");
  RequireFinite(a.azimuth, "--azimuth");
  RequireFinite(a.orbit, "--orbit");
  if (!(std::abs(a.elevation) < 90.0)) throw UsageError("--elevation must be between -90 and 90 degrees");
  if (a.camera != "whole" && a.camera != "follow") throw UsageError("--camera: expected whole or follow, got '" + a.camera + "'");
  if (a.style != "diagnostic" && a.style != "clean")
    throw UsageError("--style: expected diagnostic or clean, got '" + a.style + "'");
  const bool renders = what.count("frames") || what.count("filmstrip") || what.count("charts") || what.count("exr");
  if (renders && !pl::HasDisplay())
    throw UsageError("rendering needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run under\n"
                     "  xvfb-run -a -s \"-screen 0 1280x1024x24\" wobble ...\n"
                     "or ask only for --what vtp,disp");
  CheckOutputFolder(a.out);
}

pl::RenderOutputs RenderOutputsOf(const RenderArgs& a, const std::string& default_what, const std::string& name) {
  CheckRenderOptions(a, default_what);
  const std::set<std::string> what = ParseWhat(a.what.empty() ? default_what : a.what);
  pl::RenderOutputs out;
  out.folder = a.out;
  out.name = name;
  pl::SetOutputs(std::vector<std::string>(what.begin(), what.end()), &out);  // checked by ParseWhat
  out.fps = a.fps;
  const Size frame_size = ParseSize(a.size, "--size");
  out.view.width = frame_size.w;
  out.view.height = frame_size.h;
  out.view.color_by = a.color_by;
  out.view.shape_samples = a.shape_samples;
  out.view.title = name;
  const Size strip_size = ParseSize(a.filmstrip_size, "--filmstrip-size");
  out.filmstrip_times = ParseNumbers(a.filmstrip_times, "--filmstrip");
  out.filmstrip_width = strip_size.w;
  out.filmstrip_height = strip_size.h;
  out.filmstrip_columns = a.filmstrip_columns;
  std::tie(out.filmstrip_cycle, out.filmstrip_panels) = FilmstripCycleOf(a);
  if (!a.disp_size.empty()) {
    const Size disp = ParseSize(a.disp_size, "--disp-size");
    out.disp_width = disp.w;
    out.disp_height = disp.h;
  }
  const Size chart_size = ParseSize(a.chart_size, "--chart-size");
  out.chart_width = chart_size.w;
  out.chart_height = chart_size.h;
  const std::vector<double> trail = ParseNumbers(a.trail, "--trail");
  for (size_t i = 0; i + 1 < trail.size(); i += 2) out.trail.emplace_back(trail[i], trail[i + 1]);
  out.view.show_trails = !out.trail.empty();
  out.view.azimuth = a.azimuth;
  out.view.elevation = a.elevation;
  out.orbit_deg_per_s = a.orbit;
  out.camera = a.camera == "follow" ? pl::RenderOutputs::Camera::kFollow : pl::RenderOutputs::Camera::kWhole;
  out.view.style = a.style == "clean" ? pl::RenderStyle::kClean : pl::RenderStyle::kDiagnostic;
  out.view.exr_terrain_layer = a.exr_terrain;
  return out;
}

void RenderRun(const RenderArgs& a, const std::string& default_what, World& world, const record::Trajectory& run,
               double t_end) {
  if (run.empty()) throw std::invalid_argument("nothing was recorded: no frames to render");
  const std::string name = run.bodies().empty() ? "run" : run.bodies()[0].name;
  pl::RenderOutputs out = RenderOutputsOf(a, default_what, name);
  out.t_end = t_end;
  Progress progress(isatty(STDERR_FILENO) == 1, "t");
  out.progress = [&](double fraction, double t) { progress.Update(fraction, t); };
  const auto start = std::chrono::steady_clock::now();
  const pl::RenderReport report = pl::RenderTrajectory(world, run, pl::SceneSpec{}, out);
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.Finish();
  std::cout << name << ": " << report.frames << " frames at " << Num(a.fps) << " fps over "
            << Num(run.time(run.size() - 1)) << " s, " << Num(wall) << " s wall ("
            << (wall > 0 ? Num(report.frames / wall) : std::string("-")) << " frames/s).\n";
  for (const pl::RenderReport::File& f : report.files) std::cout << "  " << f.Line() << "\n";
  bool ffd = false;
  for (const record::BodyInfo& b : run.bodies()) ffd = ffd || b.kind == BodyKind::kFfd || b.kind == BodyKind::kFfd3;
  if (out.disp && !ffd) std::cout << "  no displacement images: they are drawn for FFD bodies only\n";
  std::cout << std::flush;
}

}  // namespace wobble::app
