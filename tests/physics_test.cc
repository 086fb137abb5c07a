// Physics validation against closed forms and conservation laws: free fall, the appendix A rod's
// frequency, convergence orders, energy and momentum conservation, resting contact, friction
// on a slope, stiff contact with the implicit integrator, and failure statuses.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <algorithm>

#include "support/test_bodies.h"
#include "wobble/core/errors.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

using testing::Rod;
using testing::TableDef;
using testing::TableModes;

constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

WorldOptions NoGround(Integrator integrator, double dt, bool gravity = true) {
  WorldOptions o;
  o.params.ground.enabled = false;
  o.params.gravity_on = gravity;
  o.integrator = integrator;
  o.dt = dt;
  return o;
}

Eigen::VectorXd State(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double e : v) x[i++] = e;
  return x;
}

// Linear momentum Σ m ẋ and angular momentum Σ m x × ẋ about the world origin, point by point.
std::pair<Eigen::Vector2d, double> Momenta(const World& w) {
  const BodyModel& b = w.body<2>(0);
  const BodyState<2, double>& s = w.state<2>(0);
  const Frame<2, double> frame(s.q);
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  double L = 0;
  for (int k = 0; k < b.num_points(); ++k) {
    const Vec2<double> l = LocalPosition<double>(b.rest_local(k), b.mode_matrix(k), s.q);
    const Vec2<double> x = WorldFromLocal(frame, l), v = PointVelocity(frame, s.qd, l, b.mode_matrix(k));
    p += b.mass(k) * v;
    L += b.mass(k) * (x.x() * v.y() - x.y() * v.x());
  }
  return {p, L};
}

// The thesis scheme (Eq. 4.22/4.23) under constant acceleration has the closed form
// v_n = v0 − g n Δt, y_n = y0 + n Δt v0 − g Δt² n(n+1)/2; RK4 is exact for the parabola.
TEST(FreeFall, MatchesClosedFormsWithAndWithoutModes) {
  for (bool with_modes : {false, true}) {
    for (Integrator integrator : {Integrator::kThesis, Integrator::kRK4}) {
      World w(NoGround(integrator, 0.01));
      auto body = std::make_shared<BodyModel>(TableDef(), with_modes ? TableModes(1e5) : std::vector<DeformationMode>{});
      w.AddBody(body);
      Eigen::VectorXd q = Eigen::VectorXd::Zero(body->num_q()), qd = q;
      q << 10, 1000, 0.4, Eigen::VectorXd::Zero(body->num_modes());
      qd[0] = 3;
      qd[1] = 20;
      w.SetState(0, q, qd);
      const int n = 500;
      for (int i = 0; i < n; ++i) ASSERT_TRUE(w.Step());
      const double t = n * 0.01;
      const double y_expected = integrator == Integrator::kThesis ? 1000 + n * 0.01 * 20 - kG * 0.01 * 0.01 * n * (n + 1) / 2
                                                                  : 1000 + 20 * t - 0.5 * kG * t * t;
      SCOPED_TRACE(IntegratorName(integrator) + (with_modes ? " with modes" : " rigid"));
      EXPECT_NEAR(w.q(0)[1], y_expected, 1e-9 * 1000);
      EXPECT_NEAR(w.q(0)[0], 10 + 3 * t, 1e-9 * 100);
      EXPECT_NEAR(w.qd(0)[1], 20 - kG * t, 1e-10 * 100);
      // uniform gravity neither turns nor deforms the body
      EXPECT_NEAR(w.q(0)[2], 0.4, 1e-12);
      for (int d = 0; d < body->num_modes(); ++d) EXPECT_NEAR(w.q(0)[3 + d], 0.0, 1e-12);
    }
  }
}

