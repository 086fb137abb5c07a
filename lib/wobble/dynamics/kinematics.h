// Kinematics and inertia of an FFD body from its mass moments (the fast path).
//
// Position of a point (Eq. 4.2): x = t + R(θ) l, l = b0 + B γ. Jacobian (Eq. 4.6–4.8):
// J = [ I | R S l | R B ]. Mass matrix (Eq. 4.10) M = Σ m_k J_kᵀ J_k and the velocity terms of
// Eq. 4.21, w = Σ m_k J_kᵀ J̇_k q̇ (so that M q̈ = Q − w), follow exactly from the moments of
// MassMoments (derivation in ARCHITECTURE.md); the per-point reference in reference.h checks
// them. Every function is a template on the scalar type.
#pragma once

#include "wobble/body/body_model.h"
#include "wobble/body/group.h"
#include "wobble/core/types.h"
#include "wobble/core/cholesky.h"

namespace wobble {

// Body-frame position l = b0 + B γ of a point with rest position b0 and mode matrix B, γ read
// from the positions q (group.h's layout). A plain loop over B's contiguous columns: this runs
// for every point of every contact scan, and Eigen's per-column expressions over a
// dynamic-width map cost three times as much in 3D.
template <class T, int Dim, class Derived>
Eigen::Matrix<T, Dim, 1> LocalPosition(const Eigen::Matrix<double, Dim, 1>& b0, const Eigen::MatrixBase<Derived>& B,
                                       const VecQ<T>& q) {
  Eigen::Matrix<T, Dim, 1> l = b0.template cast<T>();
  const int D = int(B.cols());
  const T* gamma = q.data() + Group<Dim>::kRigidParams;
  for (int d = 0; d < D; ++d)
    for (int i = 0; i < Dim; ++i) l[i] += T(B(i, d)) * gamma[d];
  return l;
}

// The rigid part of q: translation t and rotation matrix R, computed once per evaluation (sin
// and cos, or the quaternion's matrix, per point would dominate a step of a small body).
template <int Dim, class T> struct Frame {
  explicit Frame(const VecQ<T>& q) : t(q.template head<Dim>()), R(Group<Dim>::RotationOf(q)) {}
  Eigen::Matrix<T, Dim, 1> t;
  Eigen::Matrix<T, Dim, Dim> R;
};

// World position x = t + R l (Eq. 4.2).
template <int Dim, class T>
Eigen::Matrix<T, Dim, 1> WorldFromLocal(const Frame<Dim, T>& frame, const Eigen::Matrix<T, Dim, 1>& l) {
  return frame.t + frame.R * l;
}

// World velocity J q̇ = ṫ + R (ω × l + B γ̇) (Eq. 4.6–4.8; planar ω × l = ω S l).
template <int Dim, class T, class Derived>
Eigen::Matrix<T, Dim, 1> PointVelocity(const Frame<Dim, T>& frame, const VecQ<T>& qd, const Eigen::Matrix<T, Dim, 1>& l,
                                       const Eigen::MatrixBase<Derived>& B) {
  Eigen::Matrix<T, Dim, 1> v_local = Group<Dim>::Turn(qd, l);
  const T* gamma_dot = qd.data() + Group<Dim>::kRigidDofs;
  for (int d = 0; d < B.cols(); ++d)
    for (int i = 0; i < Dim; ++i) v_local[i] += T(B(i, d)) * gamma_dot[d];
  return qd.template head<Dim>() + frame.R * v_local;
}

// Adds Jᵀ f (Eq. 4.20) for a world force f at a point with local position l and mode matrix B:
// Q_t += f, Q_ω += l × Rᵀf, Q_γ += Bᵀ Rᵀ f.
template <int Dim, class T, class Derived>
void AddGeneralizedForce(const Frame<Dim, T>& frame, const Eigen::Matrix<T, Dim, 1>& l,
                         const Eigen::MatrixBase<Derived>& B, const Eigen::Matrix<T, Dim, 1>& f, VecQ<T>* Q) {
  const Eigen::Matrix<T, Dim, 1> f_local = frame.R.transpose() * f;
  Q->template head<Dim>() += f;
  Group<Dim>::AddTorque(l, f_local, Q);
  T* Q_gamma = Q->data() + Group<Dim>::kRigidDofs;
  for (int d = 0; d < B.cols(); ++d) {
    T sum = T(B(0, d)) * f_local[0];
    for (int i = 1; i < Dim; ++i) sum += T(B(i, d)) * f_local[i];
    Q_gamma[d] += sum;
  }
}

// M(q) from the moments:
//   M_tt = m I, M_tθ = R S (c0 + Cγ), M_tγ = R C, M_θθ = I0 + 2 e0ᵀγ + γᵀGγ, M_θγ = (h0 + Pγ)ᵀ, M_γγ = G.
// R = R(θ) is passed in so that one step computes sin and cos once, not once per term.
template <class T> void MassMatrix(const MassMoments& mm, const VecQ<T>& q, const Mat2<T>& R, MatQ<T>* M) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D);
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>().lazyProduct(gamma);
  const Vec2<T> RSc = R * Perp(c);
  M->setZero(kRigidDofs + D, kRigidDofs + D);
  (*M)(0, 0) = (*M)(1, 1) = T(mm.m);
  M->template block<2, 1>(0, 2) = RSc;
  M->template block<1, 2>(2, 0) = RSc.transpose();
  const VecD<T> Ggamma = mm.G.cast<T>().lazyProduct(gamma);
  (*M)(2, 2) = T(mm.I0) + T(2.0) * mm.e0.cast<T>().dot(gamma) + gamma.dot(Ggamma);
  if (D == 0) return;
  const Mat2D<T> RC = R.lazyProduct(mm.C.cast<T>());
  M->block(0, kRigidDofs, 2, D) = RC;
  M->block(kRigidDofs, 0, D, 2) = RC.transpose();
  const VecD<T> theta_gamma = mm.h0.cast<T>() + mm.P.cast<T>().lazyProduct(gamma);
  M->block(2, kRigidDofs, 1, D) = theta_gamma.transpose();
  M->block(kRigidDofs, 2, D, 1) = theta_gamma;
  M->block(kRigidDofs, kRigidDofs, D, D) = mm.G.cast<T>();
}
template <class T> void MassMatrix(const MassMoments& mm, const VecQ<T>& q, MatQ<T>* M) {
  MassMatrix(mm, q, Rotation(q[2]), M);
}

