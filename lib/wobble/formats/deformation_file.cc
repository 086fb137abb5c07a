#include "wobble/formats/deformation_file.h"

#include "wobble/formats/line_reader.h"

namespace wobble::formats {

namespace {

using detail::Line;

const char* const kHeaderUsage = "mode <name> [stiffness <K>] [damping <c>] [active|passive]";

std::string Rows(size_t n) { return std::to_string(n) + (n == 1 ? " row" : " rows"); }
bool StartsWith(const std::string& word, const char* prefix) { return word.rfind(prefix, 0) == 0; }
bool IsOption(const std::string& word) {
  return word == "stiffness" || word == "damping" || word == "active" || word == "passive";
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
    for (const Line& line : lines) Process(line);
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
    bool seen_stiffness = false, seen_damping = false, seen_activity = false;
    for (size_t i = 2; i < w.size(); ++i) {
      const std::string& option = w[i];
      if (option == "stiffness" || option == "damping") {
        bool& seen = option == "stiffness" ? seen_stiffness : seen_damping;
        if (seen) Fail(line.number, "'" + option + "' given twice");
        seen = true;
        double value = 0;
        if (i + 1 >= w.size()) Fail(line.number, "expected a number after '" + option + "' (" + kHeaderUsage + ")");
        if (!detail::ParseNumber(w[i + 1], &value))
          Fail(line.number, "expected a number after '" + option + "', got '" + w[i + 1] + "' (" + kHeaderUsage + ")");
        if (value < 0) Fail(line.number, option + " must be >= 0, got " + w[i + 1]);
        (option == "stiffness" ? mode.stiffness : mode.damping) = value;
        ++i;
      } else if (option == "active" || option == "passive") {
        if (seen_activity) Fail(line.number, "'active' / 'passive' given twice");
        seen_activity = true;
        mode.active = option == "active";
      } else {
        Fail(line.number, "unknown mode option '" + option +
                              "' (expected stiffness <K>, damping <c>, active or passive)");
      }
    }
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
      mode.num_s = num_s_;
      mode.num_t = num_t_;
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

}  // namespace

std::vector<DeformationMode> ParseDeformations(std::istream& in, const std::string& name_for_errors) {
  return DeformationParser(name_for_errors).Parse(in);
}

std::vector<DeformationMode> ReadDeformationFile(const std::string& path) {
  return detail::WithFile(path, [&](std::istream& in) { return ParseDeformations(in, path); });
}

}  // namespace wobble::formats
