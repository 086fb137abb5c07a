// `wobble sweep SCRIPT`: a study, one run of the script per case of a grid or list of its
// variables, one results table (lib/wobble/script/sweep.h), on threads or MPI ranks.
#pragma once

#include "cli_common.h"

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace wobble::app {

struct SweepArgs {
  std::string script;
  std::vector<std::string> params;  // NAME=VALUES
  std::string list;                 // a CSV of cases instead of a grid
  std::string measures = "cost";
  std::string plot;                 // the measure plotted (default: the first numeric one)
  std::string out = "out/sweep";
  std::string gait = "1,2";         // SKIP,CYCLES of the distance measure
  int threads = 0;
  Limits limits;
};
CLI::App* AddSweepCommand(CLI::App* app, SweepArgs* args);
int RunSweep(const SweepArgs& args);

}  // namespace wobble::app
