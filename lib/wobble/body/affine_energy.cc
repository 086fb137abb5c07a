#include "wobble/body/affine_energy.h"

#include <Eigen/LU>

namespace wobble {
namespace {

// Cofactor matrix of m (∂ det m / ∂m), written out so that it exists for singular m too.
Eigen::MatrixXd Cofactor(const Eigen::MatrixXd& m) {
  Eigen::MatrixXd c(m.rows(), m.cols());
  if (m.rows() == 2) {
    c << m(1, 1), -m(1, 0), -m(0, 1), m(0, 0);
    return c;
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      c(i, j) = m(i1, j1) * m(i2, j2) - m(i1, j2) * m(i2, j1);
    }
  return c;
}

}  // namespace

double AffineEnergy(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const int d = int(R.rows());
  const Eigen::MatrixXd m = R.leftCols(d);
  double v = 0.0;
  if (mat.rigidity != 0.0) v += mat.rigidity * (m.transpose() * m - Eigen::MatrixXd::Identity(d, d)).squaredNorm();
  if (mat.volume != 0.0) {
    const double e = m.determinant() - 1.0;
    v += mat.volume * e * e;
  }
  if (mat.bending != 0.0 && R.cols() > d + 1) v += mat.bending * R.rightCols(R.cols() - d - 1).squaredNorm();
  return v;
}

Eigen::MatrixXd AffineEnergyGradient(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const int d = int(R.rows());
  const Eigen::MatrixXd m = R.leftCols(d);
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(R.rows(), R.cols());
  // ∂/∂m |mᵀm − I|² = 4 m (mᵀm − I) (mᵀm − I is symmetric)
  if (mat.rigidity != 0.0) g.leftCols(d) += 4.0 * mat.rigidity * m * (m.transpose() * m - Eigen::MatrixXd::Identity(d, d));
  // ∂/∂m (det m − 1)² = 2 (det m − 1) cof(m)
  if (mat.volume != 0.0) g.leftCols(d) += 2.0 * mat.volume * (m.determinant() - 1.0) * Cofactor(m);
  if (mat.bending != 0.0 && R.cols() > d + 1) g.rightCols(R.cols() - d - 1) += 2.0 * mat.bending * R.rightCols(R.cols() - d - 1);
  return g;
}

Eigen::MatrixXd AffineForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot) {
  const Eigen::MatrixXd grad = AffineEnergyGradient(mat, R);
  const double v_dot = (grad.array() * R_dot.array()).sum();  // V̇ = ⟨∂V/∂R, Ṙ⟩
  return -(1.0 + mat.damping * v_dot) * grad;                 // −∂V/∂R − k_d V̇ ∂V/∂R (§2.4)
}

}  // namespace wobble
