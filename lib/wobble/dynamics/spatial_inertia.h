// Kinematics and inertia of a 3D FFD body from its mass moments (the fast path), the thesis'
// Eq. 4.2–4.21 carried to three dimensions as its §6.2 proposes.
//
// A point is x = t + R l with l = b0 + B γ (B is 3 x D). The generalized velocities are
// v = [ṫ (world), ω (body frame, Ṙ = R ω̂), γ̇], so ẋ = J v with
//   J = [ 1 | −R [l]× | R B ]                                  (Eq. 4.6–4.8 in 3D)
// (the orientation is no coordinate: there is no ∂/∂θ, and no Euler angle to become singular).
// By d'Alembert's principle projected on J (Kane's equations, which hold for the
// quasi-velocity ω), Σ_k m_k J_kᵀ (ẍ_k − f_k/m_k) = 0 gives
//   M v̇ = Q − w,   M = Σ m_k J_kᵀ J_k,   w = Σ m_k J_kᵀ J̇_k v,   Q = Σ J_kᵀ f_k,
// the 3D Eq. 4.21, with J̇_k v = R a_k, a_k = ω × (ω × l_k) + 2 ω × B_k γ̇ (centripetal and
// Coriolis). Summed with the moments of MassMomentsN<3> (body_model.h), with c = c0 + Cγ,
// K = Σ m l lᵀ, I = tr(K) 1 − K, N_d = Σ m l × B^d, L_d = Σ m B^d lᵀ, e_d = tr L_d:
//   M = [ m 1     −R[c]×   R C ]
//       [ ·       I        N   ]
//       [ ·       ·        G   ]
//   w_t = R (ω × (ω × c) + 2 ω × C γ̇)
//   w_ω = ω × I ω + 2 (ω (e·γ̇) − (Σ_d γ̇_d L_d) ω)              (gyroscopic terms)
//   w_γd = ωᵀ L_d ω − |ω|² e_d + 2 ω · Σ_e γ̇_e X_ed
// and a world force f at a point adds Q_t = f, Q_ω = l × Rᵀf, Q_γ = Bᵀ Rᵀ f. Every term costs
// O(D²) whatever the number of mass points; tests/body3_test.cc checks each against the sums
// over the points.
#pragma once

#include <algorithm>
#include <array>

#include "wobble/body/body_model.h"
#include "wobble/body/group.h"
#include "wobble/core/cholesky.h"
#include "wobble/core/rotation3.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/core/types.h"

