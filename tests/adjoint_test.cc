// The adjoint gradient of a rollout (lib/wobble/fit/adjoint.h, issue 18), checked against
// two independent derivatives of the same cost:
//  - forward-mode Jets through the WHOLE simulation (written here, with its own PD force and
//    its own passive body): the directional derivative along random directions in the space
//    of every parameter (q0, q̇0, K, c and all steps × modes targets), to 1e-9 relative;
//  - central differences of the plain cost, per parameter, to 1e-7 relative, where the cost
//    is smooth (in the air, and through contacts with the probes on one contact branch).
// In the air and through ground contacts with friction (contacts begin, slip and end), for
// the thesis and symplectic Euler integrators; the checkpoint interval does not change the
// gradient; bad input is refused with a message.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "support/test_bodies.h"
#include "wobble/dynamics/step.h"
#include "wobble/dynamics/terrain.h"
#include "wobble/fit/adjoint.h"

namespace wobble {
namespace {

constexpr int kNq = 7, kModes = 4;  // the table of Fig. 1.2 with the four modes of §4.10.1
constexpr int kPoint = 1;           // the cost follows this mass point (the top, 75 along)

// ℓ_n = ½ w |x_k(q_n) − y(n)|² + ½ ρ |q̇_n|²: a point chasing a moving target, and a velocity
// penalty. Templated so that the reference can run it on Jets.
template <class T> T Stage(const BodyModel& body, int n, const VecQ<T>& q, const VecQ<T>& qd) {
  const Frame<2, T> frame(q);
  const Vec2<T> x = WorldFromLocal(frame, LocalPosition<T>(body.rest_local(kPoint), body.mode_matrix(kPoint), q));
  const Eigen::Vector2d y(100.0 + 2.0 * n, 80.0 - 0.5 * n);
  T cost = T(0.5e-2) * (x - y.cast<T>()).squaredNorm();
  for (int i = 0; i < qd.size(); ++i) cost += T(0.5e-3) * qd[i] * qd[i];
  return cost;
}

fit::StageCost StageOf(const BodyModel& body) {
  return [&body](int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) {
    const Eigen::VectorXd q = s.q, qd = s.qd;
    using J = ceres::Jet<double, 2 * kNq>;
    VecQ<J> qj(kNq), qdj(kNq);
    for (int i = 0; i < kNq; ++i) {
      qj[i] = J(q[i], i);
      qdj[i] = J(qd[i], kNq + i);
    }
    const J c = Stage(body, n, qj, qdj);
    dz->head(kNq) += c.v.head(kNq);  // z = (q, q̇)
    dz->tail(kNq) += c.v.tail(kNq);
    return c.a;
  };
}

// The reference: the mode forces −2K (γ − γ0(n)) − c γ̇ written out here, on a body whose own
// mode forces are zero.
template <class T> struct PdForce {
  const std::vector<T>* K;
  const std::vector<T>* c;
  const std::vector<T>* target;
  void operator()(const BodyState<2, T>& s, VecQ<T>* Q) const {
    for (int d = 0; d < kModes; ++d)
      (*Q)[3 + d] += -T(2.0) * (*K)[d] * (s.q[3 + d] - (*target)[d]) - (*c)[d] * s.qd[3 + d];
  }
};

// Every parameter in one flat vector: q0, q̇0, K, c, then the targets step by step.
Eigen::VectorXd Flatten(const fit::ControlledRollout& r) {
  const int N = r.steps();
  Eigen::VectorXd p(2 * kNq + 2 * kModes + kModes * N);
  p << r.start.q, r.start.qd, r.stiffness, r.damping, Eigen::Map<const Eigen::VectorXd>(r.targets.data(), kModes * N);
  return p;
}
Eigen::VectorXd Flatten(const fit::RolloutGradient& g) {
  const int N = int(g.targets.cols());
  Eigen::VectorXd p(2 * kNq + 2 * kModes + kModes * N);
  p << g.start, g.stiffness, g.damping, Eigen::Map<const Eigen::VectorXd>(g.targets.data(), kModes * N);
  return p;
}

// The cost of the rollout from q0, q̇0, gains K, c and the targets target_of(n) of each step.
template <class T, class Targets>
T ReferenceCostOf(const BodyModel& passive, const fit::ControlledRollout& r, const std::vector<T>& start,
                  const std::vector<T>& K, const std::vector<T>& c, const Targets& target_of) {
  BodyState<2, T> s;
  s.q.resize(kNq);
  s.qd.resize(kNq);
  for (int i = 0; i < kNq; ++i) {
    s.q[i] = start[i];
    s.qd[i] = start[kNq + i];
  }
  UpdateContacts(passive, r.world.ground, &s);
  T total = Stage(passive, 0, s.q, s.qd);
  for (int n = 0; n < r.steps(); ++n) {
    const std::vector<T> target = target_of(n);
    EXPECT_TRUE(StepBody(passive, r.world, 0, r.integrator, r.dt, &s, PdForce<T>{&K, &c, &target}).ok());
    total += Stage(passive, n + 1, s.q, s.qd);
  }
  return total;
}

// The cost with parameters p + ε v (in Flatten's order), ε a Jet of one dimension (or double).
template <class T>
T ReferenceCost(const BodyModel& passive, const fit::ControlledRollout& r, const Eigen::VectorXd& p, const Eigen::VectorXd& v) {
  auto param = [&](int i) {
    T x(p[i]);
    if constexpr (!std::is_same_v<T, double>) x.v[0] = v[i];
    return x;
  };
  std::vector<T> start(2 * kNq), K(kModes), c(kModes);
  for (int i = 0; i < 2 * kNq; ++i) start[i] = param(i);
  for (int d = 0; d < kModes; ++d) {
    K[d] = param(2 * kNq + d);
    c[d] = param(2 * kNq + kModes + d);
  }
  return ReferenceCostOf<T>(passive, r, start, K, c, [&](int n) {
    std::vector<T> target(kModes);
    for (int d = 0; d < kModes; ++d) target[d] = param(2 * kNq + 2 * kModes + kModes * n + d);
    return target;
  });
}

struct Case {
  BodyModel body;     // its own mode gains, which the rollout's replace
  BodyModel passive;  // the same with no mode forces: the reference's
  fit::ControlledRollout rollout;
};

// The table with random gains, random PD targets every step and a random start; `grounded`:
// falling onto the ground, sliding sideways (friction slips), bouncing; else in the air.
// `active`: every mode is under the controller (a pose graph's poses have an entry per mode).
std::vector<DeformationMode> Modes(double stiffness, double damping, bool active) {
  std::vector<DeformationMode> modes = testing::TableModes(stiffness, damping);
  for (DeformationMode& m : modes) m.active = active;
  return modes;
}

Case MakeCase(Integrator integrator, bool grounded, int steps, unsigned seed, bool active = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case k{BodyModel(testing::TableDef(), Modes(3e5, 2e3, active)), BodyModel(testing::TableDef(), Modes(0, 0, active)),
         {}};
  fit::ControlledRollout& r = k.rollout;
  r.integrator = integrator;
  r.dt = 0.005;
  r.world.ground.enabled = grounded;
  r.start.q.resize(kNq);
  r.start.qd.resize(kNq);
  const double height = grounded ? 12.0 : 200.0;
  const double vx = grounded ? 80.0 : 20 * u(rng), vy = grounded ? -60.0 : 20 * u(rng);
  r.start.q << 10 * u(rng), height, 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng);
  r.start.qd << vx, vy, 0.3 * u(rng), 0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng);
  r.stiffness.resize(kModes);
  r.damping.resize(kModes);
  for (int d = 0; d < kModes; ++d) {
    r.stiffness[d] = 4e5 * (1.0 + 0.5 * u(rng));
    r.damping[d] = 2e3 * (1.0 + 0.5 * u(rng));
  }
  r.targets = 0.1 * Eigen::MatrixXd::NullaryExpr(kModes, steps, [&] { return u(rng); });
  return k;
}

