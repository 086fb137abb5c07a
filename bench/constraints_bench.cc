// Witkin–Welch constraints (issue 7): cost of a constrained step.
//
//  - the triple pendulum of Fig. 2 (three affine links attached end to end, nailed at the top):
//    steps per second;
//  - hanging chains of N = 10, 100, 1000 attached affine links (2 constraint rows per joint),
//    dense pre-inverted A against the cached sparse LDLT: the cost of one step with A already
//    factored (ChainStep), and the cost of refactoring A after a switch (ChainRefactor);
//  - an FFD table nailed at a corner: A depends on q, factored every step.
// Run: build/bench/constraints_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <memory>

#include "support/test_bodies.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

std::shared_ptr<const LinearBodyModel> Link() {
  static const auto model = std::make_shared<LinearBodyModel>(
      MakeBoxBody("link", 2, LinearOrder::kAffine, Eigen::Vector2d(0.15, 0.5), 3, 1.0));
  return model;
}

// N links in a line straight down from a nail at the origin. Gravity is off for the chains
// and the whole chain turns slowly about the nail instead (ω = 0.05 rad/s, installed by an
// impulse): under gravity the top joints of a 1000-link chain would carry 1000 links' weight,
// far too stiff for soft links at this step. The cost of a step does not depend on the motion.
std::unique_ptr<World> Chain(int links, MultiplierMethod method, int* top_nail, bool gravity = false) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  opt.method = method;
  opt.params.gravity_on = gravity;
  auto world = std::make_unique<World>(opt);
  const AffineMaterial mat{200.0, 200.0, 0.01, 0.0};
  for (int i = 0; i < links; ++i) {
    const int b = world->AddLinearBody(Link(), mat);
    world->SetLinearState(b, Link()->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(0.0, -0.5 - i)),
                          Eigen::MatrixXd::Zero(2, 3));
  }
  *top_nail = world->AddNail(At(0, Eigen::Vector2d(0.0, 0.5)));
  for (int i = 0; i + 1 < links; ++i) world->AddAttachment(At(i, Eigen::Vector2d(0.0, -0.5)), At(i + 1, Eigen::Vector2d(0.0, 0.5)));
  if (!gravity) {
    const MaterialPoint bottom = At(links - 1, Eigen::Vector2d(0.0, -0.5));
    world->ApplyImpulse({{bottom, MaterialPoint(), Eigen::Vector2d(0.05 * links, 0.0)}});
  }
  return world;
}

void BM_TriplePendulum(benchmark::State& state) {
  // under gravity, released horizontal (link i from x = i to i + 1); restarted every 10 s
  auto make = [] {
    int nail;
    auto world = Chain(3, MultiplierMethod::kAuto, &nail, true);
    for (int i = 0; i < 3; ++i)
      world->SetLinearState(i, Link()->PlacedState(Eigen::Rotation2Dd(1.5707963267948966).toRotationMatrix(),
                                                   Eigen::Vector2d(0.5 + i, 0.0)),
                            Eigen::MatrixXd::Zero(2, 3));
    world->SetNailPosition(nail, Eigen::Vector2d::Zero());
    return world;
  };
  auto world = make();
  for (auto _ : state) {
    if (!world->Step()) state.SkipWithError(world->status().message.c_str());
    if (world->steps() == 10000) {
      state.PauseTiming();
      world = make();
      state.ResumeTiming();
    }
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["factorizations"] = double(world->factorizations());
  state.SetLabel(MultiplierMethodName(world->last_method()));
}
BENCHMARK(BM_TriplePendulum);

void BM_ChainStep(benchmark::State& state) {
  const int links = int(state.range(0));
  const auto method = MultiplierMethod(state.range(1));
  int nail;
  auto world = Chain(links, method, &nail);
  if (!world->Step()) state.SkipWithError(world->status().message.c_str());  // factor once, untimed
  for (auto _ : state)
    if (!world->Step()) state.SkipWithError(world->status().message.c_str());
  state.counters["links"] = links;
  state.counters["rows"] = world->constraint_rows();
  state.counters["factorizations"] = double(world->factorizations());
  state.SetLabel(MultiplierMethodName(method));
}
BENCHMARK(BM_ChainStep)
    ->ArgsProduct({{10, 30, 100, 300, 1000}, {int(MultiplierMethod::kSparse)}})
    ->ArgsProduct({{10, 30, 100, 300, 1000}, {int(MultiplierMethod::kDense)}})
    ->Unit(benchmark::kMicrosecond);

// Switching the top nail off and on forces a refactor at the next step: the timed step pays
// for assembling and factoring A (dense: forming Y = A⁻¹; sparse: the LDLT).
void BM_ChainRefactor(benchmark::State& state) {
  const int links = int(state.range(0));
  const auto method = MultiplierMethod(state.range(1));
  int nail;
  auto world = Chain(links, method, &nail);
  if (!world->Step()) state.SkipWithError(world->status().message.c_str());
  for (auto _ : state) {
    world->SetEnabled(nail, false);
    world->SetEnabled(nail, true);
    if (!world->Step()) state.SkipWithError(world->status().message.c_str());
  }
  state.counters["rows"] = world->constraint_rows();
  state.counters["factorizations"] = double(world->factorizations());
  state.SetLabel(MultiplierMethodName(method));
}
BENCHMARK(BM_ChainRefactor)
    ->ArgsProduct({{10, 30, 100, 300, 1000}, {int(MultiplierMethod::kSparse)}})
    ->ArgsProduct({{10, 30, 100, 300, 1000}, {int(MultiplierMethod::kDense)}})
    ->Unit(benchmark::kMicrosecond);

void BM_FfdTableNailed(benchmark::State& state) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 0.005;
  opt.params.ground.enabled = false;
  auto make = [&] {
    auto world = std::make_unique<World>(opt);
    const int table = world->AddBody(std::make_shared<BodyModel>(testing::TableDef(), testing::TableModes(4e6, 1e6)));
    world->AddNail(At(table, Eigen::Vector2d(0.0, 1.0)));
    return world;
  };
  auto world = make();  // restarted every 10000 steps
  for (auto _ : state) {
    if (!world->Step()) state.SkipWithError(world->status().message.c_str());
    if (world->steps() == 10000) {
      state.PauseTiming();
      world = make();
      state.ResumeTiming();
    }
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FfdTableNailed);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