// Appendix A: two masses m joined through d_y = C j. The relative coordinate δ = 3Cγ feels
// V = Kγ² = K δ²/(9C²) and has reduced mass m/2, so ω² = 4K / (9 C² m).
TEST(Rod, OscillatesAtTheFrequencyItsStiffnessAndMassPredict) {
  const double K = 4.5e6, C = -100, m = 50;
  const double omega = std::sqrt(4 * K / (9 * C * C * m));  // = 2 rad/s
  World w(NoGround(Integrator::kRK4, 1e-3, /*gravity=*/false));
  w.AddBody(std::make_shared<BodyModel>(Rod(K, C)));
  w.SetState(0, State({0, 0, 0, 0.1}), State({0, 0, 0, 0}));
  // γ(t) = 0.1 cos ωt; the centre of mass stays put, so ty(t) = −(3C/2)(γ − 0.1)
  double max_err = 0, max_ty_err = 0;
  for (int i = 1; i <= 10000; ++i) {
    ASSERT_TRUE(w.Step());
    const double t = w.time();
    max_err = std::max(max_err, std::abs(w.q(0)[3] - 0.1 * std::cos(omega * t)));
    max_ty_err = std::max(max_ty_err, std::abs(w.q(0)[1] + 1.5 * C * (w.q(0)[3] - 0.1)));
  }
  EXPECT_LT(max_err, 1e-9);
  EXPECT_LT(max_ty_err, 1e-7);
  EXPECT_NEAR(w.q(0)[2], 0.0, 1e-12);
}

// Error against the rod's closed form at Δt and Δt/2: first order for the Euler family,
// fourth order for RK4.
TEST(Integrators, ConvergeAtTheirOrder) {
  const double K = 4.5e6, C = -100;
  auto error = [&](Integrator integrator, double dt) {
    World w(NoGround(integrator, dt, false));
    w.AddBody(std::make_shared<BodyModel>(Rod(K, C)));
    w.SetState(0, State({0, 0, 0, 0.1}), State({0, 0, 0, 0}));
    w.RunUntil(2.0, [](const World&) {});
    return std::abs(w.q(0)[3] - 0.1 * std::cos(2.0 * w.time()));
  };
  for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler, Integrator::kImplicitEuler}) {
    const double ratio = error(integrator, 0.002) / error(integrator, 0.001);
    EXPECT_NEAR(ratio, 2.0, 0.3) << IntegratorName(integrator);
  }
  EXPECT_NEAR(error(Integrator::kRK4, 0.02) / error(Integrator::kRK4, 0.01), 16.0, 2.0);
}

// No damping, ground or friction: a spinning, wobbling table over 10⁵ steps. The midpoint
// variational integrator is symplectic for any M(q): its energy error stays in a band that
// does not widen. The thesis scheme (symplectic only when M is constant) drifts slowly; its
// measured bound is stated so that a regression shows.
double MaxEnergyDeviation(Integrator integrator, double* first_half) {
  World w(NoGround(integrator, 1e-3, /*gravity=*/false));
  w.AddBody(std::make_shared<BodyModel>(TableDef(), TableModes(2e5)));
  w.SetState(0, State({0, 0, 0, 0.05, -0.03, 0.02, 0.04}), State({1, -2, 0.3, 0.1, 0.05, -0.1, 0.08}));
  const double e0 = w.ComputeEnergies(0).total();
  double max_dev = 0;
  for (int i = 0; i < 100000; ++i) {
    if (!w.Step()) return std::numeric_limits<double>::infinity();
    max_dev = std::max(max_dev, std::abs(w.ComputeEnergies(0).total() - e0) / e0);
    if (i == 49999) *first_half = max_dev;
  }
  return max_dev;
}

TEST(Conservation, VariationalEnergyStaysBoundedOver1e5Steps) {
  double first_half = 0;
  const double max_dev = MaxEnergyDeviation(Integrator::kVariational, &first_half);
  EXPECT_LT(max_dev, 1e-5);
  EXPECT_LT(max_dev, 1.2 * first_half);  // bounded, not drifting
}

TEST(Conservation, ThesisSchemeEnergyErrorWithinMeasuredBound) {
  double first_half = 0;
  EXPECT_LT(MaxEnergyDeviation(Integrator::kThesis, &first_half), 2e-3);
}

// A constant PD target γ0 makes the mode force −2K(γ − γ0): the energy World reports must be
// the potential of that force, K(γ − γ0)², or the total would swing by K((γ−γ0)² − γ²) as the
// modes oscillate about their targets instead of staying put.
TEST(Conservation, EnergyWithPdTargetsIsConserved) {
  World w(NoGround(Integrator::kVariational, 1e-3, /*gravity=*/false));
  w.AddBody(std::make_shared<BodyModel>(TableDef(), TableModes(2e5)));
  w.SetState(0, State({0, 0, 0, 0, 0, 0, 0}), State({0.5, 0, 0.1, 0, 0, 0, 0}));
  w.SetModeTargets(0, State({0.3, -0.2, 0.1, 0.25}));
  const double e0 = w.ComputeEnergies(0).total();
  double max_dev = 0, max_modes = 0;
  for (int i = 0; i < 20000; ++i) {
    ASSERT_TRUE(w.Step()) << w.status().message;
    const Energies e = w.ComputeEnergies(0);
    max_dev = std::max(max_dev, std::abs(e.total() - e0));
    max_modes = std::max(max_modes, e.modes);
  }
  EXPECT_GT(max_modes, 0.0);
  EXPECT_LT(max_dev, 1e-5 * max_modes);
}

