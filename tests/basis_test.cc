// The lattice bases: partition of unity, Eq. 4.1's binomials, linear precision, and the
// Sederberg–Parry local coordinates.
#include <gtest/gtest.h>

#include <numeric>

#include "wobble/core/basis.h"
#include "wobble/body/lattice.h"

namespace wobble {
namespace {

TEST(Basis, BinomialsOfEq41) {
  EXPECT_EQ(Binomial(3, 0), 1);
  EXPECT_EQ(Binomial(3, 1), 3);
  EXPECT_EQ(Binomial(3, 2), 3);
  EXPECT_EQ(Binomial(10, 5), 252);
  EXPECT_EQ(Binomial(4, 7), 0);
}

TEST(Basis, CubicBernsteinClosedForm) {
  const Basis1D b(BasisKind::kBernstein, 4);
  const double u = 0.3, v = 1 - u;
  const std::vector<double> w = b.Weights(u);
  EXPECT_DOUBLE_EQ(w[0], v * v * v);
  EXPECT_DOUBLE_EQ(w[1], 3 * u * v * v);
  EXPECT_DOUBLE_EQ(w[2], 3 * u * u * v);
  EXPECT_DOUBLE_EQ(w[3], u * u * u);
}

class BasisKinds : public ::testing::TestWithParam<std::pair<BasisKind, int>> {};

TEST_P(BasisKinds, PartitionOfUnityNonNegativeAndLinearPrecision) {
  const Basis1D b(GetParam().first, GetParam().second);
  for (double u = 0.0; u <= 1.0; u += 0.0625) {
    const std::vector<double> w = b.Weights(u);
    double sum = 0, first_moment = 0;
    for (int i = 0; i < b.size(); ++i) {
      EXPECT_GE(w[i], 0.0);
      sum += w[i];
      first_moment += w[i] * b.Abscissa(i);
    }
    EXPECT_NEAR(sum, 1.0, 1e-14);
    // control points at the abscissae reproduce the identity map
    EXPECT_NEAR(first_moment, u, 1e-14);
  }
}

INSTANTIATE_TEST_SUITE_P(All, BasisKinds,
                         ::testing::Values(std::make_pair(BasisKind::kBernstein, 2), std::make_pair(BasisKind::kBernstein, 4),
                                           std::make_pair(BasisKind::kBernstein, 7), std::make_pair(BasisKind::kCubicBSpline, 4),
                                           std::make_pair(BasisKind::kCubicBSpline, 6),
                                           std::make_pair(BasisKind::kCubicBSpline, 9)));

TEST(Basis, CubicBSplineWithFourControlPointsIsBernstein) {
  const Basis1D bs(BasisKind::kCubicBSpline, 4), bz(BasisKind::kBernstein, 4);
  for (double u : {0.0, 0.2, 0.5, 0.9, 1.0})
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(bs.Weights(u)[i], bz.Weights(u)[i], 1e-15);
}

TEST(Basis, CubicBSplineIsLocal) {
  const Basis1D b(BasisKind::kCubicBSpline, 8);  // 5 spans
  const std::vector<double> w = b.Weights(0.1);  // first span: only control points 0..3
  for (int i = 4; i < 8; ++i) EXPECT_EQ(w[i], 0.0);
}

TEST(Basis, RejectsTooFewControlPoints) {
  EXPECT_THROW(Basis1D(BasisKind::kBernstein, 1), std::invalid_argument);
  EXPECT_THROW(Basis1D(BasisKind::kCubicBSpline, 3), std::invalid_argument);
}

TEST(Lattice, LocalCoordsOfSlantedLattice) {
  const Lattice lat({10, 20}, {300, 30}, {-20, 100}, 4, 5);
  for (double s : {0.0, 0.25, 1.0})
    for (double t : {0.0, 0.6, 1.0}) {
      const Eigen::Vector2d p = lat.origin() + s * lat.axis_s() + t * lat.axis_t();
      const Eigen::Vector2d st = lat.LocalCoords(p);
      EXPECT_NEAR(st.x(), s, 1e-14);
      EXPECT_NEAR(st.y(), t, 1e-14);
      // undeformed lattice maps (s, t) back to p
      EXPECT_NEAR((lat.Evaluate(lat.RestPoints(), st) - p).norm(), 0.0, 1e-11);
    }
}

TEST(Lattice, RejectsDegenerateAxes) {
  EXPECT_THROW(Lattice({0, 0}, {1, 0}, {2, 0}), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
