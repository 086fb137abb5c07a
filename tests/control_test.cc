// Control of active characters (chapter 5, §4.10.1): PD response against the closed form of the
// damped oscillator, control energy against the spring's energy, pose-graph timing and
// periodicity, keyframes with a held point, and the hand-over to simulation.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <cmath>
#include <memory>

#include "support/test_bodies.h"
#include "wobble/control/control.h"
#include "wobble/control/controllers.h"
#include "wobble/control/pulls.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

using testing::TableDef;

WorldOptions FreeSpace(Integrator integrator, double dt) {
  WorldOptions o;
  o.params.gravity_on = false;
  o.params.ground.enabled = false;
  o.integrator = integrator;
  o.dt = dt;
  return o;
}

// Effective mass of mode d for a free body at rest (linearised at q = 0): the rigid coordinates
// move with it, so it is 1 / (M⁻¹)_dd, the Schur complement of M.
double EffectiveMass(const BodyModel& body, int d) {
  MatQ<double> M;
  MassMatrix(body.moments(), VecQ<double>(VecQ<double>::Zero(body.num_q())), &M);
  const Eigen::MatrixXd inv = Eigen::MatrixXd(M).inverse();
  return 1.0 / inv(kRigidDofs + d, kRigidDofs + d);
}

struct PdCase {
  const char* name;
  DeformationMode (*mode)(double, double);
};

class PdControl : public ::testing::TestWithParam<PdCase> {};

// A single active mode, free in space, PD-driven from rest to γ0: m γ̈ + c γ̇ + 2K(γ − γ0) = 0
// gives γ = γ0 (1 − e^{−ζωt}(cos ω_d t + ζ/√(1−ζ²) sin ω_d t)), ω = √(2K/m), ζ = c / (2√(2K m)).
TEST_P(PdControl, DrivesAFreeModeToTargetWithTheDampingRatioItsGainsImply) {
  const double K = 4e6, c = 1.2e6, target = 1e-3;  // a small target: the coupling to θ is O(γ²)
  auto body = std::make_shared<const BodyModel>(TableDef(), std::vector<DeformationMode>{GetParam().mode(K, c)});
  const double m = EffectiveMass(*body, 0);
  const double omega = std::sqrt(2 * K / m), zeta = c / (2 * std::sqrt(2 * K * m));
  ASSERT_LT(zeta, 0.5) << "the case must oscillate to measure a decrement";
  const double wd = omega * std::sqrt(1 - zeta * zeta);
  World world(FreeSpace(Integrator::kRK4, 1e-3));
  world.AddBody(body);
  world.SetModeTargets(0, Eigen::VectorXd::Constant(1, target));
  double max_err = 0;
  std::vector<double> peaks;  // overshoots γ − γ0 at the maxima
  double prev = 0, prev2 = 0;
  const double duration = 4 * 2 * M_PI / wd;
  while (world.time() < duration) {
    ASSERT_TRUE(world.Step());
    const double t = world.time(), g = world.q(0)[kRigidDofs];
    const double exact =
        target * (1 - std::exp(-zeta * omega * t) * (std::cos(wd * t) + zeta / std::sqrt(1 - zeta * zeta) * std::sin(wd * t)));
    max_err = std::max(max_err, std::abs(g - exact));
    if (prev > prev2 && prev > g) peaks.push_back(prev - target);
    prev2 = prev;
    prev = g;
  }
  EXPECT_LT(max_err / target, 2e-3) << GetParam().name << ": m_eff " << m << ", zeta " << zeta;
  // logarithmic decrement between successive maxima: δ = 2πζ/√(1−ζ²)
  ASSERT_GE(peaks.size(), 3u);
  const double delta = std::log(peaks[0] / peaks[1]);
  const double zeta_measured = delta / std::sqrt(4 * M_PI * M_PI + delta * delta);
  EXPECT_NEAR(zeta_measured, zeta, 0.01 * zeta) << GetParam().name;
}

INSTANTIATE_TEST_SUITE_P(Modes, PdControl,
                         ::testing::Values(PdCase{"bend", testing::Bend}, PdCase{"shear", testing::Shear},
                                           PdCase{"vsquash", testing::VerticalSquash}),
                         [](const auto& info) { return std::string(info.param.name); });

