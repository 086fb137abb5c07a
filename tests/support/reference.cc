#include "support/reference.h"

namespace wobble::reference {

namespace {

Eigen::Matrix2d Rot(double theta) {
  Eigen::Matrix2d r;
  r << std::cos(theta), -std::sin(theta), std::sin(theta), std::cos(theta);
  return r;
}
Eigen::Matrix2d dRot(double theta) {  // ∂R/∂θ
  Eigen::Matrix2d r;
  r << -std::sin(theta), -std::cos(theta), std::cos(theta), -std::sin(theta);
  return r;
}

// Σ_ij (Σ_d γ_d d^d_ij + L_ij) B(s,i) B(t,j) and Σ_ij d^d_ij B(s,i) B(t,j), straight from the
// lattice (not from the body's cached b0/B), so the reference shares nothing with the fast path.
void DeformedLocal(const BodyModel& body, int k, const Vector& q, Eigen::Vector2d* l, Eigen::MatrixXd* b) {
  const Lattice& lat = body.lattice();
  const int D = body.num_modes();
  const std::vector<double> w = lat.Weights(body.lattice_coords(k));
  l->setZero();
  b->setZero(2, D);
  for (int i = 0; i < lat.num_s(); ++i)
    for (int j = 0; j < lat.num_t(); ++j) {
      const int c = lat.Index(i, j);
      Eigen::Vector2d control = lat.RestPoint(i, j);
      for (int d = 0; d < D; ++d) {
        control += q[3 + d] * body.modes()[d].displacement[c];
        b->col(d) += w[c] * body.modes()[d].displacement[c];
      }
      *l += w[c] * control;
    }
}

}  // namespace

Matrix Jacobian(const BodyModel& body, int k, const Vector& q) {
  Eigen::Vector2d l;
  Eigen::MatrixXd b;
  DeformedLocal(body, k, q, &l, &b);
  Matrix J = Matrix::Zero(2, body.num_q());
  J.block<2, 2>(0, 0).setIdentity();
  J.col(2) = dRot(q[2]) * l;                               // a(s,t), Eq. 4.7
  J.rightCols(body.num_modes()) = Rot(q[2]) * b;           // b(s,t,k), Eq. 4.8
  return J;
}

Matrix JacobianDerivative(const BodyModel& body, int k, const Vector& q, int j) {
  Matrix dJ = Matrix::Zero(2, body.num_q());
  if (j < 2) return dJ;  // Eq. 4.14, 4.15
  Eigen::Vector2d l;
  Eigen::MatrixXd b;
  DeformedLocal(body, k, q, &l, &b);
  if (j == 2) {
    dJ.col(2) = -Rot(q[2]) * l;                            // c(s,t) = ∂²R/∂θ² (...), Eq. 4.18
    dJ.rightCols(body.num_modes()) = dRot(q[2]) * b;       // f(s,t,k), Eq. 4.19
  } else {
    dJ.col(2) = dRot(q[2]) * b.col(j - 3);                 // Eq. 4.17 (with the B(s,i)B(t,j) weights)
  }
  return dJ;
}

Matrix MassMatrix(const BodyModel& body, const Vector& q) {
  Matrix M = Matrix::Zero(body.num_q(), body.num_q());
  for (int k = 0; k < body.num_points(); ++k) {
    const Matrix J = Jacobian(body, k, q);
    M += body.mass(k) * J.transpose() * J;
  }
  return M;
}

Matrix MassMatrixDerivative(const BodyModel& body, const Vector& q, int j) {
  Matrix dM = Matrix::Zero(body.num_q(), body.num_q());
  for (int k = 0; k < body.num_points(); ++k) {
    const Matrix J = Jacobian(body, k, q);
    const Matrix JdJ = J.transpose() * JacobianDerivative(body, k, q, j);
    dM += body.mass(k) * (JdJ.transpose() + JdJ);
  }
  return dM;
}

Vector VelocityTerms(const BodyModel& body, const Vector& q, const Vector& qd) {
  const int nq = body.num_q();
  std::vector<Matrix> dM(nq);
  for (int l = 0; l < nq; ++l) dM[l] = MassMatrixDerivative(body, q, l);
  Matrix Mdot = Matrix::Zero(nq, nq);
  for (int l = 0; l < nq; ++l) Mdot += dM[l] * qd[l];
  Vector w = Mdot * qd;
  for (int k = 0; k < nq; ++k) w[k] -= 0.5 * qd.dot(dM[k] * qd);
  return w;
}

Vector GravityForce(const BodyModel& body, const Vector& q, const Eigen::Vector2d& g) {
  Vector Q = Vector::Zero(body.num_q());
  for (int k = 0; k < body.num_points(); ++k) Q += Jacobian(body, k, q).transpose() * (body.mass(k) * g);
  return Q;
}

}  // namespace wobble::reference
