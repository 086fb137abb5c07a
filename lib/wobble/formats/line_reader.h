// Shared helpers of the wobble text readers (object and deformation files): lines split into
// words with '#' comments removed, strict number parsing, and the file stem used for default
// names. Internal to wobble::formats; the public entry points are object_file.h and deformation_file.h.
#pragma once

#include <istream>
#include <string>
#include <vector>

namespace wobble::formats::detail {

// One line that holds something besides comments and white space.
struct Line {
  int number = 0;                  // 1-based physical line number
  std::vector<std::string> words;  // white-space separated, never empty
};

// Reads every line of `in`, drops '#' comments (anywhere on a line) and blank lines.
// Throws ParseError(name_for_errors, 0, ...) if the stream fails other than by reaching its end.
std::vector<Line> ReadLines(std::istream& in, const std::string& name_for_errors);

// Opens `path` for reading; throws ParseError(path, 0, ...) when it cannot be opened or is
// not a regular file. The callback receives the open stream.
template <class F> auto WithFile(const std::string& path, F&& parse);

// A whole word as a finite double ("1e5", "-33.3", "+2"); false for anything else, including
// "nan", "inf" and trailing garbage ("1.5kg").
bool ParseNumber(const std::string& word, double* value);
// A whole word as an int (no sign, decimals or exponent beyond what an int holds).
bool ParseInt(const std::string& word, int* value);

// "table" for "data/table.obj", "def_pot" for "def_pot"; `fallback` when there is no stem.
std::string FileStem(const std::string& path, const std::string& fallback);

// Formats a double the short way (up to 12 significant digits), for messages.
std::string FormatNumber(double value);

}  // namespace wobble::formats::detail

// ---- implementation of the template ----
#include <filesystem>
#include <fstream>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/parse_error.h"

namespace wobble::formats::detail {

template <class F> auto WithFile(const std::string& path, F&& parse) {
  std::error_code ec;
  // before opening: opening a FIFO waits for a writer, a device may never end
  const std::string kind = NonRegularKind(path);
  if (kind == "a directory") throw ParseError(path, 0, "is a directory, not a file");
  if (!kind.empty()) throw ParseError(path, 0, "is " + kind + ", not a regular file");
  std::ifstream in(path);
  if (!in) {
    if (!std::filesystem::exists(path, ec)) throw ParseError(path, 0, "cannot open file: no such file");
    throw ParseError(path, 0, "cannot open file for reading");
  }
  return parse(in);
}

}  // namespace wobble::formats::detail
