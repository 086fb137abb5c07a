// The adjoint gradient of a 3D rollout (lib/wobble/fit/adjoint.h, issue 18), checked as the
// 2D one is (adjoint_test.cc) against two independent derivatives of the same cost:
//  - forward-mode Jets through the WHOLE simulation (written here, with its own PD force, its
//    own passive body and its own perturbation of the orientation, R0 exp(ε̂)): single
//    parameters and random directions in the space of every parameter, to 1e-9 relative;
//  - central differences of the plain cost, per parameter, to 1e-7 relative, in the air.
// In the air, through contacts with friction on a tilted plane (contacts begin, slip and end)
// and on a heightfield valley with a spring, for the thesis and symplectic Euler integrators.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <vector>

#include "support/test_bodies.h"
#include "wobble/core/rotation3.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/adjoint.h"

namespace wobble {
namespace {

constexpr int kModes = 3;                  // the chair's bend, twist and squash
constexpr int kNz = 12 + 2 * kModes;       // tangent coordinates of a state
constexpr int kPoint = 7;                  // the cost follows this mass point

BodyModelN<3> PassiveChair() {
  const BodyModelN<3> chair = testing::Chair3();
  std::vector<DeformationModeN<3>> modes = chair.modes();
  for (DeformationModeN<3>& m : modes) m.stiffness = m.damping = 0.0;
  return BodyModelN<3>(chair.def(), modes);
}

// ℓ_n = ½ w |x_k − y(n)|² + ½ ρ |v|² + ½ σ |γ|²: a point chasing a moving target, a velocity
// penalty and a shape penalty. Templated so that the reference can run it on Jets.
template <class T> T Stage(const BodyModelN<3>& body, int n, const BodyState<3, T>& s) {
  const Vec3<T> l = LocalPosition<T>(body.rest_local(kPoint), body.mode_matrix(kPoint), s.q);
  const Vec3<T> x = s.translation() + s.orientation().toRotationMatrix() * l;
  const Eigen::Vector3d y(20.0 + 2.0 * n, 60.0 - 0.5 * n, 10.0 + 1.0 * n);
  T cost = T(0.5e-2) * (x - y.cast<T>()).squaredNorm();
  for (int i = 0; i < s.qd.size(); ++i) cost += T(0.5e-3) * s.qd[i] * s.qd[i];
  for (int d = 0; d < s.gamma().size(); ++d) cost += T(0.5) * s.gamma()[d] * s.gamma()[d];
  return cost;
}

// The stage cost's gradient in the tangent coordinates (δt, ε, δγ, δv) of adjoint.h, by Jets.
fit::StageCostN<3> StageOf(const BodyModelN<3>& body) {
  return [&body](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
    using J = ceres::Jet<double, kNz>;
    BodyState<3, J> sj;
    sj.q.resize(s.q.size());
    sj.qd.resize(s.qd.size());
    Vec3<J> eps;
    for (int i = 0; i < 3; ++i) {
      sj.translation()[i] = J(s.translation()[i], i);
      eps[i] = J(0.0, 3 + i);
    }
    sj.set_orientation(s.orientation().cast<J>() * ExpRotation<J>(eps));
    sj.gamma().resize(kModes);
    for (int d = 0; d < kModes; ++d) sj.gamma()[d] = J(s.gamma()[d], 6 + d);
    sj.qd.resize(6 + kModes);
    for (int i = 0; i < 6 + kModes; ++i) sj.qd[i] = J(s.qd[i], 6 + kModes + i);
    const J c = Stage(body, n, sj);
    *dz += c.v;
    return c.a;
  };
}

// The reference's mode forces −2K (γ − γ0(n)) − c γ̇, written out here.
template <class T> struct PdForce {
  const std::vector<T>* K;
  const std::vector<T>* c;
  const std::vector<T>* target;
  void operator()(const BodyState<3, T>& s, VecQ<T>* Q) const {
    for (int d = 0; d < kModes; ++d)
      (*Q)[6 + d] += -T(2.0) * (*K)[d] * (s.gamma()[d] - (*target)[d]) - (*c)[d] * s.qd[6 + d];
  }
};

// Every parameter in one flat vector: the start's tangent coordinates (zero: the start
// itself), K, c, then the targets step by step.
Eigen::VectorXd Flatten(const fit::ControlledRolloutN<3>& r) {
  const int N = r.steps();
  Eigen::VectorXd p(kNz + 2 * kModes + kModes * N);
  p << Eigen::VectorXd::Zero(kNz), r.stiffness, r.damping, Eigen::Map<const Eigen::VectorXd>(r.targets.data(), kModes * N);
  return p;
}
Eigen::VectorXd Flatten(const fit::RolloutGradient& g) {
  const int N = int(g.targets.cols());
  Eigen::VectorXd p(kNz + 2 * kModes + kModes * N);
  p << g.start, g.stiffness, g.damping, Eigen::Map<const Eigen::VectorXd>(g.targets.data(), kModes * N);
  return p;
}

// The cost with parameters p + ε v (Flatten's order; the start moved along its tangent
// coordinates), ε a Jet of one dimension (or double, v unused).
template <class T>
T ReferenceCost(const BodyModelN<3>& passive, const fit::ControlledRolloutN<3>& r, const Eigen::VectorXd& p,
                const Eigen::VectorXd& v) {
  auto param = [&](int i) {
    T x(p[i]);
    if constexpr (!std::is_same_v<T, double>) x.v[0] = v[i];
    return x;
  };
  BodyState<3, T> s;
  s.q.resize(r.start.q.size());
  s.qd.resize(r.start.qd.size());
  Vec3<T> eps;
  for (int i = 0; i < 3; ++i) {
    s.translation()[i] = T(r.start.translation()[i]) + param(i);
    eps[i] = param(3 + i);
  }
  s.set_orientation(r.start.orientation().normalized().cast<T>() * ExpRotation<T>(eps));
  s.gamma().resize(kModes);
  for (int d = 0; d < kModes; ++d) s.gamma()[d] = T(r.start.gamma()[d]) + param(6 + d);
  s.qd.resize(6 + kModes);
  for (int i = 0; i < 6 + kModes; ++i) s.qd[i] = T(r.start.qd[i]) + param(6 + kModes + i);
  std::vector<T> K(kModes), c(kModes), target(kModes);
  for (int d = 0; d < kModes; ++d) {
    K[d] = param(kNz + d);
    c[d] = param(kNz + kModes + d);
  }
  UpdateContacts(passive, r.world.ground_plane, &s);
  T total = Stage(passive, 0, s);
  for (int n = 0; n < r.steps(); ++n) {
    for (int d = 0; d < kModes; ++d) target[d] = param(kNz + 2 * kModes + kModes * n + d);
    EXPECT_TRUE(StepBody(passive, r.world, 0, r.integrator, r.dt, &s, PdForce<T>{&K, &c, &target}).ok());
    total += Stage(passive, n + 1, s);
  }
  return total;
}

struct Case {
  BodyModelN<3> body;     // the chair with its own mode gains, which the rollout's replace
  BodyModelN<3> passive;  // the same with none: the reference's
  fit::ControlledRolloutN<3> rollout;
};

// The chair with random gains, random PD targets every step and a random start; `grounded`:
// thrown onto a tilted plane, sliding (friction slips) and bouncing; else in the air.
Case MakeCase(Integrator integrator, bool grounded, int steps, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case k{testing::Chair3(), PassiveChair(), {}};
  fit::ControlledRolloutN<3>& r = k.rollout;
  r.integrator = integrator;
  r.dt = 2e-3;
  if (grounded) {
    r.world.ground_plane.enabled = true;
    r.world.ground_plane.normal = Eigen::Vector3d(-0.1, 1.0, 0.05).normalized();
    r.world.ground_plane.stiffness = 2e4;  // per point of 1/3 kg
    r.world.ground_plane.normal_damping = 100;
    r.world.ground_plane.friction_damping = 100;
    r.world.ground_plane.friction_cap = 0.3;
  }
  BodyState<3, double>& s = r.start;
  s = RestState<3, double>(k.passive);
  s.translation() = Eigen::Vector3d(10 * u(rng), grounded ? 25.0 : 200.0, 10 * u(rng));
  s.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(0.3 + 0.1 * u(rng), Eigen::Vector3d(1, 0.2 * u(rng), 1).normalized())));
  for (int d = 0; d < kModes; ++d) s.gamma()[d] = 0.05 * u(rng);
  s.qd.head<3>() = grounded ? Eigen::Vector3d(60, -120, 25) : Eigen::Vector3d(20 * u(rng), 20 * u(rng), 20 * u(rng));
  s.qd.segment<3>(3) = Eigen::Vector3d(0.3 * u(rng), 0.5 * u(rng), 0.3 * u(rng));
  for (int d = 0; d < kModes; ++d) s.qd[6 + d] = 0.2 * u(rng);
  r.stiffness.resize(kModes);
  r.damping.resize(kModes);
  for (int d = 0; d < kModes; ++d) {
    r.stiffness[d] = 2e4 * (1.0 + 0.5 * u(rng));
    r.damping[d] = 200 * (1.0 + 0.5 * u(rng));
  }
  r.targets = 0.1 * Eigen::MatrixXd::NullaryExpr(kModes, steps, [&] { return u(rng); });
  return k;
}

