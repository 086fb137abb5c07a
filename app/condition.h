// `wobble condition sweep` and `wobble condition check`: the conditioning analysis of
// thesis §4.10.3 (Fig. 4.7, 4.8) and the mode-set check, from the command line.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "cli_common.h"

namespace wobble::app {

struct ConditionSweepArgs {
  std::string object = "data/table.obj";
  double from_deg = 0.0, to_deg = 90.0, step_deg = 5.0;
  double compress = 1.0, expand = 0.5;
  std::string q;          // state the sweep is evaluated at (default: rest)
  int drop_last = 3;      // samples left out of the small-angle chart (Fig. 4.8)
  // The two-parameter map: φ against the vertical squash amplitude γ1 in [-map_gamma, map_gamma].
  int map_size = 0;       // samples per axis; 0 = no map
  double map_gamma = 0.5;
  std::string out = "out/condition";
};

struct ConditionCheckArgs {
  BodyFiles files;
  std::string q;
  double warn_angle_deg = 5.0;
  double warn_visibility = 0.05;
  std::string json;  // also write the report here
};

// Fig. 4.9: cond(M) against time while a body falls onto the ground, contact events marked.
struct ConditionTimeArgs {
  BodyFiles files{"data/table.obj", {"data/fig4_9_modes.def"}};
  WorldFlags world;
  std::string q = "0 50 0 0 0 0";  // dropped from 50 (thesis units: g = 9.81, pixels = metres)
  double dt = 0.01, duration = 12.0;
  std::string out = "out/condition";
};

struct ConditionCommands {
  CLI::App* sweep;
  CLI::App* check;
  CLI::App* time;
};
ConditionCommands AddConditionCommand(CLI::App* app, ConditionSweepArgs* sweep, ConditionCheckArgs* check,
                                      ConditionTimeArgs* time);
// Exit 3 when the simulation stops with a status (numbers up to there are still written).
int RunConditionTime(const ConditionTimeArgs& args);
int RunConditionSweep(const ConditionSweepArgs& args);
// Exit 0 when the set is fine or only warned about, 2 when it is dependent (M singular).
int RunConditionCheck(const ConditionCheckArgs& args);

}  // namespace wobble::app
