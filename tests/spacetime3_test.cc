// Spacetime fits of the 3D body (lib/wobble/fit/spacetime.h, FitSpacetime, issue 18): the 3D
// task terms against the direct per-point formulas and central differences in tangent
// coordinates, and the fit itself on a task whose answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "support/test_bodies.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/spacetime.h"

namespace wobble {
namespace {

constexpr int kModes = 3;             // the chair's bend, twist and squash
constexpr int kNz = 12 + 2 * kModes;  // tangent coordinates of a state

const BodyModelN<3>& Chair() {
  static const BodyModelN<3> chair = testing::Chair3();
  return chair;
}

BodyState<3, double> RandomState(std::mt19937* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  BodyState<3, double> s = RestState<3, double>(Chair());
  s.translation() = Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng)) * 50.0;
  s.set_orientation(Eigen::Quaterniond(normal(*rng), normal(*rng), normal(*rng), normal(*rng)).normalized());
  s.gamma() = VecD<double>(kModes);
  s.qd = VecQ<double>(6 + kModes);
  for (int d = 0; d < kModes; ++d) s.gamma()[d] = 0.3 * normal(*rng);
  for (int i = 0; i < s.qd.size(); ++i) s.qd[i] = (i < 3 ? 40.0 : 1.0) * normal(*rng);
  return s;
}

// The state moved by h along tangent coordinate i: (t + δt, R exp(ε̂), γ + δγ, v + δv).
BodyState<3, double> Moved(const BodyState<3, double>& s, int i, double h) {
  BodyState<3, double> m = s;
  if (i < 3) {
    m.translation()[i] += h;
  } else if (i < 6) {
    Eigen::Vector3d eps = Eigen::Vector3d::Zero();
    eps[i - 3] = h;
    m.set_orientation(s.orientation() * ExpRotation<double>(eps));
  } else if (i < 6 + kModes) {
    m.gamma()[i - 6] += h;
  } else {
    m.qd[i - 6 - kModes] += h;
  }
  return m;
}

// Centre of mass and its velocity by the direct per-point formulas: x_k = t + R l_k,
// ẋ_k = ṫ + R (ω × l_k + B_k γ̇), l_k = b0_k + B_k γ, summed with the point masses.
void PerPointCentre(const BodyModelN<3>& body, const BodyState<3, double>& s, Eigen::Vector3d* x, Eigen::Vector3d* v) {
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  const Eigen::Vector3d omega = s.qd.segment<3>(3);
  double m = 0.0;
  x->setZero();
  v->setZero();
  for (int k = 0; k < body.num_points(); ++k) {
    const Eigen::Vector3d l = body.rest_local(k) + body.mode_matrix(k) * s.gamma();
    *x += body.mass(k) * (s.translation() + R * l);
    *v += body.mass(k) * (s.qd.head<3>() + R * (omega.cross(l) + body.mode_matrix(k) * s.qd.tail(kModes)));
    m += body.mass(k);
  }
  *x /= m;
  *v /= m;
}

TEST(SpacetimeSpace, CentreOfMassTermsMeasureThePerPointCentre) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    const BodyState<3, double> s = RandomState(&rng);
    Eigen::Vector3d x, v;
    PerPointCentre(Chair(), s, &x, &v);
    // with goal 0 and weight 1 the gradient in δt (δṫ) is the centre (its velocity) itself
    Eigen::VectorXd dz = Eigen::VectorXd::Zero(kNz);
    const double at = fit::CentreOfMassAt(Chair(), 4, Eigen::Vector3d::Zero(), 1.0)(4, s, &dz);
    EXPECT_LT((dz.head<3>() - x).norm(), 1e-10 * x.norm()) << "trial " << trial;
    EXPECT_NEAR(at, 0.5 * x.squaredNorm(), 1e-10 * x.squaredNorm());
    dz.setZero();
    const double moving = fit::CentreOfMassVelocityAt(Chair(), 4, Eigen::Vector3d::Zero(), 1.0)(4, s, &dz);
    EXPECT_LT((dz.segment<3>(6 + kModes) - v).norm(), 1e-10 * v.norm()) << "trial " << trial;
    EXPECT_NEAR(moving, 0.5 * v.squaredNorm(), 1e-10 * v.squaredNorm());
  }
}