// A random direction, each parameter scaled to its size (q0 and q̇0 in their units, gains
// relative to themselves, targets 0.1).
Eigen::VectorXd Direction(const Eigen::VectorXd& p, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd v(p.size());
  for (int i = 0; i < p.size(); ++i) v[i] = n(rng) * (i < 2 * kNq ? 1.0 : i < 2 * kNq + 2 * kModes ? 0.01 * p[i] : 0.1);
  return v;
}

// Contact onsets, ends and slips (a kept contact whose anchor moved: the friction cap was hit)
// along the plain run: proof that a grounded case went through the branches it is meant to test.
void ContactEvents(const Case& k, int* onsets, int* ends, int* slips, std::set<int>* faces = nullptr) {
  BodyState<2, double> s;
  s.q = k.rollout.start.q;
  s.qd = k.rollout.start.qd;
  UpdateContacts(k.passive, k.rollout.world.ground, &s);
  *onsets = *ends = *slips = 0;
  std::vector<double> K(k.rollout.stiffness.data(), k.rollout.stiffness.data() + kModes);
  std::vector<double> c(k.rollout.damping.data(), k.rollout.damping.data() + kModes);
  for (int n = 0; n < k.rollout.steps(); ++n) {
    std::vector<double> target(k.rollout.targets.col(n).data(), k.rollout.targets.col(n).data() + kModes);
    const auto before = s.contacts;
    ASSERT_TRUE(StepBody(k.passive, k.rollout.world, 0, k.rollout.integrator, k.rollout.dt, &s,
                         PdForce<double>{&K, &c, &target}).ok());
    auto find = [](const std::vector<Contact<2, double>>& set, int point) -> const Contact<2, double>* {
      for (const auto& x : set)
        if (x.point == point) return &x;
      return nullptr;
    };
    for (const auto& x : s.contacts) {
      if (faces) faces->insert(x.face);
      const Contact<2, double>* was = find(before, x.point);
      *onsets += !was;
      *slips += was && was->anchor != x.anchor;
    }
    for (const auto& x : before) *ends += !find(s.contacts, x.point);
  }
}

