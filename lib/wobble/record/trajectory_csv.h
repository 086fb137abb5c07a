// The one CSV schema of a recorded run: Trajectory::Columns() as the header (t, then per body
// q and q̇ with mode names, PD targets, energy terms, contacts, penetration; then
// control_energy, pose, violation — trajectory.h), one row per sample. `wobble simulate`,
// a script's `output` and the render driver's exports write it; the fits read it back.
#pragma once

#include <istream>
#include <string>

#include "wobble/record/trajectory.h"

namespace wobble::record {

// Atomically (formats/atomic_file.h). Throws std::runtime_error naming the file on failure.
void WriteTrajectoryCsv(const std::string& path, const Trajectory& trajectory);

// Reads a file of this schema for the given bodies. The header must start with t and the q
// columns of every body (named as Columns() names them); every other column of the schema is
// optional and read by name (missing: 0; q̇ missing: hasVelocities() false); columns the schema
// does not know are ignored. Times must strictly increase. Every problem is a
// formats::ParseError "FILE:LINE: ..." (line 1 is the header).
struct ReadTrajectory {
  Trajectory trajectory;
  bool has_velocities = false;
};
ReadTrajectory ReadTrajectoryCsv(const std::string& path, std::vector<BodyInfo> bodies);
ReadTrajectory ParseTrajectoryCsv(std::istream& in, const std::string& name_for_errors, std::vector<BodyInfo> bodies);

// The bodies of a file for one FFD body of either dimension (names of its coordinates from
// the model).
BodyInfo DescribeFfdBody(std::shared_ptr<const BodyModel> body);
BodyInfo DescribeFfdBody(std::shared_ptr<const BodyModelN<3>> body);

}  // namespace wobble::record
