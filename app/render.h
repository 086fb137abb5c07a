// `wobble render` and `wobble export`: simulate one body like `wobble simulate` into a
// record::Trajectory and turn it into pictures and files through the one render driver
// (pipelines/trajectory_render.h), which a script's `render` uses too (app/script_render.h).
// They differ in what they write by default (--what):
//   render: frames (PNG sequence), filmstrip (one PNG of chosen frames), charts (energy and
//           cond(M) against time, PNG + CSV)
//   export: vtp (.vtp per frame + .pvd), exr (per frame the characters' R,G,B,A,
//           depth.Z, motion forward.u/v; with --exr-terrain terrain.R,G,B,A), disp (disp.X,
//           disp.Y over the rest lattice per frame)
// Rendering needs an X display: without DISPLAY the command stops with exit code 2 and says
// to use xvfb-run (VTK 9.1 would abort).
#pragma once

#include <CLI/CLI.hpp>
#include <map>
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

// The table's options parsed (a UsageError naming the flag otherwise).
scene::RenderSettings PictureSettings(const RenderArgs& args);
// Checks the picture options (--what, the table's options, display, --out) before anything is
// simulated; returns them parsed.
scene::RenderSettings CheckRenderOptions(const RenderArgs& args, const std::string& default_what);
// What the picture options ask of the render driver; `name` is the .pvd's stem and the title.
pipelines::RenderOutputs RenderOutputsOf(const RenderArgs& args, const std::string& default_what, const std::string& name);
// Draws `run` (put back into `world`, a world of its bodies) as the options ask and prints
// what was written: `wobble render`/`export` and a script's `render` of its FFD runs. Frames
// at --fps from the first sample up to t_end (the run's intended end), those the run reached.
void RenderRun(const RenderArgs& args, const std::string& default_what, World& world, const record::Trajectory& run,
               double t_end);

}  // namespace wobble::app