void ExpectJetDirectionalDerivatives(const Case& k, unsigned seed) {
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(g.ok) << g.message;
  const Eigen::VectorXd p = Flatten(k.rollout), grad = Flatten(g);
  using J1 = ceres::Jet<double, 1>;
  EXPECT_NEAR(g.cost, ReferenceCost<double>(k.passive, k.rollout, p, p), 1e-12 * std::abs(g.cost));
  // single parameters (the gains too, whose terms are small beside q0's in a random direction)
  const int N = k.rollout.steps(), first_target = 2 * kNq + 2 * kModes;
  for (int i : {0, 2, 5, kNq, kNq + 2, 2 * kNq, 2 * kNq + 1, 2 * kNq + kModes, 2 * kNq + kModes + 3, first_target,
                first_target + kModes * (N / 2) + 1, first_target + kModes * N - 1}) {
    const J1 ref = ReferenceCost<J1>(k.passive, k.rollout, p, Eigen::VectorXd::Unit(p.size(), i));
    EXPECT_NEAR(grad[i], ref.v[0], 1e-9 * std::abs(ref.v[0])) << "parameter " << i;
  }
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd v = Direction(p, rng);
    const J1 ref = ReferenceCost<J1>(k.passive, k.rollout, p, v);
    const double adjoint = grad.dot(v);
    // scale: the sum of the magnitudes of the terms, so that cancellation cannot hide an error
    const double scale = (grad.array() * v.array()).abs().sum();
    EXPECT_NEAR(adjoint, ref.v[0], 1e-9 * scale) << "direction " << trial << ": adjoint " << adjoint << ", Jets " << ref.v[0];
  }
}

