#include "wobble/body/affine_energy.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <limits>

namespace wobble {
namespace {

// Cofactor matrix of m (∂ det m / ∂m), written out so that it exists for singular m too.
template <int D>
Eigen::Matrix<double, D, D> Cofactor(const Eigen::Matrix<double, D, D>& m) {
  Eigen::Matrix<double, D, D> c;
  if constexpr (D == 2) {
    c << m(1, 1), -m(1, 0), -m(0, 1), m(0, 0);
  } else {
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        const int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
        c(i, j) = m(i1, j1) * m(i2, j2) - m(i1, j2) * m(i2, j1);
      }
  }
  return c;
}

// ∂V/∂m of the rigidity and volume terms, on fixed-size d×d matrices: the step evaluates this
// for every body, and run-time sized products of 2×2 matrices cost more than their arithmetic.
template <int D>
Eigen::Matrix<double, D, D> LinearPartGradient(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const Eigen::Matrix<double, D, D> m = R.topLeftCorner<D, D>();
  Eigen::Matrix<double, D, D> g = Eigen::Matrix<double, D, D>::Zero();
  // ∂/∂m |mᵀm − I|² = 4 m (mᵀm − I) (mᵀm − I is symmetric)
  if (mat.rigidity != 0.0) {
    Eigen::Matrix<double, D, D> strain = m.transpose() * m;
    strain.diagonal().array() -= 1.0;
    g.noalias() += (4.0 * mat.rigidity) * m * strain;
  }
  // ∂/∂m (det m − 1)² = 2 (det m − 1) cof(m)
  if (mat.volume != 0.0) g += (2.0 * mat.volume * (m.determinant() - 1.0)) * Cofactor<D>(m);
  return g;
}

template <int D>
double LinearPartEnergy(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const Eigen::Matrix<double, D, D> m = R.topLeftCorner<D, D>();
  double v = 0.0;
  if (mat.rigidity != 0.0) {
    Eigen::Matrix<double, D, D> strain = m.transpose() * m;
    strain.diagonal().array() -= 1.0;
    v += mat.rigidity * strain.squaredNorm();
  }
  if (mat.volume != 0.0) {
    const double e = m.determinant() - 1.0;
    v += mat.volume * e * e;
  }
  return v;
}

// Q += −(1 + k_d V̇) ∂V/∂R (§2.4), the linear part on fixed sizes, the quadratic columns after.
template <int D>
void AddForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot, Eigen::MatrixXd* Q) {
  const int quadratic = int(R.cols()) - D - 1;
  const Eigen::Matrix<double, D, D> gm = LinearPartGradient<D>(mat, R);
  const bool bends = mat.bending != 0.0 && quadratic > 0;
  // V̇ = ⟨∂V/∂R, Ṙ⟩; the bending gradient is 2 k_q times the quadratic columns
  double v_dot = (gm.array() * R_dot.topLeftCorner<D, D>().array()).sum();
  if (bends) v_dot += 2.0 * mat.bending * (R.rightCols(quadratic).array() * R_dot.rightCols(quadratic).array()).sum();
  const double scale = 1.0 + mat.damping * v_dot;
  Q->topLeftCorner<D, D>() -= scale * gm;
  if (bends) Q->rightCols(quadratic) -= (scale * 2.0 * mat.bending) * R.rightCols(quadratic);
}

void GradientInto(const AffineMaterial& mat, const Eigen::MatrixXd& R, Eigen::MatrixXd* g) {
  const int d = int(R.rows()), n = int(R.cols());
  g->setZero(d, n);
  if (d == 2)
    g->topLeftCorner<2, 2>() = LinearPartGradient<2>(mat, R);
  else
    g->topLeftCorner<3, 3>() = LinearPartGradient<3>(mat, R);
  if (mat.bending != 0.0 && n > d + 1) g->rightCols(n - d - 1) = (2.0 * mat.bending) * R.rightCols(n - d - 1);
}

}  // namespace

double AffineEnergy(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  const int d = int(R.rows());
  double v = d == 2 ? LinearPartEnergy<2>(mat, R) : LinearPartEnergy<3>(mat, R);
  if (mat.bending != 0.0 && R.cols() > d + 1) v += mat.bending * R.rightCols(R.cols() - d - 1).squaredNorm();
  return v;
}

Eigen::MatrixXd AffineEnergyGradient(const AffineMaterial& mat, const Eigen::MatrixXd& R) {
  Eigen::MatrixXd g;
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
  if (R.rows() == 2)
    AddForce<2>(mat, R, R_dot, Q);
  else
    AddForce<3>(mat, R, R_dot, Q);
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
