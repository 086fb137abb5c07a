// Reads back the CSV that `wobble simulate` writes (a recorded simulation), as a reference
// trajectory for the fits. Columns: t,tx,ty,theta,g1..gD,dtx,dty,dtheta,dg1..dgD, then any
// further columns (energies, contacts), which are ignored. The header must name the first
// 4 + D columns exactly like that for a body with D modes; every problem is a ParseError
// "FILE:LINE: ..." (line 1 is the header).
#pragma once

#include <Eigen/Core>
#include <istream>
#include <string>
#include <vector>

namespace wobble::formats {

struct SimulationCsv {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> q, qd;  // qd empty when the file has no velocity columns
};

SimulationCsv ReadSimulationCsv(const std::string& path, int num_modes);
SimulationCsv ParseSimulationCsv(std::istream& in, const std::string& name_for_errors, int num_modes);

}  // namespace wobble::formats
