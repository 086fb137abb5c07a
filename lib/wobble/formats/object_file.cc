#include "wobble/formats/object_file.h"

#include <filesystem>
#include <optional>
#include <stdexcept>

#include "wobble/core/errors.h"
#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

using detail::FormatNumber;
using detail::Line;

constexpr double kInsideTolerance = 1e-9;

const char* const kNameUsage = "name <word>";
const char* const kMeshUsage = "mesh <file: .obj .stl .ply .vtp>";
const char* const kFitUsage = "lattice fit [<num_s> <num_t> <num_u> [bernstein|bspline]] [margin <f>]";
const char* const kSampleUsage = "sample surface|volume <points> <total mass>";
constexpr double kDefaultFitMargin = 0.05;

// The statements' forms in 2D and in 3D (a 3D file starts with 'dimension 3').
template <int Dim> struct Usage;
template <> struct Usage<2> {
  static constexpr const char* lattice = "lattice <x0> <y0> <width> <height> [<num_s> <num_t> [bernstein|bspline]]";
  static constexpr const char* mass = "mass <x> <y> <m>";
  static constexpr const char* polyline = "polyline <x1> <y1> <x2> <y2> ... [closed]";
};
template <> struct Usage<3> {
  static constexpr const char* lattice =
      "lattice <x0> <y0> <z0> <width> <height> <depth> [<num_s> <num_t> <num_u> [bernstein|bspline]]";
  static constexpr const char* mass = "mass <x> <y> <z> <m>";
  static constexpr const char* polyline = "polyline <x1> <y1> <z1> <x2> <y2> <z2> ... [closed]";
};

constexpr const char* kAxisNames[] = {"x", "y", "z"};
constexpr const char* kSizeNames[] = {"width", "height", "depth"};
constexpr const char* kCountNames[] = {"num_s", "num_t", "num_u"};
constexpr const char* kCoordNames[] = {"s", "t", "u"};

