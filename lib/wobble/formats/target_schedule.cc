#include "wobble/formats/target_schedule.h"

#include <cmath>
#include <sstream>

#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats {

namespace {

std::vector<std::string> SplitCommas(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) {
    const size_t a = cell.find_first_not_of(" \t\r"), b = cell.find_last_not_of(" \t\r");
    cells.push_back(a == std::string::npos ? "" : cell.substr(a, b - a + 1));
  }
  if (!line.empty() && line.back() == ',') cells.push_back("");
  return cells;
}

}  // namespace

void WriteTargetSchedule(const std::string& path, const std::vector<std::string>& modes, double dt,
                         const Eigen::MatrixXd& targets) {
  std::vector<std::string> header{"t"};
  header.insert(header.end(), modes.begin(), modes.end());
  std::vector<std::vector<double>> rows;
  for (int n = 0; n < targets.cols(); ++n) {
    std::vector<double> row{n * dt};
    for (int d = 0; d < targets.rows(); ++d) row.push_back(targets(d, n));
    rows.push_back(row);
  }
  WriteCsvAtomically(path, header, rows);
}

Eigen::MatrixXd ReadTargetSchedule(const std::string& path, const std::vector<std::string>& modes, double dt) {
  return detail::WithFile(path, [&](std::istream& in) {
    std::string line;
    int number = 0;
    std::string expected = "t";
    for (const std::string& m : modes) expected += "," + m;
    if (!std::getline(in, line)) throw ParseError(path, 1, "empty file: expected the header '" + expected + "'");
    ++number;
    std::vector<std::string> header = SplitCommas(line);
    std::vector<std::string> want{"t"};
    want.insert(want.end(), modes.begin(), modes.end());
    if (header != want) throw ParseError(path, number, "expected the header '" + expected + "' (the object's modes)");
    std::vector<Eigen::VectorXd> columns;
    while (std::getline(in, line)) {
      ++number;
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      const std::vector<std::string> cells = SplitCommas(line);
      if (cells.size() != want.size())
        throw ParseError(path, number, "expected " + std::to_string(want.size()) + " numbers (t and one target per mode)");
      double t;
      if (!detail::ParseNumber(cells[0], &t)) throw ParseError(path, number, "expected a time, got '" + cells[0] + "'");
      const double step_time = double(columns.size()) * dt;
      if (std::abs(t - step_time) > 1e-9 * std::max(1.0, step_time))
        throw ParseError(path, number, "expected t = " + detail::FormatNumber(step_time) + " (one row per step of dt " +
                                           detail::FormatNumber(dt) + " from 0), got " + cells[0]);
      Eigen::VectorXd column(modes.size());
      for (size_t d = 0; d < modes.size(); ++d)
        if (!detail::ParseNumber(cells[d + 1], &column[Eigen::Index(d)]))
          throw ParseError(path, number, "expected a finite target for " + modes[d] + ", got '" + cells[d + 1] + "'");
      columns.push_back(column);
    }
    if (columns.empty()) throw ParseError(path, number, "no step: expected rows after the header");
    Eigen::MatrixXd targets(modes.size(), columns.size());
    for (size_t n = 0; n < columns.size(); ++n) targets.col(Eigen::Index(n)) = columns[n];
    return targets;
  });
}

}  // namespace wobble::formats