TEST(SpacetimeSpace, TaskTermsHaveTheirExactGradients) {
  const Eigen::Vector3d goal(30.0, -20.0, 45.0);
  fit::Axes xz;
  xz.y = false;
  const std::vector<fit::StageCostN<3>> terms = {
      fit::CentreOfMassAt(Chair(), 2, goal, 0.7),
      fit::CentreOfMassAt(Chair(), 2, goal, 0.7, xz),
      fit::CentreOfMassVelocityAt(Chair(), 2, goal, 0.3),
      fit::UprightAt<3>(2, 2.0, 0.4),
      fit::StillAt<3>(2, 0.5),
      fit::SumOf({fit::UprightAt<3>(2, 1.0), fit::CentreOfMassVelocityAt(Chair(), 2, goal, 0.2, xz)}),
  };
  std::mt19937 rng(11);
  for (int trial = 0; trial < 3; ++trial) {
    const BodyState<3, double> s = RandomState(&rng);
    for (size_t t = 0; t < terms.size(); ++t) {
      Eigen::VectorXd dz = Eigen::VectorXd::Zero(kNz);
      EXPECT_EQ(terms[t](3, s, &dz), 0.0) << "another step adds nothing";
      EXPECT_TRUE(dz.isZero(0.0));
      const double value = terms[t](2, s, &dz);
      EXPECT_GT(value, 0.0);
      for (int i = 0; i < kNz; ++i) {
        // five-point central differences; h relative to the coordinate's scale
        const double h = i < 3 ? 1e-3 : 1e-5;
        Eigen::VectorXd scratch = Eigen::VectorXd::Zero(kNz);
        auto at = [&](double k) { return terms[t](2, Moved(s, i, k * h), &scratch); };
        const double cd = (-at(2) + 8 * at(1) - 8 * at(-1) + at(-2)) / (12 * h);
        EXPECT_NEAR(dz[i], cd, 1e-7 * (std::abs(value) + std::abs(cd)) + 1e-9) << "term " << t << " z" << i;
      }
    }
  }
  EXPECT_THROW(fit::UprightAt<3>(-1, 1.0), std::invalid_argument);
  EXPECT_THROW(fit::StillAt<3>(1, -1.0), std::invalid_argument);
  EXPECT_THROW(fit::CentreOfMassAt(Chair(), 1, {NAN, 0.0, 0.0}, 1.0), std::invalid_argument);
  EXPECT_THROW(fit::SumOf({fit::StillAt<3>(1, 1.0), fit::StageCostN<3>()}), std::invalid_argument);
}

// A tilted chair turned by a yaw stays upright; one tipped over does not.
TEST(SpacetimeSpace, UprightIgnoresHeadingOnly) {
  BodyState<3, double> s = RestState<3, double>(Chair());
  s.gamma() = VecD<double>::Zero(kModes);
  s.qd = VecQ<double>::Zero(6 + kModes);
  Eigen::VectorXd dz = Eigen::VectorXd::Zero(kNz);
  s.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitY())));
  EXPECT_NEAR(fit::UprightAt<3>(0, 1.0)(0, s, &dz), 0.0, 1e-15);
  s.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ())));
  EXPECT_NEAR(fit::UprightAt<3>(0, 1.0)(0, s, &dz), 1.0, 1e-12);  // w (1 − cos 90°)
}

