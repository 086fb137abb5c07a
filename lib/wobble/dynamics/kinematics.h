// Kinematics and inertia of an FFD body from its mass moments (the fast path).
//
// Position of a point (Eq. 4.2): x = t + R(θ) l, l = b0 + B γ. Jacobian (Eq. 4.6–4.8):
// J = [ I | R S l | R B ]. Mass matrix (Eq. 4.10) M = Σ m_k J_kᵀ J_k and the velocity terms of
// Eq. 4.21, w = Σ m_k J_kᵀ J̇_k q̇ (so that M q̈ = Q − w), follow exactly from the moments of
// MassMoments (derivation in ARCHITECTURE.md); the per-point reference in reference.h checks
// them. Every function is a template on the scalar type.
#pragma once

#include "wobble/body/body_model.h"
#include "wobble/body/types.h"

namespace wobble {

// Body-frame position l = b0 + B γ of a point with rest position b0 and mode matrix B.
template <class T, class Derived>
Vec2<T> LocalPosition(const Eigen::Vector2d& b0, const Eigen::MatrixBase<Derived>& B, const VecQ<T>& q) {
  Vec2<T> l = b0.cast<T>();
  for (int d = 0; d < B.cols(); ++d) l += B.col(d).template cast<T>() * q[kRigidDofs + d];
  return l;
}

// The rigid part of q: translation t and R(θ), computed once per evaluation (sin and cos
// per point would dominate a step of a small body).
template <class T> struct Frame {
  explicit Frame(const VecQ<T>& q) : t(q[0], q[1]), R(Rotation(q[2])) {}
  Vec2<T> t;
  Mat2<T> R;
};

// World position x = t + R l (Eq. 4.2).
template <class T> Vec2<T> WorldFromLocal(const Frame<T>& frame, const Vec2<T>& l) { return frame.t + frame.R * l; }

// World velocity J q̇ = ṫ + R S l θ̇ + R B γ̇.
template <class T, class Derived>
Vec2<T> PointVelocity(const Frame<T>& frame, const VecQ<T>& qd, const Vec2<T>& l, const Eigen::MatrixBase<Derived>& B) {
  Vec2<T> v_local = Perp(l) * qd[2];
  for (int d = 0; d < B.cols(); ++d) v_local += B.col(d).template cast<T>() * qd[kRigidDofs + d];
  return Vec2<T>(qd[0], qd[1]) + frame.R * v_local;
}

// Adds Jᵀ f (Eq. 4.20) for a world force f at a point with local position l and mode matrix B.
template <class T, class Derived>
void AddGeneralizedForce(const Frame<T>& frame, const Vec2<T>& l, const Eigen::MatrixBase<Derived>& B,
                         const Vec2<T>& f, VecQ<T>* Q) {
  const Vec2<T> f_local = frame.R.transpose() * f;  // Rᵀ f
  (*Q)[0] += f[0];
  (*Q)[1] += f[1];
  (*Q)[2] += Perp(l).dot(f_local);  // (R S l)·f = (S l)·(Rᵀ f)
  for (int d = 0; d < B.cols(); ++d) (*Q)[kRigidDofs + d] += B.col(d).template cast<T>().dot(f_local);
}

// M(q) from the moments:
//   M_tt = m I, M_tθ = R S (c0 + Cγ), M_tγ = R C, M_θθ = I0 + 2 e0ᵀγ + γᵀGγ, M_θγ = (h0 + Pγ)ᵀ, M_γγ = G.
template <class T> void MassMatrix(const MassMoments& mm, const VecQ<T>& q, MatQ<T>* M) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D);
  const Mat2<T> R = Rotation(q[2]);
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * gamma;
  const Vec2<T> RSc = R * Perp(c);
  M->setZero(kRigidDofs + D, kRigidDofs + D);
  (*M)(0, 0) = (*M)(1, 1) = T(mm.m);
  M->template block<2, 1>(0, 2) = RSc;
  M->template block<1, 2>(2, 0) = RSc.transpose();
  (*M)(2, 2) = T(mm.I0) + T(2.0) * mm.e0.cast<T>().dot(gamma) + gamma.dot(mm.G.cast<T>() * gamma);
  if (D == 0) return;
  const Mat2D<T> RC = R * mm.C.cast<T>();
  M->block(0, kRigidDofs, 2, D) = RC;
  M->block(kRigidDofs, 0, D, 2) = RC.transpose();
  const VecD<T> theta_gamma = mm.h0.cast<T>() + mm.P.cast<T>() * gamma;
  M->block(2, kRigidDofs, 1, D) = theta_gamma.transpose();
  M->block(kRigidDofs, 2, D, 1) = theta_gamma;
  M->block(kRigidDofs, kRigidDofs, D, D) = mm.G.cast<T>();
}

