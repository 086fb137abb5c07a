// Trials on MPI ranks (issue 17): run it under mpirun, e.g.
//   mpirun -np 2 --oversubscribe build/bench/mpi_bench --benchmark_out=out/mpi_bench.json
// (as root, with OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1). Without mpirun it
// runs as one rank. Every rank runs the same benchmarks with fixed iteration counts, so that
// they reach the same DistributedMap calls; rank 0 prints.
//
//   BM_Sweep/10000   a sweep of 10,000 bounding-table trials (1200 steps each): first every
//                    rank alone on one thread (the 1-rank baseline, measured in the same run
//                    with every core as busy), then dealt over all ranks, one thread each.
//                    Counters: speed-up and efficiency = T(1 rank) / (ranks x T(all ranks)).
//   BM_CaseOverhead  200,000 items that do no work, dealt over all ranks: the cost of a case
//                    to the machinery (dealing, the result message, rank 0 storing it, the
//                    final broadcast), per case, and the bytes a trial's result takes.
// bench/mpi_scaling_model.py turns these numbers into predicted efficiency at 100 and 1,000
// ranks for a 10^6-trial study.
#include <benchmark/benchmark.h>

#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <random>
#include <sstream>
#include <streambuf>

#include "bounding_table_scene.h"
#include "wobble/core/distribute.h"
#include "wobble/script/interpreter.h"
#include "wobble/synth/anneal.h"
#ifdef WOBBLE_HAVE_MPI
#include "wobble/mpi/mpi_distributor.h"
#endif

namespace wobble {
namespace {

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

void BM_Sweep(benchmark::State& state) {
  static const bench::BoundingTable scene;
  const std::vector<control::PoseGraph> graphs = bench::Neighbours(scene.graph, int(state.range(0)));
  Distributor& everywhere = CurrentDistributor();
  const int ranks = everywhere.ranks();
  double alone = 0, all = 0;
  for (auto _ : state) {
    InstallDistributor(nullptr);  // the baseline: this rank alone, one thread
    auto start = std::chrono::steady_clock::now();
    const std::vector<synth::TrialOutcome> a = synth::RunTrials(scene.problem, graphs, 1);
    alone = Seconds(start);
    InstallDistributor(&everywhere == &LocalDistributor() ? nullptr : &everywhere);
    start = std::chrono::steady_clock::now();
    const std::vector<synth::TrialOutcome> b = synth::RunTrials(scene.problem, graphs, 1);
    all = Seconds(start);
    state.SetIterationTime(all);
    for (size_t i = 0; i < a.size(); ++i)
      if (a[i].cost != b[i].cost) state.SkipWithError("a trial's cost differs between 1 rank and all ranks");
  }
  state.counters["ranks"] = ranks;
  state.counters["t_1rank_s"] = alone;
  state.counters["t_all_s"] = all;
  state.counters["speedup"] = alone / all;
  state.counters["efficiency"] = alone / (double(ranks) * all);
  state.counters["trial_ms"] = 1e3 * alone / double(graphs.size());
  state.SetItemsProcessed(int64_t(graphs.size()) * state.iterations());
}
BENCHMARK(BM_Sweep)->Arg(10000)->Iterations(1)->UseManualTime()->Unit(benchmark::kSecond);

void BM_CaseOverhead(benchmark::State& state) {
  const size_t n = size_t(state.range(0));
  // a result the size of a trial's
  const Bytes result = synth::EncodeTrialOutcome(synth::TrialOutcome{true, 1.0, 2.0, 3.0, 4.0, ""});
  MapOptions one_thread;
  one_thread.threads = 1;
  double total = 0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(DistributedMap(n, one_thread, [&](size_t) { return result; }).size());
    const double t = Seconds(start);
    total += t;
    state.SetIterationTime(t);
  }
  state.counters["ranks"] = CurrentDistributor().ranks();
  state.counters["result_bytes"] = double(result.size());
  state.counters["ns_per_case"] = 1e9 * total / (double(n) * double(state.iterations()));
}
BENCHMARK(BM_CaseOverhead)->Arg(200000)->Iterations(3)->UseManualTime()->Unit(benchmark::kMillisecond);

class NullBuffer : public std::streambuf {
 protected:
  int overflow(int c) override { return c; }
};

}  // namespace
}  // namespace wobble

int main(int argc, char** argv) {
#ifdef WOBBLE_HAVE_MPI
  std::unique_ptr<wobble::mpi::MpiDistributor> mpi;
  if (wobble::mpi::LaunchedByMpirun()) mpi = std::make_unique<wobble::mpi::MpiDistributor>(&argc, &argv);
#endif
  static wobble::NullBuffer null;  // static: std::cout flushes it at exit, after main returned
  std::vector<char*> args(argv, argv + argc);
  std::string quiet = "--benchmark_out=/dev/null";
  if (!wobble::IsOutputRank()) {  // the other ranks compute their share and print nothing
    std::cout.rdbuf(&null);
    std::cerr.rdbuf(&null);
    for (char*& a : args)
      if (std::string(a).rfind("--benchmark_out=", 0) == 0) a = quiet.data();
  }
  int count = int(args.size());
  benchmark::Initialize(&count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