// γᵀ G γ, flattened: whether GCC inlines Eigen's product inside a dot depends on the
// translation unit that instantiates the caller, and the linker keeps one copy of it; an
// out-of-line one cost 3% of a 1000-trial synthesis (perf, issue 45).
template <class T, class Gamma> [[gnu::flatten]] inline T QuadraticForm(const MatD<double>& G, const Gamma& gamma) {
  return gamma.dot(G.cast<T>().lazyProduct(gamma));
}

// ½ q̇ᵀ M q̇ (Eq. 4.9) from M's blocks above, without forming M (a quarter of the work: the
// step checks it after every step). With ṫ, ω = θ̇, γ̇ and c, I(γ), h = h0 + Pγ as above,
//   2T = m|ṫ|² + 2ω ṫ·(R S c) + 2 ṫ·(R C γ̇) + I ω² + 2ω h·γ̇ + γ̇ᵀ G γ̇.
template <class T> T KineticEnergy(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& qd, const Mat2<T>& R) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D), gamma_dot = qd.tail(D);
  const Vec2<T> t_dot = qd.template head<2>();
  const T omega = qd[2];
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>().lazyProduct(gamma);
  T two_t = T(mm.m) * t_dot.squaredNorm() + T(2.0) * omega * t_dot.dot(R * Perp(c));
  const T inertia = T(mm.I0) + T(2.0) * mm.e0.cast<T>().dot(gamma) + QuadraticForm<T>(mm.G, gamma);
  two_t += inertia * omega * omega;
  if (D > 0) {
    const Vec2<T> C_gamma_dot = mm.C.cast<T>().lazyProduct(gamma_dot);
    const VecD<T> h = mm.h0.cast<T>() + mm.P.cast<T>().lazyProduct(gamma);
    two_t += T(2.0) * t_dot.dot(R * C_gamma_dot) + T(2.0) * omega * h.dot(gamma_dot) +
             gamma_dot.dot(mm.G.cast<T>().lazyProduct(gamma_dot));
  }
  return T(0.5) * two_t;
}

