// The moment-based fast path (kinematics.h) against the thesis' direct per-point formulas
// (reference.h), and the reference itself against finite differences of Eq. 4.2 and of the
// kinetic energy, so neither side is checked only by the other.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <random>

#include "support/test_bodies.h"
#include "wobble/dynamics/kinematics.h"
#include "support/reference.h"

namespace wobble {
namespace {

using testing::RandomBody;
using testing::TableDef;
using testing::TableModes;

struct Case {
  std::string name;
  int num_s, num_t;
  BasisKind basis;
  int modes, points;
};

std::vector<BodyModel> Bodies() {
  std::mt19937 rng(7);
  std::vector<BodyModel> bodies;
  bodies.emplace_back(TableDef(), TableModes());
  bodies.emplace_back(TableDef(), std::vector<DeformationMode>{});
  for (const Case& c : {Case{"bernstein 4x4", 4, 4, BasisKind::kBernstein, 3, 20},
                        Case{"bernstein 3x6", 3, 6, BasisKind::kBernstein, 5, 40},
                        Case{"bernstein 2x2", 2, 2, BasisKind::kBernstein, 1, 7},
                        Case{"bspline 6x5", 6, 5, BasisKind::kCubicBSpline, 4, 60},
                        Case{"bspline 8x8 12 modes", 8, 8, BasisKind::kCubicBSpline, 12, 100}})
    bodies.push_back(RandomBody(rng, c.num_s, c.num_t, c.basis, c.modes, c.points));
  return bodies;
}

Eigen::VectorXd RandomVector(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

// Eq. 4.2 straight from the lattice: deform the control points, then evaluate, rotate, translate.
Eigen::Vector2d DirectPosition(const BodyModel& b, int k, const Eigen::VectorXd& q) {
  std::vector<Eigen::Vector2d> control = b.lattice().RestPoints();
  for (int d = 0; d < b.num_modes(); ++d)
    for (size_t c = 0; c < control.size(); ++c) control[c] += q[3 + d] * b.modes()[d].displacement[c];
  const Eigen::Vector2d l = b.lattice().Evaluate(control, b.lattice_coords(k));
  return Eigen::Vector2d(q[0], q[1]) + Eigen::Rotation2Dd(q[2]).toRotationMatrix() * l;
}

double RelErr(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(b.norm(), 1e-300);
}

TEST(Inertia, FastPathEqualsPerPointReference) {
  std::mt19937 rng(11);
  for (const BodyModel& b : Bodies()) {
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0), qd = RandomVector(rng, b.num_q(), 2.0);
      q.head<2>() *= 100.0;
      q[2] *= 3.0;
      const VecQ<double> qf = q, qdf = qd;
      MatQ<double> M;
      VecQ<double> w, grav;
      MassMatrix(b.moments(), qf, &M);
      VelocityTerms(b.moments(), qf, qdf, &w);
      const Eigen::Vector2d g(0.3, -9.81);
      GravityForce(b.moments(), qf, g, &grav);
      SCOPED_TRACE(b.name() + " with " + std::to_string(b.num_modes()) + " modes");
      EXPECT_LT(RelErr(M, reference::MassMatrix(b, q)), 1e-12);
      EXPECT_LT(RelErr(w, reference::VelocityTerms(b, q, qd)), 1e-12);
      EXPECT_LT(RelErr(grav, reference::GravityForce(b, q, g)), 1e-12);
    }
  }
}

// The step never forms M: SolveMassSystem eliminates about the centre of mass with a constant,
// pre-factored mode block. Its q̈ must solve the per-point M of Eq. 4.10 (dense LU here), and
// its pivot ratio must be a true lower bound of cond₂(M).
TEST(Inertia, CentreOfMassSolveEqualsDenseSolveOfReferenceM) {
  std::mt19937 rng(13);
  for (const BodyModel& b : Bodies()) {
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0), r = RandomVector(rng, b.num_q(), 1e3);
      q.head<2>() *= 100.0;
      q[2] *= 3.0;
      const Eigen::MatrixXd M = reference::MassMatrix(b, q);
      const Eigen::VectorXd expected = M.fullPivLu().solve(r);
      VecQ<double> qdd;
      double cond_estimate = 0.0;
      const VecQ<double> qf = q, rf = r;
      ASSERT_TRUE(SolveMassSystem(b.moments(), qf, Rotation(q[2]), rf, &qdd, &cond_estimate)) << b.name();
      SCOPED_TRACE(b.name() + " with " + std::to_string(b.num_modes()) + " modes");
      EXPECT_LT(RelErr(qdd, expected), 1e-10);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M);
      const double cond = svd.singularValues()(0) / svd.singularValues().tail(1)(0);
      EXPECT_GE(cond_estimate, 1.0);
      EXPECT_LE(cond_estimate, cond * (1 + 1e-9));
    }
  }
}

// Two identical modes: M is singular and the solve says so instead of returning numbers.
TEST(Inertia, CentreOfMassSolveRejectsDependentModes) {
  std::vector<DeformationMode> modes = TableModes();
  modes.push_back(modes[0]);
  const BodyModel b(TableDef(), modes);
  EXPECT_FALSE(b.moments().G_com_positive);
  VecQ<double> q = VecQ<double>::Zero(b.num_q()), qdd;
  double cond_estimate = 0.0;
  EXPECT_FALSE(SolveMassSystem(b.moments(), q, Rotation(0.0), q, &qdd, &cond_estimate));
}

