#include "wobble/record/trajectory_csv.h"

#include <cmath>
#include <sstream>

#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"

namespace wobble::record {

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

// " (a body with D modes)" for one FFD body, the bodies' names otherwise.
std::string BodiesText(const Trajectory& t) {
  if (t.num_bodies() == 1 && t.bodies()[0].kind == BodyKind::kFfd)  // the caller's BodyInfo need not carry the model
    return " (a body with " + std::to_string(t.bodies()[0].num_modes()) + " modes)";
  std::string names;
  for (const BodyInfo& b : t.bodies()) names += (names.empty() ? "" : ", ") + b.name;
  return " (bodies " + names + ")";
}

}  // namespace

BodyInfo DescribeFfdBody(std::shared_ptr<const BodyModel> body) {
  BodyInfo info;
  info.name = body->name();
  info.kind = BodyKind::kFfd;
  info.coordinate_names = {"tx", "ty", "theta"};
  for (const DeformationMode& mode : body->modes()) info.coordinate_names.push_back(mode.name);
  info.num_q = int(info.coordinate_names.size());
  info.set_ffd(std::move(body));
  return info;
}

BodyInfo DescribeFfdBody(std::shared_ptr<const BodyModelN<3>> body) {  // as a world describes it
  World w;
  w.AddBody(body);
  return DescribeBody(w, 0);
}

void WriteTrajectoryCsv(const std::string& path, const Trajectory& t) {
  formats::WriteCsvAtomically(path, t.Columns(), t.size(), [&t](int k) { return t.Row(k); });
}

ReadTrajectory ParseTrajectoryCsv(std::istream& in, const std::string& file, std::vector<BodyInfo> bodies) {
  ReadTrajectory out{Trajectory(std::move(bodies)), false};
  Trajectory& traj = out.trajectory;
  const std::vector<std::string>& schema = traj.Columns();
  // the required columns: t and the q of every body, in the schema's order
  std::vector<int> required = {0};
  for (int i = 0; i < traj.num_columns(); ++i)
    for (int b = 0; b < traj.num_bodies(); ++b) {
      const std::string prefix = traj.num_bodies() > 1 ? traj.bodies()[b].name + "." : "";
      for (const std::string& c : traj.bodies()[b].coordinate_names)
        if (schema[i] == prefix + c) required.push_back(i);
    }
  std::string text;
  if (!std::getline(in, text)) throw formats::ParseError(file, 0, "file is empty: expected the header of `wobble simulate`");
  const std::vector<std::string> header = SplitCommas(text);
  std::string expected_text;
  for (int i : required) expected_text += (expected_text.empty() ? "" : ",") + schema[i];
  for (size_t i = 0; i < required.size(); ++i)
    if (i >= header.size() || header[i] != schema[required[i]])
      throw formats::ParseError(file, 1, "expected the header to start with " + expected_text + BodiesText(traj) + ", got '" + text + "'");
  // where each schema column is in the file (−1: absent)
  std::vector<int> source(schema.size(), -1);
  for (size_t h = 0; h < header.size(); ++h)
    for (size_t i = 0; i < schema.size(); ++i)
      if (header[h] == schema[i] && source[i] < 0) source[i] = int(h);
  out.has_velocities = true;
  for (int b = 0; b < traj.num_bodies(); ++b) {
    const std::string prefix = traj.num_bodies() > 1 ? traj.bodies()[b].name + "." : "";
    for (const std::string& c : traj.bodies()[b].velocity_names)
      out.has_velocities = out.has_velocities && traj.Column(prefix + c) >= 0 && source[traj.Column(prefix + c)] >= 0;
  }

  int number = 1;
  std::vector<double> row(schema.size());
  double last_t = 0.0;
  while (std::getline(in, text)) {
    ++number;
    if (text.empty() || text == "\r") continue;
    const std::vector<std::string> cells = SplitCommas(text);
    if (cells.size() != header.size())
      throw formats::ParseError(file, number, "expected " + std::to_string(header.size()) + " values like the header, got " +
                                                  std::to_string(cells.size()));
    for (size_t i = 0; i < schema.size(); ++i) {
      row[i] = 0.0;
      if (source[i] < 0) continue;
      if (!formats::detail::ParseNumber(cells[size_t(source[i])], &row[i]))
        throw formats::ParseError(file, number, "expected a number in column " + std::to_string(source[i] + 1) + " (" +
                                                    schema[i] + "), got '" + cells[size_t(source[i])] + "'");
    }
    // the pose is an index (Trajectory::pose() reads it as an int; −1: none)
    const size_t pose = schema.size() - 2;
    if (source[pose] >= 0 && !(row[pose] >= -1 && row[pose] <= 1e9 && row[pose] == std::floor(row[pose])))
      throw formats::ParseError(file, number, "expected a whole number >= -1 in column " + std::to_string(source[pose] + 1) +
                                                  " (pose), got '" + cells[size_t(source[pose])] + "'");
    if (!traj.empty() && !(row[0] > last_t))
      throw formats::ParseError(file, number, "times must strictly increase (previous row: t = " +
                                                  formats::detail::FormatNumber(last_t) + ")");
    last_t = row[0];
    traj.AppendRow(row);
  }
  if (in.bad()) throw formats::ParseError(file, 0, "read error after line " + std::to_string(number));
  if (traj.empty()) throw formats::ParseError(file, 0, "no rows after the header");
  return out;
}

ReadTrajectory ReadTrajectoryCsv(const std::string& path, std::vector<BodyInfo> bodies) {
  return formats::detail::WithFile(path, [&](std::istream& in) { return ParseTrajectoryCsv(in, path, std::move(bodies)); });
}

}  // namespace wobble::record
