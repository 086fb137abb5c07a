// Recording costs little (issue 13): a script's `simul` against the library's own World step
// loop on the same scene, the same number of steps, in the same run; the ratio of the two
// times is what the interpreter, the scene runtime, its controllers and its recorder add.
//  - Fig. 2's triple pendulum (data/fig2_triple_pendulum.wob, `record 30`): 10⁵ steps of
//    0.001 s (`simul 100`) against World::Step on its scene world with no controller and no
//    recorder. Goal: ratio ≤ 1.2.
//  - The bounding table (data/bounding_table.wob up to its anneal): 10⁴ steps of 0.01 s, every
//    one recorded (the FFD object's runs keep every step for `render` and `output`), against
//    World::Step with the same pose-graph controller and no recorder.
// Run: build/bench/script_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <fstream>
#include <memory>
#include <sstream>

#include "wobble/control/controllers.h"
#include "wobble/script/interpreter.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

const std::string kData = wobble::test_env::DataDir();

// A script run up to (not including) its first `simul`, `render` or `anneal`.
struct ScriptUpToSimul {
  explicit ScriptUpToSimul(const std::string& name) : interp(sink) {
    const std::string path = kData + "/" + name;
    std::ifstream f(path);
    std::string line;
    for (int n = 1; std::getline(f, line); ++n) {
      std::istringstream words(line.substr(0, line.find('#')));
      std::string first;
      words >> first;
      if (first == "simul" || first == "render" || first == "anneal") break;
      interp.RunLine(line, path, n, kData);
    }
  }
  std::ostringstream sink;
  script::Interpreter interp;
};

constexpr long kPendulumSteps = 100000;  // simul 100 at dt 0.001

void BM_Fig2ScriptSimul(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    ScriptUpToSimul s("fig2_triple_pendulum.wob");
    state.ResumeTiming();
    s.interp.RunLine("simul 100", "<bench>", 1, kData);
    benchmark::DoNotOptimize(s.interp.scene().world().time());
    state.counters["frames"] = double(s.interp.scene().recorded()->size());
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()) * kPendulumSteps, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Fig2ScriptSimul)->Unit(benchmark::kMillisecond);

void BM_Fig2WorldStepLoop(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    ScriptUpToSimul s("fig2_triple_pendulum.wob");
    World& world = s.interp.scene().world();  // the scene's world, bare: no behaviours, no recorder
    world.ClearControllers();
    world.SetRecorder(nullptr);
    state.ResumeTiming();
    for (long n = 0; n < kPendulumSteps; ++n)
      if (!world.Step()) state.SkipWithError(world.status().message.c_str());
    benchmark::DoNotOptimize(world.time());
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()) * kPendulumSteps, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Fig2WorldStepLoop)->Unit(benchmark::kMillisecond);

constexpr long kTableSteps = 10000;  // simul 100 at dt 0.01

void BM_BoundingTableScriptSimul(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    ScriptUpToSimul s("bounding_table.wob");
    state.ResumeTiming();
    s.interp.RunLine("simul 100", "<bench>", 1, kData);
    benchmark::DoNotOptimize(s.interp.scene().last_object_run()->size());
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()) * kTableSteps, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoundingTableScriptSimul)->Unit(benchmark::kMillisecond);

void BM_BoundingTableWorldStepLoop(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    ScriptUpToSimul s("bounding_table.wob");
    const scene::SimulationSetup setup = s.interp.scene().CurrentSetup();
    World world(setup.world);
    world.AddBody(setup.body);
    world.SetState(0, setup.q, setup.qd);
    world.AddController(std::make_shared<control::PoseGraphController>(world, 0, setup.graph));
    state.ResumeTiming();
    for (long n = 0; n < kTableSteps; ++n)
      if (!world.Step()) state.SkipWithError(world.status().message.c_str());
    benchmark::DoNotOptimize(world.time());
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()) * kTableSteps, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BoundingTableWorldStepLoop)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