// Contact onsets, ends and slips along the plain run (proof that a grounded case went through
// the branches it is meant to test), and the faces touched.
void ContactEvents(const Case& k, int* onsets, int* ends, int* slips, std::set<int>* faces) {
  BodyState<3, double> s = k.rollout.start;
  UpdateContacts(k.passive, k.rollout.world.ground_plane, &s);
  *onsets = *ends = *slips = 0;
  std::vector<double> K(k.rollout.stiffness.data(), k.rollout.stiffness.data() + kModes);
  std::vector<double> c(k.rollout.damping.data(), k.rollout.damping.data() + kModes);
  auto find = [](const std::vector<Contact<3, double>>& set, const Contact<3, double>& x) -> const Contact<3, double>* {
    for (const auto& y : set)
      if (y.point == x.point && y.face == x.face) return &y;
    return nullptr;
  };
  for (int n = 0; n < k.rollout.steps(); ++n) {
    std::vector<double> target(k.rollout.targets.col(n).data(), k.rollout.targets.col(n).data() + kModes);
    const auto before = s.contacts;
    ASSERT_TRUE(StepBody(k.passive, k.rollout.world, 0, k.rollout.integrator, k.rollout.dt, &s,
                          PdForce<double>{&K, &c, &target}).ok());
    for (const auto& x : s.contacts) {
      faces->insert(x.face);
      const Contact<3, double>* was = find(before, x);
      *onsets += !was;
      *slips += was && was->anchor != x.anchor;
    }
    for (const auto& x : before) *ends += !find(s.contacts, x);
  }
}

