#include "wobble/script/variables.h"

#include <cctype>

#include "wobble/formats/parse_error.h"

namespace wobble::script {
bool IsVariableName(const std::string& name) {
  if (name.empty() || std::isdigit(static_cast<unsigned char>(name[0]))) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

namespace {

// Walks the text, calling use(name, default or nullptr) for every reference and appending
// what it returns in its place.
template <class F> std::string Walk(const std::string& text, const std::string& file, F&& use) {
  std::string out;
  out.reserve(text.size());
  int line = 1;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line;
    if (c != '$' || i + 1 >= text.size() || text[i + 1] != '{') {
      out += c;
      continue;
    }
    const size_t close = text.find('}', i + 2);
    const size_t newline = text.find('\n', i + 2);
    if (close == std::string::npos || (newline != std::string::npos && newline < close))
      throw formats::ParseError(file, line, "'${' without its '}' on the same line");
    const std::string inside = text.substr(i + 2, close - i - 2);
    const size_t dash = inside.find(":-");
    const std::string name = inside.substr(0, dash);
    if (!IsVariableName(name))
      throw formats::ParseError(file, line, "'${" + inside + "}': a variable's name is letters, digits and '_'");
    const std::string fallback = dash == std::string::npos ? std::string() : inside.substr(dash + 2);
    out += use(name, dash == std::string::npos ? nullptr : &fallback, line);
    i = close;
  }
  return out;
}

}  // namespace

std::string ExpandVariables(const std::string& text, const std::map<std::string, std::string>& values,
                            const std::string& file) {
  return Walk(text, file, [&](const std::string& name, const std::string* fallback, int line) {
    const auto it = values.find(name);
    if (it != values.end()) return it->second;
    if (fallback) return *fallback;
    throw formats::ParseError(file, line, "${" + name + "} has no value: give it (wobble sweep/run --param " + name +
                                              "=VALUE) or a default, ${" + name + ":-VALUE}");
  });
}

std::set<std::string> VariablesUsed(const std::string& text, const std::string& file) {
  std::set<std::string> names;
  Walk(text, file, [&](const std::string& name, const std::string*, int) {
    names.insert(name);
    return std::string();
  });
  return names;
}

}  // namespace wobble::script
