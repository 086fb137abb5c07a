// Internal to the script interpreter (script.cc and script_scene.cc): the line context every
// error names, and the word parsers both files use. Not part of the public API.
#pragma once

#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "wobble/formats/line_reader.h"
#include "wobble/formats/parse_error.h"
#include "wobble/script/interpreter.h"

namespace wobble::script {

struct Interpreter::Context {
  std::string file;
  int line = 0;
  std::string dir;
  [[noreturn]] void Fail(const std::string& message) const { throw formats::ParseError(file, line, message); }
};

// The Witkin & Welch scene of a script: linear (and FFD) bodies in one World, named
// points and places, named constraints, the behaviour queue and the recorded frames.
struct Interpreter::Scene {
  World world;
  std::vector<LinearDrawing> drawings;         // per body
  std::map<std::string, int> bodies;            // name → body index
  std::map<std::string, control::Anchor> anchors;  // `point` and `place`
  control::ConstraintNames constraints;         // name → constraint id
  std::set<std::string> promised;               // names queued behaviours will create
  std::map<std::string, std::shared_ptr<const control::KeyframeSpline>> paths;
  control::Sequencer sequencer;
  double record_fps = 0.0;                      // 0: not recording
  double next_frame = 0.0;
  std::vector<record::SceneFrame> frames;
  double azimuth = 30.0, elevation = 20.0;      // render's 3D camera
  explicit Scene(WorldOptions o) : world(std::move(o)) {}
};

namespace script_detail {

// Shortest round-trip form of a number.
inline std::string Num(double v) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

template <class C> double Number(const std::string& word, const std::string& what, const C& ctx) {
  double v;
  if (!formats::detail::ParseNumber(word, &v) || !std::isfinite(v))
    ctx.Fail("expected " + what + " (a finite number), got '" + word + "'");
  return v;
}

template <class C> bool Boolean(const std::string& word, const std::string& what, const C& ctx) {
  for (const char* t : {"T", "t", "true", "on", "1", "yes"})
    if (word == t) return true;
  for (const char* f : {"F", "f", "false", "off", "0", "no"})
    if (word == f) return false;
  ctx.Fail("expected T or F for " + what + ", got '" + word + "'");
}

template <class C>
void ExpectWords(const std::vector<std::string>& w, size_t min, size_t max, const std::string& usage, const C& ctx) {
  if (w.size() < min || w.size() > max) ctx.Fail("expected '" + usage + "'");
}

inline std::string Resolve(const std::string& path, const std::string& dir) {
  const std::filesystem::path p(path);
  if (p.is_absolute() || dir.empty()) return path;
  return (std::filesystem::path(dir) / p).string();
}

}  // namespace script_detail
}  // namespace wobble::script
