// `wobble render` and `wobble export`: simulate one body like `wobble simulate` and turn the
// run into pictures and files (pipelines/). Both share one driver; they differ in what they
// write by default (--what):
//   render: frames (PNG sequence), filmstrip (one PNG of chosen frames), charts (energy and
//           cond(M) against time, PNG + CSV)
//   export: vtp (.vtp per frame + .pvd), exr (R,G,B,A + depth.Z per frame), disp (disp.X,
//           disp.Y over the rest lattice per frame)
// Rendering needs an X display: without DISPLAY the command stops with exit code 2 and says
// to use xvfb-run (VTK 9.1 would abort).
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "wobble/world/world.h"

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
  std::string disp_size;            // "WxH"; empty: 256 wide, lattice aspect
  std::string chart_size = "800x500";
  std::string trail;                // lattice coords "s t s t ..." of points to trace
};

// `default_what` is "frames,filmstrip,charts" for render, "vtp,exr,disp" for export.
CLI::App* AddRenderCommand(CLI::App* app, const std::string& name, const std::string& description,
                           const std::string& default_what, RenderArgs* args);
int RunRender(const RenderArgs& args, const std::string& default_what);

// The render driver both commands share, and `wobble run`'s `render` (a script's recorded runs):
// a motion puts a world holding `body` (index 0) through its states, calling on_state after each,
// the first included; it runs twice (the camera's pass, then the writing pass) and must give the
// same states both times. Returns false when it stopped early (world.status() says why).
using Motion = std::function<bool(World& world, const std::function<void(const World&)>& on_state)>;
int RenderMotion(const RenderArgs& args, const std::string& default_what, const std::shared_ptr<const BodyModel>& body,
                 const WorldOptions& options, double t_begin, double t_end, const Motion& motion);
// Checks the picture options (--what, sizes, display, --out) before anything is simulated.
void CheckRenderOptions(const RenderArgs& args, const std::string& default_what);

}  // namespace wobble::app
