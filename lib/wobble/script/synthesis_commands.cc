// Motion synthesis from a script (thesis §5.1–5.2): `anneal` and `cmaes` refine the scene's
// pose graph by trials of the FFD object, `gait` measures it, `save` writes the script that
// replays it.
#include <filesystem>

#include "wobble/core/errors.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/heightfield_file.h"
#include "wobble/formats/target_schedule.h"
#include "wobble/scene/script_writer.h"
#include "wobble/script/internal/interpreter_internal.h"
#ifdef WOBBLE_HAVE_PAGMO
#include "wobble/synth/cmaes.h"
#endif

namespace wobble::script {

using namespace script_detail;

namespace {

// The whole number after `command`, or the error naming what was expected.
int Count(const Words& w, const std::string& what, const Context& ctx) {
  int n;
  if (!formats::detail::ParseInt(w[1], &n) || n < 0) ctx.Fail("expected " + what + " as a whole number >= 0, got '" + w[1] + "'");
  return n;
}

// The optimiser's result becomes the scene's pose graph; its history goes to `csv` (and the
// CLI's hook, which draws it beside: Fig. 5.4/5.5).
void Adopt(State& s, synth::AnnealResult r, const std::string& csv, const std::string& optimiser, const char* command) {
  if (!csv.empty()) {
    // the path was checked when it was set: a failure now is the disk's (exit 1, not bad input)
    try {
      formats::WriteCsvAtomically(csv, synth::HistoryHeader(), synth::HistoryRows(r.history));
      if (s.history_hook) s.history_hook(csv, optimiser, r.history);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(std::string(command) + ": writing its history: " + e.what());
    }
  }
  s.out << command << ": " << r.trials << " trials; cost " << Num(r.initial_outcome.cost) << " -> "
        << Num(r.best_outcome.cost) << " (distance " << Num(r.best_outcome.distance) << ", end speed "
        << Num(r.best_outcome.speed) << ", control energy " << Num(r.best_outcome.energy) << ")\n";
  s.scene.control().graph = r.best;
  s.anneal = std::move(r);
}

// Adopt, then, when Ctrl-C ended the optimisation early (between two batches), Interrupted
// saying how far it got: the best pose graph so far is kept either way.
void AdoptOrStop(State& s, synth::AnnealResult r, const std::string& csv, const std::string& optimiser,
                 const char* command, const char* round, int rounds) {
  const bool interrupted = r.interrupted;
  const int done = r.history.empty() ? 0 : r.history.back().iteration;
  Adopt(s, std::move(r), csv, optimiser, command);
  if (interrupted)
    throw Interrupted(std::string(command) + " stopped by Ctrl-C after " + round + " " + std::to_string(done) + " of " +
                      std::to_string(rounds) + "; the best pose graph so far is adopted" +
                      (csv.empty() ? std::string() : ", its history written to " + csv));
}

// The start of an optimisation: the graph cycles, the trials start from the state now.
// Refuses (LimitExceeded) an optimisation whose trials together would simulate more steps
// than max_steps.
void CheckTrialWork(const State& s, double trials, const std::string& what) {
  CheckedCount(trials * double(s.trial_steps), 0, s.scene.limits().max_steps,
               what + " (trials x trial_steps, in steps)", "raise it with `set max_steps N`, or lower trial_steps");
}

using Observer = std::function<void(const synth::IterationRecord&)>;

// One optimisation with the progress bar, or with `set restarts N` the best of N from seeds
// seed, seed + 1, ... on threads and ranks (synth::BestOfRestarts; no progress from inside).
template <class Options, class Run>
synth::AnnealResult Optimise(const State& s, const Options& o, int rounds, Run run) {
  if (s.restarts > 1)
    return synth::BestOfRestarts(s.restarts, [&](int k) {
      Options restart = o;
      restart.seed = o.seed + std::uint64_t(k);
      return run(restart, Observer());
    });
  return run(o, [&](const synth::IterationRecord& rec) {
    if (s.progress) s.progress(rounds ? double(rec.iteration) / rounds : 1.0, rec.best);
  });
}

synth::Problem StartOptimising(State& s) {
  const synth::Problem problem = MakeProblem(s, s.trial_steps);
  s.scene.control().graph.cyclic = true;
  s.anneal_start_q = s.scene.object().q();
  s.anneal_start_qd = s.scene.object().qd();
  return problem;
}

}  // namespace

synth::Problem MakeProblem(const State& s, long steps) {
  // trials simulate the object alone: a constraint holding it in the Witkin & Welch scene
  // (`ffd NAME` then `nail`, `attach`, a behaviour's) would be silently left out, so refuse
  if (const World* w = s.scene.world_if_made())
    for (const auto& [name, id] : s.scene.constraints()) {
      if (!w->exists(id) || !w->enabled(id)) continue;
      const auto [a, b] = w->constraint_bodies(id);
      if (w->kind(a) == BodyKind::kFfd || (b >= 0 && w->kind(b) == BodyKind::kFfd))
        throw std::invalid_argument("the synthesis trials simulate the FFD object alone, without the scene's constraints, "
                                    "but '" + name + "' holds it in the scene: release it first (release " + name + ")");
    }
  synth::Problem p;
  if (s.scene.object().dim() == 3) {
    p.set_body(s.scene.object().Body<3>());
    p.world = s.scene.ObjectWorldOptions(*p.body<3>());
  } else {
    p.set_body(s.scene.object().Body<2>());
    p.world = s.scene.ObjectWorldOptions(*p.body<2>());
  }
  p.q0 = s.scene.object().q();
  p.qd0 = s.scene.object().qd();
  p.steps = steps;
  p.cost = s.cost;
  return p;
}

void Anneal(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireObject(s, ctx, "anneal");
  const int iterations = Count(w, "ITERATIONS", ctx);
  if (s.scene.control().graph.empty()) ctx.Fail("anneal needs an initial pose graph: 'pose ...' lines first");
  synth::AnnealOptions o = s.anneal_options;
  o.iterations = iterations;
  const std::string invalid = o.Validate();
  if (!invalid.empty()) ctx.Fail("anneal: " + invalid);
  CheckTrialWork(s, (double(iterations) * double(o.batch) + 1.0) * s.restarts, "anneal's work");
  const synth::Problem problem = StartOptimising(s);
  synth::AnnealResult r = Optimise(s, o, iterations, [&](const synth::AnnealOptions& ok, const Observer& observe) {
    return synth::Anneal(problem, s.scene.control().graph, ok, observe);
  });
  AdoptOrStop(s, std::move(r), s.anneal_csv, "simulated annealing", "anneal", "iteration", iterations);
}

void Cmaes(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireObject(s, ctx, "cmaes");
  const int generations = Count(w, "GENERATIONS", ctx);
  if (s.scene.control().graph.empty()) ctx.Fail("cmaes needs an initial pose graph: 'pose ...' lines first");
#ifdef WOBBLE_HAVE_PAGMO
  const synth::AnnealOptions& a = s.anneal_options;
  synth::CmaesOptions o;
  o.seed = a.seed;
  o.generations = generations;
  o.population = a.batch;
  o.sigma0 = s.sigma0;
  o.threads = a.threads;
  o.optimize = a.optimize;
  o.min_amplitude = a.min_amplitude;
  o.max_amplitude = a.max_amplitude;
  o.min_time = a.min_time;
  o.max_time = a.max_time;
  const std::string invalid = o.Validate();
  if (!invalid.empty()) ctx.Fail("cmaes: " + invalid + " (the population is `batch`)");
  CheckTrialWork(s, (double(generations) + 1.0) * double(o.population) * s.restarts, "cmaes' work");
  const synth::Problem problem = StartOptimising(s);
  synth::AnnealResult r = Optimise(s, o, generations, [&](const synth::CmaesOptions& ok, const Observer& observe) {
    return synth::Cmaes(problem, s.scene.control().graph, ok, observe);
  });
  AdoptOrStop(s, std::move(r), s.cmaes_csv, "CMA-ES", "cmaes", "generation", generations);
#else
  (void)generations;
  ctx.Fail("cmaes: this wobble was built without pagmo2 (Debian: libpagmo-dev); use anneal");
#endif
}

void Gait(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 3, 3);
  RequireObject(s, ctx, "gait");
  int skip, cycles;
  if (!formats::detail::ParseInt(w[1], &skip) || skip < 0 || !formats::detail::ParseInt(w[2], &cycles) || cycles < 1)
    ctx.Fail("expected 'gait SKIP CYCLES' with SKIP >= 0 and CYCLES >= 1 whole numbers");
  const control::PoseGraph& graph = s.scene.control().graph;
  if (graph.empty() || !graph.cyclic) ctx.Fail("gait needs a cyclic pose graph: 'pose ...' lines first");
  int active = 0;
  for (int d = 0; d < s.scene.object().num_modes(); ++d) active += s.scene.object().mode_active(d) ? 1 : 0;
  const std::string invalid = graph.Validate(active);
  if (!invalid.empty()) ctx.Fail("pose graph: " + invalid);
  CheckedCount((double(skip) + double(cycles)) * graph.Period() / s.scene.options().dt, 0, s.scene.limits().max_steps,
               "gait's run (SKIP + CYCLES periods, in steps)", "raise it with `set max_steps N`");
  // from the anneal's start state when there was one: the gait the trials measured
  const std::vector<double> d = synth::DistancePerCycle(SynthesisProblem(s), graph, skip, cycles);
  s.out << "gait: period " << Num(graph.Period()) << ", distance per cycle:";
  for (double x : d) s.out << " " << Num(x);
  s.out << "\n";
}

