// Motion control paths (Witkin & Welch 1990, §4.1–4.2): cubic segments, keyframe splines and
// constraint preroll, checked against their defining conditions, finite differences and the
// closed form of a cubic polynomial the spline must reproduce exactly.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "wobble/control/paths.h"

namespace wobble::control {
namespace {

Eigen::VectorXd V(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double a : v) x[i++] = a;
  return x;
}

// Central differences of position and velocity against the path's velocity and acceleration.
void ExpectDerivativesMatchDifferences(const Path& path, double t, double tol) {
  const double h = 1e-5;
  const PathPoint p = path.Evaluate(t), a = path.Evaluate(t - h), b = path.Evaluate(t + h);
  const Eigen::VectorXd fd_v = (b.n - a.n) / (2 * h);
  const Eigen::VectorXd fd_a = (b.n_dot - a.n_dot) / (2 * h);
  EXPECT_LT((fd_v - p.n_dot).norm(), tol * (1 + p.n_dot.norm())) << "t = " << t;
  EXPECT_LT((fd_a - p.n_ddot).norm(), tol * (1 + p.n_ddot.norm())) << "t = " << t;
}

TEST(HermiteSegment, MeetsBothEndsAndItsDerivativesAreConsistent) {
  const Eigen::VectorXd x0 = V({1, 2, 3}), v0 = V({-1, 0.5, 2}), x1 = V({4, -1, 0}), v1 = V({0, 3, -2});
  const HermiteSegment s(0.5, x0, v0, 2.0, x1, v1);
  EXPECT_EQ(s.dim(), 3);
  EXPECT_LT((s.Evaluate(0.5).n - x0).norm(), 1e-12);
  EXPECT_LT((s.Evaluate(0.5).n_dot - v0).norm(), 1e-12);
  EXPECT_LT((s.Evaluate(2.0).n - x1).norm(), 1e-12);
  EXPECT_LT((s.Evaluate(2.0).n_dot - v1).norm(), 1e-12);
  for (double t : {0.6, 1.0, 1.3, 1.9}) ExpectDerivativesMatchDifferences(s, t, 1e-6);
  // after the end: straight on at v1
  const PathPoint after = s.Evaluate(3.0);
  EXPECT_LT((after.n - (x1 + v1)).norm(), 1e-12);
  EXPECT_LT(after.n_ddot.norm(), 1e-15);
}

TEST(HermiteSegment, DefaultFinalVelocityMakesTheConstantAccelerationParabola) {
  // from (x0, v0) to x1 in T with a constant acceleration a: x1 = x0 + v0 T + a T²/2
  const Eigen::VectorXd x0 = V({0, 10}), v0 = V({3, -1}), a = V({-2, 5});
  const double T = 1.5;
  const Eigen::VectorXd x1 = x0 + v0 * T + 0.5 * a * T * T;
  const Eigen::VectorXd v1 = DefaultFinalVelocity(x0, v0, x1, T);
  EXPECT_LT((v1 - (v0 + a * T)).norm(), 1e-12);
  const HermiteSegment s(0.0, x0, v0, T, x1, v1);
  for (double t : {0.0, 0.4, 1.1, 1.5}) EXPECT_LT((s.Evaluate(t).n_ddot - a).norm(), 1e-12) << t;
}

TEST(KeyframeSpline, InterpolatesKeysAndIsTwiceContinuouslyDifferentiable) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5, 5);
  std::vector<double> times = {0.0, 0.3, 1.0, 1.2, 2.5, 3.0};
  std::vector<Eigen::VectorXd> keys;
  for (size_t i = 0; i < times.size(); ++i) keys.push_back(V({u(rng), u(rng), u(rng)}));
  for (bool clamped : {false, true}) {
    KeyframeSpline::Options o;
    if (clamped) {
      o.start_velocity = V({1, 0, -1});
      o.end_velocity = V({0, 2, 0});
    }
    ASSERT_EQ(KeyframeSpline::Validate(times, keys, o), "");
    const KeyframeSpline s(times, keys, o);
    for (size_t i = 0; i < times.size(); ++i) EXPECT_LT((s.Evaluate(times[i]).n - keys[i]).norm(), 1e-12);
    // C²: velocity and acceleration agree from both sides of every inner key. The difference
    // across a key at ±e shrinks like e (the jerk) when they are continuous and stays put when
    // they jump, so compare e = 1e-6 with e = 1e-8.
    auto jump = [&](double t, double e) {
      const PathPoint l = s.Evaluate(t - e), r = s.Evaluate(t + e);
      return std::make_pair((l.n_dot - r.n_dot).norm(), (l.n_ddot - r.n_ddot).norm());
    };
    for (size_t i = 1; i + 1 < times.size(); ++i) {
      const auto wide = jump(times[i], 1e-6), narrow = jump(times[i], 1e-8);
      EXPECT_LT(narrow.first, wide.first / 50 + 1e-12) << i;
      EXPECT_LT(narrow.second, wide.second / 50 + 1e-9) << i;
    }
    for (double t = 0.05; t < 3.0; t += 0.17) ExpectDerivativesMatchDifferences(s, t, 1e-5);
    if (clamped) {
      EXPECT_LT((s.Evaluate(0.0).n_dot - *o.start_velocity).norm(), 1e-12);
      EXPECT_LT((s.Evaluate(3.0).n_dot - *o.end_velocity).norm(), 1e-12);
    } else {  // natural ends: no acceleration there
      EXPECT_LT(s.Evaluate(0.0).n_ddot.norm(), 1e-9);
      EXPECT_LT(s.Evaluate(3.0 - 1e-12).n_ddot.norm(), 1e-6);
    }
  }
}