TEST(Conservation, MomentaWithoutGravity) {
  World w(NoGround(Integrator::kRK4, 1e-3, /*gravity=*/false));
  w.AddBody(std::make_shared<BodyModel>(TableDef(), TableModes(2e5)));
  w.SetState(0, State({5, 7, 0.2, 0.05, -0.03, 0.02, 0.04}), State({1, -2, 0.3, 0.1, 0.05, -0.1, 0.08}));
  const auto [p0, L0] = Momenta(w);
  for (int i = 0; i < 5000; ++i) ASSERT_TRUE(w.Step());
  const auto [p1, L1] = Momenta(w);
  EXPECT_LT((p1 - p0).norm(), 1e-9 * p0.norm());
  EXPECT_NEAR(L1, L0, 1e-9 * std::abs(L0));
}

// Dropped on level ground, the table settles on its two leg tips; each then carries half the
// weight, so the penetration approaches m g / (2 K_d).
TEST(Ground, DroppedTableComesToRestWithBoundedPenetration) {
  WorldOptions o;
  o.dt = 0.01;
  World w(o);
  // modes stiff enough to hold the table's weight, damped near critically
  auto body = std::make_shared<BodyModel>(TableDef(), TableModes(4e6, 5e6));
  w.AddBody(body);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  q[1] = 50;
  w.SetState(0, q, Eigen::VectorXd::Zero(7));
  double deepest = 0;
  for (int i = 0; i < 4000; ++i) {
    ASSERT_TRUE(w.Step()) << w.status().message;
    deepest = std::max(deepest, w.Penetration(0));
  }
  const double weight = body->moments().m * kG, Kd = o.params.ground.stiffness;
  const Energies e = w.ComputeEnergies(0);
  EXPECT_LT(e.kinetic, 1e-3 * weight);  // at rest
  EXPECT_EQ(w.state<2>(0).contacts.size(), 2u);
  EXPECT_NEAR(w.Penetration(0), weight / (2 * Kd), 0.05 * weight / (2 * Kd));
  // the impact cannot store more than the drop's energy m g h in the two ground springs
  EXPECT_LT(deepest, std::sqrt(weight * 50 / Kd));
}

// A rigid table standing on a slope α with friction cap μ = tan θ_f sticks when α < θ_f and
// slides when α > θ_f with acceleration g (sin α − μ cos α) (Coulomb).
// Large bodies scan only the point groups whose bounding box reaches below the ground: the
// points visited must be exactly those a brute-force height test finds, for both bases, any
// slope and deformed states.
TEST(Ground, GroupedScanVisitsExactlyThePointsBelowTheGround) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int partial = 0;
  for (BasisKind basis : {BasisKind::kBernstein, BasisKind::kCubicBSpline}) {
    const BodyModel body = testing::RandomBody(rng, basis == BasisKind::kBernstein ? 4 : 6, 5, basis, 3, 3000);
    ASSERT_GT(body.clusters().size(), 1u);
    for (int trial = 0; trial < 20; ++trial) {
      Ground g;
      g.slope = 0.3 * u(rng);
      g.point = Eigen::Vector2d(0.0, 40.0 * u(rng));
      BodyState<2, double> s;
      s.q = VecQ<double>::Zero(body.num_q());
      s.qd = VecQ<double>::Zero(body.num_q());
      s.q << 30 * u(rng), 30 * u(rng), 0.5 * u(rng), 0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng);
      std::vector<int> visited, expected;
      const Frame<2, double> frame(s.q);
      ForEachPointInContact(body, g, s, frame, [&](int k, const Vec2<double>&, const Vec2<double>&,
                                                   const Vec2<double>&, const Vec2<double>&, const GroundFace&,
                                                   int) { visited.push_back(k); });
      const GroundFace gf = g.Face(0);
      for (int k = 0; k < body.num_points(); ++k) {
        const Vec2<double> x = WorldFromLocal(frame, LocalPosition<double>(body.rest_local(k), body.mode_matrix(k), s.q));
        if (gf.Height(x) < 0.0) expected.push_back(k);
      }
      std::sort(visited.begin(), visited.end());
      EXPECT_EQ(visited, expected) << "trial " << trial;
      if (!expected.empty() && int(expected.size()) < body.num_points()) ++partial;
    }
  }
  EXPECT_GE(partial, 10);  // partial contacts, where skipping groups matters
}

