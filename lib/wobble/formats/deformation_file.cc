#include "wobble/formats/deformation_file.h"

#include "wobble/formats/line_reader.h"

#include <Eigen/Geometry>
#include <cmath>

namespace wobble::formats {

namespace {

using detail::Line;

const char* const kHeaderUsage = "mode <name> [stiffness <K>] [damping <c>] [active|passive]";

std::string Rows(size_t n) { return std::to_string(n) + (n == 1 ? " row" : " rows"); }
bool StartsWith(const std::string& word, const char* prefix) { return word.rfind(prefix, 0) == 0; }
bool IsOption(const std::string& word) {
  return word == "stiffness" || word == "damping" || word == "active" || word == "passive";
}

[[noreturn]] void FailAt(const std::string& file, int line, const std::string& message) {
  throw ParseError(file, line, message);
}

// The options after 'mode <name>' (words from index 2), shared by the 2D and 3D formats.
void ReadModeOptions(const Line& line, const std::string& file, double* stiffness, double* damping, bool* active) {
  const std::vector<std::string>& w = line.words;
  bool seen_stiffness = false, seen_damping = false, seen_activity = false;
  for (size_t i = 2; i < w.size(); ++i) {
    const std::string& option = w[i];
    if (option == "stiffness" || option == "damping") {
      bool& seen = option == "stiffness" ? seen_stiffness : seen_damping;
      if (seen) FailAt(file, line.number, "'" + option + "' given twice");
      seen = true;
      double value = 0;
      if (i + 1 >= w.size()) FailAt(file, line.number, "expected a number after '" + option + "' (" + kHeaderUsage + ")");
      if (!detail::ParseNumber(w[i + 1], &value))
        FailAt(file, line.number, "expected a number after '" + option + "', got '" + w[i + 1] + "' (" + kHeaderUsage + ")");
      if (value < 0) FailAt(file, line.number, option + " must be >= 0, got " + w[i + 1]);
      *(option == "stiffness" ? stiffness : damping) = value;
      ++i;
    } else if (option == "active" || option == "passive") {
      if (seen_activity) FailAt(file, line.number, "'active' / 'passive' given twice");
      seen_activity = true;
      *active = option == "active";
    } else {
      FailAt(file, line.number, "unknown mode option '" + option +
                                    "' (expected stiffness <K>, damping <c>, active or passive)");
    }
  }
}

int AxisIndex(const std::string& word) { return word == "x" ? 0 : word == "y" ? 1 : word == "z" ? 2 : -1; }
bool IsGenerator(const std::string& word) {
  return word == "bend" || word == "twist" || word == "squash" || word == "shear" || word == "taper" || word == "point";
}
// twist has no 2D form (deformation_file.h says why)
const char* GeneratorList(int dim) {
  return dim == 2 ? "bend, squash, shear, taper or point" : "bend, twist, squash, shear, taper or point";
}

// One x: or y: matrix as read: rows bottom (t = 0) to top.
struct Section {
  int line = 0;  // line of the "x:" / "y:" keyword
  std::vector<std::vector<double>> rows;
};

// A mode being read: a matrix (x: and y: sections, 2D) or generator lines over the lattice.
template <int Dim> struct PendingMode {
  int header_line = 0;  // 0: no header
  std::string name;
  double stiffness = 0, damping = 0;
  bool active = false;
  Section x, y;
  int generator_line = 0;  // first generator line; 0 for a matrix mode
  std::vector<Eigen::Matrix<double, Dim, 1>> generated;
};

// The one reader of deformation files, 2D and 3D (the grammar is in deformation_file.h). Line
// by line: the 'dimension' line, 'mode' headers, x:/y: matrices with their rows, generator lines.
template <int Dim> class ModeFileParser {
 public:
  using Point = Eigen::Matrix<double, Dim, 1>;
  using Mode = DeformationModeN<Dim>;

  // `lattice` may be null in 2D: matrix modes need none, generator lines are then refused.
  ModeFileParser(const std::string& file, const LatticeN<Dim>* lattice) : file_(file), lattice_(lattice) {
    if (lattice_) {
      rest_ = lattice->RestPoints();
      centre_ = lattice->origin();
      for (int a = 0; a < Dim; ++a) centre_ += 0.5 * lattice->axis(a);
    }
  }

  std::vector<Mode> Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, file_);
    if (lines.empty())
      Fail(0, Dim == 2 ? "file is empty: expected one or more modes, each an 'x:' and a 'y:' section or generator "
                         "lines, optionally after a '" + std::string(kHeaderUsage) + "' header"
                       : std::string("file is empty: expected 'dimension 3' and one or more modes"));
    const Line& head = lines.front();
    size_t first = 0;
    if (head.words[0] == "dimension") {
      const bool two = head.words.size() == 2 && head.words[1] == "2", three = head.words.size() == 2 && head.words[1] == "3";
      if (!two && !three) Fail(head.number, "expected 'dimension 2' or 'dimension 3'");
      if (two != (Dim == 2))
        Fail(head.number, two ? "this is a 2D deformation file; a 3D body was expected here"
                              : "this is a 3D deformation file; a 2D body was expected here");
      first = 1;
      if (lines.size() == 1) Fail(head.number, "no modes after 'dimension " + std::to_string(Dim) + "' (expected '" +
                                                   std::string(kHeaderUsage) + "')");
    } else if (Dim == 3) {
      // without the line a file is 2D, as the thesis' files are
      Fail(head.number, "a 3D deformation file starts with 'dimension 3' (got '" + head.words[0] +
                            "'; a file without it is 2D)");
    }
    for (size_t i = first; i < lines.size(); ++i) Process(lines[i]);
    Close("the end of the file", lines.back().number);
    return Build();
  }

