// A target schedule file: the PD target of every mode at every step of a run, as a spacetime
// fit finds it (`wobble fit spacetime --targets`) and a script plays it (`schedule FILE`).
//     t,bend,shear,vsquash,hsquash
//     0,0.0047,0,0.0048,0.0032
//     0.01,...
// One row per step, t = n Δt from 0; the columns after t are the object's modes, by name and
// in order. Written atomically (csv.h).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace wobble::formats {

// targets: modes × steps. Throws std::runtime_error naming the file when it cannot be written.
void WriteTargetSchedule(const std::string& path, const std::vector<std::string>& modes, double dt,
                         const Eigen::MatrixXd& targets);

// Throws ParseError "FILE:LINE: ..." when the header does not name exactly these modes, a row
// is not t and one finite number per mode, a time is not the next step of dt, or there is no row.
Eigen::MatrixXd ReadTargetSchedule(const std::string& path, const std::vector<std::string>& modes, double dt);

}  // namespace wobble::formats
