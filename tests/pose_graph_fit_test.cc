// Dynamic fit of a pose-graph controller (chapter 5) through the simulation (issue 6): the
// poses and transition times that generated a reference simulated by wobble's World are
// recovered by Ceres with Jet derivatives through StepBody, from a perturbed start; once in
// the air and once standing on the ground (contacts). Simulated annealing (lib/wobble/synth)
// with the same number of simulations is run on the same cost for comparison.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "support/test_bodies.h"
#include "wobble/world/world.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble {
namespace {

constexpr double kWidth = 0.05;  // switch width w of the smoothed pose graph, seconds

// The table with bend and shear active, both squashes passive (the bounding table's set, Fig.
// 5.3), modes ten times stiffer than data/table_modes.def like the synthesis scenes.
std::shared_ptr<const BodyModel> Table() {
  std::vector<DeformationMode> modes = testing::TableModes(4e7, 4e6);
  modes[0].active = modes[1].active = true;
  return std::make_shared<const BodyModel>(testing::TableDef(), modes);
}

control::PoseGraph TrueGraph() {
  control::PoseGraph g;
  g.poses = {(Eigen::VectorXd(2) << 0.2, -0.1).finished(), (Eigen::VectorXd(2) << -0.1, 0.15).finished(),
             (Eigen::VectorXd(2) << 0.05, 0.1).finished()};
  g.durations = {0.4, 0.3, 0.5};
  g.cyclic = true;
  return g;
}

struct Case {
  std::shared_ptr<const BodyModel> body = Table();
  fit::DynamicFitOptions options;
  fit::DynamicParameters truth;
  std::vector<fit::ReferenceFrame> frames;
  std::vector<Eigen::VectorXd> q;  // World's states, every step
  Case(bool ground, int steps) {
    options.world.ground.enabled = ground;
    if (ground) {  // the synthesis scenes' ground (data/bounding_table.wob)
      options.world.ground.stiffness = 45000;
      options.world.ground.normal_damping = 3000;
      options.world.ground.friction_damping = 3000;
      options.world.ground.friction_cap = 0.5;
    }
    options.dt = 0.01;
    options.switch_width = kWidth;
    options.fit_q0 = options.fit_qd0 = options.fit_stiffness = options.fit_damping = false;
    truth.q0 = Eigen::VectorXd::Zero(7);
    truth.q0[1] = ground ? 0.0 : 100.0;
    truth.qd0 = Eigen::VectorXd::Zero(7);
    truth.stiffness = Eigen::VectorXd::Constant(4, 4e7);
    truth.damping = Eigen::VectorXd::Constant(4, 4e6);
    truth.graph = TrueGraph();
    // the reference: World, its pose targets set before every step as the script's simul does
    WorldOptions wo;
    wo.params = options.world;
    wo.dt = options.dt;
    World world(wo);
    world.AddBody(body);
    world.SetState(0, truth.q0, truth.qd0);
    std::vector<double> t = {0};
    q.push_back(truth.q0);
    for (int n = 0; n < steps; ++n) {
      world.SetModeTargets(0, control::SmoothPoseTargets(*body, truth.graph, n * options.dt, kWidth));
      EXPECT_TRUE(world.Step()) << world.status().message;
      t.push_back(world.time());
      q.push_back(world.q(0));
    }
    frames = fit::FramesFromStates(*body, t, q, {}, 2);  // every 2nd step, all 11 mass points
  }
};

fit::DynamicParameters Perturbed(const fit::DynamicParameters& truth, bool times) {
  fit::DynamicParameters p = truth;
  const double dp[3][2] = {{0.05, -0.04}, {-0.03, 0.05}, {0.04, 0.03}};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 2; ++k) p.graph.poses[i][k] += dp[i][k];
  if (times) p.graph.durations = {0.44, 0.27, 0.56};
  return p;
}

TEST(PoseGraphFit, ItsSimulationIsWobbleWorldWithTheController) {
  for (bool ground : {false, true}) {
    Case c(ground, 200);
    std::vector<int> steps;
    for (int i = 0; i <= 200; ++i) steps.push_back(i);
    double worst = 0;
    EXPECT_TRUE(fit::SimulateWithParameters(*c.body, c.options, c.truth, steps, [&](int f, const Eigen::VectorXd& q) {
      worst = std::max(worst, (q - c.q[f]).cwiseAbs().maxCoeff() / (1 + c.q[f].cwiseAbs().maxCoeff()));
    }));
    EXPECT_LT(worst, 1e-9) << "ground " << ground;
  }
}

// The smoothed switch is the pose graph of lib/wobble/control away from the switches.
TEST(PoseGraphFit, SmoothTargetsFollowThePoseGraph) {
  const auto body = Table();
  const control::PoseGraph g = TrueGraph();
  for (double t : {0.0, 0.2, 0.55, 0.95, 1.4, 1.8, 2.6, 3.0}) {
    const Eigen::VectorXd target = control::SmoothPoseTargets(*body, g, t, 1e-3);
    const Eigen::VectorXd hard = control::TargetsFromPose(*body, g.poses[g.PoseAt(t)]);
    EXPECT_LT((target - hard).cwiseAbs().maxCoeff(), 1e-12) << t;
  }
  // half way through the switch at S = 0.4: the mean of the two poses, plus the start of the
  // next switch (S = 0.7, σ(−6)); the one after (S = 1.2, σ(−16) ≈ 1e-7) is below the tolerance
  const Eigen::VectorXd mid = control::SmoothPoseTargets(*body, g, 0.4, kWidth);
  const double sigma6 = 1.0 / (1.0 + std::exp(6.0));
  const Eigen::VectorXd expected = 0.5 * (g.poses[0] + g.poses[1]) + (g.poses[2] - g.poses[1]) * sigma6;
  EXPECT_NEAR(mid[0], expected[0], 1e-6);
  EXPECT_NEAR(mid[1], expected[1], 1e-6);
  EXPECT_EQ(mid[2], 0.0);  // passive modes: target 0
  EXPECT_EQ(mid[3], 0.0);
}