 private:
  // kHeader: a 'mode' line, nothing after it yet; kX/kY: in a matrix section; kGenerators:
  // after one or more generator lines of the current mode.
  enum class State { kIdle, kHeader, kX, kY, kGenerators };

  [[noreturn]] void Fail(int line, const std::string& message) const { throw ParseError(file_, line, message); }

  PendingMode<Dim>& current() { return modes_.back(); }
  std::string Describe(const PendingMode<Dim>& mode) const {
    if (mode.header_line != 0) return "mode '" + mode.name + "'";
    return "mode #" + std::to_string(&mode - modes_.data() + 1);
  }
  std::string LatticeSize() const { return std::to_string(num_s_) + "x" + std::to_string(num_t_); }
  std::string FirstModeRef() const {
    return "fixed by the first mode, x: on line " + std::to_string(modes_[first_matrix_].x.line);
  }
  bool IsFirstMatrix() const { return first_matrix_ == modes_.size() - 1; }

  void Process(const Line& line) {
    const std::string& w0 = line.words[0];
    if (w0 == "mode") {
      // the mode this header ends is checked first: the earliest problem is the one reported
      Close("a 'mode' header", line.number);
      HeaderName(line);
      Header(line);
    } else if (w0 == "dimension") {
      Fail(line.number, "'dimension' must be the first line of the file");
    } else if (StartsWith(w0, "x:") || StartsWith(w0, "y:")) {
      if (Dim == 3)
        Fail(line.number, "'" + w0.substr(0, 2) + "' sections are for 2D files: a 3D mode is made of generator lines (" +
                              GeneratorList(3) + ")");
      if (w0[0] == 'x') {
        if (state_ != State::kHeader) {
          Close("another 'x:'", line.number);
          modes_.emplace_back();
        }
        if (first_matrix_ == kNone) first_matrix_ = modes_.size() - 1;
        current().x.line = line.number;
        state_ = State::kX;
        Row(line, /*keyword=*/true);
      } else {
        if (state_ == State::kY)
          Fail(line.number, "second 'y:' section for " + Describe(current()) + " (the first is on line " +
                                std::to_string(current().y.line) + ")");
        if (state_ != State::kX)
          Fail(line.number, "'y:' section before any 'x:' section" +
                                (state_ == State::kHeader ? " of " + Describe(current()) : std::string()));
        CloseX();
        current().y.line = line.number;
        state_ = State::kY;
        Row(line, /*keyword=*/true);
      }
    } else if (IsGenerator(w0)) {
      Generator(line);
    } else if (state_ == State::kX || state_ == State::kY) {
      Row(line, /*keyword=*/false);
    } else if (Dim == 3) {
      if (modes_.empty()) Fail(line.number, "'" + w0 + "' before the first '" + std::string(kHeaderUsage) + "' line");
      Fail(line.number, "unknown keyword '" + w0 + "' (expected mode, " + GeneratorList(3) + ")");
    } else {
      double value = 0;
      if (detail::ParseNumber(w0, &value))
        Fail(line.number, "numbers outside an x: or y: section: expected 'x:' or '" + std::string(kHeaderUsage) + "'");
      Fail(line.number, "unknown keyword '" + w0 + "' (expected 'mode', 'x:' or 'y:', or a generator: " +
                            GeneratorList(2) + ")");
    }
  }

