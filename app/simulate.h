// `wobble simulate`: one body in a world over the ground, written as a CSV trajectory.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli_common.h"

namespace wobble::app {

struct SimulateArgs {
  BodyFiles files;
  WorldFlags world;
  std::string q, qdot;  // "tx ty theta g1 .."; empty: at rest at the origin
  std::string integrator = "thesis";
  double dt = 0.01;
  double duration = 10.0;
  long every = 1;  // write every Nth step
  std::string out;
  Limits limits;
};

CLI::App* AddSimulateCommand(CLI::App* app, SimulateArgs* args);
// Runs it; returns the exit code. Throws UsageError / formats::ParseError / std::invalid_argument
// for bad input.
int RunSimulate(const SimulateArgs& args);

}  // namespace wobble::app