synth::Problem SynthesisProblem(const State& s) {
  synth::Problem p = MakeProblem(s, s.trial_steps);
  if (s.anneal_start_q.size()) {
    p.q0 = s.anneal_start_q;
    p.qd0 = s.anneal_start_qd;
  }
  return p;
}

// `schedule_path`, `heightfield_path`: where the scene's target schedule and heightfield are
// written, for their lines.
std::string ReplayScript(const State& s, const std::string& schedule_path, const std::string& heightfield_path) {
  const scene::Scene& sc = s.scene;
  const scene::FfdObject& object = sc.object();
  scene::ScriptSetup setup;
  setup.object_path = object.path();
  setup.mode_paths = object.mode_paths();
  setup.modes = object.dim() == 3 ? scene::ModeSettings(object.modes<3>()) : scene::ModeSettings(object.modes<2>());
  setup.codam_active = object.codam_active();
  setup.world = sc.options();
  setup.springs_on = sc.springs().enabled;
  setup.dim = object.dim();
  setup.springs = sc.springs().list;
  setup.heightfield_path = heightfield_path;
  // after an anneal: from the state its trials started from, for one trial's length (the
  // motion the cost judged); otherwise from the current state over the current span
  const bool annealed = s.anneal_start_q.size() > 0;
  setup.q = annealed ? s.anneal_start_q : object.q();
  setup.qd = annealed ? s.anneal_start_qd : object.qd();
  const double t0 = annealed ? 0.0 : sc.time(), t1 = annealed ? double(s.trial_steps) * sc.options().dt : sc.end();
  return scene::ReplayScript(setup, sc.control().graph, sc.control().switch_width, t0, t1, schedule_path);
}

