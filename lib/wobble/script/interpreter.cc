#include "wobble/script/interpreter.h"

#include "wobble/formats/csv.h"
#include "wobble/script/internal/interpreter_internal.h"

#include "wobble/formats/atomic_file.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "wobble/formats/deformation_file.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/object_file.h"
#ifdef WOBBLE_HAVE_PAGMO
#include "wobble/synth/cmaes.h"
#endif

namespace wobble::script {

namespace fs = std::filesystem;
using namespace script_detail;


// ---------------------------------------------------------------------------------------------
// the language

const std::vector<CommandInfo>& Interpreter::Commands() {
  static const std::vector<CommandInfo> commands = {
      {"load_obj", "load_obj FILE", "load an object file (lattice, mass points, drawing)"},
      {"load_def", "load_def FILE [FILE...]", "load deformation files; their modes replace the current set"},
      {"trans", "trans X Y THETA", "place the object: set_vec q is relative to this placement"},
      {"set", "set NAME VALUE", "set a parameter (see Parameters)"},
      {"assign", "assign MODE STIFFNESS DAMPING", "mode MODE (1-based or name): V = K g^2, force -c g'"},
      {"mode", "mode MODE active|passive", "designate a mode active (PD-controlled) or passive"},
      {"set_vec", "set_vec q|dq V1 .. Vn", "generalized coordinates or velocities, n = 3 + modes"},
      {"simul", "simul [DURATION]", "simulate from `time` to `end` (or for DURATION)"},
      {"pose", "pose T1 .. Tk DURATION", "append a pose: one target per active mode, held for DURATION"},
      {"key", "key TIME MODE=VALUE ...", "a keyframe at TIME (from the start of the keyframed run)"},
      {"hold", "hold S T | hold off", "hold the point at lattice coordinates (S, T) in place while keyframing"},
      {"keyframe", "keyframe", "play the keys from the current state, then hand over to simulation"},
      {"spring", "spring S T X Y [K [C [REST]]]", "a spring from lattice point (S, T) to the world point (X, Y)"},
      {"clear", "clear poses|keys|springs|output|energy|track", "forget poses, keys, springs, recorded rows, energy or the runs render draws"},
      {"output", "output FILE.csv [EVERY] | output off", "record the state of every EVERY-th step as CSV"},
      {"print", "print", "print the state, energies and the control energy"},
      {"anneal", "anneal ITERATIONS", "simulated annealing of the pose graph (Fig. 5.2)"},
      {"cmaes", "cmaes GENERATIONS", "CMA-ES (pagmo2) on the same problem as anneal; population = batch (>= 5)"},
      {"gait", "gait SKIP CYCLES", "distance travelled per cycle of the pose graph, after SKIP cycles"},
      {"save", "save FILE", "write a script that rebuilds the current setup and replays its controller"},
      {"render", "render DIR [WHAT]",
       "draw into DIR: with a scene (linear bodies) its recorded frames, WHAT a comma list of frames, filmstrip, vtp "
       "(default all); otherwise every FFD run since load_obj (or clear track), WHAT of frames, filmstrip, charts, vtp, "
       "exr, disp (default frames,filmstrip,charts)"},
      {"echo", "echo TEXT", "print TEXT"},
      // Witkin & Welch scenes (linear bodies, constraints, motion control, goal behaviours)
      {"linear", "linear NAME 2d|3d affine|quadratic box HX HY [HZ] | pyramid W H [grid N] [levels N] [mass M] [at X Y [Z]] [ke K] [kc K] [kd K] [kq K]",
       "a linear-deformation body x = R p(u) (a box or a pyramid of mass points), at rest at X Y Z"},
      {"ffd", "ffd NAME", "the loaded FFD object (its modes and state q, dq) joins the scene as body NAME"},
      {"point", "point NAME BODY U1 U2 [U3]", "name a material point of a body (undeformed coordinates; lattice S T of an FFD body)"},
      {"place", "place NAME X Y [Z]", "name a fixed place in the world (a sky point)"},
      {"nail", "nail NAME POINT [X Y [Z]]", "nail a point where it is (or at X Y Z), now"},
      {"attach", "attach NAME POINT_A POINT_B", "attach two points of bodies to each other, now"},
      {"path", "path NAME 2d|3d T X Y [Z] T X Y [Z] ...", "keyframes of a control point: a C2 cubic spline through them"},
      {"trajectory", "trajectory NAME POINT PATH [preroll DT]", "queue: the point follows PATH from its first key (preroll: a cubic from where it is)"},
      {"impulse", "impulse POINT VX VY [VZ]", "queue: an impulse that gives the point this velocity (0: stop dead)"},
      {"chase", "chase POINT TARGET DURATION [VX VY [VZ]]", "queue: the point chases a point or place, meeting it after DURATION"},
      {"connect", "connect POINT TARGET [NAME]", "queue: velocity-matching impulse, then attach (nail for a place)"},
      {"grab", "grab POINT TARGET DURATION [VX VY [VZ]]", "queue: chase, then connect (constraint connect:POINT)"},
      {"release", "release NAME", "queue: remove a constraint"},
      {"on", "on NAME", "queue: switch a constraint on (with an impulse that makes velocities legal)"},
      {"off", "off NAME", "queue: switch a constraint off (the point goes ballistic)"},
      {"wait", "wait DURATION", "queue: let DURATION pass before the next behaviour"},
      {"wait_for", "wait_for time T | near A B R | below A Y | above A Y", "queue: wait until the condition holds"},
      {"record", "record FPS | record off", "record the scene's state FPS times per simulated second for render"},
      {"quit", "quit", "stop (interactive use)"},
  };
  return commands;
}

const std::vector<std::string>& Interpreter::Parameters() {
  static const std::vector<std::string> names = {
      "gravity", "ground", "spring", "debug", "control", "cyclic",                          // booleans
      "grconst", "grdam", "frconst", "frsin", "codamA", "spconst", "spdam",                  // thesis numbers
      "time", "end", "dt", "ground_height", "ground_slope", "max_penetration",             //
      "integrator", "interp",                                                               // words
      "seed", "batch", "cooling", "temperature", "optimize", "cost", "cost_scale", "trial_steps",
      "pose_step", "time_step", "threads", "anneal_csv", "cmaes_csv", "sigma0", "min_amplitude", "max_amplitude", "min_time", "max_time", "switch_width",
      "feedback_rate", "view_azimuth", "view_elevation"};  // scenes
  return names;
}

std::string Interpreter::Nearest(const std::string& word, const std::vector<std::string>& known) {
  auto lower = [](std::string s) {
    for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
    return s;
  };
  const std::string w = lower(word);
  std::string best;
  size_t best_d = std::string::npos;
  for (const std::string& k0 : known) {
    const std::string k = lower(k0);
    // Levenshtein distance, one row at a time
    std::vector<size_t> row(k.size() + 1);
    for (size_t j = 0; j <= k.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= w.size(); ++i) {
      size_t diag = row[0];
      row[0] = i;
      for (size_t j = 1; j <= k.size(); ++j) {
        const size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (w[i - 1] == k[j - 1] ? 0 : 1)});
        diag = up;
      }
    }
    if (row[k.size()] < best_d) {
      best_d = row[k.size()];
      best = k0;
    }
  }
  const size_t limit = std::max<size_t>(2, w.size() / 3);
  return best_d <= limit ? best : "";
}

