// The parameters of `set NAME VALUE`: each name once, with what it sets (README, "Parameters
// of set", gives the defaults and the wobble field of each).
#include <algorithm>
#include <cstdint>

#include "wobble/core/errors.h"
#include "wobble/formats/csv.h"
#include "wobble/script/internal/interpreter_internal.h"

namespace wobble::script {

using namespace script_detail;

double Value::Number() const { return script_detail::Number(text, name, ctx); }

double Value::NonNegative() const {
  const double v = Number();
  if (v < 0) ctx.Fail("expected a non-negative value for " + name + ", got " + text);
  return v;
}

double Value::Positive() const {
  const double v = Number();
  if (!(v > 0)) ctx.Fail("expected a positive value for " + name + ", got " + text);
  return v;
}

int Value::Whole(int min) const {
  int v;
  if (!formats::detail::ParseInt(text, &v) || v < min)
    ctx.Fail("expected a whole number >= " + std::to_string(min) + " for " + name + ", got '" + text + "'");
  return v;
}

bool Value::Boolean() const {
  for (const char* t : {"T", "t", "true", "on", "1", "yes"})
    if (text == t) return true;
  for (const char* f : {"F", "f", "false", "off", "0", "no"})
    if (text == f) return false;
  ctx.Fail("expected T or F for " + name + ", got '" + text + "'");
}

namespace {

Ground& TheGround(State& s) { return s.scene.options().params.ground; }
// The line's height and slope mean nothing under a terrain: refused rather than ignored.
void RequireGroundLine(State& s, const Value& v) {
  if (TheGround(s).terrain) v.ctx.Fail("the ground is a terrain ('terrain off' first for a ground line)");
}
synth::AnnealOptions& Search(State& s) { return s.anneal_options; }

// A file a later command writes, checked now: a path that cannot be written is bad input of
// this line (exit 2); the disk failing at the write is not (exit 1).
std::string WritablePath(const std::string& path, const std::string& name) {
  try {
    formats::CheckWritable(path);
  } catch (const std::runtime_error& e) {
    throw InputError(name + ": " + e.what());
  }
  return path;
}

}  // namespace

const std::vector<Parameter>& ParameterTable() {
  static const std::vector<Parameter> table = {
      // booleans
      {"gravity", [](State& s, const Value& v) { s.scene.options().params.gravity_on = v.Boolean(); }},
      {"ground", [](State& s, const Value& v) { TheGround(s).enabled = v.Boolean(); }},
      {"spring", [](State& s, const Value& v) { s.scene.springs().enabled = v.Boolean(); }},
      {"debug", [](State& s, const Value& v) { s.debug = v.Boolean(); }},
      {"control", [](State& s, const Value& v) { s.scene.control().enabled = v.Boolean(); }},
      {"cyclic", [](State& s, const Value& v) { s.scene.control().graph.cyclic = v.Boolean(); }},
      // the thesis' numbers
      {"grconst", [](State& s, const Value& v) { TheGround(s).stiffness = v.NonNegative(); }},
      {"grdam", [](State& s, const Value& v) { TheGround(s).normal_damping = v.NonNegative(); }},
      {"frconst", [](State& s, const Value& v) { TheGround(s).friction_damping = v.NonNegative(); }},
      {"frsin", [](State& s, const Value& v) { TheGround(s).friction_cap = v.NonNegative(); }},
      {"codamA", [](State& s, const Value& v) { s.scene.object().SetCodamActive(v.NonNegative()); }},
      {"spconst",
       [](State& s, const Value& v) {  // also the springs made already
         s.spring_stiffness = v.NonNegative();
         for (Spring& sp : s.scene.springs().list) sp.stiffness = s.spring_stiffness;
       }},
      {"spdam",
       [](State& s, const Value& v) {
         s.spring_damping = v.NonNegative();
         for (Spring& sp : s.scene.springs().list) sp.damping = s.spring_damping;
       }},
      {"time", [](State& s, const Value& v) { s.scene.set_time(v.Number()); }},
      {"end", [](State& s, const Value& v) { s.scene.set_end(v.Number()); }},
      {"dt", [](State& s, const Value& v) { s.scene.options().dt = v.Positive(); }},
      // gravity's magnitude along −y (9.81: the thesis' pixels as metres); a scene drawn in
      // centimetres takes 981 (table_cliff.wob)
      {"g", [](State& s, const Value& v) { s.scene.options().params.gravity = Eigen::Vector3d(0.0, -v.NonNegative(), 0.0); }},
      // work and memory limits (core/limits.h)
      {"max_steps",
       [](State& s, const Value& v) {
         s.scene.limits().max_steps = CheckedCount(v.Number(), 1, kMaxStepsLimit, "max_steps");
       }},
      {"max_record_mb", [](State& s, const Value& v) { s.scene.limits().max_record_mb = v.Positive(); }},
      {"ground_height",
       [](State& s, const Value& v) {
         RequireGroundLine(s, v);
         TheGround(s).point = Eigen::Vector2d(0.0, v.Number());
       }},
      {"ground_slope",
       [](State& s, const Value& v) {
         RequireGroundLine(s, v);
         const double deg = v.Number();
         if (std::abs(deg) >= 90) v.ctx.Fail("expected a ground slope between -90 and 90 degrees, got " + v.text);
         TheGround(s).slope = deg * M_PI / 180.0;
       }},
      {"max_penetration", [](State& s, const Value& v) { TheGround(s).max_penetration = v.NonNegative(); }},
      // words
      {"integrator",
       [](State& s, const Value& v) {
         Integrator integrator;
         if (!ParseIntegrator(v.text, &integrator))
           v.ctx.Fail("expected an integrator (" + IntegratorNames() + "), got '" + v.text + "'");
         s.scene.ChooseIntegrator(integrator);
       }},
      {"interp",
       [](State& s, const Value& v) {
         if (v.text == "linear") s.scene.control().keys.interpolation = control::Interpolation::kLinear;
         else if (v.text == "smooth") s.scene.control().keys.interpolation = control::Interpolation::kSmooth;
         else v.ctx.Fail("expected 'linear' or 'smooth' for interp, got '" + v.text + "'");
       }},
      // synthesis
      {"seed",
       [](State& s, const Value& v) {
         const double seed = v.Number();
         if (seed < 0 || seed != std::floor(seed) || seed > 1e18) v.ctx.Fail("expected a whole non-negative seed, got " + v.text);
         Search(s).seed = std::uint64_t(seed);
       }},
      {"batch", [](State& s, const Value& v) { Search(s).batch = v.Whole(1); }},
      {"restarts",
       [](State& s, const Value& v) {
         s.restarts = int(CheckedCount(v.Number(), 1, 100000, "restarts (independent optimisations)"));
       }},
      {"cooling",
       [](State& s, const Value& v) {
         Search(s).cooling = v.Positive();
         if (Search(s).cooling > 1) v.ctx.Fail("expected cooling in (0, 1], got " + v.text);
       }},
      {"temperature", [](State& s, const Value& v) { Search(s).initial_temperature = v.NonNegative(); }},
      {"optimize",
       [](State& s, const Value& v) {
         if (!synth::ParseOptimize(v.text, &Search(s).optimize))
           v.ctx.Fail("expected poses, times or both for optimize, got '" + v.text + "'");
       }},
      {"cost",
       [](State& s, const Value& v) {
         if (!synth::ParseCostKind(v.text, &s.cost.kind))
           v.ctx.Fail("expected a cost (inverse_distance, energy_per_distance, energy_per_sqrt_distance_speed, "
                      "energy_per_sqrt_distance), got '" + v.text + "'");
       }},
      {"cost_scale", [](State& s, const Value& v) { s.cost.scale = v.Positive(); }},
      {"trial_steps", [](State& s, const Value& v) { s.trial_steps = v.Whole(1); }},
      {"pose_step", [](State& s, const Value& v) { Search(s).pose_step = v.NonNegative(); }},
      {"time_step", [](State& s, const Value& v) { Search(s).time_step = v.NonNegative(); }},
      {"threads",
       [](State& s, const Value& v) {
         Search(s).threads = int(CheckedCount(v.Number(), 0, kMaxThreads, "threads (0: one per core)"));
       }},
      {"anneal_csv", [](State& s, const Value& v) { s.anneal_csv = WritablePath(v.text, "anneal_csv"); }},
      {"cmaes_csv", [](State& s, const Value& v) { s.cmaes_csv = WritablePath(v.text, "cmaes_csv"); }},
      {"sigma0",
       [](State& s, const Value& v) {
         s.sigma0 = v.Positive();
         if (s.sigma0 > 1) v.ctx.Fail("expected sigma0 in (0, 1], got " + v.text);
       }},
      {"min_amplitude", [](State& s, const Value& v) { Search(s).min_amplitude = v.Number(); }},
      {"max_amplitude", [](State& s, const Value& v) { Search(s).max_amplitude = v.Number(); }},
      {"min_time", [](State& s, const Value& v) { Search(s).min_time = v.Positive(); }},
      {"max_time", [](State& s, const Value& v) { Search(s).max_time = v.Positive(); }},
      {"switch_width", [](State& s, const Value& v) { s.scene.control().switch_width = v.NonNegative(); }},
      // Witkin & Welch scenes
      {"feedback_rate",
       [](State& s, const Value& v) { s.scene.world().mutable_options().feedback_rate = Positive(v.text, v.name, v.ctx); }},
      {"view_azimuth",
       [](State& s, const Value& v) { s.scene.SetCamera(v.Number(), s.scene.elevation()); }},
      {"view_elevation",
       [](State& s, const Value& v) {
         const double e = v.Number();
         if (std::abs(e) >= 90) v.ctx.Fail("expected an elevation between -90 and 90 degrees, got " + v.text);
         s.scene.SetCamera(s.scene.azimuth(), e);
       }},
  };
  return table;
}

void Set(State& s, const Words& w, const Context& ctx) {
  if (w.size() != 3) ctx.Fail("expected 'set NAME VALUE'");
  const std::vector<Parameter>& table = ParameterTable();
  const auto p = std::find_if(table.begin(), table.end(), [&](const Parameter& p) { return w[1] == p.name; });
  if (p == table.end()) ctx.Fail("unknown parameter '" + w[1] + "'" + DidYouMean(w[1], Interpreter::Parameters()));
  p->set(s, Value{w[1], w[2], ctx});
}

}  // namespace wobble::script