// The chair in the air without gravity: the task is to hold the squash at `goal` and be still
// at the last step, from targets that start at zero (the 3D twin of spacetime_test's bend).
fit::SpacetimeProblemN<3> SquashAtTheEnd(double goal, double bound, int steps, int knots) {
  fit::SpacetimeProblemN<3> p;
  fit::ControlledRolloutN<3>& r = p.rollout;
  r.world.gravity_on = false;
  r.world.ground_plane.enabled = false;
  r.integrator = Integrator::kSymplecticEuler;
  r.dt = 0.01;
  r.start = RestState<3, double>(Chair());
  r.start.translation() = Eigen::Vector3d(0.0, 100.0, 0.0);
  r.start.gamma() = VecD<double>::Zero(kModes);
  r.start.qd = VecQ<double>::Zero(6 + kModes);
  // a period of about 0.6 s per mode, damped at about a fifth of critical (the generalized
  // masses are read from the body so the gains fit whatever the sampling)
  r.stiffness = Eigen::VectorXd(kModes);
  r.damping = Eigen::VectorXd(kModes);
  const MatD<double>& G = Chair().moments().G;
  for (int d = 0; d < kModes; ++d) {
    const double mass = G(d, d), omega = 2.0 * M_PI / 0.6;
    r.stiffness[d] = 0.5 * mass * omega * omega;  // the force is −2K(γ − γ0)
    r.damping[d] = 0.4 * mass * omega;
  }
  r.targets = Eigen::MatrixXd::Zero(kModes, steps);
  p.knots = knots;
  p.lower = Eigen::VectorXd::Constant(kModes, -bound);
  p.upper = Eigen::VectorXd::Constant(kModes, bound);
  p.control_weight = 1e-3;
  p.task = fit::SumOf({fit::StillAt<3>(steps, 1e3), [goal, steps](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
                          if (n != steps) return 0.0;
                          const double miss = s.gamma()[2] - goal, w = 1e4;
                          (*dz)[6 + 2] += w * miss;
                          return 0.5 * w * miss * miss;
                        }});
  return p;
}

TEST(SpacetimeSpace, ReachesTheGoalAtTheEndWithinBounds) {
  const int steps = 120;
  const fit::SpacetimeProblemN<3> p = SquashAtTheEnd(0.2, 0.5, steps, 13);
  const fit::SpacetimeResult r = fit::FitSpacetime(Chair(), p);
  ASSERT_TRUE(r.ok) << r.message;
  fit::ControlledRolloutN<3> run = p.rollout;
  run.targets = r.targets;
  double squash = 0.0, speed = 0.0;
  fit::RolloutCost(Chair(), run, [&](int n, const BodyState<3, double>& s, Eigen::VectorXd*) {
    if (n == steps) squash = s.gamma()[2], speed = s.qd.norm();
    return 0.0;
  });
  EXPECT_NEAR(squash, 0.2, 2e-3) << r.message << " iterations " << r.iterations;
  EXPECT_LT(speed, 0.05);
  EXPECT_LT(r.cost, 1e-2 * r.initial_cost);
  EXPECT_LE(r.targets.maxCoeff(), 0.5);
  EXPECT_GE(r.targets.minCoeff(), -0.5);
  EXPECT_NEAR(fit::SpacetimeCostOf(Chair(), p, r.knots), r.cost, 1e-9 * r.cost);
}

TEST(SpacetimeSpace, RefusesBadProblems) {
  fit::SpacetimeProblemN<3> p = SquashAtTheEnd(0.2, 0.5, 20, 5);
  p.knots = 30;
  EXPECT_THROW(fit::FitSpacetime(Chair(), p), std::invalid_argument);
  p = SquashAtTheEnd(0.2, 0.5, 20, 5);
  p.lower[1] = 1.0;
  EXPECT_THROW(fit::FitSpacetime(Chair(), p), std::invalid_argument);
  p = SquashAtTheEnd(0.2, 0.5, 20, 5);
  p.task = nullptr;
  EXPECT_THROW(fit::FitSpacetime(Chair(), p), std::invalid_argument);
  EXPECT_THROW(fit::FitSpacetime(testing::Box(1, 2, 3), SquashAtTheEnd(0.2, 0.5, 20, 5)), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
