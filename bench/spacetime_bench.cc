// The hop of issue 18 (tests/support/table_hop.h: the table standing on the synthesis scenes'
// ground, 84 knot targets) solved three ways on the same cost — control energy plus the task
// — in one run: the spacetime fit (L-BFGS on the adjoint gradient), and pagmo2's CMA-ES and
// simulated annealing on the cost alone, within the same bounds, from the same zero targets.
// Counters: cost (the best found), simulations (cost evaluations; a gradient counts as one
// evaluation and costs 1.6-3.6 simulations, README).
#include <benchmark/benchmark.h>

#include <pagmo/algorithms/cmaes.hpp>
#include <pagmo/algorithms/simulated_annealing.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>

#include <random>

#include "support/table_hop.h"

namespace wobble {
namespace {

// The spacetime cost of knots (modes × knots, column-major): fit::SpacetimeCostOf.
struct HopCost {
  const BodyModel* body;
  fit::SpacetimeProblem problem;
  double operator()(const double* x) const {
    const Eigen::MatrixXd knots = Eigen::Map<const Eigen::MatrixXd>(x, problem.lower.size(), problem.knots);
    const double c = fit::SpacetimeCostOf(*body, problem, knots);
    return std::isfinite(c) ? c : 1e30;
  }
};

// pagmo's user-defined problem: the knots within the targets' bounds.
struct HopProblem {
  HopCost cost;
  long* evaluations = nullptr;
  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    ++*evaluations;
    return {cost(x.data())};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    const size_t n = cost.problem.lower.size() * size_t(cost.problem.knots);
    return {pagmo::vector_double(n, cost.problem.lower[0]), pagmo::vector_double(n, cost.problem.upper[0])};
  }
};

void BM_Hop_Spacetime(benchmark::State& state) {
  const fit::SpacetimeProblem p = testing::TableHop();
  fit::SpacetimeOptions o;
  o.max_iterations = 300;
  fit::SpacetimeResult r;
  for (auto _ : state) r = fit::FitSpacetime(testing::HopTable(), p, o);
  state.counters["cost"] = r.cost;
  state.counters["simulations"] = double(r.gradients);
  state.counters["start_cost"] = r.initial_cost;
}
BENCHMARK(BM_Hop_Spacetime)->Unit(benchmark::kMillisecond);

// A population around the zero targets (σ 0.05, a sixth of the bound), as synth's CMA-ES starts.
pagmo::population StartPopulation(const pagmo::problem& prob, int size, unsigned seed) {
  pagmo::population pop(prob, 0u, seed);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 0.05);
  const size_t n = prob.get_nx();
  pop.push_back(pagmo::vector_double(n, 0.0));
  for (int i = 1; i < size; ++i) {
    pagmo::vector_double x(n);
    for (double& v : x) v = std::clamp(normal(rng), -0.3, 0.3);
    pop.push_back(x);
  }
  return pop;
}

// CMA-ES, population 16, for the given number of generations.
void BM_Hop_Cmaes(benchmark::State& state) {
  long evaluations = 0;
  const pagmo::problem prob(HopProblem{{&testing::HopTable(), testing::TableHop()}, &evaluations});
  double best = 0;
  for (auto _ : state) {
    evaluations = 0;
    pagmo::population pop = StartPopulation(prob, 16, 1u);
    pagmo::cmaes algo(unsigned(state.range(0)), -1, -1, -1, -1, 0.05, 0.0, 0.0, false, true, 1u);
    pop = algo.evolve(pop);
    best = pop.champion_f()[0];
  }
  state.counters["cost"] = best;
  state.counters["simulations"] = double(evaluations);
}
BENCHMARK(BM_Hop_Cmaes)->Arg(25)->Arg(250)->ArgName("generations")->Unit(benchmark::kMillisecond)->Iterations(1);

// Simulated annealing (Corana's, pagmo): 10 temperatures from 100 to 0.01, bin × 84 moves
// each, from the zero targets.
void BM_Hop_Annealing(benchmark::State& state) {
  long evaluations = 0;
  const pagmo::problem prob(HopProblem{{&testing::HopTable(), testing::TableHop()}, &evaluations});
  double best = 0;
  for (auto _ : state) {
    evaluations = 0;
    pagmo::population pop = StartPopulation(prob, 1, 1u);
    pagmo::simulated_annealing algo(100.0, 0.01, 10u, 1u, unsigned(state.range(0)), 0.1, 1u);
    pop = algo.evolve(pop);
    best = pop.champion_f()[0];
  }
  state.counters["cost"] = best;
  state.counters["simulations"] = double(evaluations);
}
BENCHMARK(BM_Hop_Annealing)->Arg(1)->Arg(10)->ArgName("bin")->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