// ---------------------------------------------------------------------------------------------
// small helpers (the shared ones are in script_internal.h)

namespace {

// Rigid placement (x, y, θ) composed with a body-relative q: world = placement ∘ q.
void Place(const Eigen::Vector3d& placement, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  const Eigen::Matrix2d R = Rotation(placement[2]);
  if (q) {
    q->head<2>() = placement.head<2>() + R * q->head<2>();
    (*q)[2] += placement[2];
  }
  if (qd) qd->head<2>() = R * qd->head<2>();
}

}  // namespace


// ---------------------------------------------------------------------------------------------
// running scripts

Interpreter::Interpreter(std::ostream& out) : out_(out) {
  // the thesis' interpreter integrates with the explicit scheme; appendix C's dt = 0.1 with its
  // mode damping (c/m_eff Δt > 2) is beyond that scheme's stability, so scripts default to
  // implicit Euler (`set integrator thesis` switches back)
  world_.integrator = Integrator::kImplicitEuler;
  world_.dt = 0.01;
}

Interpreter::~Interpreter() = default;

void Interpreter::RunFile(const std::string& path) {
  formats::detail::WithFile(path, [&](std::istream& in) {
    RunStream(in, path, fs::path(path).parent_path().string());
    return 0;
  });
}

void Interpreter::RunStream(std::istream& in, const std::string& name, const std::string& dir) {
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!RunLine(line, name, number, dir)) return;
  }
}

bool Interpreter::RunLine(const std::string& line, const std::string& name, int line_number, const std::string& dir) {
  std::istringstream in(line.substr(0, line.find('#')));
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  if (words.empty()) return true;
  if (words[0] == "quit" || words[0] == "exit") return false;
  Context ctx{name, line_number, dir};
  Execute(words, ctx);
  return true;
}

void Interpreter::LoadObject(const std::string& path) {
  object_ = formats::ReadObjectFile(path);
  track_.clear();
  object_path_ = fs::absolute(path).string();
  modes_.clear();
  def_paths_.clear();
  q_.setZero(kRigidDofs);
  qd_.setZero(kRigidDofs);
  Place(placement_, &q_, &qd_);  // at rest where `trans` put it
  Invalidate();
}

std::shared_ptr<const BodyModel> Interpreter::BuildBody() {
  if (body_) return body_;
  if (!object_) return nullptr;
  std::vector<DeformationMode> modes = modes_;
  // codamA: extra damping of the active modes' PD controllers (D = c + codamA)
  for (DeformationMode& m : modes)
    if (m.active) m.damping += codam_active_;
  body_ = std::make_shared<const BodyModel>(*object_, std::move(modes));
  return body_;
}

const BodyModel* Interpreter::body() { return BuildBody().get(); }

void Interpreter::RequireBody(const Context& ctx, const std::string& command) {
  if (!object_) ctx.Fail(command + " needs an object: 'load_obj FILE' first (or run with --object FILE)");
}

int Interpreter::ModeIndex(const std::string& word, const Context& ctx) {
  int index;
  if (formats::detail::ParseInt(word, &index)) {
    if (index < 1 || index > int(modes_.size()))
      ctx.Fail("expected a mode number from 1 to " + std::to_string(modes_.size()) + ", got " + word);
    return index - 1;
  }
  std::vector<std::string> names;
  for (int d = 0; d < int(modes_.size()); ++d) {
    if (modes_[d].name == word) return d;
    names.push_back(modes_[d].name);
  }
  const std::string near = Nearest(word, names);
  ctx.Fail("no mode '" + word + "' (expected a mode number or one of the loaded names" +
           (near.empty() ? std::string(")") : "; did you mean '" + near + "'?)"));
}

WorldOptions Interpreter::MakeWorldOptions() const {
  WorldOptions o = world_;
  o.params.springs.clear();
  return o;
}