TEST(Inertia, MassMatrixIsSymmetricPositiveDefinite) {
  std::mt19937 rng(3);
  for (const BodyModel& b : Bodies()) {
    for (int trial = 0; trial < 10; ++trial) {
      const VecQ<double> q = RandomVector(rng, b.num_q(), 3.0);
      MatQ<double> M;
      MassMatrix(b.moments(), q, &M);
      EXPECT_EQ((M - M.transpose()).norm(), 0.0);
      const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
      EXPECT_GT(eig.eigenvalues().minCoeff(), 1e-9 * eig.eigenvalues().maxCoeff()) << b.name();
    }
  }
}

// The reference Jacobian (Eq. 4.6–4.8) is the derivative of Eq. 4.2.
TEST(Inertia, ReferenceJacobianIsDerivativeOfPositions) {
  std::mt19937 rng(5);
  for (const BodyModel& b : Bodies()) {
    const Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0);
    for (int k = 0; k < std::min(b.num_points(), 6); ++k) {
      const Eigen::MatrixXd J = reference::Jacobian(b, k, q);
      for (int j = 0; j < b.num_q(); ++j) {
        const double h = 1e-6;
        Eigen::VectorXd qp = q, qm = q;
        qp[j] += h;
        qm[j] -= h;
        const Eigen::Vector2d fd = (DirectPosition(b, k, qp) - DirectPosition(b, k, qm)) / (2 * h);
        EXPECT_LT((J.col(j) - fd).norm(), 1e-6 * (1.0 + fd.norm())) << b.name() << " point " << k << " q" << j;
      }
    }
  }
}

// w = Ṁ q̇ − ½ ∂(q̇ᵀ M q̇)/∂q (the Lagrangian form behind Eq. 4.21), by finite differences of M.
TEST(Inertia, VelocityTermsMatchLagrangianByFiniteDifferences) {
  std::mt19937 rng(9);
  for (const BodyModel& b : Bodies()) {
    const Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0), qd = RandomVector(rng, b.num_q(), 1.0);
    auto M = [&](const Eigen::VectorXd& x) { return reference::MassMatrix(b, x); };
    const double h = 1e-5;
    const Eigen::MatrixXd Mdot = (M(q + h * qd) - M(q - h * qd)) / (2 * h);
    Eigen::VectorXd w = Mdot * qd;
    for (int k = 0; k < b.num_q(); ++k) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(b.num_q());
      e[k] = h;
      w[k] -= 0.5 * qd.dot((M(q + e) - M(q - e)) / (2 * h) * qd);
    }
    VecQ<double> fast;
    VelocityTerms(b.moments(), VecQ<double>(q), VecQ<double>(qd), &fast);
    EXPECT_LT(RelErr(fast, w), 1e-6) << b.name();
  }
}

// Kinetic energy from the moments equals Σ ½ m |ẋ|² with ẋ by finite differences of Eq. 4.2.
TEST(Inertia, KineticEnergyMatchesPointVelocities) {
  std::mt19937 rng(13);
  for (const BodyModel& b : Bodies()) {
    const Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0), qd = RandomVector(rng, b.num_q(), 1.0);
    double direct = 0.0;
    const double h = 1e-6;
    for (int k = 0; k < b.num_points(); ++k) {
      const Eigen::Vector2d v = (DirectPosition(b, k, q + h * qd) - DirectPosition(b, k, q - h * qd)) / (2 * h);
      direct += 0.5 * b.mass(k) * v.squaredNorm();
    }
    MatQ<double> M;
    MassMatrix(b.moments(), VecQ<double>(q), &M);
    EXPECT_NEAR(0.5 * qd.dot(M * qd), direct, 1e-7 * direct) << b.name();
    // the block formula the step checks with, against the per-point M of Eq. 4.10
    const double blocks = KineticEnergy(b.moments(), VecQ<double>(q), VecQ<double>(qd), Rotation(q[2]));
    EXPECT_NEAR(blocks, 0.5 * qd.dot(reference::MassMatrix(b, q) * qd), 1e-12 * direct) << b.name();
  }
}

// ∂T/∂q at fixed q̇ from the moments equals ½ q̇ᵀ (∂M/∂q_j) q̇ with ∂M/∂q_j of Eq. 4.13.
TEST(Inertia, KineticGradientMatchesEq413) {
  std::mt19937 rng(17);
  for (const BodyModel& b : Bodies()) {
    const Eigen::VectorXd q = RandomVector(rng, b.num_q(), 1.0), qd = RandomVector(rng, b.num_q(), 1.0);
    Eigen::VectorXd expected(b.num_q());
    for (int j = 0; j < b.num_q(); ++j) expected[j] = 0.5 * qd.dot(reference::MassMatrixDerivative(b, q, j) * qd);
    VecQ<double> fast;
    KineticGradient(b.moments(), VecQ<double>(q), VecQ<double>(qd), &fast);
    EXPECT_LT(RelErr(fast, expected), 1e-12) << b.name();
  }
}

}  // namespace
}  // namespace wobble