namespace wobble {

// The γ-dependent moments at one shape γ, computed once per evaluation.
template <class T> struct ShapeMoments {
  ShapeMoments(const MassMomentsN<3>& mm, const VecD<T>& gamma) {
    const int D = int(gamma.size());
    c = mm.c0.cast<T>() + mm.C.cast<T>() * gamma;
    e = mm.e0.cast<T>() + mm.G.cast<T>() * gamma;
    K = mm.S0.cast<T>();
    N.resize(3, D);
    for (int d = 0; d < D; ++d) {
      Mat3<T> Ld = mm.E[d].transpose().cast<T>();
      Vec3<T> Nd = mm.H0.col(d).cast<T>();
      for (int g = 0; g < D; ++g) {
        Ld += mm.F[size_t(d) * D + g].cast<T>() * gamma[g];
        Nd += mm.X[size_t(g) * D + d].cast<T>() * gamma[g];
      }
      L[d] = Ld;
      N.col(d) = Nd;
      K += (mm.E[d].cast<T>() + Ld) * gamma[d];
    }
    I = Mat3<T>::Identity() * K.trace() - K;
  }
  Vec3<T> c;                          // Σ m l
  VecD<T> e;                          // e_d = Σ m l·B^d
  Mat3<T> K, I;                       // Σ m l lᵀ and the inertia tensor about the body origin
  Mat3D<T> N;                         // column d: Σ m l × B^d
  std::array<Mat3<T>, kMaxModes> L;  // L_d = Σ m B^d lᵀ
};

// M of the header comment.
template <class T> void MassMatrix(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, MatQ<T>* M) {
  const int D = int(sm.e.size());
  M->setZero(Group<3>::kRigidDofs + D, Group<3>::kRigidDofs + D);
  M->template block<3, 3>(0, 0) = Mat3<T>::Identity() * T(mm.m);
  const Mat3<T> t_omega = -R * Skew(sm.c);
  M->template block<3, 3>(0, 3) = t_omega;
  M->template block<3, 3>(3, 0) = t_omega.transpose();
  M->template block<3, 3>(3, 3) = sm.I;
  if (D == 0) return;
  const Mat3D<T> RC = R * mm.C.cast<T>();
  M->block(0, Group<3>::kRigidDofs, 3, D) = RC;
  M->block(Group<3>::kRigidDofs, 0, D, 3) = RC.transpose();
  M->block(3, Group<3>::kRigidDofs, 3, D) = sm.N;
  M->block(Group<3>::kRigidDofs, 3, D, 3) = sm.N.transpose();
  M->block(Group<3>::kRigidDofs, Group<3>::kRigidDofs, D, D) = mm.G.cast<T>();
}

// ½ vᵀ M v.
template <class T>
T KineticEnergy(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, const VecQ<T>& v) {
  MatQ<T> M;
  MassMatrix(mm, sm, R, &M);
  return T(0.5) * v.dot(M * v);
}

// w of the header comment.
template <class T>
void VelocityTerms(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, const VecQ<T>& v,
                    VecQ<T>* w) {
  const int D = int(sm.e.size());
  const Vec3<T> omega = v.template segment<3>(3);
  const auto gamma_dot = v.tail(D);
  const Vec3<T> C_gd = mm.C.cast<T>() * gamma_dot;
  w->resize(Group<3>::kRigidDofs + D);
  w->template head<3>() = R * (omega.cross(omega.cross(sm.c)) + T(2.0) * omega.cross(C_gd));
  Mat3<T> L_gd = Mat3<T>::Zero();
  for (int d = 0; d < D; ++d) L_gd += sm.L[d] * gamma_dot[d];
  w->template segment<3>(3) = omega.cross(sm.I * omega) + T(2.0) * (omega * sm.e.dot(gamma_dot) - L_gd * omega);
  const T omega2 = omega.squaredNorm();
  for (int d = 0; d < D; ++d) {
    Vec3<T> X_gd = Vec3<T>::Zero();
    for (int e = 0; e < D; ++e) X_gd += mm.X[size_t(e) * D + d].cast<T>() * gamma_dot[e];
    (*w)[Group<3>::kRigidDofs + d] = omega.dot(sm.L[d] * omega) - omega2 * sm.e[d] + T(2.0) * omega.dot(X_gd);
  }
}

// Generalized gravity Σ m_k J_kᵀ g = [m g ; c × Rᵀg ; Cᵀ Rᵀ g].
template <class T>
void GravityForce(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, const Eigen::Vector3d& g,
                   VecQ<T>* Q) {
  const int D = int(sm.e.size());
  const Vec3<T> g_local = R.transpose() * g.cast<T>();
  Q->resize(Group<3>::kRigidDofs + D);
  Q->template head<3>() = T(mm.m) * g.cast<T>();
  Q->template segment<3>(3) = sm.c.cross(g_local);
  if (D > 0) Q->tail(D) = mm.C.cast<T>().transpose() * g_local;
}

// Potential energy of gravity, −Σ m_k g·x_k = −g·(m t + R c).
template <class T>
T GravityEnergy(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Frame<3, T>& frame, const Eigen::Vector3d& g) {
  return -(T(mm.m) * frame.t + frame.R * sm.c).dot(g.cast<T>());
}

// World linear and angular momentum (about the world origin):
//   P = Σ m ẋ = m ṫ + R (ω × c + C γ̇),
//   L = Σ m x × ẋ = t × P + R (Σ m l × ẋ_local) with Σ m l × (ω × l + B γ̇) = I ω + N γ̇
//   (plus the cross term R c × ṫ from l × Rᵀṫ).
template <class T>
void Momentum(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Frame<3, T>& frame, const VecQ<T>& v,
               Vec3<T>* linear, Vec3<T>* angular) {
  const int D = int(sm.e.size());
  const Vec3<T> t_dot = v.template head<3>(), omega = v.template segment<3>(3);
  const auto gamma_dot = v.tail(D);
  *linear = T(mm.m) * t_dot + frame.R * (omega.cross(sm.c) + mm.C.cast<T>() * gamma_dot);
  const Vec3<T> spin = sm.I * omega + sm.N * gamma_dot;  // Σ m l × ẋ_local, body frame
  *angular = frame.t.cross(*linear) + frame.R * (spin + sm.c.cross(frame.R.transpose() * t_dot));
}

// Kinetic-energy gradient ∂T/∂g at fixed ξ, left-trivialized on SO(3) (δR = R ε̂), for the
// variational integrator. With a = ω × c + C γ̇ (so that M_tω ω + M_tγ γ̇ = R a):
//   ∂T/∂t = 0,  ∂T/∂R = a × Rᵀṫ,
//   ∂T/∂γ_d = ṫ·R(ω × C_d) + e_d|ω|² − ωᵀ L_d ω + ω·Σ_e γ̇_e X_de
// (∂K/∂γ_d = L_d + L_dᵀ, ∂I/∂γ_d = 2 e_d 1 − L_d − L_dᵀ, ∂N_e/∂γ_d = X_de).
template <class T>
void KineticGradient(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, const VecQ<T>& xi,
                      VecQ<T>* out) {
  const int D = int(sm.e.size());
  const Vec3<T> t_dot = xi.template head<3>(), omega = xi.template segment<3>(3);
  const auto gamma_dot = xi.tail(D);
  const Vec3<T> a = omega.cross(sm.c) + mm.C.cast<T>() * gamma_dot;
  const Vec3<T> t_local = R.transpose() * t_dot;
  out->setZero(Group<3>::kRigidDofs + D);
  out->template segment<3>(3) = a.cross(t_local);
  const T omega2 = omega.squaredNorm();
  for (int d = 0; d < D; ++d) {
    Vec3<T> X_gd = Vec3<T>::Zero();
    for (int e = 0; e < D; ++e) X_gd += mm.X[size_t(d) * D + e].cast<T>() * gamma_dot[e];
    (*out)[Group<3>::kRigidDofs + d] = t_local.dot(omega.cross(mm.C.col(d).cast<T>())) + sm.e[d] * omega2 -
                              omega.dot(sm.L[d] * omega) + omega.dot(X_gd);
  }
}

// Gravity's generalized force at positions q (group.h's layout), without the other moments.
template <class T>
void GravityForce(const MassMomentsN<3>& mm, const VecQ<T>& q, const Mat3<T>& R, const Eigen::Vector3d& g, VecQ<T>* Q) {
  const int D = int(mm.e0.size());
  const Vec3<T> g_local = R.transpose() * g.cast<T>();
  const Vec3<T> c = mm.c0.cast<T>() + mm.C.cast<T>() * q.tail(D);
  Q->resize(Group<3>::kRigidDofs + D);
  Q->template head<3>() = T(mm.m) * g.cast<T>();
  Q->template segment<3>(3) = c.cross(g_local);
  if (D > 0) Q->tail(D) = mm.C.cast<T>().transpose() * g_local;
}

// Solves M a = r (M of the header comment at shape moments sm and rotation R) by block
// elimination about the centre of mass, without forming M, as SolveMassSystem does in 2D
// (kinematics.h). With c = c0 + Cγ, r̂ = Rᵀ r_t and â = Rᵀ a_t, the translation rows give
//   â = (r̂ + c × a_ω − C a_γ)/m,
// and eliminating them leaves
//   [ I_com   U     ] [a_ω]   [ r_ω − c × r̂/m ]      I_com = I − (|c|² 1 − c cᵀ)/m
//   [ Uᵀ      G_com ] [a_γ] = [ r_γ − Cᵀ r̂/m  ],     U = N − [c]× C/m,
// whose mode block G_com = G − CᵀC/m is constant, so MassMomentsN<3> keeps its inverse W (as
// Witkin & Welch 1990, Eq. 5, precompute the inverse of their constant mass matrix): y = W ρ_γ
// and Z = W Uᵀ are products, not solves. Then the 3x3 Schur complement
// S = I_com − U Z (factored by Cholesky), S a_ω = ρ_ω − U y, a_γ = y − Z a_ω and
// a_t = (r_t − R(C a_γ − c × a_ω))/m. Returns false when M is singular. *cond_estimate receives
// the ratio of the largest to the smallest elimination pivot (m, G_com's pivots, S's pivots):
// each pivot is a 1x1 Schur complement of a principal submatrix P of M, so lies in
// [λ_min(P), λ_max(P)] ⊂ [λ_min(M), λ_max(M)] (Cauchy interlacing), and the ratio is a lower
// bound of cond₂(M).
//
// Everything but the right-hand side depends on the shape alone (U, Z, S, the pivots), so it is
// one SpatialMassFactor, made by FactorMassSystem; SolveFactored applies it to any r. A step factors
// once; the 3D adjoint keeps the factor of each recorded step and solves with M again
// (M⁻¹ λ, M symmetric) without redoing the elimination.
template <class T> struct SpatialMassFactor {
  MatND<T, 3> U;                                     // N − [c]× C/m
  Eigen::Matrix<T, Eigen::Dynamic, 3, 0, kMaxModes, 3> Z;  // G_com⁻¹ Uᵀ
  Mat3<T> S;                                         // CholeskyInPlace(I_com − U Z)
  double cond_estimate = 0.0;
};
template <class T> bool FactorMassSystem(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, SpatialMassFactor<T>* f) {
  const int D = int(sm.e.size());
  if (D > 0 && !mm.G_com_positive) return false;
  const T inv_m = T(1.0 / mm.m);
  const Vec3<T>& c = sm.c;
  f->S = sm.I - (Mat3<T>::Identity() * c.squaredNorm() - c * c.transpose()) * inv_m;
  if (D > 0) {
    // by hand: D is dynamic (at most kMaxModes), and Eigen's products of such sizes call its
    // general kernels, slower here than the solves they replace
    const MatD<double>& W = mm.G_com_inverse;
    f->U.resize(3, D);
    for (int d = 0; d < D; ++d) f->U.col(d) = sm.N.col(d) - c.cross(Vec3<T>(mm.C.col(d).template cast<T>())) * inv_m;
    f->Z.resize(D, 3);
    for (int d = 0; d < D; ++d) {
      Vec3<T> z = Vec3<T>::Zero();
      for (int e = 0; e < D; ++e) z += T(W(d, e)) * Vec3<T>(f->U.col(e));
      f->Z.row(d) = z.transpose();
    }
    for (int d = 0; d < D; ++d) f->S -= Vec3<T>(f->U.col(d)) * f->Z.row(d);
  } else {
    f->U.resize(3, 0);
    f->Z.resize(0, 3);
  }
  if (!CholeskyInPlace(&f->S)) return false;
  double lo = mm.m, hi = mm.m;
  CholeskyPivotRange(f->S, &lo, &hi);
  if (D > 0) lo = std::min(lo, mm.G_com_pivot_lo), hi = std::max(hi, mm.G_com_pivot_hi);
  f->cond_estimate = hi / lo;
  return true;
}
template <class T>
void SolveFactored(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const SpatialMassFactor<T>& f, const Mat3<T>& R,
                   const VecQ<T>& r, VecQ<T>* a) {
  constexpr int kRigid = Group<3>::kRigidDofs;
  const int D = int(sm.e.size());
  const T inv_m = T(1.0 / mm.m);
  const Vec3<T>& c = sm.c;
  const Vec3<T> r_hat = R.transpose() * r.template head<3>();
  Vec3<T> rho = r.template segment<3>(3) - c.cross(r_hat) * inv_m;
  a->resize(kRigid + D);
  VecD<T> y(D), rho_gamma(D);
  const Vec3<T> r_hat_m = r_hat * inv_m;
  for (int d = 0; d < D; ++d) rho_gamma[d] = r[kRigid + d] - Vec3<T>(mm.C.col(d).template cast<T>()).dot(r_hat_m);
  for (int d = 0; d < D; ++d) {  // y = G_com⁻¹ ρ_γ
    T yd = T(0.0);
    for (int e = 0; e < D; ++e) yd += T(mm.G_com_inverse(d, e)) * rho_gamma[e];
    y[d] = yd;
    rho -= Vec3<T>(f.U.col(d)) * yd;
  }
  Vec3<T> a_omega = rho;
  CholeskySolveInPlace(f.S, &a_omega);
  Vec3<T> local = -c.cross(a_omega);
  for (int d = 0; d < D; ++d) {
    (*a)[kRigid + d] = y[d] - f.Z.row(d).dot(a_omega.transpose());
    local += Vec3<T>(mm.C.col(d).template cast<T>()) * (*a)[kRigid + d];
  }
  a->template segment<3>(3) = a_omega;
  a->template head<3>() = (r.template head<3>() - R * local) * inv_m;
}
template <class T>
bool SolveMassSystem(const MassMomentsN<3>& mm, const ShapeMoments<T>& sm, const Mat3<T>& R, const VecQ<T>& r,
                     VecQ<T>* a, double* cond_estimate, SpatialMassFactor<T>* factor = nullptr) {
  SpatialMassFactor<T> local;
  SpatialMassFactor<T>& f = factor ? *factor : local;
  if (!FactorMassSystem(mm, sm, &f)) return false;
  SolveFactored(mm, sm, f, R, r, a);
  *cond_estimate = f.cond_estimate;
  return true;
}

// q̈ of M q̈ = Q − w at positions q and velocities q̇ (the 3D Eq. 4.21 of the header), by
// SolveMassSystem above (about the centre of mass, M never formed).
template <class T>
bool SolveAccelerations(const MassMomentsN<3>& mm, const VecQ<T>& q, const VecQ<T>& qd, const Mat3<T>& R,
                        const VecQ<T>& Q, VecQ<T>* qdd, double* cond_estimate) {
  const int D = int(mm.e0.size());
  const ShapeMoments<T> sm(mm, VecD<T>(q.tail(D)));
  VecQ<T> w;
  VelocityTerms(mm, sm, R, qd, &w);
  return SolveMassSystem(mm, sm, R, VecQ<T>(Q - w), qdd, cond_estimate);
}

}  // namespace wobble
