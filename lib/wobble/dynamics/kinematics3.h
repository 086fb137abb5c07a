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
// Coriolis). Summed with the moments of MassMoments3 (body_model.h), with c = c0 + Cγ,
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

#include <array>

#include "wobble/body/body_model.h"
#include "wobble/core/rotation3.h"
#include "wobble/core/types.h"

namespace wobble {

// The γ-dependent moments at one shape γ, computed once per evaluation.
template <class T> struct ShapeMoments3 {
  ShapeMoments3(const MassMoments3& mm, const VecD<T>& gamma) {
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

// The rigid part of a 3D state: translation and rotation matrix.
template <class T> struct Frame3 {
  Frame3(const Vec3<T>& t_in, const Eigen::Quaternion<T>& orientation) : t(t_in), R(orientation.toRotationMatrix()) {}
  Vec3<T> t;
  Mat3<T> R;
};

// Body-frame position l = b0 + B γ.
// A plain loop over B's contiguous columns: this runs for every point of every contact scan,
// and Eigen's per-column expressions over a dynamic-width map cost three times as much.
template <class T, class Derived>
Vec3<T> LocalPosition3(const Eigen::Vector3d& b0, const Eigen::MatrixBase<Derived>& B, const VecD<T>& gamma) {
  T x(b0.x()), y(b0.y()), z(b0.z());
  const int D = int(B.cols());
  for (int d = 0; d < D; ++d) {
    const T& g = gamma[d];
    x += T(B(0, d)) * g;
    y += T(B(1, d)) * g;
    z += T(B(2, d)) * g;
  }
  return Vec3<T>(x, y, z);
}

// World velocity J v = ṫ + R (ω × l + B γ̇).
template <class T, class Derived>
Vec3<T> PointVelocity3(const Frame3<T>& frame, const VecQ3<T>& v, const Vec3<T>& l, const Eigen::MatrixBase<Derived>& B) {
  Vec3<T> local = v.template segment<3>(3).cross(l);
  for (int d = 0; d < B.cols(); ++d) local += B.col(d).template cast<T>() * v[kRigidDofs3 + d];
  return v.template head<3>() + frame.R * local;
}

// Adds Jᵀ f for a world force f at a point with local position l and mode matrix B.
template <class T, class Derived>
void AddGeneralizedForce3(const Frame3<T>& frame, const Vec3<T>& l, const Eigen::MatrixBase<Derived>& B,
                          const Vec3<T>& f, VecQ3<T>* Q) {
  const Vec3<T> f_local = frame.R.transpose() * f;
  Q->template head<3>() += f;
  Q->template segment<3>(3) += l.cross(f_local);
  for (int d = 0; d < B.cols(); ++d) (*Q)[kRigidDofs3 + d] += B.col(d).template cast<T>().dot(f_local);
}

// M of the header comment.
template <class T> void MassMatrix3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Mat3<T>& R, MatQ3<T>* M) {
  const int D = int(sm.e.size());
  M->setZero(kRigidDofs3 + D, kRigidDofs3 + D);
  M->template block<3, 3>(0, 0) = Mat3<T>::Identity() * T(mm.m);
  const Mat3<T> t_omega = -R * Skew(sm.c);
  M->template block<3, 3>(0, 3) = t_omega;
  M->template block<3, 3>(3, 0) = t_omega.transpose();
  M->template block<3, 3>(3, 3) = sm.I;
  if (D == 0) return;
  const Mat3D<T> RC = R * mm.C.cast<T>();
  M->block(0, kRigidDofs3, 3, D) = RC;
  M->block(kRigidDofs3, 0, D, 3) = RC.transpose();
  M->block(3, kRigidDofs3, 3, D) = sm.N;
  M->block(kRigidDofs3, 3, D, 3) = sm.N.transpose();
  M->block(kRigidDofs3, kRigidDofs3, D, D) = mm.G.cast<T>();
}

// ½ vᵀ M v.
template <class T>
T KineticEnergy3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Mat3<T>& R, const VecQ3<T>& v) {
  MatQ3<T> M;
  MassMatrix3(mm, sm, R, &M);
  return T(0.5) * v.dot(M * v);
}

// w of the header comment.
template <class T>
void VelocityTerms3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Mat3<T>& R, const VecQ3<T>& v,
                    VecQ3<T>* w) {
  const int D = int(sm.e.size());
  const Vec3<T> omega = v.template segment<3>(3);
  const auto gamma_dot = v.tail(D);
  const Vec3<T> C_gd = mm.C.cast<T>() * gamma_dot;
  w->resize(kRigidDofs3 + D);
  w->template head<3>() = R * (omega.cross(omega.cross(sm.c)) + T(2.0) * omega.cross(C_gd));
  Mat3<T> L_gd = Mat3<T>::Zero();
  for (int d = 0; d < D; ++d) L_gd += sm.L[d] * gamma_dot[d];
  w->template segment<3>(3) = omega.cross(sm.I * omega) + T(2.0) * (omega * sm.e.dot(gamma_dot) - L_gd * omega);
  const T omega2 = omega.squaredNorm();
  for (int d = 0; d < D; ++d) {
    Vec3<T> X_gd = Vec3<T>::Zero();
    for (int e = 0; e < D; ++e) X_gd += mm.X[size_t(e) * D + d].cast<T>() * gamma_dot[e];
    (*w)[kRigidDofs3 + d] = omega.dot(sm.L[d] * omega) - omega2 * sm.e[d] + T(2.0) * omega.dot(X_gd);
  }
}

// Generalized gravity Σ m_k J_kᵀ g = [m g ; c × Rᵀg ; Cᵀ Rᵀ g].
template <class T>
void GravityForce3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Mat3<T>& R, const Eigen::Vector3d& g,
                   VecQ3<T>* Q) {
  const int D = int(sm.e.size());
  const Vec3<T> g_local = R.transpose() * g.cast<T>();
  Q->resize(kRigidDofs3 + D);
  Q->template head<3>() = T(mm.m) * g.cast<T>();
  Q->template segment<3>(3) = sm.c.cross(g_local);
  if (D > 0) Q->tail(D) = mm.C.cast<T>().transpose() * g_local;
}

// Potential energy of gravity, −Σ m_k g·x_k = −g·(m t + R c).
template <class T>
T GravityEnergy3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Frame3<T>& frame, const Eigen::Vector3d& g) {
  return -(T(mm.m) * frame.t + frame.R * sm.c).dot(g.cast<T>());
}

// World linear and angular momentum (about the world origin):
//   P = Σ m ẋ = m ṫ + R (ω × c + C γ̇),
//   L = Σ m x × ẋ = t × P + R (Σ m l × ẋ_local) with Σ m l × (ω × l + B γ̇) = I ω + N γ̇
//   (plus the cross term R c × ṫ from l × Rᵀṫ).
template <class T>
void Momentum3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Frame3<T>& frame, const VecQ3<T>& v,
               Vec3<T>* linear, Vec3<T>* angular) {
  const int D = int(sm.e.size());
  const Vec3<T> t_dot = v.template head<3>(), omega = v.template segment<3>(3);
  const auto gamma_dot = v.tail(D);
  *linear = T(mm.m) * t_dot + frame.R * (omega.cross(sm.c) + mm.C.cast<T>() * gamma_dot);
  const Vec3<T> spin = sm.I * omega + sm.N * gamma_dot;  // Σ m l × ẋ_local, body frame
  *angular = frame.t.cross(*linear) + frame.R * (spin + sm.c.cross(frame.R.transpose() * t_dot));
}

}  // namespace wobble