// w = Σ m_k J_kᵀ J̇_k q̇, with J̇_k q̇ = R(−θ̇² l_k + 2 θ̇ S B_k γ̇):
//   t-rows: R(−θ̇²(c0 + Cγ) + 2θ̇ S C γ̇), θ-row: 2θ̇ (e0 + Gγ)·γ̇, γ-rows: −θ̇²(e0 + Gγ) + 2θ̇ P γ̇.
template <class T> void VelocityTerms(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& qd, VecQ<T>* w) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D);
  const auto gamma_dot = qd.tail(D);
  const T thd = qd[2];
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * gamma;
  const Vec2<T> Cgd = mm.C.cast<T>() * gamma_dot;
  w->resize(kRigidDofs + D);
  w->template head<2>() = Rotation(q[2]) * (-thd * thd * c + T(2.0) * thd * Perp(Cgd));
  if (D == 0) {
    (*w)[2] = T(0.0);
    return;
  }
  const VecD<T> e = mm.e0.cast<T>() + mm.G.cast<T>() * gamma;
  (*w)[2] = T(2.0) * thd * e.dot(gamma_dot);
  w->tail(D) = -thd * thd * e + T(2.0) * thd * (mm.P.cast<T>() * gamma_dot);
}

// Generalized gravity force Σ m_k J_kᵀ g = [m g ; (R S (c0 + Cγ))·g ; (R C)ᵀ g].
template <class T> void GravityForce(const MassMoments& mm, const VecQ<T>& q, const Eigen::Vector2d& g, VecQ<T>* Q) {
  const int D = int(mm.e0.size());
  const Mat2<T> R = Rotation(q[2]);
  const Vec2<T> gT = g.cast<T>();
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * q.tail(D);
  Q->resize(kRigidDofs + D);
  Q->template head<2>() = T(mm.m) * gT;
  (*Q)[2] = (R * Perp(c)).dot(gT);
  if (D > 0) Q->tail(D) = (R * mm.C.cast<T>()).transpose() * gT;
}

// Potential energy of gravity, −Σ m_k g·x_k = −g·(m t + R(c0 + Cγ)).
template <class T> T GravityEnergy(const MassMoments& mm, const VecQ<T>& q, const Eigen::Vector2d& g) {
  const int D = int(mm.e0.size());
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * q.tail(D);
  const Vec2<T> moment = T(mm.m) * Vec2<T>(q[0], q[1]) + Rotation(q[2]) * c;
  return -moment.dot(g.cast<T>());
}

}  // namespace wobble

namespace wobble {

// ∂T/∂q at fixed q̇ = v, i.e. ½ vᵀ (∂M/∂q_j) v (the ∂L/∂q term of Eq. 4.5/4.12), from the
// moments: M depends on θ through R in M_tθ, M_tγ and on γ through M_tθ, M_θθ, M_θγ.
template <class T> void KineticGradient(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& v, VecQ<T>* out) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D);
  const auto gd = v.tail(D);
  const Mat2<T> R = Rotation(q[2]);
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * gamma;
  const Vec2<T> vt(v[0], v[1]);
  const T thd = v[2];
  out->setZero(kRigidDofs + D);
  // θ: ∂M_tθ/∂θ = R S S c = −R c, ∂M_tγ/∂θ = R S C
  const Vec2<T> Cgd = mm.C.cast<T>() * gd;
  (*out)[2] = vt.dot(-(R * c) * thd + R * Perp(Cgd));
  // γ_d: ∂M_tθ/∂γ_d = R S C_d, ∂M_θθ/∂γ_d = 2(e0 + Gγ)_d, ∂M_θγ_e/∂γ_d = P_ed
  if (D == 0) return;
  const VecD<T> e = mm.e0.cast<T>() + mm.G.cast<T>() * gamma;
  const VecD<T> Pt_gd = mm.P.cast<T>().transpose() * gd;
  for (int d = 0; d < D; ++d) {
    const Vec2<T> Cd = mm.C.col(d).cast<T>();
    (*out)[kRigidDofs + d] = vt.dot(R * Perp(Cd)) * thd + thd * thd * e[d] + thd * Pt_gd[d];
  }
}

}  // namespace wobble