// Undamped mode released from γ = a: over one period the spring force −2Kγ does |work| K a²
// four times (potential → kinetic → potential, twice), and its signed work returns to zero.
TEST(ControlEnergy, CountsTheAbsoluteWorkOfTheModeForces) {
  const double K = 4e6, a = 0.01;
  auto body = std::make_shared<const BodyModel>(TableDef(), std::vector<DeformationMode>{testing::VerticalSquash(K, 0)});
  const double m = EffectiveMass(*body, 0);
  const double period = 2 * M_PI / std::sqrt(2 * K / m);
  const double dt = period / 20000;
  World world(FreeSpace(Integrator::kRK4, dt));
  world.AddBody(body);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(4), qd = Eigen::VectorXd::Zero(4);
  q[kRigidDofs] = a;
  world.SetState(0, q, qd);
  control::ControlEnergy energy;
  for (int n = 0; n < 20000; ++n) {
    ASSERT_TRUE(world.Step());
    energy.Accumulate(*body, world.state<2>(0), dt);
  }
  EXPECT_NEAR(energy.consumed, 4 * K * a * a, 2e-3 * 4 * K * a * a);
  EXPECT_NEAR(energy.work, 0.0, 2e-3 * K * a * a);
}

TEST(PoseGraph, CyclesFromTheFirstPoseWithItsPeriod) {
  control::PoseGraph g;
  g.poses = {Eigen::VectorXd::Constant(1, 1), Eigen::VectorXd::Constant(1, 2), Eigen::VectorXd::Constant(1, 3)};
  g.durations = {0.3, 0.5, 0.2};
  EXPECT_DOUBLE_EQ(g.Period(), 1.0);
  EXPECT_EQ(g.PoseAt(0.0), 0);
  EXPECT_EQ(g.PoseAt(0.29), 0);
  EXPECT_EQ(g.PoseAt(0.31), 1);
  EXPECT_EQ(g.PoseAt(0.79), 1);
  EXPECT_EQ(g.PoseAt(0.81), 2);
  for (double t : {0.05, 0.4, 0.9})
    for (int k = 1; k < 5; ++k) EXPECT_EQ(g.PoseAt(t + k * g.Period()), g.PoseAt(t)) << t << " + " << k << " periods";
  g.cyclic = false;  // a sequence holds its last pose
  EXPECT_EQ(g.PoseAt(1.5), 2);
  EXPECT_EQ(g.PoseAt(0.1), 0);
  EXPECT_EQ(g.Validate(1), "");
  EXPECT_NE(g.Validate(2), "");
}

// A table whose bend (stiff and damped) a pose graph drives, its squash passive; and a
// cyclic graph of two bends held 0.7 s and 0.5 s.
std::shared_ptr<const BodyModel> BendDrivenTable() {
  auto modes = std::vector<DeformationMode>{testing::Bend(4e7, 8e6), testing::VerticalSquash(4e7, 8e6)};
  modes[0].active = true;
  return std::make_shared<const BodyModel>(TableDef(), modes);
}
control::PoseGraph TwoPoseBendGraph() {
  control::PoseGraph g;
  g.poses = {Eigen::VectorXd::Constant(1, 0.01), Eigen::VectorXd::Constant(1, -0.01)};
  g.durations = {0.7, 0.5};
  return g;
}

// A damped body driven by a cyclic pose graph settles into a motion with the graph's period.
TEST(PoseGraph, DrivenModeBecomesPeriodicWithTheGraphsPeriod) {
  const auto body = BendDrivenTable();
  const control::PoseGraph g = TwoPoseBendGraph();
  const double dt = 1e-3;
  World world(FreeSpace(Integrator::kRK4, dt));
  world.AddBody(body);
  const long per_period = std::lround(g.Period() / dt);
  std::vector<double> gamma;
  for (long n = 0; n < 40 * per_period; ++n) {
    world.SetModeTargets(0, control::TargetsFromPose(*body, g.poses[g.PoseAt(n * dt)]));
    ASSERT_TRUE(world.Step());
    gamma.push_back(world.q(0)[kRigidDofs]);
  }
  double diff = 0, range = 0;
  for (long n = 38 * per_period; n < 39 * per_period; ++n) {
    diff = std::max(diff, std::abs(gamma[n + per_period] - gamma[n]));
    range = std::max(range, std::abs(gamma[n]));
  }
  EXPECT_GT(range, 0.003);  // it moves ...
  EXPECT_LT(diff, 1e-4 * range) << "... and repeats with period " << g.Period();
  // shifted by half a period it does not repeat: the period found is the graph's
  double half = 0;
  for (long n = 38 * per_period; n < 39 * per_period; ++n) half = std::max(half, std::abs(gamma[n + per_period / 2] - gamma[n]));
  EXPECT_GT(half, 0.1 * range);
}

