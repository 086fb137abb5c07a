// `wobble run SCRIPT`: runs a command script (appendix C's interpreter, extended; README
// "Scripts"). Without a script, on a terminal, it is an interactive prompt.
#pragma once

#include "cli_common.h"

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

namespace wobble::app {

struct RunArgs {
  std::string script;  // empty: read commands from stdin (a prompt on a terminal)
  std::string object;  // loaded before the script, as `load_obj` would
  std::vector<std::string> params;  // NAME=VALUE for the script's ${NAME} (script/variables.h)
  Limits limits;       // the scene's (a script's `set max_steps` changes them)
};
CLI::App* AddRunCommand(CLI::App* app, RunArgs* args);
int RunScript(const RunArgs& args);

}  // namespace wobble::app
