// CMA-ES (pagmo2's cmaes) as a second optimiser of pose-graph controllers, on the same problem,
// cost and search space as the annealing of anneal.h, so that the two can be compared on the
// same budget of simulations. Built only when pagmo2 is found (WOBBLE_HAVE_PAGMO).
//
// The search variables are the active targets of every pose (optimize poses/both) and the
// logarithms of the transition times (times/both), each scaled to [0, 1] over its bounds, so that
// sigma0 is a fraction of the range. The population starts at the initial controller and
// `population − 1` Gaussian neighbours of it (same seed, same start); pagmo's cmaes then runs
// one generation per call with its state kept (memory), which gives the cost per generation.
// Reproducible from the seed. Each generation's population is simulated together (RunTrials:
// every thread and, under mpirun, every rank), although pagmo 2.18's cmaes has no batch
// evaluator (cmaes.cc says how), with the same result as one trial after the other.
#pragma once

#include "wobble/synth/anneal.h"

namespace wobble::synth {

struct CmaesOptions {
  std::uint64_t seed = 1;
  int generations = 60;
  int population = 8;
  double sigma0 = 0.1;  // initial step, as a fraction of each variable's range
  int threads = 0;      // a generation's trials on this many threads (0: all cores)
  Optimize optimize = Optimize::kBoth;
  double min_amplitude = -1.0, max_amplitude = 1.0;
  double min_time = 0.05, max_time = 5.0;
  // Each generation's population simulated together (threads, ranks); false: one trial after
  // the other inside pagmo, as before (the tests check both give the same run).
  bool batch_generations = true;
  std::string Validate() const;
};

// Same record and result types as the annealing: history[g] is generation g (0: the initial
// controller); `candidate` is the best of that generation, `current` and `best` the best so far.
AnnealResult Cmaes(const Problem& problem, const control::PoseGraph& initial, const CmaesOptions& options,
                   const std::function<void(const IterationRecord&)>& on_generation = nullptr);

}  // namespace wobble::synth