TEST(Keyframes, LinearAndSmoothPassThroughTheKeys) {
  control::Keyframes k;
  k.times = {0.0, 1.0, 3.0};
  k.amplitudes = {Eigen::Vector2d(0, 1), Eigen::Vector2d(0.2, 1), Eigen::Vector2d(-0.2, 0)};
  ASSERT_EQ(k.Validate(2), "");
  Eigen::VectorXd g, gd;
  k.Evaluate(0.5, &g, &gd);
  EXPECT_NEAR(g[0], 0.1, 1e-15);
  EXPECT_NEAR(gd[0], 0.2, 1e-15);
  k.Evaluate(2.0, &g, &gd);
  EXPECT_NEAR(g[0], 0.0, 1e-15);
  EXPECT_NEAR(g[1], 0.5, 1e-15);
  EXPECT_NEAR(gd[1], -0.5, 1e-15);
  k.interpolation = control::Interpolation::kSmooth;
  for (int i = 0; i < 3; ++i) {
    k.Evaluate(k.times[i], &g, &gd);
    EXPECT_NEAR((g - k.amplitudes[i]).norm(), 0.0, 1e-14) << "key " << i;
  }
  // C1 at the inner key: the derivative from both sides agrees, and matches finite differences
  Eigen::VectorXd g0, g1, d0, d1;
  k.Evaluate(1.0 - 1e-7, &g0, &d0);
  k.Evaluate(1.0 + 1e-7, &g1, &d1);
  EXPECT_NEAR((d0 - d1).norm(), 0.0, 1e-5);
  EXPECT_NEAR(((g1 - g0) / 2e-7 - d0).norm(), 0.0, 1e-5);
}

TEST(Keyframes, HeldPointStaysPutWhileTheBodyDeforms) {
  auto body = std::make_shared<const BodyModel>(TableDef(), testing::TableModes());
  control::Keyframes k;
  k.times = {0.0, 0.5, 1.2};
  k.amplitudes = {Eigen::Vector4d(0, 0, 0, 0), Eigen::Vector4d(0.2, -0.1, 0.05, 0), Eigen::Vector4d(-0.1, 0.3, 0, 0.1)};
  control::HeldPoint hold{true, {0.0, 0.0, 0.0}};  // the left foot
  const Eigen::Vector2d anchor(12.0, 3.0);
  const double theta = 0.2;
  Eigen::VectorXd g, gd, q, qd;
  for (auto interp : {control::Interpolation::kLinear, control::Interpolation::kSmooth}) {
    k.interpolation = interp;
    for (double t = 0; t <= 1.2; t += 0.01) {
      k.Evaluate(t, &g, &gd);
      control::KeyframedState(*body, hold, anchor, Eigen::Vector3d(0.0, 0.0, theta), g, gd, &q, &qd);
      EXPECT_NEAR((control::PointAt(*body, hold.coords<2>(), q) - anchor).norm(), 0.0, 1e-10) << t;
      // its velocity J q̇ is zero too
      Eigen::Vector2d b0;
      Mat2D<double> B;
      body->LocalBasis(hold.coords<2>(), &b0, &B);
      const VecQ<double> qq = q, qqd = qd;
      const Frame<2, double> frame(qq);
      EXPECT_NEAR(PointVelocity(frame, qqd, LocalPosition<double>(b0, B, qq), B).norm(), 0.0, 1e-10) << t;
      EXPECT_DOUBLE_EQ(q[2], theta);
    }
  }
  // the rest of the body did move
  k.Evaluate(0.5, &g, &gd);
  control::KeyframedState(*body, hold, anchor, Eigen::Vector3d(0.0, 0.0, theta), g, gd, &q, &qd);
  EXPECT_GT((control::PointAt(*body, {1.0, 1.0}, q) - control::PointAt(*body, {1.0, 1.0}, Eigen::VectorXd::Zero(7))).norm(), 10.0);
}