// Steps `body` from `s` and checks that every step's scan visits exactly the points that a test
// of every point finds below the ground, in that full scan's order (the clusters'; for a small
// body, point order), so the contacts and the summed ground force are the full scan's, bit for
// bit; and that the contacts the step leaves are those points. Counts the steps touching and
// those with fewer than `few` points below (where skipping matters).
// The step's contact update may skip the point tree's walk on the memo of an earlier one
// (PlaneScanMemo): each step is also redone from the same state with no memo, and the contacts,
// anchors and ground force must be the same bit for bit. Counts the touching steps that
// skipped the walk (`reused`).
struct ScanRun {
  int touching = 0, partial = 0, reused = 0;
};
ScanRun CheckScanAgainstTheExactTest(const BodyModel& body, const WorldParams& w, BodyState<2, double> s, double dt,
                                     int steps, int few) {
  ScanRun r;
  for (int step = 0; step < steps; ++step) {
    const BodyState<2, double> before = s;
    if (!StepBody(body, w, 0, Integrator::kThesis, dt, &s).ok()) {
      ADD_FAILURE() << "the step failed at step " << step;
      return r;
    }
    const Frame<2, double> frame(s.q);
    std::vector<int> visited, expected;
    ForEachPointInContact(body, w.ground, s, frame,
                          [&](int k, const Vec2<double>&, const Vec2<double>&, const Vec2<double>&,
                              const Vec2<double>&, const GroundFace&, int) { visited.push_back(k); });
    const GroundFace line = w.ground.Face(0);
    for (const PointCluster& c : body.clusters())
      for (int k : c.points) {
        const Vec2<double> x = WorldFromLocal(frame, LocalPosition<double>(body.rest_local(k), body.mode_matrix(k), s.q));
        if (line.Height(x) < 0.0) expected.push_back(k);
      }
    if (visited != expected) {
      ADD_FAILURE() << "the scan's points differ from the exact test's at step " << step;
      return r;
    }
    std::vector<int> contacts;
    for (const Contact<2, double>& c : s.contacts) contacts.push_back(c.point);
    std::sort(expected.begin(), expected.end());
    if (contacts != expected) {
      ADD_FAILURE() << "the step's contacts differ from the exact test's points at step " << step;
      return r;
    }
    BodyState<2, double> fresh = s;
    fresh.contacts = before.contacts;
    fresh.scan_memo = PlaneScanMemo<2>();
    UpdateContacts(body, w.ground, &fresh);
    bool same = fresh.contacts.size() == s.contacts.size() && fresh.ground_cache.force == s.ground_cache.force &&
                fresh.penetration == s.penetration;
    for (size_t i = 0; same && i < s.contacts.size(); ++i)
      same = fresh.contacts[i].point == s.contacts[i].point && fresh.contacts[i].face == s.contacts[i].face &&
             fresh.contacts[i].anchor == s.contacts[i].anchor;
    if (!same) {
      ADD_FAILURE() << "the contact update with the memo differs from a fresh walk's at step " << step;
      return r;
    }
    r.touching += !expected.empty();
    r.partial += !expected.empty() && int(expected.size()) < few;
    r.reused += !expected.empty() && before.scan_memo.valid && s.scan_memo.offset == before.scan_memo.offset;
  }
  return r;
}

// A table of 3,200 points in point groups (so the scan walks the point tree), at rest at
// height y.
const BodyModel& Table3200() {
  static const BodyModel body(TableDef(1100, 1000, 550.0 / 3200), {testing::Bend(4e5, 2.5e4), testing::Shear(4e5, 2.5e4)});
  return body;
}
BodyState<2, double> Table3200At(double y) {
  BodyState<2, double> s = RestState<2, double>(Table3200());
  s.q[1] = y;
  return s;
}