TEST(Adjoint, MatchesJetsThroughTheWholeRunInTheAir) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    ExpectJetDirectionalDerivatives(MakeCase(integrator, false, 80, 3), 11);
  }
}

TEST(Adjoint, MatchesJetsThroughContactsThatBeginSlipAndEnd) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    const Case k = MakeCase(integrator, true, 200, 5);
    int onsets = 0, ends = 0, slips = 0;
    ContactEvents(k, &onsets, &ends, &slips);
    EXPECT_GE(onsets, 2) << "the run must bring points onto the ground";
    EXPECT_GE(slips, 10) << "slide them along it";
    EXPECT_GE(ends, 1) << "and lift some off again";
    RecordProperty("contact_onsets_ends_slips", std::to_string(onsets) + " " + std::to_string(ends) + " " + std::to_string(slips));
    ExpectJetDirectionalDerivatives(k, 13);
  }
}

// A terrain (the table slides onto a rising slope: the hand-derived product with faces, and
// under the symplectic step the Jet product, whose new contacts' faces depend on velocity),
// and a spring holding a corner (the Jet product).
TEST(Adjoint, MatchesJetsOnATerrainAndWithASpring) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    Case k = MakeCase(integrator, true, 200, 41);
    k.rollout.world.ground.terrain = Terrain::Make({{-500, 0}, {250, 0}, {450, 40}, {900, 40}});
    int onsets = 0, ends = 0, slips = 0;
    std::set<int> faces;
    ContactEvents(k, &onsets, &ends, &slips, &faces);
    EXPECT_GE(faces.size(), 2u) << "the points must touch the level part and the slope";
    ExpectJetDirectionalDerivatives(k, 43);
  }
  Case k = MakeCase(Integrator::kThesis, true, 150, 47);
  k.rollout.world.springs.push_back(
      MakeSpring(k.passive, Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(350.0, 180.0), 2e3, 50.0, 40.0));
  ExpectJetDirectionalDerivatives(k, 53);
}

// Central differences of the plain cost, one parameter at a time: q0 (x, θ, a mode), q̇0,
// each gain and targets early, midway and at the last step.
void ExpectCentralDifferences(const Case& k, double tolerance) {
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(g.ok) << g.message;
  const Eigen::VectorXd p = Flatten(k.rollout), grad = Flatten(g);
  const int N = k.rollout.steps(), first_target = 2 * kNq + 2 * kModes;
  // not the gains: their effect on this cost is small (K ∂cost/∂K ≈ 0.5 against a cost of
  // ~10⁴), so a difference quotient's rounding lies above 1e-7 of it; the Jet tests check them
  const std::vector<int> probes = {0, 2, 4, kNq + 1, kNq + 3, first_target, first_target + kModes * (N / 2) + 2,
                                   first_target + kModes * (N - 1) + 3};
  auto cost_at = [&](int i, double offset) {
    Eigen::VectorXd x = p;
    x[i] += offset;
    return ReferenceCost<double>(k.passive, k.rollout, x, x);
  };
  const double cost = ReferenceCost<double>(k.passive, k.rollout, p, p);
  for (int i : probes) {
    // the five-point stencil (truncation O(h⁴)); its rounding error is about ε |cost| / h (the
    // stencil's weights sum to 1.5/h), which bounds how well any difference quotient can agree
    const double h = 1e-4 * std::max(1.0, std::abs(p[i]));
    const double fd = (8.0 * (cost_at(i, h) - cost_at(i, -h)) - (cost_at(i, 2 * h) - cost_at(i, -2 * h))) / (12.0 * h);
    const double rounding = 10.0 * std::numeric_limits<double>::epsilon() * std::abs(cost) / h;
    EXPECT_NEAR(grad[i], fd, tolerance * std::abs(fd) + rounding) << "parameter " << i << " (rounding bound " << rounding << ")";
  }
}

