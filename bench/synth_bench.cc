// Motion-synthesis throughput (issue 5): bounding-table trials (11 points, 4 modes, 1200 steps
// of 0.01, PD-controlled by a 4-pose graph, as in §5.2) per second on one thread, and a batch
// of 1000 trials on 1 thread and on every core (wall time; the ratio is the parallel speed-up).
// Goal: 1000 trials in under 2 s wall on the 2-core machine. The thesis: 0.12 s CPU per trial.
#include <benchmark/benchmark.h>

#include <fstream>
#include <random>
#include <sstream>
#include <thread>

#include "bounding_table_scene.h"
#include "wobble/script/interpreter.h"
#include "wobble/synth/anneal.h"
#ifdef WOBBLE_HAVE_PAGMO
#include "wobble/synth/cmaes.h"
#endif

namespace wobble {
namespace {

using bench::BoundingTable;

const BoundingTable& Scene(bool three = false) {
  static const BoundingTable scene, scene3("bounding_table3");
  return three ? scene3 : scene;
}

// 1000 random neighbours of the initial controller (fixed seed: the same work every run).
std::vector<control::PoseGraph> Candidates(int n, bool three = false) { return bench::Neighbours(Scene(three).graph, n); }

void BM_BoundingTableTrial(benchmark::State& state) {
  const BoundingTable& s = Scene();
  for (auto _ : state) benchmark::DoNotOptimize(synth::RunTrial(s.problem, s.graph).cost);
  state.SetItemsProcessed(state.iterations());  // trials
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()) * s.problem.steps, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoundingTableTrial)->Unit(benchmark::kMillisecond);

// 1000 trials on `threads` threads (0 = every core), wall time.
void BM_Trials1000(benchmark::State& state) {
  const std::vector<control::PoseGraph> graphs = Candidates(1000);
  const int threads = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(synth::RunTrials(Scene().problem, graphs, threads).size());
  state.SetItemsProcessed(state.iterations() * 1000);
  state.counters["threads"] = threads ? threads : double(std::thread::hardware_concurrency());
}
BENCHMARK(BM_Trials1000)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

// The same for the 3D bounding table (27 points, 4 modes, 1200 steps; issue 15: 1,000 trials
// in under 2 s on both cores).
void BM_Trials1000_3d(benchmark::State& state) {
  const std::vector<control::PoseGraph> graphs = Candidates(1000, true);
  const int threads = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(synth::RunTrials(Scene(true).problem, graphs, threads).size());
  state.SetItemsProcessed(state.iterations() * 1000);
  state.counters["threads"] = threads ? threads : double(std::thread::hardware_concurrency());
}
BENCHMARK(BM_Trials1000_3d)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

#ifdef WOBBLE_HAVE_PAGMO
// CMA-ES on the bounding table (population 8, 20 generations: 168 trials), each generation's
// population simulated together (issue 17) on 1 thread and on every core, wall time.
void BM_Cmaes20(benchmark::State& state) {
  synth::CmaesOptions o;
  o.seed = 4;
  o.generations = 20;
  o.population = 8;
  o.threads = int(state.range(0));
  for (auto _ : state) benchmark::DoNotOptimize(synth::Cmaes(Scene().problem, Scene().graph, o).trials);
  state.counters["threads"] = o.threads ? o.threads : double(std::thread::hardware_concurrency());
}
BENCHMARK(BM_Cmaes20)->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);
#endif

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
