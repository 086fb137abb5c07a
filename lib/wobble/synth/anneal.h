// Motion synthesis (Faloutsos 1995, §5.1–5.2): a pose-graph controller is refined by
// simulated annealing (Fig. 5.2) over its poses, its transition times, or both; each candidate
// is judged by a forward simulation and a cost function of Table 5.1.
//
// Reproducible: a run is a function of the seed alone. Candidates are drawn sequentially from
// one generator; each iteration draws `batch` neighbours of the current controller, simulates
// them in parallel (std::thread, all cores by default), keeps the cheapest, and applies the
// acceptance rule of Fig. 5.2 to it. With batch = 1 this is exactly Fig. 5.2; the result never
// depends on the number of threads, only on the seed and the options.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "wobble/control/control.h"
#include "wobble/world/world.h"

namespace wobble::synth {

// Cost functions of Table 5.1; E is the control energy consumed over the trial
// (control::ControlEnergy::consumed), q_x the distance travelled along x by the centre of mass
// (end minus start; the body-frame origin tx would count a mere tilt as travel), q̇_x the
// centre of mass' x velocity at the end. A trial that went backwards (q_x ≤ 0) or whose
// q_x q̇_x < 0 (the thesis' rule), or whose simulation stopped, gets the cost `high`.
enum class CostKind {
  kInverseDistance,               // 1 / q_x                          (hopping, unrealistic jumps)
  kEnergyPerDistance,             // E / q_x                          (hopping, normal jumps)
  kEnergyPerSqrtDistanceSpeed,    // E / (scale √(q_x q̇_x))           (bounding; scale 1e7 or 5e7)
  kEnergyPerSqrtDistance,         // E / (scale √q_x)                 (worm-like motion; scale 5e7)
};
struct CostFunction {
  CostKind kind = CostKind::kEnergyPerSqrtDistanceSpeed;
  double scale = 5e7;
  double high = 1e10;
};
std::string CostKindName(CostKind kind);
bool ParseCostKind(const std::string& text, CostKind* kind);

struct TrialOutcome {
  bool ok = false;        // the simulation ran to the end
  double distance = 0.0;  // q_x
  double speed = 0.0;     // q̇_x at the end
  double energy = 0.0;    // consumed control energy
  double cost = 0.0;
  std::string failure;    // why the simulation stopped, when it did
};
double EvaluateCost(const CostFunction& cost, const TrialOutcome& outcome);

// One synthesis problem: a body with its active modes, the world, the start state, the trial
// length and the cost.
struct Problem {
  // The body, 2D or 3D (issue 15): body<Dim>() is null for the other dimension. A 3D body's q0
  // and qd0 follow the scripts' convention, q = (t, rotation vector, γ) and q̇ = (ṫ, body ω, γ̇);
  // the travel is measured along world x all the same.
  template <int Dim> const std::shared_ptr<const BodyModelN<Dim>>& body() const { return std::get<Dim - 2>(bodies_); }
  template <int Dim> void set_body(std::shared_ptr<const BodyModelN<Dim>> body) {
    bodies_ = {};  // one body: setting one clears the other
    std::get<Dim - 2>(bodies_) = std::move(body);
  }
  int dim() const { return body<3>() ? 3 : 2; }
  WorldOptions world;
  Eigen::VectorXd q0, qd0;
  long steps = 1200;  // forward simulation per trial (thesis: 1200 steps of 0.01)
  CostFunction cost;
  // When set, a trial's cost is this function of the controller instead of a World run judged by
  // `cost` (e.g. the dynamic fit's distance to a reference trajectory, lib/wobble/fit), so the
  // same annealer can be compared with other optimisers on their problem. Must be thread-safe.
  std::function<double(const control::PoseGraph&)> custom_cost;

 private:
  std::tuple<std::shared_ptr<const BodyModel>, std::shared_ptr<const BodyModelN<3>>> bodies_;
};

// x position and velocity of the body's centre of mass: m x_c = m t + R (c0 + C γ), from the
// mass moments, so its velocity is ṫ + R S (c0 + Cγ) θ̇ / m + R C γ̇ / m.
void CenterOfMassX(const BodyModel& body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double* x, double* v);
// The same for body 0 of a world, 2D or 3D (3D: m x_c = m t + R (c0 + C γ), its velocity
// ṫ + R (ω × (c0 + Cγ) + C γ̇) / m with ω in the body frame).
void CenterOfMassX(const World& world, double* x, double* v);

// Simulates one controller from the problem's start state. Calls on_step(world) after every
// step when given (replays, gait measurements).
TrialOutcome RunTrial(const Problem& problem, const control::PoseGraph& graph,
                      const std::function<void(const World&)>& on_step = nullptr);

// The world of a batch worker: the problem's body added once, its start kept as WorldData;
// every trial puts that data back (World::SetData) and swaps the controller, so a trial copies
// only the data, never the model. Run gives what RunTrial gives, bit for bit.
class TrialWorld {
 public:
  explicit TrialWorld(const Problem& problem);  // the problem must outlive it
  TrialOutcome Run(const control::PoseGraph& graph, const std::function<void(const World&)>& on_step = nullptr);