void Save(State& s, const Words& w, const Context& ctx) {
  ctx.ExpectWords(w, 2, 2);
  RequireObject(s, ctx, "save");
  try {
    formats::CheckWritable(w[1]);
  } catch (const std::runtime_error& e) {
    ctx.Fail(std::string("save: ") + e.what());  // a path that cannot be written: bad input
  }
  // a spacetime fit's schedule plays in place of the pose graph: it goes beside the script
  // (FILE's stem + .schedule.csv), named by its absolute path, as `schedule` reads from the
  // working directory
  const Eigen::MatrixXd& schedule = s.scene.control().schedule;
  std::string schedule_path;
  if (schedule.size() > 0)
    schedule_path = std::filesystem::absolute(std::filesystem::path(w[1]).replace_extension(".schedule.csv")).string();
  // and a heightfield beside it too (FILE's stem + .heightfield)
  const std::shared_ptr<const Heightfield>& field = s.scene.options().params.ground.heightfield;
  const std::string field_path =
      field ? std::filesystem::absolute(std::filesystem::path(w[1]).replace_extension(".heightfield")).string() : "";
  try {
    if (!schedule_path.empty())
      formats::WriteTargetSchedule(schedule_path, s.scene.object().mode_names(), s.scene.options().dt, schedule);
    if (field) formats::WriteHeightfieldFile(field_path, *field);
    formats::WriteTextAtomically(w[1], ReplayScript(s, schedule_path, field_path));
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(std::string("save: ") + e.what());  // the disk failed (full, ...): exit 1
  }
}

}  // namespace wobble::script