// The scan skips the point tree's nodes (body_model.h) whose box stays above the ground, over
// a long run of a 3,200-point table thrown spinning onto the ground (it bounces, lands on its
// legs and top, rolls and slides).
TEST(Ground, TreeScanMatchesTheFullScanOverALongTumblingRun) {
  const BodyModel& body = Table3200();
  ASSERT_GT(body.clusters().size(), 1u);
  WorldParams w;
  BodyState<2, double> s = Table3200At(40.0);
  s.q[2] = 0.4;  // tilted: it lands on one foot, rocks onto both and slides
  // turning at 0.5 rad/s about its centre of mass c, which moves at (80, 0): ṫ = v − ω S R c
  const Eigen::Vector2d c = Rotation(s.q[2]) * body.moments().c0 / body.moments().m;
  s.qd[2] = 0.5;
  s.qd.head<2>() = Eigen::Vector2d(80.0, 0.0) - s.qd[2] * Eigen::Vector2d(-c.y(), c.x());
  const ScanRun r = CheckScanAgainstTheExactTest(body, w, s, 0.002, 6000, body.num_points() / 20);
  EXPECT_GT(r.touching, 1500);  // the run is mostly in contact ...
  EXPECT_GT(r.partial, 1500);   // ... through few points, where skipping matters
  RecordProperty("steps_touching", r.touching);
  RecordProperty("steps_with_few_points_below", r.partial);
  RecordProperty("steps_reusing_the_walk", r.reused);
}

// A 3,200-point table dropped on its feet comes to rest, and then its contact updates reuse
// the point tree's walk of an earlier step on most steps (PlaneScanMemo), with the contacts
// and force of a fresh walk bit for bit (CheckScanAgainstTheExactTest redoes every step).
TEST(Ground, ARestingBodyReusesItsTreeWalk) {
  const BodyModel& body = Table3200();
  WorldParams w;
  BodyState<2, double> s = Table3200At(10.0);
  const ScanRun landing = CheckScanAgainstTheExactTest(body, w, s, 0.01, 1000, body.num_points() / 20);
  EXPECT_GT(landing.touching, 500);  // it falls, lands and settles within the first 1,000 steps
  for (int i = 0; i < 1000; ++i) ASSERT_TRUE(StepBody(body, w, 0, Integrator::kThesis, 0.01, &s).ok());
  const ScanRun resting = CheckScanAgainstTheExactTest(body, w, s, 0.01, 500, body.num_points() / 20);
  EXPECT_EQ(resting.touching, 500);
  EXPECT_GT(resting.reused, 400);  // of 500 steps at rest
  RecordProperty("landing_steps_reusing_the_walk", landing.reused);
  RecordProperty("resting_steps_reusing_the_walk", resting.reused);
}

// A small body (one point group: every point is tested) on a sloped line: the per-point bound
// before the exact test (PointClearOfPlane, as in 3D) skips only points the exact test
// rejects, over a long tumbling, deforming run.
TEST(Ground, PointBoundScanMatchesTheFullScanOfASmallBody) {
  const BodyModel body(TableDef(), TableModes(2e5, 2e3));
  ASSERT_EQ(body.clusters().size(), 1u);
  WorldParams w;
  w.ground.slope = 0.2;
  BodyState<2, double> s = RestState<2, double>(body);
  s.q[1] = 15.0;
  s.q[2] = 0.5;  // tilted against the slope: it lands on one foot, rolls over and slides down
  s.qd[0] = 5.0;
  s.qd[2] = 0.3;
  const ScanRun r = CheckScanAgainstTheExactTest(body, w, s, 0.01, 4000, body.num_points());
  EXPECT_GT(r.touching, 1000);  // of 4,000 steps
  EXPECT_GT(r.partial, 1000);   // some points below, most above: where the bound skips
  RecordProperty("steps_touching", r.touching);
}

