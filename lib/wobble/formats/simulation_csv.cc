#include "wobble/formats/simulation_csv.h"

#include <sstream>

#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> cells;
  std::string cell;
  std::istringstream in(text);
  while (std::getline(in, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    cells.push_back(cell);
  }
  if (!text.empty() && text.back() == ',') cells.push_back("");
  return cells;
}

}  // namespace

SimulationCsv ParseSimulationCsv(std::istream& in, const std::string& file, int num_modes) {
  const int nq = 3 + num_modes;
  std::vector<std::string> expected = {"t", "tx", "ty", "theta"};
  for (int d = 1; d <= num_modes; ++d) expected.push_back("g" + std::to_string(d));
  std::vector<std::string> velocity = {"dtx", "dty", "dtheta"};
  for (int d = 1; d <= num_modes; ++d) velocity.push_back("dg" + std::to_string(d));
  std::string text;
  if (!std::getline(in, text)) throw ParseError(file, 0, "file is empty: expected the header of `wobble simulate`");
  const std::vector<std::string> header = SplitCommas(text);
  std::string expected_text;
  for (const std::string& e : expected) expected_text += (expected_text.empty() ? "" : ",") + e;
  for (size_t i = 0; i < expected.size(); ++i)
    if (i >= header.size() || header[i] != expected[i])
      throw ParseError(file, 1, "expected the header to start with " + expected_text + " (a body with " +
                                    std::to_string(num_modes) + " modes), got '" + text + "'");
  bool has_velocity = header.size() >= expected.size() + velocity.size();
  for (size_t i = 0; has_velocity && i < velocity.size(); ++i) has_velocity = header[expected.size() + i] == velocity[i];
  const size_t columns = has_velocity ? expected.size() + velocity.size() : expected.size();

  SimulationCsv out;
  int number = 1;
  while (std::getline(in, text)) {
    ++number;
    if (text.empty() || text == "\r") continue;
    const std::vector<std::string> cells = SplitCommas(text);
    if (cells.size() != header.size())
      throw ParseError(file, number, "expected " + std::to_string(header.size()) + " values like the header, got " +
                                         std::to_string(cells.size()));
    std::vector<double> v(columns);
    for (size_t i = 0; i < columns; ++i)
      if (!detail::ParseNumber(cells[i], &v[i]))
        throw ParseError(file, number, "expected a number in column " + std::to_string(i + 1) + " (" +
                                           (i < expected.size() ? expected[i] : velocity[i - expected.size()]) +
                                           "), got '" + cells[i] + "'");
    if (!out.t.empty() && !(v[0] > out.t.back()))
      throw ParseError(file, number, "times must strictly increase (previous row: t = " +
                                         detail::FormatNumber(out.t.back()) + ")");
    out.t.push_back(v[0]);
    out.q.push_back(Eigen::Map<Eigen::VectorXd>(v.data() + 1, nq));
    if (has_velocity) out.qd.push_back(Eigen::Map<Eigen::VectorXd>(v.data() + 1 + nq, nq));
  }
  if (in.bad()) throw ParseError(file, 0, "read error after line " + std::to_string(number));
  if (out.t.empty()) throw ParseError(file, 0, "no rows after the header");
  return out;
}

SimulationCsv ReadSimulationCsv(const std::string& path, int num_modes) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseSimulationCsv(in, path, num_modes); });
}

}  // namespace wobble::formats