  // Ends whatever is open because `what` was found on line `line`.
  void Close(const std::string& what, int line) {
    const std::string found = " (found " + what + " on line " + std::to_string(line) + ")";
    switch (state_) {
      case State::kIdle:
      case State::kGenerators:
        break;
      case State::kHeader:
        if (Dim == 3)
          Fail(current().header_line, Describe(current()) + " has no generator line" + found + " (expected " +
                                          GeneratorList(3) + ")");
        Fail(current().header_line, Describe(current()) + " has no 'x:' section and no generator line" + found);
      case State::kX:
        Fail(current().x.line, "'x:' section of " + Describe(current()) + " is not followed by a 'y:' section" + found);
      case State::kY: {
        const PendingMode<Dim>& mode = current();
        if (mode.y.rows.size() < mode.x.rows.size())
          Fail(mode.y.line, "'y:' section of " + Describe(mode) + " has " + Rows(mode.y.rows.size()) +
                                " but its 'x:' section (line " + std::to_string(mode.x.line) + ") has " +
                                Rows(mode.x.rows.size()) + "; y: must have the same shape as x:");
        break;
      }
    }
    state_ = State::kIdle;
  }

  void CloseX() {
    const PendingMode<Dim>& mode = current();
    const int rows = int(mode.x.rows.size());
    if (rows == 0) Fail(mode.x.line, "'x:' section of " + Describe(mode) + " has no rows");
    if (IsFirstMatrix()) {
      if (rows < 2)
        Fail(mode.x.line, "'x:' section has 1 row: a lattice needs at least 2 rows (one per lattice row, bottom to top)");
      num_t_ = rows;
    } else if (rows < num_t_) {
      Fail(mode.x.line, "'x:' section of " + Describe(mode) + " has " + Rows(size_t(rows)) +
                            " but the file's lattice is " + LatticeSize() + " (" + std::to_string(num_t_) +
                            " rows; " + FirstModeRef() + ")");
    }
  }

  void HeaderName(const Line& line) const {
    const std::vector<std::string>& w = line.words;
    if (w.size() < 2 || IsOption(w[1]) || StartsWith(w[1], "x:") || StartsWith(w[1], "y:"))
      Fail(line.number, "expected a mode name after 'mode'" + (w.size() < 2 ? std::string() : ", got '" + w[1] + "'") +
                            " (" + kHeaderUsage + ")");
    for (const PendingMode<Dim>& other : modes_)
      if (other.header_line != 0 && other.name == w[1])
        Fail(line.number, "mode name '" + w[1] + "' already used on line " + std::to_string(other.header_line));
  }

  void Header(const Line& line) {
    const std::vector<std::string>& w = line.words;
    PendingMode<Dim> mode;
    mode.header_line = line.number;
    mode.name = w[1];
    ReadModeOptions(line, file_, &mode.stiffness, &mode.damping, &mode.active);
    modes_.push_back(std::move(mode));
    state_ = State::kHeader;
  }

