#include "wobble/formats/object_file.h"

#include <optional>
#include <stdexcept>

#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

using detail::FormatNumber;
using detail::Line;

constexpr double kInsideTolerance = 1e-9;

const char* const kLatticeUsage = "lattice <x0> <y0> <width> <height> [<num_s> <num_t> [bernstein|bspline]]";
const char* const kMassUsage = "mass <x> <y> <m>";
const char* const kPolylineUsage = "polyline <x1> <y1> <x2> <y2> ... [closed]";
const char* const kNameUsage = "name <word>";

class ObjectParser {
 public:
  explicit ObjectParser(const std::string& file) : file_(file) {}

  BodyDef Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, file_);
    if (lines.empty()) Fail(0, "file is empty: expected a 'lattice' line and at least one 'mass' line");
    for (const Line& line : lines) Statement(line);

    if (!lattice_) Fail(0, std::string("missing 'lattice' line (") + kLatticeUsage + ")");
    if (def_.masses.empty()) Fail(0, std::string("no 'mass' lines: a body needs at least one mass point (") + kMassUsage + ")");
    def_.lattice = *lattice_;
    for (size_t k = 0; k < def_.masses.size(); ++k) CheckInside(k);
    if (def_.name.empty()) def_.name = detail::FileStem(file_, "body");
    return std::move(def_);
  }

 private:
  [[noreturn]] void Fail(int line, const std::string& message) const { throw ParseError(file_, line, message); }

  double Number(const Line& line, size_t index, const std::string& what, const char* usage) const {
    double value = 0;
    if (!detail::ParseNumber(line.words[index], &value))
      Fail(line.number, "expected a number for " + what + ", got '" + line.words[index] + "' (" + usage + ")");
    return value;
  }

  int Count(const Line& line, size_t index, const std::string& what) const {
    int value = 0;
    if (!detail::ParseInt(line.words[index], &value) || value < 2)
      Fail(line.number, "expected a whole number >= 2 for " + what + ", got '" + line.words[index] + "' (" +
                            kLatticeUsage + ")");
    return value;
  }

  void Statement(const Line& line) {
    const std::string& keyword = line.words[0];
    if (keyword == "name") {
      Name(line);
    } else if (keyword == "lattice") {
      LatticeLine(line);
    } else if (keyword == "mass") {
      Mass(line);
    } else if (keyword == "polyline") {
      PolylineLine(line);
    } else {
      Fail(line.number, "unknown keyword '" + keyword + "' (expected name, lattice, mass or polyline)");
    }
  }

  void Name(const Line& line) {
    if (name_line_ != 0) Fail(line.number, "name given twice (first on line " + std::to_string(name_line_) + ")");
    if (line.words.size() != 2)
      Fail(line.number, "expected exactly one word after 'name', got " + std::to_string(line.words.size() - 1) +
                            " (" + kNameUsage + ")");
    name_line_ = line.number;
    def_.name = line.words[1];
  }

  void LatticeLine(const Line& line) {
    if (lattice_line_ != 0)
      Fail(line.number, "lattice given twice (first on line " + std::to_string(lattice_line_) + ")");
    const size_t n = line.words.size() - 1;
    if (n != 4 && n != 6 && n != 7)
      Fail(line.number, "expected 4, 6 or 7 values after 'lattice', got " + std::to_string(n) + " (" + kLatticeUsage + ")");
    const double x0 = Number(line, 1, "<x0>", kLatticeUsage);
    const double y0 = Number(line, 2, "<y0>", kLatticeUsage);
    const double width = Number(line, 3, "<width>", kLatticeUsage);
    const double height = Number(line, 4, "<height>", kLatticeUsage);
    if (!(width > 0)) Fail(line.number, "lattice <width> must be > 0, got " + line.words[3]);
    if (!(height > 0)) Fail(line.number, "lattice <height> must be > 0, got " + line.words[4]);
    int num_s = 4, num_t = 4;
    BasisKind basis = BasisKind::kBernstein;
    if (n >= 6) {
      num_s = Count(line, 5, "<num_s>");
      num_t = Count(line, 6, "<num_t>");
    }
    if (n == 7 && !ParseBasisKind(line.words[7], &basis))
      Fail(line.number, "unknown lattice basis '" + line.words[7] + "' (expected bernstein or bspline)");
    try {
      lattice_.emplace(Eigen::Vector2d(x0, y0), Eigen::Vector2d(width, 0), Eigen::Vector2d(0, height), num_s, num_t,
                       basis);
    } catch (const std::invalid_argument& e) {
      Fail(line.number, std::string("bad lattice: ") + e.what());
    }
    lattice_line_ = line.number;
  }

  void Mass(const Line& line) {
    if (line.words.size() != 4)
      Fail(line.number, "expected 3 numbers after 'mass', got " + std::to_string(line.words.size() - 1) + " (" +
                            kMassUsage + ")");
    const double x = Number(line, 1, "<x>", kMassUsage);
    const double y = Number(line, 2, "<y>", kMassUsage);
    const double m = Number(line, 3, "<m>", kMassUsage);
    if (!(m > 0)) Fail(line.number, "mass <m> must be > 0, got " + line.words[3]);
    def_.mass_positions.emplace_back(x, y);
    def_.masses.push_back(m);
    mass_lines_.push_back(line.number);
  }

  void PolylineLine(const Line& line) {
    Polyline poly;
    size_t end = line.words.size();
    if (end > 1 && line.words[end - 1] == "closed") {
      poly.closed = true;
      --end;
    }
    const size_t n = end - 1;
    for (size_t w = 1; w < end; ++w) {
      double value = 0;
      if (!detail::ParseNumber(line.words[w], &value)) {
        const std::string what = std::string(w % 2 == 1 ? "<x" : "<y") + std::to_string((w + 1) / 2) + ">";
        Fail(line.number, "expected a number for " + what + ", got '" + line.words[w] +
                              "' (only the last word may be 'closed'; " + kPolylineUsage + ")");
      }
    }
    if (n % 2 != 0)
      Fail(line.number, "polyline has an odd number of coordinates (" + std::to_string(n) + "); expected x y pairs (" +
                            kPolylineUsage + ")");
    if (n < 4)
      Fail(line.number, "polyline needs at least 2 points, got " + std::to_string(n / 2) + " (" + kPolylineUsage + ")");
    for (size_t w = 1; w < end; w += 2) {
      double x = 0, y = 0;
      detail::ParseNumber(line.words[w], &x);
      detail::ParseNumber(line.words[w + 1], &y);
      poly.points.emplace_back(x, y);
    }
    def_.shapes.push_back(std::move(poly));
  }

  void CheckInside(size_t k) const {
    const Eigen::Vector2d& p = def_.mass_positions[k];
    const Eigen::Vector2d st = lattice_->LocalCoords(p);
    const bool inside = st.x() >= -kInsideTolerance && st.x() <= 1 + kInsideTolerance &&
                        st.y() >= -kInsideTolerance && st.y() <= 1 + kInsideTolerance;
    if (inside) return;
    const Eigen::Vector2d lo = lattice_->origin(), hi = lo + lattice_->axis_s() + lattice_->axis_t();
    Fail(mass_lines_[k], "mass point (" + FormatNumber(p.x()) + ", " + FormatNumber(p.y()) +
                             ") lies outside the lattice (s = " + FormatNumber(st.x()) + ", t = " +
                             FormatNumber(st.y()) + "; the lattice on line " + std::to_string(lattice_line_) +
                             " spans x in [" + FormatNumber(lo.x()) + ", " + FormatNumber(hi.x()) + "], y in [" +
                             FormatNumber(lo.y()) + ", " + FormatNumber(hi.y()) + "])");
  }

  const std::string& file_;
  BodyDef def_;
  std::optional<Lattice> lattice_;
  int name_line_ = 0, lattice_line_ = 0;
  std::vector<int> mass_lines_;
};

}  // namespace

BodyDef ParseObject(std::istream& in, const std::string& name_for_errors) {
  return ObjectParser(name_for_errors).Parse(in);
}

BodyDef ReadObjectFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseObject(in, path); });
}

}  // namespace wobble::formats
