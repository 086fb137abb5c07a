#include "wobble/synth/cmaes.h"

#include "wobble/core/interrupt.h"

#include <algorithm>
#include <map>
#include <cmath>
#include <mutex>
#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <random>

namespace wobble::synth {

std::string CmaesOptions::Validate() const {
  if (generations < 0) return "generations must be at least 0";
  if (population < 5) return "the CMA-ES population must be at least 5";
  if (!(sigma0 > 0.0 && sigma0 <= 1.0)) return "sigma0 must be in (0, 1]";
  if (!(min_amplitude < max_amplitude)) return "amplitude bounds must satisfy min < max";
  if (!(min_time > 0.0 && min_time < max_time)) return "time bounds must satisfy 0 < min < max";
  return "";
}

namespace {

// Maps a controller to the unit box and back.
struct Coding {
  const control::PoseGraph* initial;
  CmaesOptions o;
  bool poses() const { return o.optimize != Optimize::kTimes; }
  bool times() const { return o.optimize != Optimize::kPoses; }
  int size() const {
    int n = 0;
    if (poses())
      for (const Eigen::VectorXd& p : initial->poses) n += int(p.size());
    if (times()) n += int(initial->durations.size());
    return n;
  }
  std::vector<double> Encode(const control::PoseGraph& g) const {
    std::vector<double> x;
    const double a0 = o.min_amplitude, a1 = o.max_amplitude, t0 = std::log(o.min_time), t1 = std::log(o.max_time);
    if (poses())
      for (const Eigen::VectorXd& p : g.poses)
        for (int i = 0; i < p.size(); ++i) x.push_back(std::clamp((p[i] - a0) / (a1 - a0), 0.0, 1.0));
    if (times())
      for (double d : g.durations) x.push_back(std::clamp((std::log(d) - t0) / (t1 - t0), 0.0, 1.0));
    return x;
  }
  control::PoseGraph Decode(const std::vector<double>& x) const {
    control::PoseGraph g = *initial;
    const double a0 = o.min_amplitude, a1 = o.max_amplitude, t0 = std::log(o.min_time), t1 = std::log(o.max_time);
    size_t k = 0;
    if (poses())
      for (Eigen::VectorXd& p : g.poses)
        for (int i = 0; i < p.size(); ++i) p[i] = a0 + std::clamp(x[k++], 0.0, 1.0) * (a1 - a0);
    if (times())
      for (double& d : g.durations) d = std::exp(t0 + std::clamp(x[k++], 0.0, 1.0) * (t1 - t0));
    return g;
  }
};

// The best simulation seen, shared by the copies pagmo makes of the problem, and the
// generation's batch: pagmo 2.18's cmaes asks for one fitness at a time, but draws all λ points
// of a generation before it evaluates any. So a generation runs twice: a copy of the algorithm
// (its adapted state and random engine included) first only records the points it asks for
// (kRecord), they are simulated together (RunTrials: threads and MPI ranks), and the algorithm
// itself then runs the same draws answered from those results (kAnswer). A point not recorded
// is simulated on the spot, so the answer never depends on the trick working.
struct Tally {
  std::mutex mutex;
  long trials = 0;
  double best_cost = 0.0;
  control::PoseGraph best;
  TrialOutcome best_outcome;
  bool any = false;
  enum class Mode { kRecord, kAnswer } mode = Mode::kAnswer;
  std::vector<std::vector<double>> asked;
  std::map<std::vector<double>, TrialOutcome> answers;
};

// pagmo user-defined problem: one forward simulation per fitness evaluation.
struct ControllerProblem {
  const Problem* problem = nullptr;
  Coding coding{};
  std::shared_ptr<Tally> tally;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    {
      std::lock_guard<std::mutex> lock(tally->mutex);
      if (tally->mode == Tally::Mode::kRecord) {
        tally->asked.push_back(x);
        return {0.0};  // a placeholder for the copy that is thrown away
      }
    }
    const control::PoseGraph g = coding.Decode(x);
    TrialOutcome out;
    bool answered = false;
    {
      std::lock_guard<std::mutex> lock(tally->mutex);
      const auto it = tally->answers.find(x);
      if (it != tally->answers.end()) out = it->second, answered = true;
    }
    if (!answered) out = RunTrial(*problem, g);
    Count(g, out);
    return {out.cost};
  }
  void Count(const control::PoseGraph& g, const TrialOutcome& out) const {
    std::lock_guard<std::mutex> lock(tally->mutex);
    ++tally->trials;
    if (!tally->any || out.cost < tally->best_cost) {
      tally->any = true;
      tally->best_cost = out.cost;
      tally->best = g;
      tally->best_outcome = out;
    }
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    const int n = coding.size();
    return {pagmo::vector_double(n, 0.0), pagmo::vector_double(n, 1.0)};
  }
};

// Simulates the points together and files their outcomes as answers.
void Answer(const Problem& p, const Coding& coding, const std::vector<std::vector<double>>& points, int threads,
            Tally* tally) {
  std::vector<control::PoseGraph> graphs;
  for (const std::vector<double>& x : points) graphs.push_back(coding.Decode(x));
  const std::vector<TrialOutcome> outcomes = RunTrials(p, graphs, threads);
  std::lock_guard<std::mutex> lock(tally->mutex);
  tally->answers.clear();
  for (size_t i = 0; i < points.size(); ++i) tally->answers.emplace(points[i], outcomes[i]);
}

}  // namespace

