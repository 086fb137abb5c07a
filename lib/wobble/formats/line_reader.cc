#include "wobble/formats/line_reader.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "wobble/formats/parse_error.h"

namespace wobble::formats::detail {

std::vector<Line> ReadLines(std::istream& in, const std::string& name_for_errors) {
  std::vector<Line> lines;
  std::string text;
  int number = 0;
  while (std::getline(in, text)) {
    ++number;
    const size_t hash = text.find('#');
    if (hash != std::string::npos) text.erase(hash);
    std::istringstream words(text);  // splits on any white space, '\r' of CRLF files included
    Line line;
    line.number = number;
    for (std::string w; words >> w;) line.words.push_back(w);
    if (!line.words.empty()) lines.push_back(std::move(line));
  }
  if (in.bad()) throw ParseError(name_for_errors, 0, "read error after line " + std::to_string(number));
  return lines;
}

bool ParseNumber(const std::string& word, double* value) {
  const char* first = word.data();
  const char* last = word.data() + word.size();
  if (first != last && *first == '+') ++first;  // from_chars does not take a '+' sign
  if (first == last || *first == '+' || (*first == '-' && first != word.data())) return false;
  double v = 0;
  const auto [end, ec] = std::from_chars(first, last, v, std::chars_format::general);
  if (ec != std::errc() || end != last || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

bool ParseInt(const std::string& word, int* value) {
  const char* first = word.data();
  const char* last = word.data() + word.size();
  if (first != last && *first == '+') ++first;
  if (first == last || *first == '+' || (*first == '-' && first != word.data())) return false;
  int v = 0;
  const auto [end, ec] = std::from_chars(first, last, v);
  if (ec != std::errc() || end != last) return false;
  *value = v;
  return true;
}

std::string FileStem(const std::string& path, const std::string& fallback) {
  const std::string stem = std::filesystem::path(path).stem().string();
  return stem.empty() ? fallback : stem;
}

std::string FormatNumber(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.12g", value);
  return buffer;
}

}  // namespace wobble::formats::detail