// ---------------------------------------------------------------- controllers

// The one pose-graph loop (control::PoseGraphController) against the rule written out here:
// before step n the targets are those of pose PoseAt(n dt). The world with the controllers
// and a world whose targets are set by hand before each step are identical, and the
// ModeTargetController behind the graph logs exactly the steps where PoseAt changes.
TEST(Controllers, PoseGraphControllerIsThePoseAtRuleAndTheTargetLogHasItsSwitches) {
  const auto body = BendDrivenTable();
  const control::PoseGraph g = TwoPoseBendGraph();
  const double dt = 1e-3;
  const long steps = 2600;
  World driven(FreeSpace(Integrator::kRK4, dt)), by_hand(FreeSpace(Integrator::kRK4, dt));
  driven.AddBody(body);
  by_hand.AddBody(body);
  driven.AddController(std::make_shared<control::PoseGraphController>(driven, 0, g));
  auto log = std::make_shared<control::ModeTargetController>(driven, 0);
  driven.AddController(log);
  std::vector<control::TargetSegment> expected;
  for (long n = 0; n < steps; ++n) {
    const Eigen::VectorXd t = control::TargetsFromPose(*body, g.poses[g.PoseAt(n * dt)]);
    if (expected.empty() || expected.back().targets != t) expected.push_back({n, t});
    by_hand.SetModeTargets(0, t);
    ASSERT_TRUE(by_hand.Step());
    ASSERT_TRUE(driven.Step());
  }
  EXPECT_EQ((driven.q(0) - by_hand.q(0)).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(log->steps(), steps);
  ASSERT_EQ(log->segments().size(), expected.size());
  EXPECT_GE(expected.size(), 5u);  // 2.6 s of a 1.2 s cycle: switches at about 0, 0.7, 1.2, 1.9, 2.4
  for (size_t k = 0; k < expected.size(); ++k) {
    EXPECT_EQ(log->segments()[k].step, expected[k].step) << k;
    EXPECT_EQ(log->segments()[k].targets, expected[k].targets) << k;
  }
}

// A slider's Set acts from the next step on, not between steps, and is logged at that step;
// two Sets before one step log once.
TEST(Controllers, ModeTargetSetActsAtTheNextStep) {
  auto body = std::make_shared<const BodyModel>(TableDef(), testing::TableModes(4e7, 8e6));
  World world(FreeSpace(Integrator::kRK4, 1e-3));
  world.AddBody(body);
  auto sliders = std::make_shared<control::ModeTargetController>(world, 0);
  world.AddController(sliders);
  const int D = body->num_modes();
  for (int n = 0; n < 3; ++n) ASSERT_TRUE(world.Step());
  Eigen::VectorXd a = Eigen::VectorXd::Zero(D), b = Eigen::VectorXd::Zero(D);
  a[1] = 0.2;
  b[1] = -0.1;
  sliders->Set(a);
  sliders->Set(b);
  EXPECT_EQ(sliders->targets(), b);
  EXPECT_EQ(world.mode_targets(0).size() == 0 ? 0.0 : world.mode_targets(0).cwiseAbs().maxCoeff(), 0.0)
      << "the world's targets changed between steps";
  ASSERT_TRUE(world.Step());
  EXPECT_EQ(world.mode_targets(0), b);
  ASSERT_EQ(sliders->segments().size(), 2u);
  EXPECT_EQ(sliders->segments()[0].step, 0);
  EXPECT_EQ(sliders->segments()[0].targets, Eigen::VectorXd::Zero(D));
  EXPECT_EQ(sliders->segments()[1].step, 3);
  EXPECT_EQ(sliders->segments()[1].targets, b);
  EXPECT_THROW(sliders->Set(Eigen::VectorXd::Zero(D + 1)), std::invalid_argument);
}

// The drag path is the critically damped approach: it starts at n0 with velocity v0 and obeys
// n'' + 2 n'/tau + (n - c)/tau^2 = 0; its derivatives match central differences of n.
TEST(Controllers, ApproachPathIsTheCriticallyDampedApproach) {
  const double t0 = 0.4, tau = 0.08;
  const Eigen::Vector3d n0(1, -2, 0.5), v0(3, 0.5, -1), c(-1, 1, 2);
  const control::ApproachPath path(t0, n0, v0, c, tau);
  const PathSample start = path.Evaluate(t0);
  EXPECT_LT((start.n - n0).norm(), 1e-15);
  EXPECT_LT((start.n_dot - v0).norm(), 1e-14);
  for (double s : {0.01, 0.05, 0.1, 0.3}) {
    const PathSample p = path.Evaluate(t0 + s);
    EXPECT_LT((p.n_ddot + 2.0 * p.n_dot / tau + (p.n - c) / (tau * tau)).norm(), 1e-9) << s;
    const double h = 1e-6;
    const Eigen::VectorXd fd = (path.Evaluate(t0 + s + h).n - path.Evaluate(t0 + s - h).n) / (2 * h);
    EXPECT_LT((fd - p.n_dot).norm(), 1e-6 * (1 + p.n_dot.norm())) << s;
  }
  EXPECT_LT((path.Evaluate(t0 + 40 * tau).n - c).norm(), 1e-12);
}

// A mouse pull by trajectory constraint takes a bar's end to the aim within a few time
// constants while the constraint holds, and Release leaves the bar free again.
TEST(Controllers, ConstraintPullTakesThePointToTheAimAndReleaseRemovesIt) {
  WorldOptions o = testing::WitkinWelchOptions();
  o.dt = 1e-3;
  o.params.gravity_on = false;
  World world(o);
  const int bar = world.AddLinearBody(
      std::make_shared<LinearBodyModel>(MakeBoxBody("bar", 2, LinearOrder::kAffine, Eigen::Vector2d(0.5, 0.1), 3, 1.0)),
      AffineMaterial{200.0, 200.0, 0.0, 0.0});
  const MaterialPoint end = MassPointOf(bar, 0);
  const Eigen::VectorXd start = world.PointPosition(end);
  auto pull = std::make_shared<control::ConstraintPull>(world, end, 0.08);
  world.AddController(pull);
  ASSERT_GE(pull->constraint(), 0);
  const Eigen::Vector2d aim = start + Eigen::Vector2d(0.3, 0.2);
  pull->Aim(aim);
  double worst = 0;
  for (int n = 0; n < 1000; ++n) {  // 1 s = 12.5 time constants
    ASSERT_TRUE(world.Step()) << world.status().message;
    worst = std::max(worst, world.MaxViolation());
  }
  EXPECT_LT((world.PointPosition(end) - aim).norm(), 1e-3);
  EXPECT_LT(worst, 1e-4);
  const int id = pull->constraint();
  pull->Release(world);
  world.RemoveController(pull.get());
  EXPECT_FALSE(world.exists(id));
  EXPECT_EQ(pull->constraint(), -1);
  ASSERT_TRUE(world.Step());
}

TEST(Controllers, SpringPullMovesItsAnchorAndReleaseRemovesTheSpring) {
  auto body = std::make_shared<const BodyModel>(TableDef(), testing::TableModes(4e7, 8e6));
  World world(FreeSpace(Integrator::kRK4, 1e-3));
  world.AddBody(body);
  Spring s;
  s.lattice_coords = Eigen::Vector3d(0.2, 1.0, 0.0);  // a 2D body: z is 0
  s.anchor = Eigen::Vector3d(1, 2, 0);
  s.stiffness = 10;
  auto pull = std::make_shared<control::SpringPull>(world, s);
  world.AddController(pull);
  ASSERT_EQ(world.options().params.springs.size(), 1u);
  pull->Aim(world, Eigen::Vector2d(3, 4));
  EXPECT_EQ(world.options().params.springs[0].anchor, Eigen::Vector3d(3, 4, 0));
  EXPECT_EQ(world.options().params.springs[0].lattice_coords, s.lattice_coords);
  ASSERT_TRUE(world.Step());
  pull->Release(world);
  world.RemoveController(pull.get());
  EXPECT_TRUE(world.options().params.springs.empty());
}

}  // namespace
}  // namespace wobble
