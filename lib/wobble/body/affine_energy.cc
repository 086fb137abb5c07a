#include "wobble/body/affine_energy.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <limits>

namespace wobble {
namespace {

// Stack-sized work matrices (d ≤ 3, n ≤ 10): a step evaluates these for every body, and heap
// traffic would cost more than the arithmetic.
using SmallSq = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
using SmallR = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 10>;

// Cofactor matrix of m (∂ det m / ∂m), written out so that it exists for singular m too.
SmallSq Cofactor(const SmallSq& m) {
  SmallSq c(m.rows(), m.cols());
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

double Determinant(const SmallSq& m) {
  if (m.rows() == 2) return m(0, 0) * m(1, 1) - m(0, 1) * m(1, 0);
  return m.row(0).dot(Cofactor(m).row(0));
}

void GradientInto(const AffineMaterial& mat, const Eigen::MatrixXd& R, SmallR* g) {
  const int d = int(R.rows()), n = int(R.cols());
  const SmallSq m = R.leftCols(d);
  g->setZero(d, n);
  // ∂/∂m |mᵀm − I|² = 4 m (mᵀm − I) (mᵀm − I is symmetric)
  if (mat.rigidity != 0.0) {
    SmallSq strain;
    strain.noalias() = m.transpose() * m;
    strain.diagonal().array() -= 1.0;
    g->leftCols(d).noalias() += (4.0 * mat.rigidity) * m * strain;
  }
  // ∂/∂m (det m − 1)² = 2 (det m − 1) cof(m)
  if (mat.volume != 0.0) g->leftCols(d) += (2.0 * mat.volume * (Determinant(m) - 1.0)) * Cofactor(m);
  if (mat.bending != 0.0 && n > d + 1) g->rightCols(n - d - 1) = (2.0 * mat.bending) * R.rightCols(n - d - 1);
}

}  // namespace

double AffineEnergy(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const int d = int(R.rows());
  const SmallSq m = R.leftCols(d);
  double v = 0.0;
  if (mat.rigidity != 0.0) {
    SmallSq strain = m.transpose() * m;
    strain.diagonal().array() -= 1.0;
    v += mat.rigidity * strain.squaredNorm();
  }
  if (mat.volume != 0.0) {
    const double e = Determinant(m) - 1.0;
    v += mat.volume * e * e;
  }
  if (mat.bending != 0.0 && R.cols() > d + 1) v += mat.bending * R.rightCols(R.cols() - d - 1).squaredNorm();
  return v;
}

Eigen::MatrixXd AffineEnergyGradient(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  SmallR g;
  GradientInto(mat, R, &g);
  return g;
}

Eigen::MatrixXd AffineForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot) {
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(R.rows(), R.cols());
  AddAffineForce(mat, R, R_dot, &Q);
  return Q;
}

void AddAffineForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot, Eigen::MatrixXd* Q) {
  if (mat.rigidity == 0.0 && mat.volume == 0.0 && mat.bending == 0.0) return;
  SmallR grad;
  GradientInto(mat, R, &grad);
  const double v_dot = (grad.array() * R_dot.array()).sum();  // V̇ = ⟨∂V/∂R, Ṙ⟩
  *Q -= (1.0 + mat.damping * v_dot) * grad;                   // −∂V/∂R − k_d V̇ ∂V/∂R (§2.4)
}

Eigen::VectorXd VibrationFrequencies(const LinearBodyModel& model, const AffineMaterial& mat) {
  const int d = model.dim(), n = model.basis_size(), N = d * n;
  const Eigen::MatrixXd R0 = model.RestState();
  // H by central differences of the gradient, in the flattening index i·n + s
  Eigen::MatrixXd H(N, N);
  const double eps = 1e-6;
  for (int a = 0; a < N; ++a) {
    Eigen::MatrixXd Rp = R0, Rm = R0;
    Rp(a / n, a % n) += eps;
    Rm(a / n, a % n) -= eps;
    const Eigen::MatrixXd dg = (AffineEnergyGradient(mat, Rp) - AffineEnergyGradient(mat, Rm)) / (2 * eps);
    for (int b = 0; b < N; ++b) H(b, a) = dg(b / n, b % n);
  }
  H = 0.5 * (H + H.transpose());
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(N, N);
  for (int i = 0; i < d; ++i) M.block(i * n, i * n, n, n) = model.mass_matrix();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(H, M);
  Eigen::VectorXd w = es.eigenvalues();
  for (int i = 0; i < N; ++i) w[i] = std::sqrt(std::max(0.0, w[i]));
  return w;
}

double StableTimeStep(const LinearBodyModel& model, const AffineMaterial& mat) {
  const double w_max = VibrationFrequencies(model, mat).maxCoeff();
  return w_max > 0 ? 1.0 / w_max : std::numeric_limits<double>::infinity();
}

}  // namespace wobble