TEST(Ground, SticksBelowFrictionCapAndSlidesAbove) {
  const double mu = std::tan(20.0 * kPi / 180);
  for (double alpha_deg : {10.0, 30.0}) {
    const double alpha = alpha_deg * kPi / 180;
    WorldOptions o;
    o.dt = 0.002;
    o.params.ground.slope = alpha;
    o.params.ground.friction_cap = mu;
    o.params.ground.friction_damping = 1000;  // settles the tangential spring within the first seconds
    World w(o);
    w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
    const Eigen::Vector2d n(-std::sin(alpha), std::cos(alpha)), tau(std::cos(alpha), std::sin(alpha));
    const Eigen::Vector2d t0 = 0.01 * n;
    w.SetState(0, State({t0.x(), t0.y(), alpha}), State({0, 0, 0}));
    auto along = [&] { return tau.dot(Eigen::Vector2d(w.q(0)[0], w.q(0)[1])); };
    w.RunUntil(6.0, [](const World&) {});
    const double s1 = along(), v1 = tau.dot(Eigen::Vector2d(w.qd(0)[0], w.qd(0)[1]));
    ASSERT_TRUE(w.RunUntil(10.0, [](const World&) {})) << w.status().message;
    const double s2 = along();
    SCOPED_TRACE(alpha_deg);
    const double weight = 550 * kG, Kd = o.params.ground.stiffness;
    if (alpha_deg < 20) {
      // stuck: over 4 s it moves less than 1% of its static deflection (a slide moves tens of units)
      EXPECT_LT(std::abs(s2 - s1), 1e-3);
      // held by the two tangential springs: deflection m g sin α / (2 K_d) downhill
      EXPECT_NEAR(s2, -weight * std::sin(alpha) / (2 * Kd), 0.05 * weight * std::sin(alpha) / (2 * Kd));
    } else {
      // downhill is −τ: s(t) = s1 + v1 t − ½ a t² over the 4 s
      const double a = kG * (std::sin(alpha) - mu * std::cos(alpha));
      EXPECT_NEAR(v1, -a * 6.0, 0.01 * a * 6.0);
      EXPECT_NEAR(s2 - s1, v1 * 4.0 - 0.5 * a * 16.0, 0.01 * std::abs(s2 - s1));
    }
  }
}

// A ground 20000 times stiffer than appendix C's: the explicit thesis scheme at Δt = 0.01 is
// unstable and stops with a status; backward Euler settles the table.
TEST(Ground, ImplicitEulerHandlesStiffContact) {
  for (Integrator integrator : {Integrator::kThesis, Integrator::kImplicitEuler}) {
    WorldOptions o;
    o.dt = 0.01;
    o.integrator = integrator;
    o.params.ground.stiffness = 9e7;
    o.params.ground.normal_damping = 1e5;
    World w(o);
    w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
    w.SetState(0, State({0, 5, 0}), State({0, 0, 0}));
    const bool ok = w.RunUntil(5.0, [](const World&) {});
    if (integrator == Integrator::kThesis) {
      // explicit: stops with a status or keeps bouncing, never at rest
      EXPECT_TRUE(!ok || w.ComputeEnergies(0).kinetic > 1.0);
    } else {
      ASSERT_TRUE(ok) << w.status().message;
      EXPECT_LT(std::abs(w.qd(0)[1]), 1e-3);
      EXPECT_NEAR(w.Penetration(0), 550 * kG / (2 * 9e7), 1e-6);
    }
  }
}

// Fig. 4.4: a spring holding a point. A rigid table hung by a damped spring at its centre of
// mass comes to rest with the spring stretched by m g / k, and does not turn.
TEST(Spring, HoldsTheTableAtTheStaticStretch) {
  World w(NoGround(Integrator::kRK4, 0.005));
  auto body = std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{});
  w.AddBody(body);
  const Eigen::Vector2d com = body->moments().c0 / body->moments().m;
  const Eigen::Vector2d anchor(0, 500);
  w.AddSpring(MakeSpring(*body, body->lattice().LocalCoords(com), anchor, 2000, 1500, 100));
  w.SetState(0, State({-com.x(), 300 - com.y(), 0}), State({0, 0, 0}));
  ASSERT_TRUE(w.RunUntil(60.0, [](const World&) {})) << w.status().message;
  const double m = body->moments().m;
  const Eigen::Vector2d held(w.q(0)[0] + com.x(), w.q(0)[1] + com.y());
  EXPECT_NEAR((anchor - held).norm(), 100 + m * kG / 2000, 1e-6);
  EXPECT_NEAR(held.x(), 0.0, 1e-9);
  EXPECT_NEAR(w.q(0)[2], 0.0, 1e-9);
  EXPECT_NEAR(w.ComputeEnergies(0).springs, 0.5 * 2000 * std::pow(m * kG / 2000, 2), 1e-3);
}

