#include "wobble/formats/target_file.h"

#include <filesystem>

#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

using detail::Line;

// The statements' forms in 2D and 3D.
template <int Dim> struct Usage;
template <> struct Usage<2> {
  static constexpr const char* point = "point <k> <x> <y> [weight <w>]";
  static constexpr const char* sample = "sample <s> <t> <x> <y> [weight <w>]";
  static constexpr const char* cloud = "cloud <x> <y>";
  static constexpr const char* keywords = "point, sample, polyline, cloud or frame";
  static constexpr const char* curve = "a curve (polyline/cloud)";
};
template <> struct Usage<3> {
  static constexpr const char* point = "point <k> <x> <y> <z> [weight <w>]";
  static constexpr const char* sample = "sample <s> <t> <u> <x> <y> <z> [weight <w>]";
  static constexpr const char* cloud = "cloud <x> <y> <z>";
  static constexpr const char* keywords = "point, sample, cloud, mesh or frame";
  static constexpr const char* curve = "a surface (mesh/cloud)";
};
const char* const kPolylineUsage = "polyline <x1> <y1> <x2> <y2> ... [closed]";
const char* const kMeshUsage = "mesh <FILE>";
const char* const kFrameUsage = "frame <time>";
const char* const kAxes[] = {"x", "y", "z"};
const char* const kLatticeAxes[] = {"s", "t", "u"};

template <int Dim> class TargetParser {
 public:
  using Vec = Eigen::Matrix<double, Dim, 1>;
  using Use = Usage<Dim>;
  TargetParser(const std::string& file, const MeshReader& read_mesh) : read_mesh_(read_mesh) { out_.file = file; }

  TargetFileN<Dim> Parse(std::istream& in) {
    std::vector<Line> lines = detail::ReadLines(in, out_.file);
    if (lines.empty())
      Fail(0, std::string("file is empty: expected ") + (Dim == 3 ? "'dimension 3' and " : "") + Use::keywords + " lines");
    const bool declared = lines.front().words[0] == "dimension";
    if (Dim == 3 && !declared)
      Fail(lines.front().number, "the object is 3D: its target file starts with 'dimension 3' (got '" +
                                     lines.front().words[0] + "')");
    if (declared) {
      const Line& first = lines.front();
      int dim = 0;
      if (first.words.size() != 2 || !detail::ParseInt(first.words[1], &dim) || (dim != 2 && dim != 3))
        Fail(first.number, "expected 'dimension 2' or 'dimension 3'");
      if (dim != Dim)
        Fail(first.number, std::string("a ") + std::to_string(dim) + "D target file for a " + std::to_string(Dim) +
                               "D object");
      lines.erase(lines.begin());
      if (lines.empty()) Fail(first.number, std::string("expected ") + Use::keywords + " lines after 'dimension'");
    }
    for (const Line& line : lines) Statement(line);
    for (const TargetFrameN<Dim>& f : out_.frames)
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
    } else if (keyword == "polyline" && Dim == 2) {
      PolylineLine(line);
    } else if (keyword == "mesh" && Dim == 3) {
      MeshLine(line);
    } else if (keyword == "cloud") {
      CurveAllowed(line);
      if (int(line.words.size()) != 1 + Dim)
        Fail(line.number, "expected " + std::to_string(Dim) + " numbers (" + Use::cloud + ")");
      out_.cloud.push_back(Numbers(line, 1, kAxes, Use::cloud));
    } else if (keyword == "frame") {
      FrameLine(line);
    } else if (keyword == "dimension") {
      Fail(line.number, "'dimension' must be the first statement of the file");
    } else if (keyword == "polyline" || keyword == "mesh") {
      Fail(line.number, "'" + keyword + "' is for " + (Dim == 2 ? "3D" : "2D") + " target files (expected " +
                            Use::keywords + ")");
    } else {
      Fail(line.number, "unknown keyword '" + keyword + "' (expected " + Use::keywords + ")");
    }
  }

  // Dim numbers at words[first..], named by `names`.
  Vec Numbers(const Line& line, size_t first, const char* const* names, const char* usage) const {
    Vec v;
    for (int i = 0; i < Dim; ++i) v[i] = Number(line, first + i, names[i], usage);
    return v;
  }

  void Correspondence(const Line& line, bool is_point) {
    if (out_.has_curve())
      Fail(line.number, std::string("a file holds correspondences (point/sample) or ") + Use::curve + ", not both");
    PointTargetN<Dim> p;
    p.line = line.number;
    if (is_point) {
      if (int(line.words.size()) < 2 + Dim)
        Fail(line.number, "expected " + std::to_string(1 + Dim) + " numbers (" + Use::point + ")");
      if (!detail::ParseInt(line.words[1], &p.mass_point) || p.mass_point < 0)
        Fail(line.number, "expected a mass point index >= 0, got '" + line.words[1] + "' (" + Use::point + ")");
      p.position = Numbers(line, 2, kAxes, Use::point);
      p.weight = Weight(line, 2 + Dim, Use::point);
    } else {
      if (int(line.words.size()) < 1 + 2 * Dim)
        Fail(line.number, "expected " + std::to_string(2 * Dim) + " numbers (" + Use::sample + ")");
      p.lattice_coords = Numbers(line, 1, kLatticeAxes, Use::sample);
      for (int i = 0; i < Dim; ++i)
        if (p.lattice_coords[i] < -1e-9 || p.lattice_coords[i] > 1 + 1e-9)
          Fail(line.number, std::string("lattice coordinate ") + kLatticeAxes[i] + " must be in [0, 1], got " +
                                line.words[1 + i]);
      p.position = Numbers(line, 1 + Dim, kAxes, Use::sample);
      p.weight = Weight(line, 1 + 2 * Dim, Use::sample);
    }
    if (out_.frames.empty()) {
      out_.points.push_back(p);
    } else {
      out_.frames.back().points.push_back(p);
    }
  }

  void CurveAllowed(const Line& line) const {
    if (!out_.frames.empty())
      Fail(line.number, std::string(Dim == 2 ? "polyline/cloud" : "mesh/cloud") +
                            " lines are not allowed in a trajectory (frame) file");
    if (out_.has_correspondences())
      Fail(line.number, std::string("a file holds correspondences (point/sample) or ") + Use::curve + ", not both");
  }

  void MeshLine(const Line& line) {
    CurveAllowed(line);
    if (mesh_line_ != 0) Fail(line.number, "mesh given twice (first on line " + std::to_string(mesh_line_) + ")");
    if (line.words.size() != 2) Fail(line.number, std::string("expected one file name after 'mesh' (") + kMeshUsage + ")");
    if (!read_mesh_) Fail(line.number, "mesh: this reader cannot read mesh files (the wobble command reads them with VTK)");
    // relative to the target file's folder, as the object file's mesh
    std::filesystem::path path(line.words[1]);
    if (path.is_relative()) path = std::filesystem::path(out_.file).parent_path() / path;
    try {
      out_.mesh = read_mesh_(path.string());
      CheckSurfaceMesh(out_.mesh);
    } catch (const ParseError& e) {
      Fail(line.number, std::string("mesh: ") + e.what());
    } catch (const std::exception& e) {
      Fail(line.number, "mesh " + path.string() + ": " + e.what());
    }
    mesh_line_ = line.number;
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
    if (out_.has_curve()) Fail(line.number, std::string("frame lines are not allowed in ") + Use::curve + " file");
    if (out_.has_correspondences())
      Fail(line.number, "point/sample lines before the first frame (" + std::string(kFrameUsage) +
                            " must come first in a trajectory file)");
    if (line.words.size() != 2) Fail(line.number, std::string("expected one number (") + kFrameUsage + ")");
    TargetFrameN<Dim> f;
    f.time = Number(line, 1, "the time", kFrameUsage);
    f.line = line.number;
    if (!out_.frames.empty() && !(f.time > out_.frames.back().time))
      Fail(line.number, "frame times must strictly increase (previous frame: " +
                            detail::FormatNumber(out_.frames.back().time) + ")");
    out_.frames.push_back(f);
  }

  TargetFileN<Dim> out_;
  MeshReader read_mesh_;
  int mesh_line_ = 0;
};

}  // namespace