  // A row of numbers; when `keyword`, the line starts with "x:" / "y:" (possibly glued to the
  // first number, "x:150"), and an empty remainder just opens the section.
  void Row(const Line& line, bool keyword) {
    std::vector<std::string> words;
    if (keyword) {
      if (line.words[0].size() > 2) words.push_back(line.words[0].substr(2));
      words.insert(words.end(), line.words.begin() + 1, line.words.end());
    } else {
      words = line.words;
    }
    if (words.empty()) return;

    PendingMode<Dim>& mode = current();
    const bool in_x = state_ == State::kX;
    Section& section = in_x ? mode.x : mode.y;
    const char* name = in_x ? "'x:'" : "'y:'";
    const int row = int(section.rows.size());

    double first = 0;
    if (!keyword && !detail::ParseNumber(words[0], &first))
      Fail(line.number, "unknown keyword '" + words[0] + "' (expected 'mode', 'x:', 'y:' or a row of numbers)");
    std::vector<double> numbers(words.size());
    for (size_t k = 0; k < words.size(); ++k)
      if (!detail::ParseNumber(words[k], &numbers[k]))
        Fail(line.number, "expected a number, got '" + words[k] + "' (column " + std::to_string(k + 1) + " of row " +
                              std::to_string(row + 1) + " of the " + name + " section of " + Describe(mode) + ")");
    const int count = int(numbers.size());

    const bool later_mode = !IsFirstMatrix();
    if (in_x && later_mode && row == num_t_)
      Fail(line.number, "'x:' section of " + Describe(mode) + " has more than " + std::to_string(num_t_) +
                            " rows but the file's lattice is " + LatticeSize() + " (" + FirstModeRef() + ")");
    if (!in_x && row == int(mode.x.rows.size()))
      Fail(line.number, "'y:' section of " + Describe(mode) + " has more rows than its 'x:' section (" +
                            Rows(mode.x.rows.size()) + ", line " + std::to_string(mode.x.line) + ")");

    if (in_x && !later_mode && row == 0) {
      if (count < 2)
        Fail(line.number, "a row needs at least 2 numbers (one per lattice column, s = 0 to 1), got " +
                              std::to_string(count));
      num_s_ = count;
      first_row_line_ = line.number;
    } else if (count != num_s_) {
      std::string expected;
      if (!in_x)
        expected = "the 'x:' rows of " + Describe(mode) + " have " + std::to_string(num_s_);
      else if (later_mode)
        expected = "the file's lattice is " + LatticeSize() + " (" + std::to_string(num_s_) + " columns; " +
                   FirstModeRef() + ")";
      else
        expected = "the first 'x:' row (line " + std::to_string(first_row_line_) + ") has " + std::to_string(num_s_);
      Fail(line.number, "row " + std::to_string(row + 1) + " of the " + name + " section of " + Describe(mode) +
                            " has " + std::to_string(count) + " numbers but " + expected);
    }
    section.rows.push_back(std::move(numbers));
  }

  // ---- generator lines: displacements computed over the body's lattice, added up per mode

  void Generator(const Line& line) {
    const std::string& g = line.words[0];
    if (state_ == State::kIdle)
      Fail(line.number, "'" + g + "' before the first '" + std::string(kHeaderUsage) + "' line");
    if (state_ == State::kX || state_ == State::kY)
      Fail(line.number, "'" + g + "' after the matrix of " + Describe(current()) + " (x: on line " +
                            std::to_string(current().x.line) + "): a mode is either a matrix or generator lines; " +
                            "start another with '" + kHeaderUsage + "'");
    if (Dim == 2 && g == "twist")
      Fail(line.number, "twist needs dimension 3 (in a plane every twist is zero: about an axis in the plane it "
                        "moves points out of the plane, about the normal it varies along an axis the plane lacks)");
    if (!lattice_)
      Fail(line.number, "'" + g + "' needs the body's lattice, and this file is read without one (read it with its "
                        "object: ReadDeformationFile(path, lattice))");
    PendingMode<Dim>& mode = current();
    if (state_ == State::kHeader) {
      mode.generator_line = line.number;
      mode.generated.assign(size_t(lattice_->size()), Point::Zero());
      state_ = State::kGenerators;
    }
    if (g == "bend") Bend(line);
    else if (g == "twist") Twist(line);
    else if (g == "squash") Squash(line);
    else if (g == "shear") Shear(line);
    else if (g == "taper") Taper(line);
    else PointLine(line);
    for (const Point& d : mode.generated)
      if (!d.allFinite()) Fail(line.number, "the displacements of " + Describe(mode) + " overflow (not finite)");
  }