TEST(Adjoint, MatchesCentralDifferencesInTheAir) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    ExpectCentralDifferences(MakeCase(integrator, false, 80, 7), 1e-7);
  }
}

// A smoothed pose-graph controller (three poses, cyclic) standing on the ground: the gradient
// with respect to its poses and switch times is the chain rule through its per-step targets,
// checked against Jets through SmoothPoseTargets and the whole simulation.
TEST(Adjoint, PoseGraphPosesAndSwitchTimesMatchJets) {
  Case k = MakeCase(Integrator::kSymplecticEuler, true, 240, 31, true);
  control::PoseGraph graph;
  graph.poses = {Eigen::Vector4d(0.0, 0.0, 0.0, 0.0), Eigen::Vector4d(0.15, 0.0, -0.2, 0.1),
                 Eigen::Vector4d(-0.1, 0.05, 0.2, -0.1)};
  graph.durations = {0.3, 0.25, 0.4};
  const double width = 0.05;
  k.rollout.targets = fit::PoseGraphTargets(k.body, graph, k.rollout.dt, 240, width);
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(g.ok) << g.message;
  const fit::PoseGraphGradient pg = fit::PoseGraphGradientOf(k.body, graph, k.rollout.dt, width, g.targets);
  ASSERT_EQ(pg.poses.size(), 3u);
  ASSERT_EQ(pg.durations.size(), 3u);
  using J1 = ceres::Jet<double, 1>;
  std::mt19937 rng(37);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    control::PoseGraphOf<J1> c = control::PoseGraphOf<J1>::From(k.body, graph);
    double adjoint = 0.0, scale = 0.0;
    for (int i = 0; i < 3; ++i) {
      for (int d = 0; d < kModes; ++d) {
        const double v = 0.1 * normal(rng);
        c.poses[i][d].v[0] = v;
        adjoint += pg.poses[i][d] * v;
        scale += std::abs(pg.poses[i][d] * v);
      }
      const double v = 0.05 * normal(rng);
      c.durations[i].v[0] = v;
      adjoint += pg.durations[i] * v;
      scale += std::abs(pg.durations[i] * v);
    }
    std::vector<J1> start(2 * kNq), K(kModes), damping(kModes);
    for (int i = 0; i < kNq; ++i) {
      start[i] = J1(k.rollout.start.q[i]);
      start[kNq + i] = J1(k.rollout.start.qd[i]);
    }
    for (int d = 0; d < kModes; ++d) {
      K[d] = J1(k.rollout.stiffness[d]);
      damping[d] = J1(k.rollout.damping[d]);
    }
    const J1 ref = ReferenceCostOf<J1>(k.passive, k.rollout, start, K, damping, [&](int n) {
      const VecD<J1> t = control::SmoothPoseTargets(c, kModes, n * k.rollout.dt, width);
      return std::vector<J1>(t.data(), t.data() + kModes);
    });
    EXPECT_NEAR(adjoint, ref.v[0], 1e-9 * scale) << "direction " << trial;
  }
}

TEST(Adjoint, CheckpointIntervalDoesNotChangeTheGradient) {
  const Case k = MakeCase(Integrator::kThesis, true, 100, 17);
  const fit::RolloutGradient every = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), 1);
  const fit::RolloutGradient sqrt_n = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), fit::kCheckpointSqrt);
  const fit::RolloutGradient odd = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), 7);
  const fit::RolloutGradient whole = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), 100);
  const fit::RolloutGradient automatic = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(every.ok && sqrt_n.ok && odd.ok && whole.ok && automatic.ok);
  // recomputation from a checkpoint repeats the same arithmetic: the same numbers exactly
  EXPECT_EQ(Flatten(every), Flatten(sqrt_n));
  EXPECT_EQ(Flatten(every), Flatten(odd));
  EXPECT_EQ(Flatten(every), Flatten(whole));
  EXPECT_EQ(Flatten(every), Flatten(automatic));
  // ⌈√100⌉ = 10 checkpoints and one interval of 10 states; all 100 when not checkpointing,
  // which a 100-step run does by default (far below the budget)
  EXPECT_EQ(sqrt_n.states_held, 20);
  EXPECT_EQ(whole.states_held, 101);
  EXPECT_EQ(automatic.states_held, 101);
}