AnnealResult Cmaes(const Problem& p, const control::PoseGraph& initial, const CmaesOptions& o,
                   const std::function<void(const IterationRecord&)>& on_generation) {
  Coding coding{&initial, o};
  auto tally = std::make_shared<Tally>();
  pagmo::problem prob(ControllerProblem{&p, coding, tally});
  // the start: the initial controller and Gaussian neighbours of it, from the seed
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, o.sigma0);
  pagmo::population pop(prob, 0u, static_cast<unsigned>(o.seed));
  std::vector<std::vector<double>> start{coding.Encode(initial)};
  for (int i = 1; i < o.population; ++i) {
    std::vector<double> x = start[0];
    for (double& v : x) v = std::clamp(v + normal(rng), 0.0, 1.0);
    start.push_back(x);
  }
  Answer(p, coding, start, o.threads, tally.get());
  for (const std::vector<double>& x : start) pop.push_back(x);  // answered, in order
  AnnealResult r;
  r.initial_outcome = tally->answers.at(start[0]);
  auto record = [&](int g, double generation_best) {
    const IterationRecord rec{g, tally->trials, generation_best, tally->best_cost, tally->best_cost, 0.0, true};
    r.history.push_back(rec);
    if (on_generation) on_generation(rec);
  };
  record(0, tally->best_cost);
  // one generation per evolve call, with the adapted state kept between calls (memory = true)
  pagmo::cmaes algo(1u, -1, -1, -1, -1, o.sigma0, 0.0, 0.0, true, true, static_cast<unsigned>(o.seed));
  for (int g = 1; g <= o.generations; ++g) {
    if (InterruptRequested()) {  // between two generations: what is best so far is a result
      r.interrupted = true;
      break;
    }
    const long before = tally->trials;
    if (o.batch_generations) {
      pagmo::cmaes rehearsal = algo;  // same state, same random engine: the same draws
      tally->mode = Tally::Mode::kRecord;
      tally->asked.clear();
      rehearsal.evolve(pop);
      tally->mode = Tally::Mode::kAnswer;
      Answer(p, coding, tally->asked, o.threads, tally.get());
    }
    pop = algo.evolve(pop);
    if (tally->trials == before) break;  // cmaes stopped (converged)
    double generation_best = p.cost.high;
    for (const pagmo::vector_double& f : pop.get_f()) generation_best = std::min(generation_best, f[0]);
    record(g, generation_best);
  }
  r.best = tally->best;
  r.best_outcome = tally->best_outcome;
  r.trials = tally->trials;
  return r;
}

}  // namespace wobble::synth