  // Checks the word count of a generator line.
  void Args(const Line& line, size_t count, const std::string& usage) const {
    if (line.words.size() != count + 1)
      Fail(line.number, "expected " + std::to_string(count) + " values after '" + line.words[0] + "', got " +
                            std::to_string(line.words.size() - 1) + " (" + usage + ")");
  }
  int Axis(const Line& line, size_t index, const std::string& usage) const {
    const int a = AxisIndex(line.words[index]);
    if (a >= Dim)
      Fail(line.number, "expected an axis x or y, got 'z': axis z needs dimension 3 (" + usage + ")");
    if (a < 0)
      Fail(line.number, std::string(Dim == 2 ? "expected an axis x or y" : "expected an axis x, y or z") + ", got '" +
                            line.words[index] + "' (" + usage + ")");
    return a;
  }
  double Number(const Line& line, size_t index, const std::string& usage) const {
    double value = 0;
    if (!detail::ParseNumber(line.words[index], &value))
      Fail(line.number, "expected a number, got '" + line.words[index] + "' (" + usage + ")");
    return value;
  }
  Point Unit(int a) const { return lattice_->axis(a).normalized(); }
  // lattice coordinate u_a of control point c, in [0, 1]
  double Coord(int c, int a) const { return lattice_->LocalCoords(rest_[c])[a]; }
  // r − (r·e)e with r = p − centre: the part of a control point's offset across axis a
  Point Across(int c, int a) const {
    const Point r = rest_[c] - centre_, e = Unit(a);
    return r - e * e.dot(r);
  }
  template <class F> void Add(F&& displacement) {
    std::vector<Point>& out = current().generated;
    for (int c = 0; c < lattice_->size(); ++c) out[c] += displacement(c);
  }

  void Bend(const Line& line) {
    static const std::string usage = "bend <along> <toward> <amount>";
    Args(line, 3, usage);
    const int along = Axis(line, 1, usage), toward = Axis(line, 2, usage);
    if (along == toward) Fail(line.number, "bend needs two different axes (" + usage + ")");
    const double amount = Number(line, 3, usage);
    // an arch: the middle of the <along> axis moves by <amount> toward <toward>, the ends stay
    Add([&](int c) {
      const double u = 2.0 * Coord(c, along) - 1.0;
      return Point(amount * (1.0 - u * u) * Unit(toward));
    });
  }
  void Twist(const Line& line) {
    if constexpr (Dim == 3) {
      static const std::string usage = "twist <axis> <degrees>";
      Args(line, 2, usage);
      const int axis = Axis(line, 1, usage);
      const double angle = Number(line, 2, usage) * M_PI / 180.0;
      // the ends turn by ±angle/2 about the lattice's centre line along <axis> (the linear part)
      Add([&](int c) { return Point(angle * (Coord(c, axis) - 0.5) * Unit(axis).cross(Across(c, axis))); });
    }
  }
  void Squash(const Line& line) {
    static const std::string usage = "squash <axis> <fraction>";
    Args(line, 2, usage);
    const int axis = Axis(line, 1, usage);
    const double f = Number(line, 2, usage);
    // longer by the fraction along <axis> (γ > 0 stretches, γ < 0 squashes), thinner by half of
    // it across: in 3D the volume is kept to first order, in 2D the area grows by f/2
    Add([&](int c) {
      const Point r = rest_[c] - centre_, e = Unit(axis);
      return Point(f * (e * e.dot(r) - 0.5 * Across(c, axis)));
    });
  }
  void Shear(const Line& line) {
    static const std::string usage = "shear <axis> <toward> <amount>";
    Args(line, 3, usage);
    const int axis = Axis(line, 1, usage), toward = Axis(line, 2, usage);
    if (axis == toward) Fail(line.number, "shear needs two different axes (" + usage + ")");
    const double amount = Number(line, 3, usage);
    // the u = 1 end moves by amount/2 toward <toward>, the u = 0 end by −amount/2
    Add([&](int c) { return Point(amount * (Coord(c, axis) - 0.5) * Unit(toward)); });
  }
  void Taper(const Line& line) {
    static const std::string usage = "taper <axis> <fraction>";
    Args(line, 2, usage);
    const int axis = Axis(line, 1, usage);
    const double f = Number(line, 2, usage);
    // cross-sections scale by 1 + f/2 at the u = 1 end and 1 − f/2 at u = 0
    Add([&](int c) { return Point(f * (Coord(c, axis) - 0.5) * Across(c, axis)); });
  }
  void PointLine(const Line& line) {
    static const std::string usage =
        Dim == 2 ? "point <i> <j> <dx> <dy>" : "point <i> <j> <k> <dx> <dy> <dz>";
    Args(line, 2 * Dim, usage);
    typename LatticeN<Dim>::Cell cell;
    std::string sizes;
    for (int a = 0; a < Dim; ++a) sizes += (a ? "x" : "") + std::to_string(lattice_->num(a));
    for (int a = 0; a < Dim; ++a) {
      int index = -1;
      if (!detail::ParseInt(line.words[1 + a], &index) || index < 0 || index >= lattice_->num(a))
        Fail(line.number, std::string("expected a control-point index ") + "ijk"[a] + " in 0.." +
                              std::to_string(lattice_->num(a) - 1) + ", got '" + line.words[1 + a] + "' (" + usage +
                              "; the lattice is " + sizes + ")");
      cell[a] = index;
    }
    Point d;
    for (int a = 0; a < Dim; ++a) d[a] = Number(line, 1 + Dim + a, usage);
    current().generated[lattice_->FlatIndex(cell)] += d;
  }

