// Rotations in 3D for the FFD body: unit quaternions for the orientation, rotation vectors
// (so(3)) for increments, and the maps between them that the integrators on SO(3) need.
// Templates on the scalar, like every dynamics routine (double and ceres::Jet).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "wobble/core/types.h"

namespace wobble {

// [x]×: the matrix of y ↦ x × y.
template <class T> Mat3<T> Skew(const Vec3<T>& x) {
  Mat3<T> s;
  s << T(0.0), -x.z(), x.y(), x.z(), T(0.0), -x.x(), -x.y(), x.x(), T(0.0);
  return s;
}

// exp(x̂) as a unit quaternion: a turn by |x| about x/|x| (series near 0: no division by |x|).
template <class T> Eigen::Quaternion<T> ExpRotation(const Vec3<T>& x) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T angle2 = x.squaredNorm();
  T real, scale;  // scale = sin(|x|/2)/|x|
  if (ScalarValue(angle2) < 1e-12) {
    real = T(1.0) - angle2 / T(8.0);
    scale = T(0.5) - angle2 / T(48.0);
  } else {
    const T angle = sqrt(angle2);
    real = cos(T(0.5) * angle);
    scale = sin(T(0.5) * angle) / angle;
  }
  return Eigen::Quaternion<T>(real, scale * x.x(), scale * x.y(), scale * x.z());
}

// The right Jacobian of exp on SO(3): exp((x + δ)^) = exp(x̂) exp((J_r(x) δ)^) to first order,
// J_r(x) = 1 − (1 − cos θ)/θ² x̂ + (θ − sin θ)/θ³ x̂², θ = |x| (series near 0). The 3D adjoint
// pulls a step's turn exp(Δt ω̂) back to ω with it.
template <class T> Mat3<T> RightJacobianExp(const Vec3<T>& x) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T angle2 = x.squaredNorm();
  T a, b;  // (1 − cos θ)/θ², (θ − sin θ)/θ³
  if (ScalarValue(angle2) < 1e-8) {
    a = T(0.5) - angle2 / T(24.0);
    b = T(1.0 / 6.0) - angle2 / T(120.0);
  } else {
    const T angle = sqrt(angle2);
    a = (T(1.0) - cos(angle)) / angle2;
    b = (angle - sin(angle)) / (angle2 * angle);
  }
  const Mat3<T> s = Skew(x);
  return Mat3<T>::Identity() - a * s + b * s * s;
}

// log of a unit quaternion: the rotation vector r (|r| ≤ π) with ExpRotation(r) = ±q.
template <class T> Vec3<T> LogRotation(const Eigen::Quaternion<T>& q_in) {
  using std::atan2;
  using std::sqrt;
  const Eigen::Quaternion<T> q = ScalarValue(q_in.w()) < 0 ? Eigen::Quaternion<T>(-q_in.coeffs()) : q_in;
  const T s2 = q.vec().squaredNorm();
  if (ScalarValue(s2) < 1e-16) return T(2.0) * q.vec() / q.w();  // 2 atan(s/w)/s → 2/w near 0
  const T s = sqrt(s2);
  return T(2.0) * atan2(s, q.w()) / s * q.vec();
}

// The Cayley map cay(x) = (1 − x̂/2)⁻¹ (1 + x̂/2) as a unit quaternion: (1, x/2) normalized,
// a turn by 2 atan(|x|/2). Exactly rational, which is why the variational integrator uses it.
template <class T> Eigen::Quaternion<T> CayleyRotation(const Vec3<T>& x) {
  using std::sqrt;
  const T inv_norm = T(1.0) / sqrt(T(1.0) + T(0.25) * x.squaredNorm());
  return Eigen::Quaternion<T>(inv_norm, T(0.5) * inv_norm * x.x(), T(0.5) * inv_norm * x.y(),
                              T(0.5) * inv_norm * x.z());
}

// (dcay⁻¹_x)ᵀ μ = μ + ½ x × μ + ¼ x (x·μ): the transposed inverse right-trivialized tangent of
// the Cayley map (Kobilarov & Marsden 2011, §3), which maps body momenta across a step.
template <class T> Vec3<T> CayleyMomentumMap(const Vec3<T>& x, const Vec3<T>& mu) {
  return mu + T(0.5) * x.cross(mu) + T(0.25) * x * x.dot(mu);
}

// Θ̇ for R(τ) = R0 exp(Θ̂(τ)) moving with body angular velocity ω (Ṙ = R ω̂):
// Θ̇ = dexp⁻¹_{−Θ}(ω) = ω + ½ Θ × ω + c(|Θ|) Θ × (Θ × ω), c(θ) = (1 − (θ/2) cot(θ/2))/θ²
// (Bernoulli series 1/12 + θ²/720 + ... near 0). Used by the Runge–Kutta–Munthe-Kaas stages.
template <class T> Vec3<T> RotationVectorRate(const Vec3<T>& theta, const Vec3<T>& omega) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T a2 = theta.squaredNorm();
  T c;
  if (ScalarValue(a2) < 1e-8) {
    c = T(1.0 / 12.0) + a2 / T(720.0);
  } else {
    const T a = sqrt(a2), half = T(0.5) * a;
    c = (T(1.0) - half * cos(half) / sin(half)) / a2;
  }
  const Vec3<T> cross = theta.cross(omega);
  return omega + T(0.5) * cross + c * theta.cross(cross);
}

}  // namespace wobble
