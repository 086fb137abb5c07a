// `wobble fit pose` and `wobble fit trajectory`: the Ceres fits of lib/wobble/fit on files.
//
// Results are one JSON object (written atomically with --out, otherwise nothing is written),
// the cost per iteration as CSV (--costs), and a short summary on stdout. With a display the
// pictures go beside them: the cost chart (FILE.png beside --costs) and, for 2D bodies, the
// fitted points over their targets (FILE_overlay.png beside --out). A 3D object (`dimension 3`)
// takes 3D target files; the fits of lib/wobble/fit are the same functions for both.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli_common.h"

namespace wobble::app {

// Flags shared by both fits.
struct FitFlags {
  std::string q0;            // starting q; empty: each fit's own start
  double gamma_min = -1.0, gamma_max = 1.0;
  std::string loss = "squared";
  double loss_scale = 1.0;
  double prior = 0.0;
  int max_iterations = 200;
  bool full_report = false;
  std::string out, costs;
};

struct FitPoseArgs {
  BodyFiles files;
  FitFlags fit;
  std::string targets;
  int samples_per_segment = 8;
  bool one_sided = false;
  bool alternate = false;
  int max_rounds = 30;
  int mesh_samples = 400;  // 3D surface targets: body mesh vertices used as samples
};

struct FitTrajectoryArgs {
  BodyFiles files;
  FitFlags fit;
  WorldFlags world;  // --dynamic only
  std::string reference;
  std::string points;  // CSV reference: "0,4,5" (default all mass points)
  int every = 1;       // CSV reference: every Nth row
  double smoothness = 1.0;
  bool dynamic = false;
  double dt = 0.01;
  std::string fit_what = "q0,qdot0,stiffness,damping";
  std::string qdot0;
  std::string gradient = "jets";  // jets (Levenberg–Marquardt) or adjoint (BFGS), 2D
  bool anneal = false;
  // --dynamic with a pose-graph controller (poses, times in --fit)
  std::string poses;     // "T1 .. Tk DURATION; T1 .. Tk DURATION; ..." (k = active modes)
  std::string active;    // mode names made active, "bend,shear" (default: the .def headers')
  bool sequence = false;  // acyclic: hold the last pose
  double switch_width = 0.05;
};

// `wobble fit spacetime` (fit_spacetime.cc): PD targets for a task, 2D objects.
struct FitSpacetimeArgs {
  BodyFiles files;
  WorldFlags world;
  std::string q, qdot;
  double dt = 0.01, duration = 1.0;
  int knots = 21;
  std::string rise, reach;  // "DY T", "X Y T"
  bool upright = false, still = false;
  double weight = 2000.0, bound = 0.3, effort = 1.0;
  int max_iterations = 300;
  int starts = 1, threads = 0;  // multi-start (fit/spacetime.h: SpacetimeOptions)
  double start_spread = 1.0;
  unsigned seed = 1;
  std::string start;  // a schedule file to start from (continuation from an easier task)
  std::string targets, out;
};
CLI::App* AddFitSpacetimeCommand(CLI::App* fit, FitSpacetimeArgs* args);
int RunFitSpacetime(const FitSpacetimeArgs& args);

struct FitCommands {
  CLI::App* fit = nullptr;
  CLI::App* pose = nullptr;
  CLI::App* trajectory = nullptr;
};
FitCommands AddFitCommand(CLI::App* app, FitPoseArgs* pose, FitTrajectoryArgs* trajectory);
int RunFitPose(const FitPoseArgs& args);
int RunFitTrajectory(const FitTrajectoryArgs& args);

}  // namespace wobble::app
