// Spacetime control fits (lib/wobble/fit/spacetime.h, issue 18): the PD targets of a whole
// motion found by L-BFGS on the adjoint gradient, within bounds.
#include <gtest/gtest.h>

#include <cmath>

#include "support/test_bodies.h"
#include "wobble/fit/spacetime.h"

namespace wobble {
namespace {

constexpr int kNq = 7, kModes = 4;

// The table at rest in the air, gravity off: the task is to hold the bend at `goal` and be
// still at the last step, from targets that start at zero.
fit::SpacetimeProblem BendAtTheEnd(double goal, double upper, int steps, int knots) {
  fit::SpacetimeProblem p;
  fit::ControlledRollout& r = p.rollout;
  r.world.gravity_on = false;
  r.world.ground.enabled = false;
  r.integrator = Integrator::kSymplecticEuler;
  r.dt = 0.005;
  r.q0 = Eigen::VectorXd::Zero(kNq);
  r.q0[1] = 100.0;
  r.qd0 = Eigen::VectorXd::Zero(kNq);
  // the bend's generalized mass is ~1.2e7 (550 kg moving up to 150): K = 4e8 gives it a period
  // of ~0.8 s, damped at about a fifth of critical
  r.stiffness = Eigen::VectorXd::Constant(kModes, 4e8);
  r.damping = Eigen::VectorXd::Constant(kModes, 4e7);
  r.targets = Eigen::MatrixXd::Zero(kModes, steps);
  p.knots = knots;
  p.lower = Eigen::VectorXd::Constant(kModes, -upper);
  p.upper = Eigen::VectorXd::Constant(kModes, upper);
  p.control_weight = 1e-2;  // small beside the task: the optimum misses the goal by ~1e-4
  p.task = [goal, steps](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* dq,
                         Eigen::VectorXd* dqd) {
    if (n != steps) return 0.0;
    const double miss = q[3] - goal, w = 1e4;
    (*dq)[3] += 2.0 * w * miss;
    *dqd += 2.0 * w * qd;
    return w * (miss * miss + qd.squaredNorm());
  };
  return p;
}

const BodyModel& Table() {
  static const BodyModel body(testing::TableDef(), testing::TableModes(4e5, 4e3));
  return body;
}

// The bend at the end of the run with the fitted targets, and its speed.
void EndOf(const fit::SpacetimeProblem& p, const Eigen::MatrixXd& targets, double* bend, double* speed) {
  fit::ControlledRollout run = p.rollout;
  run.targets = targets;
  fit::RolloutCost(Table(), run, [&](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd*,
                                     Eigen::VectorXd*) {
    if (n == run.steps()) {
      *bend = q[3];
      *speed = qd.norm();
    }
    return 0.0;
  });
}

TEST(Spacetime, KnotTargetsInterpolateLinearly) {
  Eigen::MatrixXd knots(1, 3);
  knots << 0.0, 1.0, -1.0;
  const Eigen::MatrixXd t = fit::KnotTargets(knots, 4);  // knots at steps 0, 2, 4
  ASSERT_EQ(t.cols(), 4);
  EXPECT_DOUBLE_EQ(t(0, 0), 0.0);
  EXPECT_DOUBLE_EQ(t(0, 1), 0.5);
  EXPECT_DOUBLE_EQ(t(0, 2), 1.0);
  EXPECT_DOUBLE_EQ(t(0, 3), 0.0);
}

TEST(Spacetime, ReachesTheGoalAtTheEndWithinBounds) {
  const fit::SpacetimeProblem p = BendAtTheEnd(0.2, 0.5, 120, 13);
  int progress_calls = 0;
  fit::SpacetimeOptions o;
  o.on_iteration = [&](int, double) { ++progress_calls; };
  o.max_iterations = 300;
  const fit::SpacetimeResult r = fit::FitSpacetime(Table(), p, o);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_GT(progress_calls, 0);
  // the run with the fitted targets ends at the goal and nearly still
  double end_bend = 0, end_speed = 0;
  EndOf(p, r.targets, &end_bend, &end_speed);
  EXPECT_NEAR(end_bend, 0.2, 2e-3) << r.message << " iterations " << r.iterations << " gradients " << r.gradients;
  EXPECT_LT(end_speed, 0.05);
  EXPECT_LT(r.cost, 1e-2 * r.initial_cost);
  EXPECT_GT(r.control_energy, 0.0);
  EXPECT_LE(r.targets.maxCoeff(), 0.5);
  EXPECT_GE(r.targets.minCoeff(), -0.5);
  RecordProperty("cost", std::to_string(r.initial_cost) + " -> " + std::to_string(r.cost));
  RecordProperty("gradients", std::to_string(r.gradients));
}

// A goal past the bound: the targets never cross it, and the fit beats the best static
// control (the bend's target held at the bound throughout) by using the motion: an
// underdamped PD servo overshoots its target.
TEST(Spacetime, BoundsHoldWhenTheGoalLiesBeyondThem) {
  const fit::SpacetimeProblem p = BendAtTheEnd(0.2, 0.1, 120, 11);
  fit::SpacetimeOptions o;
  o.max_iterations = 300;
  const fit::SpacetimeResult r = fit::FitSpacetime(Table(), p, o);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_LE(r.targets.maxCoeff(), 0.1);
  EXPECT_GE(r.targets.minCoeff(), -0.1);
  fit::ControlledRollout held = p.rollout;
  held.targets.row(0).setConstant(0.1);
  const double held_cost = fit::RolloutCost(Table(), held, p.task) + p.control_weight * held.dt * held.targets.squaredNorm();
  EXPECT_LT(r.cost, 0.5 * held_cost) << r.message;
  double bend = 0, speed = 0;
  EndOf(p, r.targets, &bend, &speed);
  EXPECT_GT(bend, 0.1) << "past the bound of its targets";
}

TEST(Spacetime, RefusesBadProblems) {
  fit::SpacetimeProblem p = BendAtTheEnd(0.2, 0.5, 10, 3);
  p.knots = 1;
  EXPECT_THROW(fit::FitSpacetime(Table(), p), std::invalid_argument);
  p.knots = 12;
  EXPECT_THROW(fit::FitSpacetime(Table(), p), std::invalid_argument);
  p.knots = 3;
  p.lower[2] = 1.0;
  EXPECT_THROW(fit::FitSpacetime(Table(), p), std::invalid_argument);
  p = BendAtTheEnd(0.2, 0.5, 10, 3);
  p.task = nullptr;
  EXPECT_THROW(fit::FitSpacetime(Table(), p), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