void ExpectJetDirectionalDerivatives(const Case& k, unsigned seed) {
  const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(g.ok) << g.message;
  const Eigen::VectorXd p = Flatten(k.rollout), grad = Flatten(g);
  using J1 = ceres::Jet<double, 1>;
  EXPECT_NEAR(g.cost, ReferenceCost<double>(k.passive, k.rollout, p, p), 1e-12 * std::abs(g.cost));
  const int N = k.rollout.steps(), first_target = kNz + 2 * kModes;
  // every start coordinate (translation, rotation, shape, velocity), a gain of each kind and
  // targets early, midway and last
  std::vector<int> probes = {kNz, kNz + kModes + 2, first_target, first_target + kModes * (N / 2) + 1,
                             first_target + kModes * N - 1};
  for (int i = 0; i < kNz; ++i) probes.push_back(i);
  for (int i : probes) {
    const J1 ref = ReferenceCost<J1>(k.passive, k.rollout, p, Eigen::VectorXd::Unit(p.size(), i));
    EXPECT_NEAR(grad[i], ref.v[0], 1e-9 * std::abs(ref.v[0]) + 1e-12 * std::abs(g.cost)) << "parameter " << i;
  }
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd v(p.size());
    for (int i = 0; i < p.size(); ++i) v[i] = normal(rng) * (i < kNz ? 1.0 : i < first_target ? 0.01 * p[i] : 0.1);
    const J1 ref = ReferenceCost<J1>(k.passive, k.rollout, p, v);
    const double scale = (grad.array() * v.array()).abs().sum();  // cancellation cannot hide an error
    EXPECT_NEAR(grad.dot(v), ref.v[0], 1e-9 * scale) << "direction " << trial;
  }
}

TEST(AdjointSpace, MatchesJetsThroughTheWholeRunInTheAir) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    ExpectJetDirectionalDerivatives(MakeCase(integrator, false, 60, 3), 11);
  }
}

TEST(AdjointSpace, MatchesJetsThroughContactsThatBeginSlipAndEnd) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    const Case k = MakeCase(integrator, true, 150, 5);
    int onsets = 0, ends = 0, slips = 0;
    std::set<int> faces;
    ContactEvents(k, &onsets, &ends, &slips, &faces);
    EXPECT_GE(onsets, 10) << "the run must bring points onto the ground";
    EXPECT_GE(slips, 10) << "slide them along it";
    EXPECT_GE(ends, 1) << "and lift some off again";
    RecordProperty("contact_onsets_ends_slips", std::to_string(onsets) + " " + std::to_string(ends) + " " + std::to_string(slips));
    ExpectJetDirectionalDerivatives(k, 13);
  }
}