// Solves M(q) q̈ = r exactly by block elimination about the centre of mass, without forming M.
// Eliminating the translation (M_tt = m I) leaves, with c = c0 + Cγ, h = h0 + Pγ, r̂ = Rᵀ r_t:
//   [ I_θθ − |c|²/m   uᵀ    ] [θ̈]   [ r_θ − (S c)·r̂/m ]
//   [ u               G_com ] [γ̈] = [ r_γ − Cᵀ r̂/m    ],   u = h − Cᵀ S c / m,
// whose mode block G_com = G − CᵀC/m is constant and factored once (MassMoments). Then
// G_com y = ρ_γ, G_com z = u, θ̈ = (ρ_θ − u·y)/(s − u·z), γ̈ = y − z θ̈, and
// ẗ = (r_t − R(S c θ̈ + C γ̈))/m. About half the work of a Cholesky factorization of M per step.
// Returns false when M is singular. *cond_estimate receives the ratio of the largest to the
// smallest elimination pivot (m, G_com's pivots, the θ pivot): a lower bound of cond₂(M).
template <class T>
bool SolveMassSystem(const MassMoments& mm, const VecQ<T>& q, const Mat2<T>& R, const VecQ<T>& r, VecQ<T>* qdd,
                     double* cond_estimate) {
  const int D = int(mm.e0.size());
  if (D > 0 && !mm.G_com_positive) return false;
  const auto gamma = q.tail(D);
  const T inv_m = T(1.0 / mm.m);
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>().lazyProduct(gamma);
  const Vec2<T> Sc = Perp(c);
  const Vec2<T> r_hat = R.transpose() * r.template head<2>();
  const T I_theta = T(mm.I0) + T(2.0) * mm.e0.cast<T>().dot(gamma) + QuadraticForm<T>(mm.G, gamma);
  T pivot_theta = I_theta - c.squaredNorm() * inv_m;
  T rho_theta = r[2] - Sc.dot(r_hat) * inv_m;
  qdd->resize(kRigidDofs + D);
  T theta_dd;
  if (D == 0) {
    if (!(ScalarValue(pivot_theta) > 0.0)) return false;
    theta_dd = rho_theta / pivot_theta;
  } else {
    VecD<T> u = mm.h0.cast<T>() + mm.P.cast<T>().lazyProduct(gamma) - mm.C.cast<T>().transpose().lazyProduct(Sc) * inv_m;
    VecD<T> y = r.tail(D) - mm.C.cast<T>().transpose().lazyProduct(r_hat) * inv_m;
    VecD<T> z = u;
    CholeskySolveInPlace(mm.G_com_factor, &y);
    CholeskySolveInPlace(mm.G_com_factor, &z);
    pivot_theta -= u.dot(z);
    if (!(ScalarValue(pivot_theta) > 0.0)) return false;
    theta_dd = (rho_theta - u.dot(y)) / pivot_theta;
    qdd->tail(D) = y - z * theta_dd;
  }
  (*qdd)[2] = theta_dd;
  const Vec2<T> local = Sc * theta_dd + mm.C.cast<T>().lazyProduct(qdd->tail(D));
  qdd->template head<2>() = (r.template head<2>() - R * local) * inv_m;
  double lo = std::min(mm.m, double(ScalarValue(pivot_theta))), hi = std::max(mm.m, double(ScalarValue(pivot_theta)));
  if (D > 0) CholeskyPivotRange(mm.G_com_factor, &lo, &hi);
  *cond_estimate = hi / lo;
  return true;
}

// w = Σ m_k J_kᵀ J̇_k q̇, with J̇_k q̇ = R(−θ̇² l_k + 2 θ̇ S B_k γ̇):
//   t-rows: R(−θ̇²(c0 + Cγ) + 2θ̇ S C γ̇), θ-row: 2θ̇ (e0 + Gγ)·γ̇, γ-rows: −θ̇²(e0 + Gγ) + 2θ̇ P γ̇.
template <class T>
void VelocityTerms(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& qd, const Mat2<T>& R, VecQ<T>* w) {
  const int D = int(mm.e0.size());
  const auto gamma = q.tail(D);
  const auto gamma_dot = qd.tail(D);
  const T thd = qd[2];
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>().lazyProduct(gamma);
  const Vec2<T> Cgd = mm.C.cast<T>().lazyProduct(gamma_dot);
  w->resize(kRigidDofs + D);
  w->template head<2>() = R * (-thd * thd * c + T(2.0) * thd * Perp(Cgd));
  if (D == 0) {
    (*w)[2] = T(0.0);
    return;
  }
  const VecD<T> e = mm.e0.cast<T>() + mm.G.cast<T>().lazyProduct(gamma);
  (*w)[2] = T(2.0) * thd * e.dot(gamma_dot);
  w->tail(D) = -thd * thd * e + T(2.0) * thd * mm.P.cast<T>().lazyProduct(gamma_dot);
}
template <class T> void VelocityTerms(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& qd, VecQ<T>* w) {
  VelocityTerms(mm, q, qd, Rotation(q[2]), w);
}

// q̈ of Eq. 4.21, M q̈ = Q − w, by SolveMassSystem (the dimension's own mass solve; the 3D one
// is in spatial_inertia.h).
template <class T>
bool SolveAccelerations(const MassMoments& mm, const VecQ<T>& q, const VecQ<T>& qd, const Mat2<T>& R, const VecQ<T>& Q,
                        VecQ<T>* qdd, double* cond_estimate) {
  VecQ<T> w;
  VelocityTerms(mm, q, qd, R, &w);
  return SolveMassSystem(mm, q, R, VecQ<T>(Q - w), qdd, cond_estimate);
}

// Generalized gravity force Σ m_k J_kᵀ g = [m g ; (R S (c0 + Cγ))·g ; (R C)ᵀ g].
template <class T>
void GravityForce(const MassMoments& mm, const VecQ<T>& q, const Mat2<T>& R, const Eigen::Vector2d& g, VecQ<T>* Q) {
  const int D = int(mm.e0.size());
  const Vec2<T> gT = g.cast<T>();
  const Vec2<T> c = mm.c0.cast<T>() + mm.C.cast<T>().lazyProduct(q.tail(D));
  Q->resize(kRigidDofs + D);
  Q->template head<2>() = T(mm.m) * gT;
  (*Q)[2] = (R * Perp(c)).dot(gT);
  if (D > 0) Q->tail(D) = mm.C.cast<T>().transpose().lazyProduct(R.transpose() * gT);  // (R C)ᵀ g = Cᵀ (Rᵀ g)
}
template <class T> void GravityForce(const MassMoments& mm, const VecQ<T>& q, const Eigen::Vector2d& g, VecQ<T>* Q) {
  GravityForce(mm, q, Rotation(q[2]), g, Q);
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