TEST(KeyframeSpline, ReproducesACubicPolynomialExactly) {
  // the C² cubic spline through samples of a cubic with its true end velocities is unique and
  // so is the cubic itself: position, velocity and acceleration everywhere in between
  auto f = [](double t) { return V({1 + 2 * t - 3 * t * t + 0.5 * t * t * t, -t * t * t + t}); };
  auto fd = [](double t) { return V({2 - 6 * t + 1.5 * t * t, -3 * t * t + 1}); };
  auto fdd = [](double t) { return V({-6 + 3 * t, -6 * t}); };
  const std::vector<double> times = {-1.0, -0.2, 0.5, 0.6, 2.0};
  std::vector<Eigen::VectorXd> keys;
  for (double t : times) keys.push_back(f(t));
  KeyframeSpline::Options o;
  o.start_velocity = fd(-1.0);
  o.end_velocity = fd(2.0);
  const KeyframeSpline s(times, keys, o);
  for (double t = -1.0; t <= 2.0; t += 0.0625) {
    const PathPoint p = s.Evaluate(t);
    EXPECT_LT((p.n - f(t)).norm(), 1e-10) << t;
    EXPECT_LT((p.n_dot - fd(t)).norm(), 1e-9) << t;
    EXPECT_LT((p.n_ddot - fdd(t)).norm(), 1e-8) << t;
  }
}

TEST(KeyframeSpline, TwoNaturalKeysAreAStraightLineAndItMovesOnAfterTheEnd) {
  const KeyframeSpline s({1.0, 3.0}, {V({0, 0}), V({4, 2})});
  EXPECT_LT((s.Evaluate(2.0).n - V({2, 1})).norm(), 1e-12);
  EXPECT_LT((s.Evaluate(2.0).n_dot - V({2, 1})).norm(), 1e-12);
  EXPECT_LT((s.Evaluate(4.0).n - V({6, 3})).norm(), 1e-12);  // straight on
  EXPECT_LT((s.Evaluate(0.0).n - V({-2, -1})).norm(), 1e-12);
}

TEST(KeyframeSpline, ValidateNamesWhatIsWrong) {
  KeyframeSpline::Options none;
  EXPECT_NE(KeyframeSpline::Validate({0.0}, {V({1})}, none).find("two keys"), std::string::npos);
  EXPECT_NE(KeyframeSpline::Validate({0.0, 0.0}, {V({1}), V({2})}, none).find("strictly increase"), std::string::npos);
  EXPECT_NE(KeyframeSpline::Validate({0.0, 1.0}, {V({1}), V({2, 3})}, none).find("same dimension"), std::string::npos);
  EXPECT_NE(KeyframeSpline::Validate({0.0, 1.0}, {V({1})}, none).find("as many"), std::string::npos);
  KeyframeSpline::Options bad;
  bad.end_velocity = V({1, 2});
  EXPECT_NE(KeyframeSpline::Validate({0.0, 1.0}, {V({1}), V({2})}, bad).find("velocities"), std::string::npos);
  EXPECT_NE(KeyframeSpline::Validate({0.0, NAN}, {V({1}), V({2})}, none).find("finite"), std::string::npos);
}

TEST(Preroll, MeetsThePointsStateNowAndThePathsStateAtOnset) {
  auto path = std::make_shared<KeyframeSpline>(std::vector<double>{2.0, 3.0, 4.5},
                                               std::vector<Eigen::VectorXd>{V({5, 1, 0}), V({6, 3, 1}), V({4, 4, 2})});
  const Eigen::VectorXd x = V({0, 0, 0}), v = V({1, -2, 0.5});
  const PrerolledPath p(path, 1.2, x, v, 2.0);
  EXPECT_LT((p.Evaluate(1.2).n - x).norm(), 1e-12);
  EXPECT_LT((p.Evaluate(1.2).n_dot - v).norm(), 1e-12);
  const PathPoint onset = path->Evaluate(2.0);
  // approaching the onset from the preroll side and at it: the path's position and velocity
  const PathPoint before = p.Evaluate(2.0 - 1e-10);
  EXPECT_LT((before.n - onset.n).norm(), 1e-8);
  EXPECT_LT((before.n_dot - onset.n_dot).norm(), 1e-8);
  EXPECT_LT((p.Evaluate(2.0).n - onset.n).norm(), 1e-12);
  // then the path itself
  for (double t : {2.5, 3.0, 4.0}) EXPECT_LT((p.Evaluate(t).n - path->Evaluate(t).n).norm(), 1e-15);
  for (double t : {1.3, 1.7, 1.95}) ExpectDerivativesMatchDifferences(p, t, 1e-6);
}

}  // namespace
}  // namespace wobble::control