  std::vector<Mode> Build() const {
    const std::string stem = detail::FileStem(file_, "mode");
    std::vector<Mode> out;
    for (size_t k = 0; k < modes_.size(); ++k) {
      const PendingMode<Dim>& p = modes_[k];
      Mode mode;
      mode.name = p.header_line != 0 ? p.name : modes_.size() == 1 ? stem : stem + "_" + std::to_string(k + 1);
      if (p.header_line == 0)
        for (const PendingMode<Dim>& other : modes_)
          if (other.header_line != 0 && other.name == mode.name)
            Fail(p.x.line, "this mode has no header, so it is named '" + mode.name + "', but the mode on line " +
                               std::to_string(other.header_line) + " has that name; give it a 'mode <name>' header");
      mode.source = file_ + ":" + std::to_string(p.header_line != 0 ? p.header_line : p.x.line);
      if (p.generator_line != 0) {
        mode.lattice_size = lattice_->sizes();
        mode.displacement = p.generated;
      } else if constexpr (Dim == 2) {
        mode.lattice_size = {num_s_, num_t_};
        mode.displacement.resize(size_t(num_s_) * num_t_);
        for (int i = 0; i < num_s_; ++i)
          for (int j = 0; j < num_t_; ++j)
            mode.displacement[size_t(i) * num_t_ + j] = {p.x.rows[j][i], p.y.rows[j][i]};
      }
      mode.stiffness = p.stiffness;
      mode.damping = p.damping;
      mode.active = p.active;
      out.push_back(std::move(mode));
    }
    return out;
  }

  static constexpr size_t kNone = size_t(-1);

  const std::string& file_;
  const LatticeN<Dim>* lattice_;
  std::vector<Point> rest_;
  Point centre_ = Point::Zero();
  std::vector<PendingMode<Dim>> modes_;
  State state_ = State::kIdle;
  size_t first_matrix_ = kNone;  // the first matrix mode fixes the size of every matrix
  int num_s_ = 0, num_t_ = 0;
  int first_row_line_ = 0;
};

}  // namespace

std::vector<DeformationMode> ParseDeformations(std::istream& in, const std::string& name_for_errors) {
  return ModeFileParser<2>(name_for_errors, nullptr).Parse(in);
}

template <int Dim>
std::vector<DeformationModeN<Dim>> ParseDeformations(std::istream& in, const std::string& name_for_errors,
                                                     const LatticeN<Dim>& lattice) {
  return ModeFileParser<Dim>(name_for_errors, &lattice).Parse(in);
}

std::vector<DeformationMode> ReadDeformationFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseDeformations(in, path); });
}

template <int Dim>
std::vector<DeformationModeN<Dim>> ReadDeformationFile(const std::string& path, const LatticeN<Dim>& lattice) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseDeformations(in, path, lattice); });
}

template std::vector<DeformationModeN<2>> ParseDeformations(std::istream&, const std::string&, const LatticeN<2>&);
template std::vector<DeformationModeN<3>> ParseDeformations(std::istream&, const std::string&, const LatticeN<3>&);
template std::vector<DeformationModeN<2>> ReadDeformationFile(const std::string&, const LatticeN<2>&);
template std::vector<DeformationModeN<3>> ReadDeformationFile(const std::string&, const LatticeN<3>&);

}  // namespace wobble::formats
