// `wobble inspect`: everything the dynamics computes for one state, as one JSON object.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli_common.h"

namespace wobble::app {

struct InspectArgs {
  BodyFiles files;
  WorldFlags world;
  std::string q, qdot;
  int indent = -1;  // -1: one line
};

CLI::App* AddInspectCommand(CLI::App* app, InspectArgs* args);
// Prints the JSON object to stdout; returns the exit code.
int RunInspect(const InspectArgs& args);

}  // namespace wobble::app