// A V valley of heightfield triangles (contacts on both walls and carried across edges) and a
// spring holding the chair's back.
TEST(AdjointSpace, MatchesJetsInAHeightfieldValleyWithASpring) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    Case k = MakeCase(integrator, true, 150, 41);
    const int nx = 21, nz = 21;
    std::vector<double> heights;
    for (int j = 0; j < nz; ++j)
      for (int i = 0; i < nx; ++i) heights.push_back(0.25 * std::abs(-200.0 + 20.0 * i - 50.0));
    k.rollout.world.ground_plane.heightfield = Heightfield::Make({-200, -200}, {20, 20}, nx, nz, heights);
    k.rollout.world.springs.push_back(MakeSpring(k.passive, Eigen::Vector3d(0.1, 0.9, 0.5), Eigen::Vector3d(0, 150, 0), 50.0, 5.0, 80.0));
    int onsets = 0, ends = 0, slips = 0;
    std::set<int> faces;
    ContactEvents(k, &onsets, &ends, &slips, &faces);
    EXPECT_GE(faces.size(), 4u) << "contacts on several triangles";
    ExpectJetDirectionalDerivatives(k, 43);
  }
}

// Central differences of the plain cost, one parameter at a time (five-point stencil, its
// rounding bound added as in adjoint_test.cc).
TEST(AdjointSpace, MatchesCentralDifferencesInTheAir) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler}) {
    SCOPED_TRACE(IntegratorName(integrator));
    const Case k = MakeCase(integrator, false, 60, 7);
    const fit::RolloutGradient g = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
    ASSERT_TRUE(g.ok) << g.message;
    const Eigen::VectorXd p = Flatten(k.rollout), grad = Flatten(g);
    const int N = k.rollout.steps(), first_target = kNz + 2 * kModes;
    auto cost_at = [&](int i, double offset) {
      Eigen::VectorXd x = p;
      x[i] += offset;
      return ReferenceCost<double>(k.passive, k.rollout, x, x);
    };
    const double cost = cost_at(0, 0.0);
    for (int i : {0, 1, 3, 4, 5, 6, 8, 12, 15, 17, first_target, first_target + kModes * (N / 2) + 2,
                  first_target + kModes * (N - 1) + 1}) {
      const double h = 1e-4 * std::max(1.0, std::abs(p[i]));
      const double fd = (8.0 * (cost_at(i, h) - cost_at(i, -h)) - (cost_at(i, 2 * h) - cost_at(i, -2 * h))) / (12.0 * h);
      const double rounding = 10.0 * std::numeric_limits<double>::epsilon() * std::abs(cost) / h;
      EXPECT_NEAR(grad[i], fd, 1e-7 * std::abs(fd) + rounding) << "parameter " << i;
    }
  }
}

TEST(AdjointSpace, CheckpointIntervalDoesNotChangeTheGradient) {
  const Case k = MakeCase(Integrator::kThesis, true, 90, 17);
  const fit::RolloutGradient a = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), 1);
  const fit::RolloutGradient b = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), fit::kCheckpointSqrt);
  const fit::RolloutGradient c = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive), 90);
  const fit::RolloutGradient d = fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
  ASSERT_TRUE(a.ok && b.ok && c.ok && d.ok);
  EXPECT_EQ(Flatten(a), Flatten(b));
  EXPECT_EQ(Flatten(a), Flatten(c));
  EXPECT_EQ(Flatten(a), Flatten(d));
  EXPECT_EQ(b.states_held, 9 + 10) << "intervals of ⌈√90⌉ = 10: 9 checkpoints and one interval";
  EXPECT_EQ(a.states_held, 90 + 1);
  EXPECT_EQ(c.states_held, 90 + 1) << "the whole run kept by its forward run";
  EXPECT_EQ(d.states_held, 90 + 1) << "a 90-step run is kept whole by default";
}

TEST(AdjointSpace, RefusesBadInputWithAMessage) {
  const Case good = MakeCase(Integrator::kThesis, false, 5, 1);
  auto refused = [&](auto&& edit, const std::string& words) {
    Case k = good;
    edit(&k.rollout);
    try {
      fit::RolloutCostGradient(k.body, k.rollout, StageOf(k.passive));
      ADD_FAILURE() << "accepted: " << words;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  refused([](fit::ControlledRolloutN<3>* r) { r->integrator = Integrator::kRK4; }, "thesis and symplectic integrators");
  refused([](fit::ControlledRolloutN<3>* r) { r->dt = 0.0; }, "dt must be positive");
  refused([](fit::ControlledRolloutN<3>* r) { r->stiffness.resize(2); }, "one value per mode");
  refused([](fit::ControlledRolloutN<3>* r) { r->targets.resize(2, 5); }, "one row per mode");
  refused([](fit::ControlledRolloutN<3>* r) { r->start.qd[2] = std::nan(""); }, "finite");
  refused([](fit::ControlledRolloutN<3>* r) { r->start.q.segment<4>(3).setZero(); }, "must not be zero");
  refused([](fit::ControlledRolloutN<3>* r) { r->start.q.conservativeResize(Group<3>::kRigidParams + 1); }, "mode amplitudes");
}

}  // namespace
}  // namespace wobble