void ExpectRecovered(const fit::DynamicParameters& got, const fit::DynamicParameters& truth, double pose_tol,
                     double time_tol) {
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(got.graph.poses[i][k], truth.graph.poses[i][k], pose_tol) << i << " " << k;
    EXPECT_NEAR(got.graph.durations[i], truth.graph.durations[i], time_tol) << i;
  }
}

// In the air (gravity, no ground): poses and times from a start 0.03-0.05 off in every target
// and 8-12% off in every time. Tolerances: 1e-6 on targets and times (exact data).
TEST(PoseGraphFit, RecoversPosesAndTimesInTheAir) {
  Case c(false, 200);  // 2 s: the graph cycles 1.7 times
  c.options.fit_poses = c.options.fit_times = true;
  const fit::DynamicParameters start = Perturbed(c.truth, true);
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, c.frames, start, c.options);
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  std::cout << r.report.brief_report << "\n" << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
  ExpectRecovered(r.params, c.truth, 1e-6, 1e-6);
  const double start_cost = fit::DynamicCost(*c.body, c.frames, start, c.options);
  EXPECT_GT(start_cost, 1e3);
  // simulated annealing (Fig. 5.2, lib/wobble/synth) on the same cost and budget
  const fit::AnnealingResult sa = fit::AnnealPoseGraph(*c.body, c.frames, start, c.options, r.simulations, 1);
  std::cout << "poses + times, same budget (" << r.simulations << " simulations): start cost " << start_cost
            << ", Ceres " << r.report.final_cost << ", simulated annealing " << sa.cost << std::endl;
  EXPECT_EQ(sa.simulations, r.simulations);
  EXPECT_LT(sa.cost, start_cost);  // annealing does improve ...
  EXPECT_GT(sa.cost, 1e3 * r.report.final_cost + 1e-6);  // ... but far less
}

// Standing on the ground (contacts come and go at the feet): the poses from the same start.
// The cost is only piecewise smooth (a contact starting or ending between iterations), so the
// tolerance is looser: 1e-5 on targets and times.
TEST(PoseGraphFit, RecoversPosesAndTimesOnTheGround) {
  Case c(true, 300);  // 3 s
  c.options.fit_poses = c.options.fit_times = true;
  const fit::DynamicParameters start = Perturbed(c.truth, true);
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, c.frames, start, c.options);
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  std::cout << r.report.brief_report << "\n" << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
  ExpectRecovered(r.params, c.truth, 1e-5, 1e-5);
  const double start_cost = fit::DynamicCost(*c.body, c.frames, start, c.options);
  const fit::AnnealingResult sa = fit::AnnealPoseGraph(*c.body, c.frames, start, c.options, r.simulations, 1);
  std::cout << "on the ground, same budget (" << r.simulations << " simulations): start cost " << start_cost
            << ", Ceres " << r.report.final_cost << ", simulated annealing " << sa.cost << std::endl;
  EXPECT_GT(sa.cost, 1e3 * r.report.final_cost + 1e-6);
}

// The same two fits with the adjoint gradient (issue 18) and Ceres' BFGS line search: the same
// poses and times to the same tolerances as the Jet fits above.
TEST(PoseGraphFit, TheAdjointGradientRecoversPosesAndTimesInTheAirAndOnTheGround) {
  for (bool ground : {false, true}) {
    Case c(ground, ground ? 300 : 200);
    c.options.fit_poses = c.options.fit_times = true;
    c.options.gradient = fit::FitGradient::kAdjoint;
    c.options.max_iterations = 2000;
    const fit::DynamicParameters start = Perturbed(c.truth, true);
    const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*c.body, c.frames, start, c.options);
    ASSERT_TRUE(r.report.usable) << r.report.brief_report;
    std::cout << (ground ? "on the ground: " : "in the air: ") << r.report.brief_report << "\n"
              << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
    ExpectRecovered(r.params, c.truth, ground ? 1e-5 : 1e-6, ground ? 1e-5 : 1e-6);
  }
}

TEST(PoseGraphFit, RejectsTimesWithAHardSwitchAndMissingGraphs) {
  Case c(false, 10);
  c.options.fit_times = true;
  c.options.switch_width = 0;
  EXPECT_THROW(fit::FitDynamicTrajectory(*c.body, c.frames, c.truth, c.options), std::invalid_argument);
  c.options.switch_width = kWidth;
  fit::DynamicParameters none = c.truth;
  none.graph = {};
  EXPECT_THROW(fit::FitDynamicTrajectory(*c.body, c.frames, none, c.options), std::invalid_argument);
  fit::DynamicParameters wrong = c.truth;
  wrong.graph.poses[1] = Eigen::VectorXd::Zero(3);  // 3 targets for 2 active modes
  EXPECT_THROW(fit::FitDynamicTrajectory(*c.body, c.frames, wrong, c.options), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
