// The adjoint gradient of a rollout against one plain simulation of it (issue 18).
//
// The table (7 coordinates, 4 modes) with a PD target per mode per step: 16, 64, 1,024 and
// 10,000 per-step controls (4 to 2,500 steps of 0.005 s) plus q0, q̇0, K and c. Each case
// times RolloutCost (one plain simulation) and RolloutCostGradient (the gradient with respect
// to every parameter) in the same run: the gradient's cost is the ratio of the two rows with
// the same arguments. In the air (second argument 0) and falling onto the ground (1; contacts
// add 2 inputs per point to each step's differentiation).
// The chair rows (SimulationChair, GradientChair) do the same for the chair of tests/support (about 300
// mass points, 3 modes; 12 + 2·3 state coordinates), controls/3 steps of 0.002 s, falling onto
// a plane in the grounded case; GradientChair's third argument is its checkpoint interval (0: the
// default, the whole run kept within checkpoints.h's budget, else ⌈√steps⌉ checkpoints; -1:
// ⌈√steps⌉ checkpoints; 2^30: the whole run kept at any size), to compare them.
// Run: build/bench/adjoint_bench --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <cmath>

#include "support/test_bodies.h"
#include "wobble/fit/adjoint.h"

namespace wobble {
namespace {

const BodyModel& Table() {
  static const BodyModel body(testing::TableDef(), testing::TableModes(4e5, 2e3));
  return body;
}

fit::ControlledRollout Rollout(int controls, bool grounded) {
  fit::ControlledRollout r;
  r.integrator = Integrator::kThesis;
  r.dt = 0.005;
  r.world.ground.enabled = grounded;
  r.start.q = Eigen::VectorXd::Zero(7);
  r.start.q[1] = grounded ? 5.0 : 200.0;
  r.start.qd = Eigen::VectorXd::Zero(7);
  r.start.qd[0] = 30.0;
  r.stiffness = Eigen::VectorXd::Constant(4, 4e5);
  r.damping = Eigen::VectorXd::Constant(4, 2e3);
  const int steps = controls / 4;
  r.targets.resize(4, steps);
  for (int n = 0; n < steps; ++n)
    for (int d = 0; d < 4; ++d) r.targets(d, n) = 0.05 * std::sin(0.01 * n + d);
  return r;
}

// ½ |x − y|² of the table's top middle point against a fixed goal, every step.
double Stage(int, const BodyState<2, double>& state, Eigen::VectorXd* dz) {
  const VecQ<double>& q = state.q;
  const Eigen::Vector2d goal(400.0, 120.0);
  // the cost of a rigid point (150, 100) of the body frame: x = t + R l
  const double c = std::cos(q[2]), s = std::sin(q[2]);
  const Eigen::Vector2d l(150.0, 100.0), x(q[0] + c * l.x() - s * l.y(), q[1] + s * l.x() + c * l.y());
  const Eigen::Vector2d e = x - goal;
  (*dz)[0] += e.x();
  (*dz)[1] += e.y();
  (*dz)[2] += e.x() * (-s * l.x() - c * l.y()) + e.y() * (c * l.x() - s * l.y());
  return 0.5 * e.squaredNorm();
}

void BM_Simulation(benchmark::State& state) {
  const fit::ControlledRollout r = Rollout(int(state.range(0)), state.range(1) != 0);
  for (auto _ : state) benchmark::DoNotOptimize(fit::RolloutCost(Table(), r, Stage));
  state.counters["controls"] = double(state.range(0));
}

void BM_Gradient(benchmark::State& state) {
  const fit::ControlledRollout r = Rollout(int(state.range(0)), state.range(1) != 0);
  int held = 0;
  for (auto _ : state) {
    const fit::RolloutGradient g = fit::RolloutCostGradient(Table(), r, Stage);
    if (!g.ok) state.SkipWithError(g.message.c_str());
    held = g.states_held;
  }
  state.counters["controls"] = double(state.range(0));
  state.counters["states_held"] = held;
}

const BodyModelN<3>& Chair() {
  static const BodyModelN<3> body = testing::Chair3();
  return body;
}

fit::ControlledRolloutN<3> ChairRollout(int controls, bool grounded) {
  fit::ControlledRolloutN<3> r;
  r.integrator = Integrator::kThesis;
  r.dt = 0.002;
  r.world.ground.enabled = grounded;
  r.world.ground.stiffness = 2e4;  // per point of 1/3 kg
  r.world.ground.normal_damping = 100;
  r.world.ground.friction_damping = 100;
  r.world.ground.friction_cap = 0.3;
  r.start = RestState<3, double>(Chair());
  r.start.translation().y() = grounded ? 3.0 : 200.0;
  r.start.qd[0] = 30.0;
  r.stiffness = Eigen::VectorXd::Constant(3, 2e4);
  r.damping = Eigen::VectorXd::Constant(3, 200);
  const int steps = (controls + 2) / 3;
  r.targets.resize(3, steps);
  for (int n = 0; n < steps; ++n)
    for (int d = 0; d < 3; ++d) r.targets(d, n) = 0.05 * std::sin(0.01 * n + d);
  return r;
}

// ½ |x − y|² of a rigid point l of the chair's frame against a fixed goal, every step:
// x = t + R l, so ∂/∂δt = e and ∂/∂ε = l × Rᵀe.
double ChairStage(int, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
  const Eigen::Vector3d goal(400.0, 120.0, 50.0), l(50.0, 50.0, 30.0);
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  const Eigen::Vector3d e = s.translation() + R * l - goal;
  dz->head<3>() += e;
  dz->segment<3>(3) += l.cross(R.transpose() * e);
  return 0.5 * e.squaredNorm();
}

void BM_SimulationChair(benchmark::State& state) {
  const fit::ControlledRolloutN<3> r = ChairRollout(int(state.range(0)), state.range(1) != 0);
  for (auto _ : state) benchmark::DoNotOptimize(fit::RolloutCost(Chair(), r, ChairStage));
  state.counters["controls"] = double(3 * r.steps());
}

void BM_GradientChair(benchmark::State& state) {
  const fit::ControlledRolloutN<3> r = ChairRollout(int(state.range(0)), state.range(1) != 0);
  int held = 0;
  for (auto _ : state) {
    const fit::RolloutGradient g = fit::RolloutCostGradient(Chair(), r, ChairStage, int(state.range(2)));
    if (!g.ok) state.SkipWithError(g.message.c_str());
    held = g.states_held;
  }
  state.counters["controls"] = double(3 * r.steps());
  state.counters["states_held"] = held;
}

BENCHMARK(BM_Simulation)->ArgsProduct({{16, 64, 1024, 10000}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Gradient)->ArgsProduct({{16, 64, 1024, 10000}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SimulationChair)->ArgsProduct({{16, 64, 1024, 10000}, {0, 1}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_GradientChair)
    ->ArgsProduct({{16, 64, 1024, 10000}, {0, 1}, {fit::kCheckpointAuto, fit::kCheckpointSqrt, 1 << 30}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