void Interpreter::Execute(const std::vector<std::string>& w, const Context& ctx) {
  if (ExecuteScene(w, ctx)) return;  // script_scene.cc
  const std::string& cmd = w[0];
  auto usage = [&]() -> std::string {
    for (const CommandInfo& c : Commands())
      if (c.name == cmd) return c.usage;
    return cmd;
  };
  if (cmd == "load_obj") {
    ExpectWords(w, 2, 2, usage(), ctx);
    LoadObject(Resolve(w[1], ctx.dir));
  } else if (cmd == "load_def") {
    ExpectWords(w, 2, 64, usage(), ctx);
    RequireBody(ctx, "load_def");
    std::vector<DeformationMode> modes;
    std::vector<std::string> paths;
    for (size_t i = 1; i < w.size(); ++i) {
      const std::string path = Resolve(w[i], ctx.dir);
      std::vector<DeformationMode> more = formats::ReadDeformationFile(path);
      modes.insert(modes.end(), more.begin(), more.end());
      paths.push_back(fs::absolute(path).string());
    }
    try {
      BodyModel check(*object_, modes);  // do the modes fit the object?
    } catch (const std::invalid_argument& e) {
      ctx.Fail(std::string("the modes do not fit the object: ") + e.what());
    }
    // a new mode set (§4.10): amplitudes of modes with the same name carry over, others start at 0
    Eigen::VectorXd q(kRigidDofs + modes.size()), qd(kRigidDofs + modes.size());
    q.setZero();
    qd.setZero();
    q.head<kRigidDofs>() = q_.head<kRigidDofs>();
    qd.head<kRigidDofs>() = qd_.head<kRigidDofs>();
    for (size_t d = 0; d < modes.size(); ++d)
      for (size_t e = 0; e < modes_.size(); ++e)
        if (modes_[e].name == modes[d].name) {
          q[kRigidDofs + d] = q_[kRigidDofs + e];
          qd[kRigidDofs + d] = qd_[kRigidDofs + e];
        }
    modes_ = std::move(modes);
    def_paths_ = std::move(paths);
    q_ = q;
    qd_ = qd;
    graph_ = {};
    keys_ = {};
    Invalidate();
  } else if (cmd == "trans") {
    ExpectWords(w, 4, 4, usage(), ctx);
    const Eigen::Vector3d p(Number(w[1], "X", ctx), Number(w[2], "Y", ctx), Number(w[3], "THETA", ctx));
    // re-place the current state: its body-relative part is kept
    if (q_.size() >= kRigidDofs) {
      Eigen::VectorXd rel = q_, rel_d = qd_;
      const Eigen::Matrix2d Rinv = Rotation(-placement_[2]);
      rel.head<2>() = Rinv * (q_.head<2>() - placement_.head<2>());
      rel[2] -= placement_[2];
      rel_d.head<2>() = Rinv * qd_.head<2>();
      placement_ = p;
      Place(placement_, &rel, &rel_d);
      q_ = rel;
      qd_ = rel_d;
    } else {
      placement_ = p;
    }
  } else if (cmd == "set") {
    Set(w, ctx);
  } else if (cmd == "assign") {
    ExpectWords(w, 4, 4, usage(), ctx);
    RequireBody(ctx, "assign");
    if (modes_.empty()) ctx.Fail("assign needs modes: 'load_def FILE' first");
    const int d = ModeIndex(w[1], ctx);
    const double k = Number(w[2], "STIFFNESS", ctx), c = Number(w[3], "DAMPING", ctx);
    if (k < 0 || c < 0) ctx.Fail("expected a non-negative stiffness and damping");
    modes_[d].stiffness = k;
    modes_[d].damping = c;
    Invalidate();
  } else if (cmd == "mode") {
    ExpectWords(w, 3, 3, usage(), ctx);
    RequireBody(ctx, "mode");
    if (modes_.empty()) ctx.Fail("mode needs modes: 'load_def FILE' first");
    const int d = ModeIndex(w[1], ctx);
    if (w[2] != "active" && w[2] != "passive") ctx.Fail("expected 'active' or 'passive', got '" + w[2] + "'");
    const bool active = w[2] == "active";
    if (modes_[d].active != active) graph_ = {};  // poses list the active modes: they no longer fit
    modes_[d].active = active;
    Invalidate();
  } else if (cmd == "set_vec") {
    RequireBody(ctx, "set_vec");
    const int n = kRigidDofs + int(modes_.size());
    if (w.size() < 2 || (w[1] != "q" && w[1] != "dq"))
      ctx.Fail("expected 'set_vec q V1 .. Vn' or 'set_vec dq V1 .. Vn'");
    if (int(w.size()) - 2 != n)
      ctx.Fail("expected " + std::to_string(n) + " numbers after 'set_vec " + w[1] + "' (tx ty theta and one per mode), got " +
               std::to_string(w.size() - 2));
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v[i] = Number(w[2 + i], "a coordinate", ctx);
    if (w[1] == "q") {
      Place(placement_, &v, nullptr);
      q_ = v;
    } else {
      Place(placement_, nullptr, &v);
      qd_ = v;
    }
  } else if (cmd == "simul") {
    ExpectWords(w, 1, 2, usage(), ctx);
    RequireBody(ctx, "simul");
    double duration = end_ - time_;
    if (w.size() == 2) {
      duration = Number(w[1], "DURATION", ctx);
      if (duration < 0) ctx.Fail("expected a non-negative DURATION");
    } else if (duration < 0) {
      ctx.Fail("end (" + Num(end_) + ") is before time (" + Num(time_) + "): set end later, or give a DURATION");
    }
    Simulate(duration, ctx);
  } else if (cmd == "pose") {
    RequireBody(ctx, "pose");
    const int k = int(control::ActiveModes(*BuildBody()).size());
    if (k == 0) ctx.Fail("pose needs active modes: 'mode MODE active' first");
    if (int(w.size()) != k + 2)
      ctx.Fail("expected 'pose' with " + std::to_string(k) + " targets (one per active mode) and a DURATION");
    Eigen::VectorXd pose(k);
    for (int i = 0; i < k; ++i) pose[i] = Number(w[1 + i], "a target amplitude", ctx);
    const double duration = Number(w.back(), "DURATION", ctx);
    if (!(duration > 0)) ctx.Fail("expected a positive DURATION, got " + w.back());
    graph_.poses.push_back(pose);
    graph_.durations.push_back(duration);
  } else if (cmd == "key") {
    RequireBody(ctx, "key");
    if (w.size() < 2) ctx.Fail("expected '" + usage() + "'");
    const double t = Number(w[1], "TIME", ctx);
    if (keys_.times.empty() && t != 0.0) ctx.Fail("the first key must be at time 0");
    if (!keys_.times.empty() && !(t > keys_.times.back()))
      ctx.Fail("expected a key time after " + Num(keys_.times.back()) + ", got " + w[1]);
    Eigen::VectorXd a = keys_.amplitudes.empty() ? Eigen::VectorXd(q_.tail(modes_.size())) : keys_.amplitudes.back();
    for (size_t i = 2; i < w.size(); ++i) {
      const size_t eq = w[i].find('=');
      if (eq == std::string::npos || eq == 0) ctx.Fail("expected MODE=VALUE, got '" + w[i] + "'");
      a[ModeIndex(w[i].substr(0, eq), ctx)] = Number(w[i].substr(eq + 1), "an amplitude after '='", ctx);
    }
    keys_.times.push_back(t);
    keys_.amplitudes.push_back(a);
  } else if (cmd == "hold") {
    if (w.size() == 2 && w[1] == "off") {
      hold_.enabled = false;
    } else {
      ExpectWords(w, 3, 3, usage(), ctx);
      const double s = Number(w[1], "S", ctx), t = Number(w[2], "T", ctx);
      if (s < 0 || s > 1 || t < 0 || t > 1) ctx.Fail("expected lattice coordinates S and T in [0, 1]");
      hold_.enabled = true;
      hold_.lattice_coords = {s, t};
    }
  } else if (cmd == "keyframe") {
    ExpectWords(w, 1, 1, usage(), ctx);
    RequireBody(ctx, "keyframe");
    RunKeyframes(ctx);
  } else if (cmd == "spring") {
    ExpectWords(w, 5, 8, usage(), ctx);
    RequireBody(ctx, "spring");
    Spring sp;
    sp.lattice_coords = {Number(w[1], "S", ctx), Number(w[2], "T", ctx)};
    if (sp.lattice_coords.minCoeff() < 0 || sp.lattice_coords.maxCoeff() > 1)
      ctx.Fail("expected lattice coordinates S and T in [0, 1]");
    sp.anchor = {Number(w[3], "X", ctx), Number(w[4], "Y", ctx)};
    sp.stiffness = w.size() > 5 ? Number(w[5], "K", ctx) : spring_stiffness_;
    sp.damping = w.size() > 6 ? Number(w[6], "C", ctx) : spring_damping_;
    sp.rest_length = w.size() > 7 ? Number(w[7], "REST", ctx) : 0.0;
    if (sp.stiffness < 0 || sp.damping < 0 || sp.rest_length < 0) ctx.Fail("expected non-negative K, C and REST");
    springs_.push_back(sp);
  } else if (cmd == "clear") {
    ExpectWords(w, 2, 2, usage(), ctx);
    if (w[1] == "poses") graph_ = {};
    else if (w[1] == "keys") keys_ = {};
    else if (w[1] == "springs") springs_.clear();
    else if (w[1] == "output") ClearOutputRows();
    else if (w[1] == "energy") energy_ = {};
    else if (w[1] == "track") track_.clear();
    else ctx.Fail("expected poses, keys, springs, output, energy or track after 'clear', got '" + w[1] + "'");
  } else if (cmd == "output") {
    ExpectWords(w, 2, 3, usage(), ctx);
    if (w[1] == "off") {
      output_path_.clear();
      return;
    }
    int every = 1;
    if (w.size() == 3 && (!formats::detail::ParseInt(w[2], &every) || every < 1))
      ctx.Fail("expected EVERY as a whole number >= 1, got '" + w[2] + "'");
    output_path_ = w[1];
    output_every_ = every;
    output_counter_ = 0;
    ClearOutputRows();
  } else if (cmd == "print") {
    ExpectWords(w, 1, 1, usage(), ctx);
    RequireBody(ctx, "print");
    out_ << "t = " << Num(time_) << "  q = [";
    for (int i = 0; i < q_.size(); ++i) out_ << (i ? " " : "") << Num(q_[i]);
    out_ << "]  dq = [";
    for (int i = 0; i < qd_.size(); ++i) out_ << (i ? " " : "") << Num(qd_[i]);
    out_ << "]  control energy " << Num(energy_.consumed) << "\n";
  } else if (cmd == "anneal") {
    ExpectWords(w, 2, 2, usage(), ctx);
    RequireBody(ctx, "anneal");
    int iterations;
    if (!formats::detail::ParseInt(w[1], &iterations) || iterations < 0)
      ctx.Fail("expected ITERATIONS as a whole number >= 0, got '" + w[1] + "'");
    if (graph_.empty()) ctx.Fail("anneal needs an initial pose graph: 'pose ...' lines first");
    synth::AnnealOptions o = anneal_options_;
    o.iterations = iterations;
    const std::string invalid = o.Validate();
    if (!invalid.empty()) ctx.Fail("anneal: " + invalid);
    const synth::Problem problem = MakeProblem(trial_steps_);
    graph_.cyclic = true;
    anneal_start_q_ = q_;
    anneal_start_qd_ = qd_;
    synth::AnnealResult r = synth::Anneal(problem, graph_, o, [&](const synth::IterationRecord& rec) {
      if (progress_) progress_(iterations ? double(rec.iteration) / iterations : 1.0, rec.best);
    });
    if (!anneal_csv_.empty()) {
      // cost against iteration (Fig. 5.4/5.5); the hook draws it
      try {
        formats::WriteTextAtomically(anneal_csv_, formats::CsvText(synth::HistoryHeader(), synth::HistoryRows(r.history)));
        if (history_hook_) history_hook_(anneal_csv_, "simulated annealing", r.history);
      } catch (const std::runtime_error& e) {
        ctx.Fail(e.what());
      }
    }
    out_ << "anneal: " << r.trials << " trials; cost " << Num(r.initial_outcome.cost) << " -> " << Num(r.best_outcome.cost)
         << " (distance " << Num(r.best_outcome.distance) << ", end speed " << Num(r.best_outcome.speed)
         << ", control energy " << Num(r.best_outcome.energy) << ")\n";
    graph_ = r.best;
    anneal_ = std::move(r);
  } else if (cmd == "cmaes") {
    ExpectWords(w, 2, 2, usage(), ctx);
    RequireBody(ctx, "cmaes");
    int generations;
    if (!formats::detail::ParseInt(w[1], &generations) || generations < 0)
      ctx.Fail("expected GENERATIONS as a whole number >= 0, got '" + w[1] + "'");
    if (graph_.empty()) ctx.Fail("cmaes needs an initial pose graph: 'pose ...' lines first");
#ifdef WOBBLE_HAVE_PAGMO
    synth::CmaesOptions o;
    o.seed = anneal_options_.seed;
    o.generations = generations;
    o.population = anneal_options_.batch;
    o.sigma0 = sigma0_;
    o.optimize = anneal_options_.optimize;
    o.min_amplitude = anneal_options_.min_amplitude;
    o.max_amplitude = anneal_options_.max_amplitude;
    o.min_time = anneal_options_.min_time;
    o.max_time = anneal_options_.max_time;
    const std::string invalid = o.Validate();
    if (!invalid.empty()) ctx.Fail("cmaes: " + invalid + " (the population is `batch`)");
    const synth::Problem problem = MakeProblem(trial_steps_);
    graph_.cyclic = true;
    anneal_start_q_ = q_;
    anneal_start_qd_ = qd_;
    synth::AnnealResult r = synth::Cmaes(problem, graph_, o, [&](const synth::IterationRecord& rec) {
      if (progress_) progress_(generations ? double(rec.iteration) / generations : 1.0, rec.best);
    });
    if (!cmaes_csv_.empty()) {
      try {
        formats::WriteTextAtomically(cmaes_csv_, formats::CsvText(synth::HistoryHeader(), synth::HistoryRows(r.history)));
        if (history_hook_) history_hook_(cmaes_csv_, "CMA-ES", r.history);
      } catch (const std::runtime_error& e) {
        ctx.Fail(e.what());
      }
    }
    out_ << "cmaes: " << r.trials << " trials; cost " << Num(r.initial_outcome.cost) << " -> " << Num(r.best_outcome.cost)
         << " (distance " << Num(r.best_outcome.distance) << ", end speed " << Num(r.best_outcome.speed)
         << ", control energy " << Num(r.best_outcome.energy) << ")\n";
    graph_ = r.best;
    anneal_ = std::move(r);
#else
    ctx.Fail("cmaes: this wobble was built without pagmo2 (Debian: libpagmo-dev); use anneal");
#endif
  } else if (cmd == "gait") {
    ExpectWords(w, 3, 3, usage(), ctx);
    RequireBody(ctx, "gait");
    int skip, cycles;
    if (!formats::detail::ParseInt(w[1], &skip) || skip < 0 || !formats::detail::ParseInt(w[2], &cycles) || cycles < 1)
      ctx.Fail("expected 'gait SKIP CYCLES' with SKIP >= 0 and CYCLES >= 1 whole numbers");
    if (graph_.empty() || !graph_.cyclic) ctx.Fail("gait needs a cyclic pose graph: 'pose ...' lines first");
    const std::string invalid = graph_.Validate(int(control::ActiveModes(*BuildBody()).size()));
    if (!invalid.empty()) ctx.Fail("pose graph: " + invalid);
    // from the anneal's start state when there was one: the gait the trials measured
    const synth::Problem p = SynthesisProblem();
    const std::vector<double> d = synth::DistancePerCycle(p, graph_, skip, cycles);
    out_ << "gait: period " << Num(graph_.Period()) << ", distance per cycle:";
    for (double x : d) out_ << " " << Num(x);
    out_ << "\n";
  } else if (cmd == "save") {
    ExpectWords(w, 2, 2, usage(), ctx);
    RequireBody(ctx, "save");
    try {
      formats::WriteTextAtomically(w[1], ReplayScript());
    } catch (const std::runtime_error& e) {
      ctx.Fail(e.what());
    }
  } else if (cmd == "render") {
    ExpectWords(w, 2, 3, usage(), ctx);
    RequireBody(ctx, "render");
    if (track_.empty()) ctx.Fail("render: nothing to draw yet (run 'simul' or 'keyframe' first)");
    if (!render_hook_) ctx.Fail("render: this program has no renderer ('wobble run' has one)");
    RenderRequest request = MakeRenderRequest();
    request.dir = w[1];
    request.what = w.size() > 2 ? w[2] : "";
    try {
      render_hook_(request);
    } catch (const std::exception& e) {
      ctx.Fail(std::string("render: ") + e.what());
    }
  } else if (cmd == "echo") {
    for (size_t i = 1; i < w.size(); ++i) out_ << (i > 1 ? " " : "") << w[i];
    out_ << "\n";
  } else {
    std::vector<std::string> names;
    for (const CommandInfo& c : Commands()) names.push_back(c.name);
    const std::string near = Nearest(cmd, names);
    ctx.Fail("unknown command '" + cmd + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?"));
  }
}

void Interpreter::Set(const std::vector<std::string>& w, const Context& ctx) {
  if (w.size() != 3) ctx.Fail("expected 'set NAME VALUE'");
  const std::string& name = w[1];
  const std::string& value = w[2];
  Ground& g = world_.params.ground;
  auto number = [&]() { return Number(value, name, ctx); };
  auto non_negative = [&]() {
    const double v = number();
    if (v < 0) ctx.Fail("expected a non-negative value for " + name + ", got " + value);
    return v;
  };
  auto positive = [&]() {
    const double v = number();
    if (!(v > 0)) ctx.Fail("expected a positive value for " + name + ", got " + value);
    return v;
  };
  auto whole = [&](int min) {
    int v;
    if (!formats::detail::ParseInt(value, &v) || v < min)
      ctx.Fail("expected a whole number >= " + std::to_string(min) + " for " + name + ", got '" + value + "'");
    return v;
  };
  if (name == "gravity") world_.params.gravity_on = Boolean(value, name, ctx);
  else if (name == "ground") g.enabled = Boolean(value, name, ctx);
  else if (name == "spring") springs_on_ = Boolean(value, name, ctx);
  else if (name == "debug") debug_ = Boolean(value, name, ctx);
  else if (name == "control") control_on_ = Boolean(value, name, ctx);
  else if (name == "cyclic") graph_.cyclic = Boolean(value, name, ctx);
  else if (name == "grconst") g.stiffness = non_negative();
  else if (name == "grdam") g.normal_damping = non_negative();
  else if (name == "frconst") g.friction_damping = non_negative();
  else if (name == "frsin") g.friction_cap = non_negative();
  else if (name == "codamA") {
    codam_active_ = non_negative();
    Invalidate();
  } else if (name == "spconst") {
    spring_stiffness_ = non_negative();
    for (Spring& sp : springs_) sp.stiffness = spring_stiffness_;
  } else if (name == "spdam") {
    spring_damping_ = non_negative();
    for (Spring& sp : springs_) sp.damping = spring_damping_;
  } else if (name == "time") time_ = number();
  else if (name == "end") end_ = number();
  else if (name == "dt") world_.dt = positive();
  else if (name == "ground_height") g.point = Eigen::Vector2d(0.0, number());
  else if (name == "ground_slope") {
    const double deg = number();
    if (std::abs(deg) >= 90) ctx.Fail("expected a ground slope between -90 and 90 degrees, got " + value);
    g.slope = deg * M_PI / 180.0;
  } else if (name == "max_penetration") g.max_penetration = non_negative();
  else if (name == "integrator") {
    if (!ParseIntegrator(value, &world_.integrator))
      ctx.Fail("expected an integrator (thesis, symplectic, rk4, implicit, variational), got '" + value + "'");
  } else if (name == "interp") {
    if (value == "linear") keys_.interpolation = control::Interpolation::kLinear;
    else if (value == "smooth") keys_.interpolation = control::Interpolation::kSmooth;
    else ctx.Fail("expected 'linear' or 'smooth' for interp, got '" + value + "'");
  } else if (name == "seed") {
    double v = number();
    if (v < 0 || v != std::floor(v) || v > 1e18) ctx.Fail("expected a whole non-negative seed, got " + value);
    anneal_options_.seed = std::uint64_t(v);
  } else if (name == "batch") anneal_options_.batch = whole(1);
  else if (name == "threads") anneal_options_.threads = whole(0);
  else if (name == "trial_steps") trial_steps_ = whole(1);
  else if (name == "cooling") {
    anneal_options_.cooling = positive();
    if (anneal_options_.cooling > 1) ctx.Fail("expected cooling in (0, 1], got " + value);
  } else if (name == "temperature") anneal_options_.initial_temperature = non_negative();
  else if (name == "pose_step") anneal_options_.pose_step = non_negative();
  else if (name == "time_step") anneal_options_.time_step = non_negative();
  else if (name == "min_amplitude") anneal_options_.min_amplitude = number();
  else if (name == "max_amplitude") anneal_options_.max_amplitude = number();
  else if (name == "min_time") anneal_options_.min_time = positive();
  else if (name == "max_time") anneal_options_.max_time = positive();
  else if (name == "cost_scale") cost_.scale = positive();
  else if (name == "optimize") {
    if (!synth::ParseOptimize(value, &anneal_options_.optimize))
      ctx.Fail("expected poses, times or both for optimize, got '" + value + "'");
  } else if (name == "cost") {
    if (!synth::ParseCostKind(value, &cost_.kind))
      ctx.Fail("expected a cost (inverse_distance, energy_per_distance, energy_per_sqrt_distance_speed, "
               "energy_per_sqrt_distance), got '" + value + "'");
  } else if (name == "anneal_csv") anneal_csv_ = value;
  else if (name == "cmaes_csv") cmaes_csv_ = value;
  else if (name == "switch_width") switch_width_ = non_negative();
  else if (name == "sigma0") {
    sigma0_ = positive();
    if (sigma0_ > 1) ctx.Fail("expected sigma0 in (0, 1], got " + value);
  }
  else if (SetSceneParameter(name, value, ctx)) {
  } else {
    const std::string near = Nearest(name, Parameters());
    ctx.Fail("unknown parameter '" + name + "'" + (near.empty() ? "" : "; did you mean '" + near + "'?"));
  }
}

// ---------------------------------------------------------------------------------------------
// simulation, keyframes, output

namespace {
std::vector<std::string> OutputHeader(int D) {
  std::vector<std::string> h = {"t", "tx", "ty", "theta"};
  for (int d = 1; d <= D; ++d) h.push_back("g" + std::to_string(d));
  for (const char* n : {"dtx", "dty", "dtheta"}) h.push_back(n);
  for (int d = 1; d <= D; ++d) h.push_back("dg" + std::to_string(d));
  for (const char* n : {"kinetic", "gravity", "modes", "ground", "springs", "total", "control_energy", "pose", "contacts"})
    h.push_back(n);
  return h;
}
}  // namespace

void Interpreter::RecordRow(const World& world, double t, int pose) {
  if (output_path_.empty()) return;
  if (output_counter_++ % output_every_ != 0) return;
  const BodyState<double>& s = world.state(0);
  const Energies e = world.ComputeEnergies(0);
  std::vector<double> row = {t};
  row.insert(row.end(), s.q.data(), s.q.data() + s.q.size());
  row.insert(row.end(), s.qd.data(), s.qd.data() + s.qd.size());
  for (double v : {e.kinetic, e.gravity, e.modes, e.ground, e.springs, e.total(), energy_.consumed, double(pose),
                   double(s.contacts.size())})
    row.push_back(v);
  // the column of each mode, by name: a load_def between runs (the cliff jump's switch of mode
  // sets) keeps a mode's column, and a new mode gets a new one
  std::vector<int> slots;
  for (const DeformationMode& m : world.body(0).modes()) {
    const auto it = std::find(output_modes_.begin(), output_modes_.end(), m.name);
    slots.push_back(int(it - output_modes_.begin()));
    if (it == output_modes_.end()) output_modes_.push_back(m.name);
  }
  if (slot_sets_.empty() || slot_sets_.back() != slots) slot_sets_.push_back(slots);
  rows_.push_back(std::move(row));
  row_slot_set_.push_back(int(slot_sets_.size()) - 1);
}

void Interpreter::RecordTrack(const World& world, double t) {
  // a state at the same time as the last one (the hand-over) replaces it: the later run goes on
  if (!track_.empty() && track_.back().state.t == t) track_.pop_back();
  const BodyState<double>& s = world.state(0);
  track_.push_back({body_, {t, s.q, s.qd, s.mode_target}});
}

RenderRequest Interpreter::MakeRenderRequest() const {
  // one body with every mode the recorded runs used (the last definition of each name)
  std::vector<DeformationMode> modes;
  std::vector<std::vector<int>> slots;  // per distinct run body: column of each of its modes
  std::vector<const BodyModel*> bodies;
  for (const TrackEntry& e : track_) {
    if (!bodies.empty() && bodies.back() == e.body.get()) continue;
    bodies.push_back(e.body.get());
    std::vector<int> s;
    for (const DeformationMode& m : e.body->modes()) {
      auto it = std::find_if(modes.begin(), modes.end(), [&](const DeformationMode& x) { return x.name == m.name; });
      if (it == modes.end()) {
        modes.push_back(m);
        it = modes.end() - 1;
      } else {
        *it = m;
      }
      s.push_back(int(it - modes.begin()));
    }
    slots.push_back(s);
  }
  RenderRequest r;
  r.body = std::make_shared<const BodyModel>(*object_, modes);
  r.world = MakeWorldOptions();
  if (springs_on_)
    for (Spring sp : springs_) {
      r.body->LocalBasis(sp.lattice_coords, &sp.rest_local, &sp.mode_matrix);
      r.world.params.springs.push_back(sp);
    }
  const int N = int(modes.size());
  size_t b = 0;
  for (size_t i = 0; i < track_.size(); ++i) {
    if (i > 0 && track_[i].body != track_[i - 1].body) ++b;
    const TrackState& in = track_[i].state;
    TrackState out;
    out.t = in.t;
    out.q.setZero(kRigidDofs + N);
    out.qd.setZero(kRigidDofs + N);
    out.q.head<kRigidDofs>() = in.q.head<kRigidDofs>();
    out.qd.head<kRigidDofs>() = in.qd.head<kRigidDofs>();
    if (in.targets.size()) out.targets.setZero(N);
    for (size_t d = 0; d < slots[b].size(); ++d) {
      out.q[kRigidDofs + slots[b][d]] = in.q[kRigidDofs + d];
      out.qd[kRigidDofs + slots[b][d]] = in.qd[kRigidDofs + d];
      if (in.targets.size()) out.targets[slots[b][d]] = in.targets[d];
    }
    r.states.push_back(std::move(out));
  }
  return r;
}

void Interpreter::ClearOutputRows() {
  rows_.clear();
  row_slot_set_.clear();
  slot_sets_.clear();
  output_modes_.clear();
}

std::vector<std::vector<double>> Interpreter::OutputRows() const {
  // every row gets a column per mode recorded since `output`; a mode that was not loaded during
  // a row's run has amplitude and rate 0 there
  const int N = int(output_modes_.size());
  std::vector<std::vector<double>> rows;
  rows.reserve(rows_.size());
  for (size_t r = 0; r < rows_.size(); ++r) {
    const std::vector<double>& raw = rows_[r];
    const std::vector<int>& slots = slot_sets_[row_slot_set_[r]];
    const int D = int(slots.size());
    std::vector<double> row(1 + 2 * (kRigidDofs + N) + (raw.size() - 1 - 2 * (kRigidDofs + D)), 0.0);
    row[0] = raw[0];
    for (int i = 0; i < kRigidDofs; ++i) {
      row[1 + i] = raw[1 + i];
      row[1 + kRigidDofs + N + i] = raw[1 + kRigidDofs + D + i];
    }
    for (int d = 0; d < D; ++d) {
      row[1 + kRigidDofs + slots[d]] = raw[1 + kRigidDofs + d];
      row[1 + 2 * kRigidDofs + N + slots[d]] = raw[1 + 2 * kRigidDofs + D + d];
    }
    std::copy(raw.begin() + 1 + 2 * (kRigidDofs + D), raw.end(), row.begin() + 1 + 2 * (kRigidDofs + N));
    rows.push_back(std::move(row));
  }
  return rows;
}

void Interpreter::FlushOutput(const Context& ctx) {
  if (output_path_.empty()) return;
  try {
    formats::WriteTextAtomically(output_path_, formats::CsvText(OutputHeader(int(output_modes_.size())), OutputRows()));
  } catch (const std::runtime_error& e) {
    ctx.Fail(std::string("output: ") + e.what());
  }
}

synth::Problem Interpreter::MakeProblem(long steps) {
  synth::Problem p;
  p.body = BuildBody();
  p.world = MakeWorldOptions();
  if (springs_on_)
    for (Spring sp : springs_) {
      p.body->LocalBasis(sp.lattice_coords, &sp.rest_local, &sp.mode_matrix);
      p.world.params.springs.push_back(sp);
    }
  p.q0 = q_;
  p.qd0 = qd_;
  p.steps = steps;
  p.cost = cost_;
  return p;
}

synth::Problem Interpreter::SynthesisProblem() {
  synth::Problem p = MakeProblem(trial_steps_);
  if (anneal_start_q_.size()) {
    p.q0 = anneal_start_q_;
    p.qd0 = anneal_start_qd_;
  }
  return p;
}

void Interpreter::Simulate(double duration, const Context& ctx) {
  const std::shared_ptr<const BodyModel> body = BuildBody();
  const long steps = std::lround(duration / world_.dt);
  World world(MakeWorldOptions());
  world.AddBody(body);
  world.SetState(0, q_, qd_);
  if (springs_on_)
    for (const Spring& sp : springs_) world.AddSpring(sp);
  const bool controlled = control_on_ && !graph_.empty();
  if (controlled) {
    const std::string invalid = graph_.Validate(int(control::ActiveModes(*body).size()));
    if (!invalid.empty()) ctx.Fail("pose graph: " + invalid);
  }
  const double t0 = time_;
  int pose = -1;
  // the start state, unless the run before (a keyframed one, say) already recorded it
  if (rows_.empty() || rows_.back()[0] != t0) RecordRow(world, t0, pose);
  RecordTrack(world, t0);
  for (long n = 0; n < steps; ++n) {
    // the pose graph cycles from its first pose at the start of every simul (chapter 5)
    if (controlled && switch_width_ > 0) {
      // smoothed switches (control::SmoothPoseTargets), as the dynamic fit models the controller
      pose = graph_.PoseAt(n * world_.dt);
      world.SetModeTargets(0, control::SmoothPoseTargets(*body, graph_, n * world_.dt, switch_width_));
    } else if (controlled) {
      const int now = graph_.PoseAt(n * world_.dt);
      if (now != pose) {
        pose = now;
        world.SetModeTargets(0, control::TargetsFromPose(*body, graph_.poses[pose]));
      }
    }
    if (!world.Step()) {
      q_ = world.state(0).q;
      qd_ = world.state(0).qd;
      time_ = t0 + world.time();
      FlushOutput(ctx);
      throw SimulationStopped(ctx.file + ":" + std::to_string(ctx.line) + ": simulation stopped: " +
                              world.status().message);
    }
    energy_.Accumulate(*body, world.state(0), world_.dt);
    const double t = t0 + world.time();
    RecordRow(world, t, pose);
    RecordTrack(world, t);
    if (debug_) {
      out_ << "t " << Num(t) << " q";
      for (int i = 0; i < world.state(0).q.size(); ++i) out_ << " " << Num(world.state(0).q[i]);
      out_ << "\n";
    }
    if (progress_ && (n % 64 == 0 || n + 1 == steps)) progress_(double(n + 1) / double(steps), t);
  }
  q_ = world.state(0).q;
  qd_ = world.state(0).qd;
  time_ = t0 + world.time();
  FlushOutput(ctx);
  const Energies e = world.ComputeEnergies(0);
  out_ << "simul: t = " << Num(time_) << ", " << steps << " steps; kinetic " << Num(e.kinetic) << ", total "
       << Num(e.total()) << ", control energy " << Num(energy_.consumed) << "\n";
}

void Interpreter::RunKeyframes(const Context& ctx) {
  const std::shared_ptr<const BodyModel> body = BuildBody();
  const std::string invalid = keys_.Validate(body->num_modes());
  if (!invalid.empty()) ctx.Fail("keyframe: " + invalid + " ('key TIME MODE=VALUE ...' lines first)");
  // the held point stays where it is at the start; θ and, without a hold, t stay as they are
  const Eigen::Vector2d anchor = hold_.enabled ? control::PointAt(*body, hold_.lattice_coords, q_) : Eigen::Vector2d::Zero();
  const Eigen::Vector2d translation = q_.head<2>();
  const double theta = q_[2];
  const long steps = std::lround(keys_.Duration() / world_.dt);
  World view(MakeWorldOptions());  // only to evaluate energies and contacts for the output
  view.AddBody(body);
  Eigen::VectorXd gamma, gamma_dot, q, qd;
  const double t0 = time_;
  for (long n = 0; n <= steps; ++n) {
    const double t = std::min(n * world_.dt, keys_.Duration());
    keys_.Evaluate(t, &gamma, &gamma_dot);
    control::KeyframedState(*body, hold_, anchor, translation, theta, gamma, gamma_dot, &q, &qd);
    view.SetState(0, q, qd);
    RecordRow(view, t0 + t, -1);
    RecordTrack(view, t0 + t);
    if (progress_ && (n % 64 == 0 || n == steps)) progress_(double(n) / double(std::max(1L, steps)), t0 + t);
  }
  // hand-over: the simulation continues from the keyframed q and the velocity it had
  q_ = q;
  qd_ = qd;
  time_ = t0 + keys_.Duration();
  FlushOutput(ctx);
  out_ << "keyframe: t = " << Num(time_) << ", " << steps << " frames; handed over with dq = [";
  for (int i = 0; i < qd_.size(); ++i) out_ << (i ? " " : "") << Num(qd_[i]);
  out_ << "]\n";
}

Interpreter::SimulationSetup Interpreter::CurrentSetup() {
  SimulationSetup setup;
  setup.body = BuildBody();
  if (!setup.body) return setup;
  const synth::Problem p = MakeProblem(0);  // the world options with the springs, as simul builds them
  setup.world = p.world;
  setup.q = q_;
  setup.qd = qd_;
  setup.time = time_;
  setup.end = end_;
  if (control_on_) setup.graph = graph_;
  setup.object_path = object_path_;
  setup.mode_paths = def_paths_;
  return setup;
}

std::string Interpreter::ReplayScript() const {
  std::ostringstream s;
  const Ground& g = world_.params.ground;
  s << "# Written by wobble (save): rebuilds the setup and replays its controller with simul.\n";
  s << "load_obj " << object_path_ << "\n";
  if (!def_paths_.empty()) {
    s << "load_def";
    for (const std::string& p : def_paths_) s << " " << p;
    s << "\n";
  }
  for (size_t d = 0; d < modes_.size(); ++d) {
    s << "assign " << d + 1 << " " << Num(modes_[d].stiffness) << " " << Num(modes_[d].damping) << "\n";
    s << "mode " << d + 1 << (modes_[d].active ? " active" : " passive") << "\n";
  }
  s << "set codamA " << Num(codam_active_) << "\n";
  s << "set gravity " << (world_.params.gravity_on ? "T" : "F") << "\n";
  s << "set ground " << (g.enabled ? "T" : "F") << "\n";
  s << "set grconst " << Num(g.stiffness) << "\nset grdam " << Num(g.normal_damping) << "\nset frconst "
    << Num(g.friction_damping) << "\nset frsin " << Num(g.friction_cap) << "\n";
  s << "set ground_height " << Num(g.point.y()) << "\nset ground_slope " << Num(g.slope * 180.0 / M_PI) << "\n";
  s << "set max_penetration " << Num(g.max_penetration) << "\n";
  s << "set integrator " << IntegratorName(world_.integrator) << "\nset dt " << Num(world_.dt) << "\n";
  s << "set spring " << (springs_on_ ? "T" : "F") << "\n";
  for (const Spring& sp : springs_)
    s << "spring " << Num(sp.lattice_coords.x()) << " " << Num(sp.lattice_coords.y()) << " " << Num(sp.anchor.x()) << " "
      << Num(sp.anchor.y()) << " " << Num(sp.stiffness) << " " << Num(sp.damping) << " " << Num(sp.rest_length) << "\n";
  // the state the last anneal started from when there was one, so that the replay is the trial
  s << "trans 0 0 0\n";
  auto vec = [&](const char* name, const Eigen::VectorXd& v) {
    s << "set_vec " << name;
    for (int i = 0; i < v.size(); ++i) s << " " << Num(v[i]);
    s << "\n";
  };
  vec("q", anneal_start_q_.size() ? anneal_start_q_ : q_);
  vec("dq", anneal_start_q_.size() ? anneal_start_qd_ : qd_);
  s << "set cyclic " << (graph_.cyclic ? "T" : "F") << "\n";
  s << "set switch_width " << Num(switch_width_) << "\n";
  for (size_t i = 0; i < graph_.poses.size(); ++i) {
    s << "pose";
    for (int k = 0; k < graph_.poses[i].size(); ++k) s << " " << Num(graph_.poses[i][k]);
    s << " " << Num(graph_.durations[i]) << "\n";
  }
  // after an anneal: one trial's length, the motion the cost judged; otherwise the current span
  if (anneal_start_q_.size()) s << "set time 0\nset end " << Num(trial_steps_ * world_.dt) << "\n";
  else s << "set time " << Num(time_) << "\nset end " << Num(end_) << "\n";
  s << "# output replay.csv   # uncomment to record the motion\n";
  s << "simul\nprint\n";
  return s.str();
}

}  // namespace wobble::script
