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

// One x: or y: matrix as read: rows bottom (t = 0) to top.
struct Section {
  int line = 0;  // line of the "x:" / "y:" keyword
  std::vector<std::vector<double>> rows;
};

struct PendingMode {
  int header_line = 0;  // 0: no header
  std::string name;
  double stiffness = 0, damping = 0;
  bool active = false;
  Section x, y;
};

class DeformationParser {
 public:
  explicit DeformationParser(const std::string& file) : file_(file) {}

  std::vector<DeformationMode> Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, file_);
    if (lines.empty())
      Fail(0, "file is empty: expected one or more modes, each an 'x:' and a 'y:' section, optionally after a '" +
                  std::string(kHeaderUsage) + "' header");
    size_t first = 0;
    if (lines.front().words[0] == "dimension") {
      if (lines.front().words.size() != 2 || lines.front().words[1] != "2")
        Fail(lines.front().number, lines.front().words.size() == 2 && lines.front().words[1] == "3"
                                       ? "this is a 3D deformation file; a 2D body was expected here"
                                       : "expected 'dimension 2' or 'dimension 3'");
      first = 1;
      if (lines.size() == 1) Fail(lines.front().number, "no modes after 'dimension 2'");
    }
    for (size_t i = first; i < lines.size(); ++i) Process(lines[i]);
    Close("the end of the file", lines.back().number);
    return Build();
  }

 private:
  enum class State { kIdle, kHeader, kX, kY };

  [[noreturn]] void Fail(int line, const std::string& message) const { throw ParseError(file_, line, message); }

  PendingMode& current() { return modes_.back(); }
  std::string Describe(const PendingMode& mode) const {
    if (mode.header_line != 0) return "mode '" + mode.name + "'";
    return "mode #" + std::to_string(&mode - modes_.data() + 1);
  }
  std::string LatticeSize() const { return std::to_string(num_s_) + "x" + std::to_string(num_t_); }
  std::string FirstModeRef() const { return "fixed by the first mode, x: on line " + std::to_string(modes_[0].x.line); }

  void Process(const Line& line) {
    const std::string& w0 = line.words[0];
    if (w0 == "mode") {
      Close("a 'mode' header", line.number);
      Header(line);
    } else if (StartsWith(w0, "x:")) {
      if (state_ != State::kHeader) {
        Close("another 'x:'", line.number);
        modes_.emplace_back();
      }
      current().x.line = line.number;
      state_ = State::kX;
      Row(line, /*keyword=*/true);
    } else if (StartsWith(w0, "y:")) {
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
    } else if (state_ == State::kX || state_ == State::kY) {
      Row(line, /*keyword=*/false);
    } else {
      double value = 0;
      if (detail::ParseNumber(w0, &value))
        Fail(line.number, "numbers outside an x: or y: section: expected 'x:' or '" + std::string(kHeaderUsage) + "'");
      Fail(line.number, "unknown keyword '" + w0 + "' (expected 'mode', 'x:' or 'y:')");
    }
  }

  // Ends whatever is open because `what` was found on line `line`.
  void Close(const std::string& what, int line) {
    const std::string found = " (found " + what + " on line " + std::to_string(line) + ")";
    switch (state_) {
      case State::kIdle:
        break;
      case State::kHeader:
        Fail(current().header_line, Describe(current()) + " has no 'x:' section" + found);
      case State::kX:
        Fail(current().x.line, "'x:' section of " + Describe(current()) + " is not followed by a 'y:' section" + found);
      case State::kY: {
        const PendingMode& mode = current();
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
    const PendingMode& mode = current();
    const int rows = int(mode.x.rows.size());
    if (rows == 0) Fail(mode.x.line, "'x:' section of " + Describe(mode) + " has no rows");
    if (modes_.size() == 1) {
      if (rows < 2)
        Fail(mode.x.line, "'x:' section has 1 row: a lattice needs at least 2 rows (one per lattice row, bottom to top)");
      num_t_ = rows;
    } else if (rows < num_t_) {
      Fail(mode.x.line, "'x:' section of " + Describe(mode) + " has " + Rows(size_t(rows)) +
                            " but the file's lattice is " + LatticeSize() + " (" + std::to_string(num_t_) +
                            " rows; " + FirstModeRef() + ")");
    }
  }

  void Header(const Line& line) {
    const std::vector<std::string>& w = line.words;
    if (w.size() < 2 || IsOption(w[1]) || StartsWith(w[1], "x:") || StartsWith(w[1], "y:"))
      Fail(line.number, "expected a mode name after 'mode'" + (w.size() < 2 ? std::string() : ", got '" + w[1] + "'") +
                            " (" + kHeaderUsage + ")");
    for (const PendingMode& other : modes_)
      if (other.header_line != 0 && other.name == w[1])
        Fail(line.number, "mode name '" + w[1] + "' already used on line " + std::to_string(other.header_line));
    PendingMode mode;
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

    PendingMode& mode = current();
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

    const bool later_mode = modes_.size() > 1;
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

  std::vector<DeformationMode> Build() const {
    const std::string stem = detail::FileStem(file_, "mode");
    std::vector<DeformationMode> out;
    for (size_t k = 0; k < modes_.size(); ++k) {
      const PendingMode& p = modes_[k];
      DeformationMode mode;
      mode.name = p.header_line != 0 ? p.name : modes_.size() == 1 ? stem : stem + "_" + std::to_string(k + 1);
      if (p.header_line == 0)
        for (const PendingMode& other : modes_)
          if (other.header_line != 0 && other.name == mode.name)
            Fail(p.x.line, "this mode has no header, so it is named '" + mode.name + "', but the mode on line " +
                               std::to_string(other.header_line) + " has that name; give it a 'mode <name>' header");
      mode.lattice_size = {num_s_, num_t_};
      mode.source = file_ + ":" + std::to_string(p.header_line != 0 ? p.header_line : p.x.line);
      mode.displacement.resize(size_t(num_s_) * num_t_);
      for (int i = 0; i < num_s_; ++i)
        for (int j = 0; j < num_t_; ++j) mode.displacement[size_t(i) * num_t_ + j] = {p.x.rows[j][i], p.y.rows[j][i]};
      mode.stiffness = p.stiffness;
      mode.damping = p.damping;
      mode.active = p.active;
      out.push_back(std::move(mode));
    }
    return out;
  }

  const std::string& file_;
  std::vector<PendingMode> modes_;
  State state_ = State::kIdle;
  int num_s_ = 0, num_t_ = 0;  // the file's lattice size, fixed by the first mode
  int first_row_line_ = 0;
};


// ---- 3D: modes from named generators over the body's lattice ----

const char* const kGeneratorList = "bend, twist, squash, shear, taper or point";

int AxisIndex(const std::string& word) { return word == "x" ? 0 : word == "y" ? 1 : word == "z" ? 2 : -1; }

class Deformation3Parser {
 public:
  Deformation3Parser(const std::string& file, const Lattice3& lattice)
      : file_(file), lattice_(lattice), rest_(lattice.RestPoints()) {
    centre_ = lattice.origin();
    for (int a = 0; a < 3; ++a) centre_ += 0.5 * lattice.axis(a);
  }

  std::vector<DeformationMode3> Parse(std::istream& in) {
    const std::vector<Line> lines = detail::ReadLines(in, file_);
    if (lines.empty()) Fail(0, "file is empty: expected 'dimension 3' and one or more modes");
    const Line& head = lines.front();
    if (head.words[0] != "dimension" || head.words.size() != 2 || head.words[1] != "3")
      Fail(head.number, "a 3D deformation file starts with 'dimension 3' (got '" + head.words[0] + "')");
    for (size_t i = 1; i < lines.size(); ++i) Statement(lines[i]);
    if (modes_.empty()) Fail(head.number, "no modes after 'dimension 3' (expected '" + std::string(kHeaderUsage) + "')");
    CheckLastMode(lines.back().number);
    return std::move(modes_);
  }

 private:
  [[noreturn]] void Fail(int line, const std::string& message) const { throw ParseError(file_, line, message); }

  void Statement(const Line& line) {
    const std::string& keyword = line.words[0];
    if (keyword == "mode") return Header(line);
    if (modes_.empty())
      Fail(line.number, "'" + keyword + "' before the first '" + std::string(kHeaderUsage) + "' line");
    if (keyword == "bend") return Bend(line);
    if (keyword == "twist") return Twist(line);
    if (keyword == "squash") return Squash(line);
    if (keyword == "shear") return Shear(line);
    if (keyword == "taper") return Taper(line);
    if (keyword == "point") return PointLine(line);
    Fail(line.number, "unknown keyword '" + keyword + "' (expected mode, " + kGeneratorList + ")");
  }

  void Header(const Line& line) {
    const std::vector<std::string>& w = line.words;
    if (w.size() < 2 || IsOption(w[1]))
      Fail(line.number, "expected a mode name after 'mode'" + (w.size() < 2 ? std::string() : ", got '" + w[1] + "'") +
                            " (" + kHeaderUsage + ")");
    for (size_t k = 0; k < modes_.size(); ++k)
      if (modes_[k].name == w[1])
        Fail(line.number, "mode name '" + w[1] + "' already used on line " + std::to_string(header_lines_[k]));
    if (!modes_.empty()) CheckLastMode(line.number);
    DeformationMode3 mode;
    mode.name = w[1];
    ReadModeOptions(line, file_, &mode.stiffness, &mode.damping, &mode.active);
    mode.lattice_size = lattice_.sizes();
    mode.displacement.assign(lattice_.size(), Eigen::Vector3d::Zero());
    mode.source = file_ + ":" + std::to_string(line.number);
    modes_.push_back(std::move(mode));
    header_lines_.push_back(line.number);
    generators_ = 0;
  }

  void CheckLastMode(int line) const {
    if (generators_ == 0)
      Fail(header_lines_.back(), "mode '" + modes_.back().name + "' has no generator line before line " +
                                     std::to_string(line) + " (expected " + kGeneratorList + ")");
  }

  // Checks the word count and returns the words after the keyword.
  const std::vector<std::string>& Args(const Line& line, size_t count, const char* usage) const {
    if (line.words.size() != count + 1)
      Fail(line.number, "expected " + std::to_string(count) + " values after '" + line.words[0] + "', got " +
                            std::to_string(line.words.size() - 1) + " (" + usage + ")");
    return line.words;
  }
  int Axis(const Line& line, size_t index, const char* usage) const {
    const int a = AxisIndex(line.words[index]);
    if (a < 0) Fail(line.number, "expected an axis x, y or z, got '" + line.words[index] + "' (" + usage + ")");
    return a;
  }
  double Number(const Line& line, size_t index, const char* usage) const {
    double value = 0;
    if (!detail::ParseNumber(line.words[index], &value))
      Fail(line.number, "expected a number, got '" + line.words[index] + "' (" + usage + ")");
    return value;
  }
  Eigen::Vector3d Unit(int a) const { return lattice_.axis(a).normalized(); }
  // lattice coordinate u_a of control point c, in [0, 1]
  double Coord(int c, int a) const { return lattice_.LocalCoords(rest_[c])[a]; }
  // r − (r·e)e with r = p − centre: the part of a control point's offset across axis a
  Eigen::Vector3d Across(int c, int a) const {
    const Eigen::Vector3d r = rest_[c] - centre_, e = Unit(a);
    return r - e * e.dot(r);
  }
  template <class F> void Add(const Line& line, F&& displacement) {
    for (int c = 0; c < lattice_.size(); ++c) modes_.back().displacement[c] += displacement(c);
    CheckFinite(line);
    ++generators_;
  }
  void CheckFinite(const Line& line) const {
    for (const Eigen::Vector3d& d : modes_.back().displacement)
      if (!d.allFinite())
        Fail(line.number, "the displacements of mode '" + modes_.back().name + "' overflow (not finite)");
  }

  void Bend(const Line& line) {
    static const char* usage = "bend <along> <toward> <amount>";
    Args(line, 3, usage);
    const int along = Axis(line, 1, usage), toward = Axis(line, 2, usage);
    if (along == toward) Fail(line.number, "bend needs two different axes (" + std::string(usage) + ")");
    const double amount = Number(line, 3, usage);
    // an arch: the middle of the <along> axis moves by <amount> toward <toward>, the ends stay
    Add(line, [&](int c) {
      const double u = 2.0 * Coord(c, along) - 1.0;
      return Eigen::Vector3d(amount * (1.0 - u * u) * Unit(toward));
    });
  }
  void Twist(const Line& line) {
    static const char* usage = "twist <axis> <degrees>";
    Args(line, 2, usage);
    const int axis = Axis(line, 1, usage);
    const double angle = Number(line, 2, usage) * M_PI / 180.0;
    // the ends turn by ±angle/2 about the lattice's centre line along <axis> (the linear part)
    Add(line, [&](int c) { return Eigen::Vector3d(angle * (Coord(c, axis) - 0.5) * Unit(axis).cross(Across(c, axis))); });
  }
  void Squash(const Line& line) {
    static const char* usage = "squash <axis> <fraction>";
    Args(line, 2, usage);
    const int axis = Axis(line, 1, usage);
    const double f = Number(line, 2, usage);
    // longer by the fraction along <axis> (γ > 0 stretches, γ < 0 squashes), thinner by half of
    // it across: volume kept to first order
    Add(line, [&](int c) {
      const Eigen::Vector3d r = rest_[c] - centre_, e = Unit(axis);
      return Eigen::Vector3d(f * (e * e.dot(r) - 0.5 * Across(c, axis)));
    });
  }
  void Shear(const Line& line) {
    static const char* usage = "shear <axis> <toward> <amount>";
    Args(line, 3, usage);
    const int axis = Axis(line, 1, usage), toward = Axis(line, 2, usage);
    if (axis == toward) Fail(line.number, "shear needs two different axes (" + std::string(usage) + ")");
    const double amount = Number(line, 3, usage);
    // the u = 1 end moves by amount/2 toward <toward>, the u = 0 end by −amount/2
    Add(line, [&](int c) { return Eigen::Vector3d(amount * (Coord(c, axis) - 0.5) * Unit(toward)); });
  }
  void Taper(const Line& line) {
    static const char* usage = "taper <axis> <fraction>";
    Args(line, 2, usage);
    const int axis = Axis(line, 1, usage);
    const double f = Number(line, 2, usage);
    // cross-sections scale by 1 + f/2 at the u = 1 end and 1 − f/2 at u = 0
    Add(line, [&](int c) { return Eigen::Vector3d(f * (Coord(c, axis) - 0.5) * Across(c, axis)); });
  }
  void PointLine(const Line& line) {
    static const char* usage = "point <i> <j> <k> <dx> <dy> <dz>";
    Args(line, 6, usage);
    LatticeN<3>::Cell cell;
    for (int a = 0; a < 3; ++a) {
      int index = -1;
      if (!detail::ParseInt(line.words[1 + a], &index) || index < 0 || index >= lattice_.num(a))
        Fail(line.number, std::string("expected a control-point index ") + "ijk"[a] + " in 0.." +
                              std::to_string(lattice_.num(a) - 1) + ", got '" + line.words[1 + a] + "' (" + usage +
                              "; the lattice is " + std::to_string(lattice_.num(0)) + "x" +
                              std::to_string(lattice_.num(1)) + "x" + std::to_string(lattice_.num(2)) + ")");
      cell[a] = index;
    }
    const Eigen::Vector3d d(Number(line, 4, usage), Number(line, 5, usage), Number(line, 6, usage));
    modes_.back().displacement[lattice_.FlatIndex(cell)] += d;
    CheckFinite(line);
    ++generators_;
  }

  const std::string& file_;
  const Lattice3& lattice_;
  std::vector<Eigen::Vector3d> rest_;
  Eigen::Vector3d centre_;
  std::vector<DeformationMode3> modes_;
  std::vector<int> header_lines_;
  int generators_ = 0;  // generator lines of the mode being read
};

}  // namespace

std::vector<DeformationMode> ParseDeformations(std::istream& in, const std::string& name_for_errors) {
  return DeformationParser(name_for_errors).Parse(in);
}

std::vector<DeformationMode> ReadDeformationFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseDeformations(in, path); });
}

std::vector<DeformationMode3> ParseDeformations3(std::istream& in, const std::string& name_for_errors,
                                                 const Lattice3& lattice) {
  return Deformation3Parser(name_for_errors, lattice).Parse(in);
}

std::vector<DeformationMode3> ReadDeformationFile3(const std::string& path, const Lattice3& lattice) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseDeformations3(in, path, lattice); });
}

}  // namespace wobble::formats
