// `wobble render` and `wobble export`: simulate one body like `wobble simulate` into a
// record::Trajectory and turn it into pictures and files through the one render driver
// (pipelines/trajectory_render.h), which a script's `render` uses too (app/script_render.h).
// They differ in what they write by default (--what):
//   render: frames (PNG sequence), filmstrip (one PNG of chosen frames), charts (energy and
//           cond(M) against time, PNG + CSV)
//   export: vtp (.vtp per frame + .pvd), exr (per frame the characters' R,G,B,A,
//           depth.Z, motion forward.u/v (--exr-motion: and/or ViewLayer.Vector.X/Y/Z/W); with --exr-terrain
//           terrain.R,G,B,A), disp (disp.X, disp.Y over the rest lattice per frame)
// Rendering needs an X display: without DISPLAY the command stops with exit code 2 and says
// to use xvfb-run (VTK 9.1 would abort).
#pragma once

#include <CLI/CLI.hpp>
#include <map>
#include <set>
#include <string>

#include "cli_common.h"
#include "wobble/record/trajectory.h"
#include "wobble/scene/render_options.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {
struct RenderOutputs;
}

namespace wobble::app {

struct RenderArgs {
  BodyFiles files;
  WorldFlags world;
  std::string q, qdot;
  std::string integrator = "thesis";
  double dt = 0.01;
  double duration = 10.0;
  std::string out;                  // output folder
  std::string what;                 // comma list; empty: the command's default
  // the picture options as typed, by name (scene/render_options.h: one table for these flags and
  // a script's NAME=VALUE)
  std::map<std::string, std::string> picture;
  Limits limits;
};

// `default_what` is "frames,filmstrip,charts" for render, "vtp,exr,disp" for export.
CLI::App* AddRenderCommand(CLI::App* app, const std::string& name, const std::string& description,
                           const std::string& default_what, RenderArgs* args);
int RunRender(const RenderArgs& args, const std::string& default_what);

// A render's options, checked once: which outputs (--what) and the picture settings.
struct RenderRequest {
  std::set<std::string> what;
  scene::RenderSettings settings;
};
// How an error names a bad picture option: as the flag (--size: a UsageError) or as a script's
// NAME=VALUE (size=: std::invalid_argument, which the interpreter puts at the script's line).
enum class OptionSpelling { kFlag, kScript };
// --what (`default_what` when empty) and the table's options, parsed.
RenderRequest ParseRenderRequest(const RenderArgs& args, const std::string& default_what,
                                 OptionSpelling spelling = OptionSpelling::kFlag);
// Stops before anything is simulated when the request draws without an X display or the
// output folder cannot be written.
void CheckRenderRequest(const RenderRequest& request, const std::string& out);
// Draws `run` (put back into `world`, a world of its bodies) as the request asks, into
// args.out, and prints what was written: `wobble render`/`export` and a script's `render` of
// its FFD runs. Frames at the request's fps from the first sample up to t_end (the run's
// intended end), those the run reached.
void RenderRun(const RenderArgs& args, const RenderRequest& request, World& world, const record::Trajectory& run,
               double t_end);

}  // namespace wobble::app