TEST(Status, DuplicatedModeStopsTheRunAtTheFirstStep) {
  World w(NoGround(Integrator::kThesis, 0.01));
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{testing::Bend(), testing::Bend()}));
  EXPECT_FALSE(w.Step());
  EXPECT_EQ(w.status().step, 1);
  EXPECT_EQ(w.status().time, 0.0);
  EXPECT_TRUE(w.status().code == StepStatus::Code::kSingularMass || w.status().code == StepStatus::Code::kIllConditioned);
  EXPECT_NE(w.status().message.find("step 1"), std::string::npos) << w.status().message;
  EXPECT_NE(w.status().message.find("mass matrix"), std::string::npos) << w.status().message;
  EXPECT_FALSE(w.Step());  // stays stopped
}

TEST(Status, RunawayPenetrationIsNamedWithStepAndTime) {
  WorldOptions o;
  o.dt = 0.01;
  o.params.ground.stiffness = 1.0;  // far too soft to hold the table
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
  EXPECT_FALSE(w.RunUntil(100.0, [](const World&) {}));
  EXPECT_EQ(w.status().code, StepStatus::Code::kPenetration);
  EXPECT_GT(w.status().step, 1);
  EXPECT_NEAR(w.status().time, (w.status().step - 1) * 0.01, 1e-9);
  EXPECT_NE(w.status().message.find("below the ground"), std::string::npos);
  // the last good state is kept: finite, and within the automatic limit (half the lattice's
  // shorter side, 50)
  EXPECT_TRUE(w.q(0).allFinite());
  EXPECT_LE(w.Penetration(0), 50.0);
  EXPECT_GT(w.Penetration(0), 40.0);
}

// A state is finite with finite energies, or refused: SetState refuses inf, and a finite q̇ of
// 1e160 whose ½ m v² is not finite, leaving the state as it was.
TEST(Status, StatesWithoutAFiniteEnergyAreRefused) {
  World w(NoGround(Integrator::kThesis, 0.01));
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
  EXPECT_THROW(w.SetState(0, State({0, 0, 0}), State({0, std::numeric_limits<double>::infinity(), 0})), InputError);
  try {
    w.SetState(0, State({0, 0, 0}), State({0, 1e160, 0}));
    ADD_FAILURE() << "a state with an infinite kinetic energy was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("kinetic inf"), std::string::npos) << e.what();
  }
  EXPECT_EQ(w.qd(0), State({0, 0, 0}));
  EXPECT_TRUE(std::isfinite(w.ComputeEnergies(0).total()));
}

// Under a gravity of 1e300 one step leaves a finite state (q̈ = g, q̇ = g Δt, q = g Δt²) whose
// energies are not (m g y, ½ m q̇²): the step is refused with that cause and the body keeps its
// state before it. Without the check the trajectory's energy columns read inf with status ok.
TEST(Status, AStepToAnInfiniteEnergyIsRefusedWithThatCause) {
  WorldOptions o = NoGround(Integrator::kThesis, 0.01);
  o.params.gravity = Eigen::Vector3d(0.0, -1e300, 0.0);
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
  EXPECT_FALSE(w.Step());
  EXPECT_EQ(w.status().code, StepStatus::Code::kNonFiniteEnergy) << w.status().message;
  EXPECT_NE(w.status().message.find("kinetic"), std::string::npos) << w.status().message;
  EXPECT_EQ(w.q(0), State({0, 0, 0}));
  EXPECT_EQ(w.qd(0), State({0, 0, 0}));
}

// A force past the largest double is named as such, not as a singular mass matrix (a ground
// stiffness of 1e308 on a table landing at 1 unit/s: k d r for the torque overflows).
TEST(Status, AnOverflowingForceIsNotASingularMassMatrix) {
  WorldOptions o;
  o.dt = 0.01;
  o.params.gravity_on = false;
  o.params.ground.stiffness = 1e308;
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
  w.SetState(0, State({0, 0.001, 0}), State({0, -1.0, 0}));
  EXPECT_FALSE(w.RunUntil(1.0));
  EXPECT_TRUE(w.status().code == StepStatus::Code::kOverflowingForce ||
              w.status().code == StepStatus::Code::kNonFiniteEnergy)
      << w.status().message;
  EXPECT_TRUE(w.q(0).allFinite() && w.qd(0).allFinite());
  EXPECT_TRUE(std::isfinite(w.ComputeEnergies(0).total()));
}

}  // namespace
}  // namespace wobble