TEST(Adjoint, CheckpointIntervalKeepsTheWholeRunOnlyWithinTheBudget) {
  const size_t mib = size_t(1) << 20;
  EXPECT_EQ(fit::CheckpointInterval(10000, 0, 4096, 64 * mib), 10000);  // 39 MiB: kept whole
  EXPECT_EQ(fit::CheckpointInterval(10000, 0, 8192, 64 * mib), 100);    // 78 MiB: ⌈√10000⌉
  EXPECT_EQ(fit::CheckpointInterval(10001, 0, 8192, 64 * mib), 101);
  EXPECT_EQ(fit::CheckpointInterval(10000, fit::kCheckpointSqrt, 1, 64 * mib), 100);
  EXPECT_EQ(fit::CheckpointInterval(10000, 7, 1 << 30, 64 * mib), 7);  // an interval asked for
  EXPECT_EQ(fit::CheckpointInterval(0, 0, 4096, 64 * mib), 1);
}

TEST(Adjoint, ZeroStepsIsTheGradientOfTheFirstStageCost) {
  Case k = MakeCase(Integrator::kThesis, false, 0, 19);
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(g.ok);
  Eigen::VectorXd dz = Eigen::VectorXd::Zero(2 * kNq);
  const double c = StageOf(k.passive)(0, k.rollout.start, &dz);
  EXPECT_EQ(g.cost, c);
  EXPECT_EQ(Eigen::VectorXd(g.start.head(kNq)), Eigen::VectorXd(dz.head(kNq)));  // q0
  EXPECT_EQ(Eigen::VectorXd(g.start.tail(kNq)), Eigen::VectorXd(dz.tail(kNq)));  // q̇0
  EXPECT_EQ(g.stiffness, Eigen::VectorXd::Zero(kModes));
}

TEST(Adjoint, RefusesBadInputWithAMessage) {
  const Case k = MakeCase(Integrator::kThesis, false, 5, 23);
  auto expect_refused = [&](fit::ControlledRollout r, const std::string& needle) {
    try {
      fit::RolloutCostGradient(k.body, r, StageOf(k.passive));
      ADD_FAILURE() << "accepted; expected an error naming " << needle;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  fit::ControlledRollout r = k.rollout;
  r.integrator = Integrator::kRK4;
  expect_refused(r, "thesis and symplectic integrators");
  r = k.rollout;
  r.start.q.resize(3);
  expect_refused(r, "q0 and qdot0 need 7 values");
  r = k.rollout;
  r.targets.resize(2, 5);
  expect_refused(r, "one row per mode");
  r = k.rollout;
  r.damping[1] = std::nan("");
  expect_refused(r, "finite");
  r = k.rollout;
  r.dt = 0;
  expect_refused(r, "dt");
}

TEST(Adjoint, AFailingStepIsReportedNotDifferentiated) {
  Case k = MakeCase(Integrator::kThesis, true, 50, 29);
  k.rollout.world.max_condition = 1.0;  // every step's condition estimate exceeds it
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  EXPECT_FALSE(g.ok);
  EXPECT_NE(g.message.find("step 0 failed"), std::string::npos) << g.message;
  EXPECT_TRUE(std::isinf(fit::RolloutCost(k.body, k.rollout, StageOf(k.passive))));
}

}  // namespace
}  // namespace wobble