template <int Dim>
TargetFileN<Dim> ParseTargets(std::istream& in, const std::string& name_for_errors, const MeshReader& read_mesh) {
  return TargetParser<Dim>(name_for_errors, read_mesh).Parse(in);
}

template <int Dim> TargetFileN<Dim> ReadTargetFile(const std::string& path, const MeshReader& read_mesh) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseTargets<Dim>(in, path, read_mesh); });
}

template TargetFileN<2> ParseTargets<2>(std::istream&, const std::string&, const MeshReader&);
template TargetFileN<3> ParseTargets<3>(std::istream&, const std::string&, const MeshReader&);
template TargetFileN<2> ReadTargetFile<2>(const std::string&, const MeshReader&);
template TargetFileN<3> ReadTargetFile<3>(const std::string&, const MeshReader&);

template <int Dim> void CheckMassPointIndices(const TargetFileN<Dim>& targets, int num_points) {
  auto check = [&](const PointTargetN<Dim>& p) {
    if (p.mass_point >= num_points)
      throw ParseError(targets.file, p.line,
                       "mass point " + std::to_string(p.mass_point) + " does not exist: the body has " +
                           std::to_string(num_points) + " (numbered from 0)");
  };
  for (const PointTargetN<Dim>& p : targets.points) check(p);
  for (const TargetFrameN<Dim>& f : targets.frames)
    for (const PointTargetN<Dim>& p : f.points) check(p);
}
template void CheckMassPointIndices(const TargetFileN<2>&, int);
template void CheckMassPointIndices(const TargetFileN<3>&, int);

}  // namespace wobble::formats
