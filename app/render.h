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
#include <string>

#include "cli_common.h"
#include "wobble/record/trajectory.h"
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
  std::string size = "640x480";     // frames
  double fps = 30.0;
  std::string color_by;             // mass-point array or "displacement"
  int shape_samples = 16;
  std::string filmstrip_times;      // "0 0.5 1 ..."; empty: 6 evenly spaced
  std::string filmstrip_size = "320x240";
  int filmstrip_columns = 3;
  std::string filmstrip_cycle;      // "K [PANELS]": the panels sample the pose graph's cycle K
  std::string disp_size;            // "WxH"; empty: 256 wide, lattice aspect
  std::string chart_size = "800x500";
  std::string trail;                // lattice coords "s t s t ..." of points to trace
  double azimuth = 30.0, elevation = 20.0;  // 3D camera, degrees
  double orbit = 0.0;               // 3D camera turn, degrees per simulated second
  std::string camera = "whole";     // 2D: whole (the run framed once) or follow
  std::string style = "diagnostic"; // diagnostic (lattice, mass points) or clean (the character only)
  bool exr_terrain = false;         // EXR frames: the terrain as its own layer too
  Limits limits;
};

// `default_what` is "frames,filmstrip,charts" for render, "vtp,exr,disp" for export.
CLI::App* AddRenderCommand(CLI::App* app, const std::string& name, const std::string& description,
                           const std::string& default_what, RenderArgs* args);
int RunRender(const RenderArgs& args, const std::string& default_what);

// Checks the picture options (--what, sizes, display, --out) before anything is simulated.
void CheckRenderOptions(const RenderArgs& args, const std::string& default_what);
// What the picture options ask of the render driver; `name` is the .pvd's stem and the title.
pipelines::RenderOutputs RenderOutputsOf(const RenderArgs& args, const std::string& default_what, const std::string& name);
// Draws `run` (put back into `world`, a world of its bodies) as the options ask and prints
// what was written: `wobble render`/`export` and a script's `render` of its FFD runs. Frames
// at --fps from the first sample up to t_end (the run's intended end), those the run reached.
void RenderRun(const RenderArgs& args, const std::string& default_what, World& world, const record::Trajectory& run,
               double t_end);

}  // namespace wobble::app
