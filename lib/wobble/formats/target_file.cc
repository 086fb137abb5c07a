#include "wobble/formats/target_file.h"

#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

using detail::Line;

const char* const kPointUsage = "point <k> <x> <y> [weight <w>]";
const char* const kSampleUsage = "sample <s> <t> <x> <y> [weight <w>]";
const char* const kPolylineUsage = "polyline <x1> <y1> <x2> <y2> ... [closed]";
const char* const kCloudUsage = "cloud <x> <y>";
const char* const kFrameUsage = "frame <time>";

class TargetParser {
 public:
  explicit TargetParser(const std::string& file) { out_.file = file; }

  TargetFile Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, out_.file);
    if (lines.empty()) Fail(0, "file is empty: expected point, sample, polyline, cloud or frame lines");
    for (const Line& line : lines) Statement(line);
    for (const TargetFrame& f : out_.frames)
      if (f.points.empty()) Fail(f.line, "frame has no point or sample lines");
    return std::move(out_);
  }

 private:
  [[noreturn]] void Fail(int line, const std::string& message) const { throw ParseError(out_.file, line, message); }

  double Number(const Line& line, size_t index, const std::string& what, const char* usage) const {
    if (index >= line.words.size()) Fail(line.number, "missing " + what + " (" + usage + ")");
    double value = 0;
    if (!detail::ParseNumber(line.words[index], &value))
      Fail(line.number, "expected a number for " + what + ", got '" + line.words[index] + "' (" + usage + ")");
    return value;
  }

  // The optional "weight <w>" at words[index..].
  double Weight(const Line& line, size_t index, const char* usage) const {
    if (index == line.words.size()) return 1.0;
    if (line.words[index] != "weight" || index + 2 != line.words.size())
      Fail(line.number, "unexpected '" + line.words[index] + "' (" + usage + ")");
    const double w = Number(line, index + 1, "the weight", usage);
    if (!(w > 0)) Fail(line.number, "the weight must be > 0, got " + line.words[index + 1]);
    return w;
  }

  void Statement(const Line& line) {
    const std::string& keyword = line.words[0];
    if (keyword == "point" || keyword == "sample") {
      Correspondence(line, keyword == "point");
    } else if (keyword == "polyline") {
      PolylineLine(line);
    } else if (keyword == "cloud") {
      CurveAllowed(line);
      if (line.words.size() != 3) Fail(line.number, std::string("expected 2 numbers (") + kCloudUsage + ")");
      out_.cloud.push_back({Number(line, 1, "x", kCloudUsage), Number(line, 2, "y", kCloudUsage)});
    } else if (keyword == "frame") {
      FrameLine(line);
    } else {
      Fail(line.number, "unknown keyword '" + keyword + "' (expected point, sample, polyline, cloud or frame)");
    }
  }

  void Correspondence(const Line& line, bool is_point) {
    if (out_.has_curve())
      Fail(line.number, "a file holds correspondences (point/sample) or a curve (polyline/cloud), not both");
    PointTarget p;
    p.line = line.number;
    if (is_point) {
      if (line.words.size() < 4) Fail(line.number, std::string("expected 3 numbers (") + kPointUsage + ")");
      if (!detail::ParseInt(line.words[1], &p.mass_point) || p.mass_point < 0)
        Fail(line.number, "expected a mass point index >= 0, got '" + line.words[1] + "' (" + kPointUsage + ")");
      p.position = {Number(line, 2, "x", kPointUsage), Number(line, 3, "y", kPointUsage)};
      p.weight = Weight(line, 4, kPointUsage);
    } else {
      if (line.words.size() < 5) Fail(line.number, std::string("expected 4 numbers (") + kSampleUsage + ")");
      p.lattice_coords = {Number(line, 1, "s", kSampleUsage), Number(line, 2, "t", kSampleUsage)};
      for (int i = 0; i < 2; ++i)
        if (p.lattice_coords[i] < -1e-9 || p.lattice_coords[i] > 1 + 1e-9)
          Fail(line.number, std::string("lattice coordinate ") + (i ? "t" : "s") + " must be in [0, 1], got " +
                                line.words[1 + i]);
      p.position = {Number(line, 3, "x", kSampleUsage), Number(line, 4, "y", kSampleUsage)};
      p.weight = Weight(line, 5, kSampleUsage);
    }
    if (out_.frames.empty()) {
      out_.points.push_back(p);
    } else {
      out_.frames.back().points.push_back(p);
    }
  }

  void CurveAllowed(const Line& line) const {
    if (!out_.frames.empty()) Fail(line.number, "polyline/cloud lines are not allowed in a trajectory (frame) file");
    if (out_.has_correspondences())
      Fail(line.number, "a file holds correspondences (point/sample) or a curve (polyline/cloud), not both");
  }

  void PolylineLine(const Line& line) {
    CurveAllowed(line);
    TargetCurve c;
    size_t n = line.words.size();
    if (n > 1 && line.words.back() == "closed") {
      c.closed = true;
      --n;
    }
    if ((n - 1) % 2 != 0) Fail(line.number, std::string("expected pairs of numbers (") + kPolylineUsage + ")");
    for (size_t i = 1; i + 1 < n; i += 2)
      c.points.push_back({Number(line, i, "x", kPolylineUsage), Number(line, i + 1, "y", kPolylineUsage)});
    if (c.points.size() < 2) Fail(line.number, std::string("a polyline needs at least 2 points (") + kPolylineUsage + ")");
    out_.polylines.push_back(std::move(c));
  }

  void FrameLine(const Line& line) {
    if (out_.has_curve()) Fail(line.number, "frame lines are not allowed in a curve (polyline/cloud) file");
    if (out_.has_correspondences())
      Fail(line.number, "point/sample lines before the first frame (" + std::string(kFrameUsage) +
                            " must come first in a trajectory file)");
    if (line.words.size() != 2) Fail(line.number, std::string("expected one number (") + kFrameUsage + ")");
    TargetFrame f;
    f.time = Number(line, 1, "the time", kFrameUsage);
    f.line = line.number;
    if (!out_.frames.empty() && !(f.time > out_.frames.back().time))
      Fail(line.number, "frame times must strictly increase (previous frame: " +
                            detail::FormatNumber(out_.frames.back().time) + ")");
    out_.frames.push_back(f);
  }

  TargetFile out_;
};

}  // namespace

TargetFile ParseTargets(std::istream& in, const std::string& name_for_errors) {
  return TargetParser(name_for_errors).Parse(in);
}

TargetFile ReadTargetFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseTargets(in, path); });
}

void CheckMassPointIndices(const TargetFile& targets, int num_points) {
  auto check = [&](const PointTarget& p) {
    if (p.mass_point >= num_points)
      throw ParseError(targets.file, p.line,
                       "mass point " + std::to_string(p.mass_point) + " does not exist: the body has " +
                           std::to_string(num_points) + " (numbered from 0)");
  };
  for (const PointTarget& p : targets.points) check(p);
  for (const TargetFrame& f : targets.frames)
    for (const PointTarget& p : f.points) check(p);
}

}  // namespace wobble::formats
