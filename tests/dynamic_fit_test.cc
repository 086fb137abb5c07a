// Dynamic trajectory fit: the parameters (initial state, mode stiffness and damping) that
// generated a reference simulated by wobble's World are recovered by Ceres through Jet
// simulations; its simulation is checked against World first.
#include <gtest/gtest.h>

#include <iostream>

#include "support/test_bodies.h"
#include "wobble/world/world.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble {
namespace {

// Table modes with different stiffness and damping each (the truth to recover).
std::vector<DeformationMode> TrueModes() {
  std::vector<DeformationMode> modes = testing::TableModes();
  const double K[4] = {2e6, 3e6, 1.5e6, 4e6}, c[4] = {2e5, 1e5, 3e5, 5e4};
  for (int d = 0; d < 4; ++d) {
    modes[d].stiffness = K[d];
    modes[d].damping = c[d];
  }
  return modes;
}

struct Case {
  std::shared_ptr<const BodyModel> body = std::make_shared<const BodyModel>(testing::TableDef(), TrueModes());
  fit::DynamicFitOptions options;
  fit::DynamicParameters truth;
  std::vector<double> t;
  std::vector<Eigen::VectorXd> q;
  Case(int steps) {
    options.world.ground.enabled = false;
    options.dt = 0.01;
    truth.q0.resize(7);
    truth.qd0.resize(7);
    truth.q0 << 0, 100, 0.1, 0.2, -0.1, 0.1, 0.05;
    truth.qd0 << 30, 60, 1.0, 0.5, -0.8, 0.6, 0.4;
    truth.stiffness.resize(4);
    truth.damping.resize(4);
    for (int d = 0; d < 4; ++d) {
      truth.stiffness[d] = body->modes()[d].stiffness;
      truth.damping[d] = body->modes()[d].damping;
    }
    WorldOptions wo;
    wo.params = options.world;
    wo.dt = options.dt;
    wo.integrator = Integrator::kThesis;
    World world(wo);
    world.AddBody(body);
    world.SetState(0, truth.q0, truth.qd0);
    t.push_back(0);
    q.push_back(truth.q0);
    for (int i = 0; i < steps; ++i) {
      EXPECT_TRUE(world.Step());
      t.push_back(world.time());
      q.push_back(world.q(0));
    }
  }
};

TEST(DynamicFit, ItsSimulationIsWobbleWorld) {
  Case c(100);
  std::vector<int> steps;
  for (int i = 0; i <= 100; ++i) steps.push_back(i);
  int frames = 0;
  EXPECT_TRUE(fit::SimulateWithParameters(*c.body, c.options, c.truth, steps, [&](int f, const Eigen::VectorXd& q) {
    ++frames;
    for (int i = 0; i < 7; ++i) EXPECT_NEAR(q[i], c.q[f][i], 1e-9 * (1 + std::abs(c.q[f][i]))) << f << " " << i;
  }));
  EXPECT_EQ(frames, 101);
}

// The start: stiffness x1.4, damping x0.6, and a perturbed initial state.
fit::DynamicParameters Perturbed(const fit::DynamicParameters& truth) {
  fit::DynamicParameters p = truth;
  p.stiffness *= 1.4;
  p.damping *= 0.6;
  p.q0 += (Eigen::VectorXd(7) << 2, -1, 0.01, 0.02, -0.02, 0.01, 0.02).finished();
  p.qd0 += (Eigen::VectorXd(7) << -3, 2, 0.1, 0.1, 0.1, -0.1, 0.1).finished();
  return p;
}

// K within 1e-5, c 1e-4, q0 1e-6, q̇0 1e-5 of the truth, and the reference's points to 1e-5.
void ExpectTruth(const fit::DynamicFitResult& r, const Case& c) {
  for (int d = 0; d < 4; ++d) {
    EXPECT_NEAR(r.params.stiffness[d] / c.truth.stiffness[d], 1.0, 1e-5) << d;
    EXPECT_NEAR(r.params.damping[d] / c.truth.damping[d], 1.0, 1e-4) << d;
  }
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(r.params.q0[i], c.truth.q0[i], 1e-6) << i;
    EXPECT_NEAR(r.params.qd0[i], c.truth.qd0[i], 1e-5) << i;
  }
  EXPECT_LT(r.rms_residual, 1e-5);
}

TEST(DynamicFit, RecoversTheParametersThatGeneratedTheReference) {
  Case c(100);  // 1 s
  const std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*c.body, c.t, c.q, {}, 2);  // every 2nd step
  const fit::DynamicParameters start = Perturbed(c.truth);
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, frames, start, c.options);
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  std::cout << r.report.brief_report << "\n" << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
  ExpectTruth(r, c);
  // the start was far off: the fit did the work
  EXPECT_GT(fit::DynamicCost(*c.body, frames, start, c.options), 1e3);

  // simulated annealing with the same number of simulations gets nowhere near
  const fit::AnnealingResult sa = fit::AnnealDynamicTrajectory(*c.body, frames, start, c.options, r.simulations, 1);
  std::cout << "same budget (" << r.simulations << " simulations): Ceres cost " << r.report.final_cost
            << ", simulated annealing cost " << sa.cost << std::endl;
  EXPECT_EQ(sa.simulations, r.simulations);
  EXPECT_GT(sa.cost, 1e3 * r.report.final_cost + 1e-6);
}

// The same fit with the adjoint gradient (issue 18) and Ceres' L-BFGS: the same parameters to
// the same tolerances as the Jet fit above.
TEST(DynamicFit, TheAdjointGradientRecoversTheSameParameters) {
  Case c(100);
  const std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*c.body, c.t, c.q, {}, 2);
  const fit::DynamicParameters start = Perturbed(c.truth);
  fit::DynamicFitOptions o = c.options;
  o.gradient = fit::FitGradient::kAdjoint;
  o.max_iterations = 2000;
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, frames, start, o);
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  std::cout << r.report.brief_report << "\n" << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
  ExpectTruth(r, c);
}

TEST(DynamicFit, EstimatesTheInitialStateFromTheFirstFrames) {
  Case c(60);
  const std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*c.body, c.t, c.q, {});
  fit::DynamicParameters start;  // q0, q̇0 from pose fits; K, c from the body's modes ...
  fit::DynamicFitOptions o = c.options;
  o.fit_stiffness = o.fit_damping = false;  // ... and kept: only the initial state is fitted
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, frames, start, o);
  ASSERT_TRUE(r.report.usable);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(r.params.qd0[i], c.truth.qd0[i], 1e-5) << i;
  for (int d = 0; d < 4; ++d) EXPECT_NEAR(r.params.stiffness[d] / c.truth.stiffness[d], 1.0, 1e-14);  // exp(log K)
}

TEST(DynamicFit, RejectsFramesOffTheStepGridAndBadStarts) {
  Case c(10);
  std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*c.body, c.t, c.q, {});
  frames[3].time += 0.004;
  EXPECT_THROW(fit::FitDynamicTrajectory(*c.body, frames, c.truth, c.options), std::invalid_argument);
  frames = fit::FramesFromStates(*c.body, c.t, c.q, {});
  fit::DynamicParameters bad = c.truth;
  bad.stiffness[1] = 0;
  EXPECT_THROW(fit::FitDynamicTrajectory(*c.body, frames, bad, c.options), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
