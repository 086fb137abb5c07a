// The FFD object's runs seen as one motion. Each run is recorded with the mode set it had, and
// a `load_def` between runs changes the set (the cliff jump's keyframes and flight, Fig. 4.12),
// so modes are matched by name: a kept mode keeps its column, a new one gets a new column, and
// where a mode was not loaded it reads 0. A run's first sample at the time of the previous
// run's last one replaces it (the hand-over: the later run goes on from there).
//   MergeRuns    one trajectory on the object with every mode the runs used (`render`)
//   OutputTrajectory  the `output` CSV of the script language (README, "Scripts")
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "wobble/record/trajectory.h"

namespace wobble::scene {

// Runs of one FFD body each (Scene::last_object_run()), in the order they ran.
using ObjectRuns = std::vector<std::shared_ptr<const record::Trajectory>>;

// The runs on one body: the object of the first run with every mode of the runs, each as the
// last run that had it defined it. std::invalid_argument when `runs` is empty.
record::Trajectory MergeRuns(const ObjectRuns& runs);

// Every `every`-th sample of MergeRuns: the `output` CSV of the script language, written in the
// one trajectory schema (record/trajectory_csv.h; mode columns by name).
record::Trajectory OutputTrajectory(const ObjectRuns& runs, int every);

}  // namespace wobble::scene