template <int Dim> class ObjectParser {
  using Point = Eigen::Matrix<double, Dim, 1>;
  static constexpr const char* kLatticeUsage = Usage<Dim>::lattice;
  static constexpr const char* kMassUsage = Usage<Dim>::mass;
  static constexpr const char* kPolylineUsage = Usage<Dim>::polyline;

 public:
  ObjectParser(const std::string& file, const MeshReader& read_mesh) : file_(file), read_mesh_(read_mesh) {}

  BodyDefN<Dim> Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, file_);
    if (lines.empty()) Fail(0, "file is empty: expected a 'lattice' line and at least one 'mass' line");
    const bool declared = lines.front().words[0] == "dimension";
    if (declared) Dimension(lines.front());
    if (Dim == 3 && !declared)
      Fail(lines.front().number, "a 3D object file starts with 'dimension 3' (got '" + lines.front().words[0] + "')");
    for (size_t i = declared ? 1 : 0; i < lines.size(); ++i) Statement(lines[i]);

    if constexpr (Dim == 3) FromMesh();
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

  void Dimension(const Line& line) {
    int dim = 0;
    if (line.words.size() != 2 || !detail::ParseInt(line.words[1], &dim) || (dim != 2 && dim != 3))
      Fail(line.number, "expected 'dimension 2' or 'dimension 3'");
    if (dim != Dim)
      Fail(line.number, "this is a " + std::to_string(dim) + "D object file; a " + std::to_string(Dim) +
                            "D body was expected here");
  }

  void Statement(const Line& line) {
    const std::string& keyword = line.words[0];
    if (keyword == "dimension") {
      Fail(line.number, "'dimension' must be the first statement of the file");
    } else if (keyword == "name") {
      Name(line);
    } else if (keyword == "lattice" && line.words.size() > 1 && line.words[1] == "fit") {
      if constexpr (Dim == 3) LatticeFit(line);
      else Fail(line.number, "'lattice fit' is for 3D object files, around their mesh");
    } else if (keyword == "lattice") {
      LatticeLine(line);
    } else if (keyword == "mass") {
      Mass(line);
    } else if (keyword == "polyline") {
      PolylineLine(line);
    } else if (keyword == "mesh" || keyword == "sample") {
      if constexpr (Dim == 3) keyword == "mesh" ? MeshLine(line) : Sample(line);
      else Fail(line.number, "'" + keyword + "' is for 3D object files (start the file with 'dimension 3')");
    } else {
      Fail(line.number, "unknown keyword '" + keyword + "' (expected name, lattice, mass" +
                            (Dim == 3 ? ", polyline, mesh or sample)" : " or polyline)"));
    }
  }

  // ---- 3D: a user's mesh, the lattice fitted around it and mass points sampled from it ----
  void MeshLine(const Line& line) {
    if (mesh_line_ != 0) Fail(line.number, "mesh given twice (first on line " + std::to_string(mesh_line_) + ")");
    if (line.words.size() != 2) Fail(line.number, std::string("expected one file name after 'mesh' (") + kMeshUsage + ")");
    if (!read_mesh_)
      Fail(line.number, "mesh: this reader cannot read mesh files (VTK reads them: load the object with the wobble "
                        "command or pipelines::ReadObject<3>)");
    // relative to the object file's folder, as a user expects of a file beside it
    std::filesystem::path mesh_path(line.words[1]);
    if (mesh_path.is_relative()) mesh_path = std::filesystem::path(file_).parent_path() / mesh_path;
    try {
      def_.mesh = read_mesh_(mesh_path.string());
      CheckSurfaceMesh(def_.mesh);
    } catch (const ParseError& e) {
      Fail(line.number, std::string("mesh: ") + e.what());
    } catch (const std::exception& e) {
      Fail(line.number, "mesh " + mesh_path.string() + ": " + e.what());
    }
    mesh_line_ = line.number;
  }

  void LatticeFit(const Line& line) {
    if (lattice_line_ != 0)
      Fail(line.number, "lattice given twice (first on line " + std::to_string(lattice_line_) + ")");
    std::vector<std::string> w(line.words.begin() + 2, line.words.end());
    if (w.size() >= 2 && w[w.size() - 2] == "margin") {
      if (!detail::ParseNumber(w.back(), &fit_margin_) || fit_margin_ < 0 || fit_margin_ > 10)
        Fail(line.number, "expected a margin in [0, 10] (a fraction of the mesh's largest side), got '" + w.back() +
                              "' (" + kFitUsage + ")");
      w.resize(w.size() - 2);
    }
    if (!w.empty() && w.size() != 3 && w.size() != 4)
      Fail(line.number, std::string("expected 3 control-point counts (and a basis) after 'lattice fit' (") + kFitUsage + ")");
    for (size_t a = 0; a < w.size() && a < 3; ++a)
      if (!detail::ParseInt(w[a], &fit_sizes_[a]) || fit_sizes_[a] < 2)
        Fail(line.number, std::string("expected a whole number >= 2 for <") + kCountNames[a] + ">, got '" + w[a] + "' (" +
                              kFitUsage + ")");
    if (w.size() == 4 && !ParseBasisKind(w[3], &fit_basis_))
      Fail(line.number, "unknown lattice basis '" + w[3] + "' (expected bernstein or bspline)");
    lattice_line_ = fit_line_ = line.number;
  }

  void Sample(const Line& line) {
    if (line.words.size() != 4 || (line.words[1] != "surface" && line.words[1] != "volume"))
      Fail(line.number, std::string("expected 'sample surface' or 'sample volume', a point count and a total mass (") +
                            kSampleUsage + ")");
    int count = 0;
    double mass = 0;
    if (!detail::ParseInt(line.words[2], &count) || count < 1 || count > kMaxSampledPoints)
      Fail(line.number, "expected a point count 1.." + std::to_string(kMaxSampledPoints) + ", got '" + line.words[2] +
                            "' (" + kSampleUsage + ")");
    if (!detail::ParseNumber(line.words[3], &mass) || !(mass > 0) || mass > 1e30)
      Fail(line.number, "expected a total mass > 0 (and at most 1e30), got '" + line.words[3] + "' (" + kSampleUsage + ")");
    samples_.push_back({line.number, line.words[1] == "volume", count, mass});
  }

  // After every line: the fitted lattice and the sampled mass points (they need the mesh).
  void FromMesh() {
    if (mesh_line_ == 0) {
      const int needs = fit_line_ != 0 ? fit_line_ : (samples_.empty() ? 0 : samples_.front().line);
      if (needs != 0) Fail(needs, "there is no mesh to fit or sample (add a 'mesh' line: " + std::string(kMeshUsage) + ")");
      return;
    }
    if (!lattice_) {  // 'lattice fit', or no lattice line at all: fitted around the mesh
      try {
        lattice_ = FitLattice(def_.mesh, fit_sizes_, fit_basis_, fit_margin_);
      } catch (const std::exception& e) {
        Fail(fit_line_ != 0 ? fit_line_ : mesh_line_, std::string("cannot fit a lattice around the mesh: ") + e.what());
      }
      if (lattice_line_ == 0) lattice_line_ = mesh_line_;
    } else {
      for (size_t v = 0; v < def_.mesh.points.size(); ++v) {
        const Point u = lattice_->LocalCoords(def_.mesh.points[v]);
        if ((u.array() < -kInsideTolerance).any() || (u.array() > 1 + kInsideTolerance).any())
          Fail(mesh_line_, "mesh point " + std::to_string(v) + " lies outside the lattice on line " +
                               std::to_string(lattice_line_) + " (use 'lattice fit' to fit one around the mesh)");
      }
    }
    for (const SampleSpec& spec : samples_) {
      std::vector<Eigen::Vector3d> points;
      try {
        points = spec.volume ? SampleVolume(def_.mesh, spec.count) : SampleSurface(def_.mesh, spec.count);
      } catch (const std::exception& e) {
        Fail(spec.line, std::string("sample: ") + e.what());
      }
      if (def_.masses.size() + points.size() > size_t(kMaxSampledPoints))
        Fail(spec.line, "more than " + std::to_string(kMaxSampledPoints) + " mass points in all");
      for (const Eigen::Vector3d& p : points) {
        def_.mass_positions.push_back(p);
        def_.masses.push_back(spec.mass / double(points.size()));
        mass_lines_.push_back(spec.line);
      }
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
    const size_t with_counts = 3 * Dim;  // origin, sizes, counts
    if (n != 2 * Dim && n != with_counts && n != with_counts + 1)
      Fail(line.number, "expected " + std::to_string(2 * Dim) + ", " + std::to_string(with_counts) + " or " +
                            std::to_string(with_counts + 1) + " values after 'lattice', got " + std::to_string(n) +
                            " (" + kLatticeUsage + ")");
    Point origin;
    typename LatticeN<Dim>::Axes axes;
    for (int a = 0; a < Dim; ++a)
      origin[a] = Number(line, 1 + a, std::string("<") + kAxisNames[a] + "0>", kLatticeUsage);
    for (int a = 0; a < Dim; ++a) {
      const double size = Number(line, 1 + Dim + a, std::string("<") + kSizeNames[a] + ">", kLatticeUsage);
      if (!(size > 0))
        Fail(line.number, std::string("lattice <") + kSizeNames[a] + "> must be > 0, got " + line.words[1 + Dim + a]);
      axes[a] = Point::Unit(a) * size;
    }
    typename LatticeN<Dim>::Sizes counts;
    counts.fill(4);
    BasisKind basis = BasisKind::kBernstein;
    if (n >= with_counts)
      for (int a = 0; a < Dim; ++a) counts[a] = Count(line, 1 + 2 * Dim + a, std::string("<") + kCountNames[a] + ">");
    if (n == with_counts + 1 && !ParseBasisKind(line.words[n], &basis))
      Fail(line.number, "unknown lattice basis '" + line.words[n] + "' (expected bernstein or bspline)");
    try {
      lattice_.emplace(origin, axes, counts, basis);
    } catch (const std::invalid_argument& e) {
      Fail(line.number, std::string("bad lattice: ") + e.what());
    }
    lattice_line_ = line.number;
  }

  void Mass(const Line& line) {
    if (line.words.size() != Dim + 2)
      Fail(line.number, "expected " + std::to_string(Dim + 1) + " numbers after 'mass', got " +
                            std::to_string(line.words.size() - 1) + " (" + kMassUsage + ")");
    Point p;
    for (int a = 0; a < Dim; ++a) p[a] = Number(line, 1 + a, std::string("<") + kAxisNames[a] + ">", kMassUsage);
    const double m = Number(line, Dim + 1, "<m>", kMassUsage);
    if (!(m > 0)) Fail(line.number, "mass <m> must be > 0, got " + line.words[Dim + 1]);
    def_.mass_positions.push_back(p);
    def_.masses.push_back(m);
    mass_lines_.push_back(line.number);
  }

  void PolylineLine(const Line& line) {
    PolylineN<Dim> poly;
    size_t end = line.words.size();
    if (end > 1 && line.words[end - 1] == "closed") {
      poly.closed = true;
      --end;
    }
    const size_t n = end - 1;
    for (size_t w = 1; w < end; ++w) {
      double value = 0;
      if (!detail::ParseNumber(line.words[w], &value)) {
        const std::string what = std::string("<") + kAxisNames[(w - 1) % Dim] + std::to_string((w - 1) / Dim + 1) + ">";
        Fail(line.number, "expected a number for " + what + ", got '" + line.words[w] +
                              "' (only the last word may be 'closed'; " + kPolylineUsage + ")");
      }
    }
    if (n % Dim != 0)
      Fail(line.number, Dim == 2 ? "polyline has an odd number of coordinates (" + std::to_string(n) +
                                       "); expected x y pairs (" + kPolylineUsage + ")"
                                 : "polyline has " + std::to_string(n) +
                                       " coordinates, not a multiple of 3; expected x y z triples (" +
                                       kPolylineUsage + ")");
    if (n < 2 * Dim)
      Fail(line.number, "polyline needs at least 2 points, got " + std::to_string(n / Dim) + " (" + kPolylineUsage + ")");
    for (size_t w = 1; w < end; w += Dim) {
      Point p;
      for (int a = 0; a < Dim; ++a) detail::ParseNumber(line.words[w + a], &p[a]);
      poly.points.push_back(p);
    }
    def_.shapes.push_back(std::move(poly));
  }

  void CheckInside(size_t k) const {
    const Point& p = def_.mass_positions[k];
    const Point u = lattice_->LocalCoords(p);
    bool inside = true;
    for (int a = 0; a < Dim; ++a) inside = inside && u[a] >= -kInsideTolerance && u[a] <= 1 + kInsideTolerance;
    if (inside) return;
    Point hi = lattice_->origin();
    for (int a = 0; a < Dim; ++a) hi += lattice_->axis(a);
    std::string where, coords, spans;
    for (int a = 0; a < Dim; ++a) {
      where += (a ? ", " : "") + FormatNumber(p[a]);
      coords += std::string(a ? ", " : "") + kCoordNames[a] + " = " + FormatNumber(u[a]);
      spans += std::string(a ? ", " : "") + kAxisNames[a] + " in [" + FormatNumber(lattice_->origin()[a]) + ", " +
               FormatNumber(hi[a]) + "]";
    }
    Fail(mass_lines_[k], "mass point (" + where + ") lies outside the lattice (" + coords + "; the lattice on line " +
                             std::to_string(lattice_line_) + " spans " + spans + ")");
  }

  struct SampleSpec {
    int line = 0;
    bool volume = false;
    int count = 0;
    double mass = 0;
  };

  const std::string& file_;
  const MeshReader& read_mesh_;
  BodyDefN<Dim> def_;
  int mesh_line_ = 0, fit_line_ = 0;
  std::array<int, 3> fit_sizes_{4, 4, 4};
  BasisKind fit_basis_ = BasisKind::kBernstein;
  double fit_margin_ = kDefaultFitMargin;
  std::vector<SampleSpec> samples_;
  std::optional<LatticeN<Dim>> lattice_;
  int name_line_ = 0, lattice_line_ = 0;
  std::vector<int> mass_lines_;
};

}  // namespace

template <int Dim>
BodyDefN<Dim> ParseObject(std::istream& in, const std::string& name_for_errors, const MeshReader& read_mesh) {
  return ObjectParser<Dim>(name_for_errors, read_mesh).Parse(in);
}

template <int Dim> BodyDefN<Dim> ReadObjectFile(const std::string& path, const MeshReader& read_mesh) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseObject<Dim>(in, path, read_mesh); });
}

template BodyDefN<2> ParseObject<2>(std::istream&, const std::string&, const MeshReader&);
template BodyDefN<3> ParseObject<3>(std::istream&, const std::string&, const MeshReader&);
template BodyDefN<2> ReadObjectFile<2>(const std::string&, const MeshReader&);
template BodyDefN<3> ReadObjectFile<3>(const std::string&, const MeshReader&);

int ObjectFileDimension(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, path);
    int dim = 2;
    if (!lines.empty() && lines.front().words[0] == "dimension" && lines.front().words.size() == 2 &&
        detail::ParseInt(lines.front().words[1], &dim) && dim == 3)
      return 3;
    return 2;
  });
}

}  // namespace wobble::formats
