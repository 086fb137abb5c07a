// Spacetime control fits (lib/wobble/fit/spacetime.h, issue 18): the PD targets of a whole
// motion found by L-BFGS on the adjoint gradient, within bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>

#include "support/table_hop.h"
#include "support/test_bodies.h"
#include "wobble/fit/spacetime.h"
#include "wobble/fit/targets.h"

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
  r.start.q = Eigen::VectorXd::Zero(kNq);
  r.start.q[1] = 100.0;
  r.start.qd = Eigen::VectorXd::Zero(kNq);
  // the bend's generalized mass is ~1.2e7 (550 kg moving up to 150): K = 4e8 gives it a period
  // of ~0.8 s, damped at about a fifth of critical
  r.stiffness = Eigen::VectorXd::Constant(kModes, 4e8);
  r.damping = Eigen::VectorXd::Constant(kModes, 4e7);
  r.targets = Eigen::MatrixXd::Zero(kModes, steps);
  p.knots = knots;
  p.lower = Eigen::VectorXd::Constant(kModes, -upper);
  p.upper = Eigen::VectorXd::Constant(kModes, upper);
  p.control_weight = 1e-2;  // small beside the task: the optimum misses the goal by ~1e-4
  p.task = [goal, steps](int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) {
    if (n != steps) return 0.0;
    const Eigen::VectorXd q = s.q, qd = s.qd;
    const double miss = q[3] - goal, w = 1e4;
    (*dz)[3] += 2.0 * w * miss;        // z = (q, q̇)
    dz->tail(kNq) += 2.0 * w * qd;
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
  fit::RolloutCost(Table(), run, [&](int n, const BodyState<2, double>& s, Eigen::VectorXd*) {
    const Eigen::VectorXd q = s.q, qd = s.qd;
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

// A 2D stage cost at (q, q̇), its gradient added to *dq and *dqd (the halves of its z).
double CallAt(const fit::StageCost& term, int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
              Eigen::VectorXd* dq, Eigen::VectorXd* dqd) {
  Eigen::VectorXd dz(2 * q.size());
  dz << *dq, *dqd;
  const double value = term(n, StateFromCoordinates<2>(q, qd), &dz);
  *dq = dz.head(q.size());
  *dqd = dz.tail(q.size());
  return value;
}

// The ready-made task terms' gradients against central differences of their values.
TEST(Spacetime, TaskTermsHaveTheirExactGradients) {
  const BodyModel& body = testing::HopTable();
  fit::Axes only_y;
  only_y.x = false;
  const std::vector<fit::StageCost> terms = {
      fit::CentreOfMassAt(body, 3, {10.0, 80.0}, 2.0), fit::CentreOfMassAt(body, 3, {10.0, 80.0}, 2.0, only_y),
      fit::UprightAt<2>(3, 5.0, 0.3), fit::StillAt<2>(3, 0.7), fit::CentreOfMassVelocityAt(body, 3, {1.0, -2.0}, 3.0),
      fit::CentreOfMassVelocityAt(body, 3, {0.0, 0.0}, 3.0, only_y),
      fit::SumOf({fit::UprightAt<2>(3, 1.0), fit::CentreOfMassAt(body, 3, {0.0, 50.0}, 1.0)})};
  Eigen::VectorXd q(7), qd(7);
  q << 3.0, 70.0, 0.4, 0.1, -0.2, 0.15, 0.05;
  qd << 1.0, -2.0, 0.5, 0.3, 0.2, -0.1, 0.4;
  for (size_t t = 0; t < terms.size(); ++t) {
    Eigen::VectorXd dq = Eigen::VectorXd::Zero(7), dqd = Eigen::VectorXd::Zero(7), scratch = dq, scratch2 = dq;
    EXPECT_EQ(CallAt(terms[t], 2, q, qd, &scratch, &scratch2), 0.0) << "another step adds nothing";
    EXPECT_TRUE(scratch.isZero(0.0) && scratch2.isZero(0.0));
    const double value = CallAt(terms[t], 3, q, qd, &dq, &dqd);
    EXPECT_GT(value, 0.0);
    auto at = [&](const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
      Eigen::VectorXd g1 = Eigen::VectorXd::Zero(7), g2 = g1;
      return CallAt(terms[t], 3, a, b, &g1, &g2);
    };
    for (int i = 0; i < 7; ++i) {
      const double h = 1e-6;
      Eigen::VectorXd e = Eigen::VectorXd::Zero(7);
      e[i] = h;
      const double cd_q = (at(q + e, qd) - at(q - e, qd)) / (2 * h), cd_qd = (at(q, qd + e) - at(q, qd - e)) / (2 * h);
      EXPECT_NEAR(dq[i], cd_q, 1e-6 * (1.0 + std::abs(cd_q))) << "term " << t << " q" << i;
      EXPECT_NEAR(dqd[i], cd_qd, 1e-6 * (1.0 + std::abs(cd_qd))) << "term " << t << " qdot" << i;
    }
  }
  EXPECT_THROW(fit::UprightAt<2>(-1, 1.0), std::invalid_argument);
  EXPECT_THROW(fit::StillAt<2>(1, -1.0), std::invalid_argument);
  EXPECT_THROW(fit::CentreOfMassAt(body, 1, {NAN, 0.0}, 1.0), std::invalid_argument);
}

// A hop from a standing start (tests/support/table_hop.h): from zero targets the table stands
// still; the fitted targets make it leave the ground. At 0.7 s its centre of mass is within
// 0.05 of 2 above its rest height and every mass point is clear of the ground, and it comes
// down upright.
TEST(Spacetime, FindsAHopFromAStandingStart) {
  const fit::SpacetimeProblem p = testing::TableHop(2.0);
  const BodyModel& body = testing::HopTable();
  fit::SpacetimeOptions o;
  o.max_iterations = 300;
  const fit::SpacetimeResult r = fit::FitSpacetime(body, p, o);
  ASSERT_TRUE(r.ok) << r.message;
  std::cout << r.message << ", " << r.gradients << " gradients, cost " << r.initial_cost << " -> " << r.cost
            << ", control energy " << r.control_energy << "\nknots (bend, shear, vsquash, hsquash):\n"
            << r.knots << std::endl;
  const double rest_height = body.moments().c0.y() / body.moments().m;
  double height = 0, lowest = 0, end_angle = 1;
  fit::ControlledRollout run = p.rollout;
  run.targets = r.targets;
  fit::RolloutCost(body, run, [&](int n, const BodyState<2, double>& s, Eigen::VectorXd*) {
    const Eigen::VectorXd q = s.q;
    if (n == testing::kHopPeak) {
      const Eigen::Vector2d c = (body.moments().c0 + body.moments().C * q.tail(4)) / body.moments().m;
      height = q[1] + (Eigen::Rotation2Dd(q[2]) * c).y();
      lowest = std::numeric_limits<double>::infinity();
      for (int k = 0; k < body.num_points(); ++k)
        lowest = std::min(lowest, fit::PointPosition(fit::BasisOf(body, k, {}), q.data(), 7).y());
    }
    if (n == testing::kHopSteps) end_angle = q[2];
    return 0.0;
  });
  EXPECT_NEAR(height - rest_height, 2.0, 0.05);
  EXPECT_GT(lowest, 0.5) << "every mass point is in the air";
  EXPECT_LT(std::abs(end_angle), 0.01);
  EXPECT_GT(r.initial_cost, 1e3 * r.cost);  // zero targets: the table just stands
}

// Multi-start (SpacetimeOptions::starts): every start is seeded by its index, so one thread and
// two give the same fit bit for bit; start 0 is the plain fit; the winner is the lowest final
// cost, and its cost is the cost of its knots.
TEST(Spacetime, MultiStartRepeatsOnAnyThreadCountAndKeepsTheBest) {
  const fit::SpacetimeProblem p = testing::TableHop(2.0);
  const BodyModel& body = testing::HopTable();
  fit::SpacetimeOptions o;
  o.max_iterations = 40;
  const fit::SpacetimeResult single = fit::FitSpacetime(body, p, o);
  o.starts = 5;
  o.threads = 1;
  int reports = 0;
  o.on_start = [&](int done, int starts, double) {
    EXPECT_EQ(starts, 5);
    EXPECT_EQ(done, ++reports);
  };
  const fit::SpacetimeResult one = fit::FitSpacetime(body, p, o);
  EXPECT_EQ(reports, 5);
  o.on_start = nullptr;
  o.threads = 2;
  const fit::SpacetimeResult two = fit::FitSpacetime(body, p, o);
  ASSERT_TRUE(one.ok && two.ok && single.ok);
  ASSERT_EQ(one.start_costs.size(), 5u);
  EXPECT_EQ(one.start_costs, two.start_costs);
  EXPECT_EQ(one.best_start, two.best_start);
  EXPECT_TRUE(one.knots == two.knots);
  EXPECT_EQ(one.start_costs[0], single.cost);
  EXPECT_EQ(one.initial_cost, single.initial_cost);
  for (int k = 0; k < 5; ++k) EXPECT_LE(one.cost, one.start_costs[k]) << "start " << k;
  EXPECT_EQ(one.cost, one.start_costs[one.best_start]);
  EXPECT_NEAR(fit::SpacetimeCostOf(body, p, one.knots), one.cost, 1e-9 * one.cost);
  EXPECT_LE(one.knots.maxCoeff(), 0.3);
  EXPECT_GE(one.knots.minCoeff(), -0.3);
  // another seed perturbs differently
  o.seed = 2;
  const fit::SpacetimeResult other = fit::FitSpacetime(body, p, o);
  EXPECT_EQ(other.start_costs[0], one.start_costs[0]);
  EXPECT_NE(other.start_costs[1], one.start_costs[1]);
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
