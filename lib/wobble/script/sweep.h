// Studies (issue 17): one script run for every case of a grid or list of its variables
// (script/variables.h: `${NAME}` stands for any word of the script), with one row of results
// per case. The cases are independent items of core/distribute.h: they run on one thread, on
// every thread, or on every MPI rank's threads, and the table is the same bit for bit.
//
// A case that fails (a bad value, a numerical stop) is a row with its status and message, not
// a failed study.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "wobble/core/limits.h"

namespace wobble::script {

struct SweepParameter {
  std::string name;
  std::vector<std::string> values;
};

// "NAME=a,b,c" (a list of words), "NAME=FROM:TO:N" (N numbers evenly from FROM to TO) or
// "NAME=FROM:TO:N:log" (N numbers evenly in log from FROM to TO, both > 0). InputError saying
// what was expected otherwise.
SweepParameter ParseSweepParameter(const std::string& spec);

// What a study runs: the parameters' names and one value per name for every case.
struct SweepPlan {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> cases;
};
// Every combination of the parameters' values, the first parameter varying slowest.
SweepPlan GridPlan(const std::vector<SweepParameter>& parameters);
// A CSV file: a header of names, then a row of values per case (formats::ParseError with
// FILE:LINE for a row of the wrong width or an empty file).
SweepPlan ReadCaseList(const std::string& path);

// The measures a row can hold, besides the case's values and its status:
//   cost      the last optimisation's best cost (anneal, cmaes), or else one trial of the pose
//             graph the script ends with, judged by its `cost` (Table 5.1)
//   trials    simulations the script's optimisations ran
//   distance  distance per cycle of the centre of mass, mean over `gait_cycles` periods after
//             `gait_skip` (the `gait` command's measure; needs a cyclic pose graph)
//   state     the object's final q and q̇ (two cells, numbers separated by spaces)
//   time      the scene's time at the end
const std::vector<std::string>& SweepMeasures();

struct SweepOptions {
  std::string script;                 // the script file, run once per case
  SweepPlan plan;
  std::vector<std::string> measures;  // from SweepMeasures()
  int gait_skip = 1, gait_cycles = 2;
  int threads = 0;                    // threads per process (0: every core)
  Limits limits;                      // each case's scene limits
  // On rank 0, as each case finishes (any order): its row, for streaming to disk.
  std::function<void(size_t index, const std::vector<std::string>& row)> on_row;
};

struct SweepTable {
  std::vector<std::string> header;  // case, the names, status, the measures' columns, message
  std::vector<std::vector<std::string>> rows;
  size_t not_run = 0;  // cases Ctrl-C kept from starting (their status says so)
};

// The header RunSweep's rows follow.
std::vector<std::string> SweepHeader(const SweepOptions& options);
// Runs every case (InputError before any runs for an unknown measure, a parameter no line of
// the script uses, or a script that cannot be read).
SweepTable RunSweep(const SweepOptions& options);
// CSV text of a header and rows (cells with a comma, quote or space quoted).
std::string CsvLine(const std::vector<std::string>& cells);

// Status words of a row.
inline constexpr const char* kCaseOk = "ok";
inline constexpr const char* kCaseNotRun = "not run";

}  // namespace wobble::script