 private:
  const Problem& problem_;
  World world_;
  WorldData start_;
};

// A trial's outcome as bytes and back, exactly: how trials cross threads and MPI ranks
// (core/distribute.h).
std::string EncodeTrialOutcome(const TrialOutcome& outcome);
TrialOutcome DecodeTrialOutcome(const std::string& bytes);

// Runs the trials on `threads` threads (0: all cores) and, under mpirun, on every rank. Results are in input order. After Ctrl-C
// (core/interrupt.h) the trials not yet started are not run: their failure is
// kInterruptedTrial and their cost the cost's `high` (the caller says it stopped).
inline constexpr const char* kInterruptedTrial = "not run: interrupted (Ctrl-C)";
std::vector<TrialOutcome> RunTrials(const Problem& problem, const std::vector<control::PoseGraph>& graphs,
                                    int threads = 0);

enum class Optimize { kPoses, kTimes, kBoth };
std::string OptimizeName(Optimize what);
bool ParseOptimize(const std::string& text, Optimize* what);

struct AnnealOptions {
  std::uint64_t seed = 1;
  int iterations = 60;          // neighbour batches after the initial trial
  int batch = 1;                // neighbours per iteration (simulated in parallel)
  double initial_temperature = 0.0;  // 0: a tenth of the initial cost
  double cooling = 0.9;         // T ← r T (Fig. 5.2)
  Optimize optimize = Optimize::kBoth;
  double pose_step = 0.1;       // standard deviation of a target's change
  double time_step = 0.15;      // standard deviation of log(transition time)'s change
  double min_amplitude = -1.0, max_amplitude = 1.0;  // thesis: amplitudes in [-1, 1]
  double min_time = 0.05, max_time = 5.0;
  int threads = 0;              // 0: all cores
  // Returns an empty string or what is wrong.
  std::string Validate() const;
};

struct IterationRecord {
  int iteration = 0;      // 0: the initial controller
  long trials = 0;        // simulations so far
  double candidate = 0;   // cost of the best neighbour of this iteration
  double current = 0;     // cost of P after the acceptance step
  double best = 0;        // lowest cost so far
  double temperature = 0;
  bool accepted = false;
};

struct AnnealResult {
  control::PoseGraph best;
  TrialOutcome best_outcome, initial_outcome;
  std::vector<IterationRecord> history;
  long trials = 0;
  bool interrupted = false;  // Ctrl-C ended it early: the best so far, the history so far
};

// Fig. 5.2 from `initial`. on_iteration (optional) sees every record as it is made.
AnnealResult Anneal(const Problem& problem, const control::PoseGraph& initial, const AnnealOptions& options,
                    const std::function<void(const IterationRecord&)>& on_iteration = nullptr);

// Independent restarts: run(k) for k = 0 .. restarts−1 (the same optimisation from seed + k),
// spread over threads and MPI ranks (core/distribute.h; each restart's own trials then run on
// the thread it got). The result is the restart whose best cost is lowest (the first of equal
// ones) with its history; `trials` counts every restart's.
AnnealResult BestOfRestarts(int restarts, const std::function<AnnealResult(int restart)>& run);
// A result as bytes and back, exactly.
std::string EncodeAnnealResult(const AnnealResult& result);
AnnealResult DecodeAnnealResult(const std::string& bytes);

// The history as CSV rows: iteration,trials,candidate,current,best,temperature,accepted.
std::vector<std::string> HistoryHeader();
std::vector<std::vector<double>> HistoryRows(const std::vector<IterationRecord>& history);

// Distance travelled by the centre of mass in each of `cycles` consecutive periods of a cyclic controller, after
// `skip` periods to let the gait settle (a stable periodic gait has equal, positive entries).
std::vector<double> DistancePerCycle(const Problem& problem, const control::PoseGraph& graph, int skip, int cycles);

}  // namespace wobble::synth
