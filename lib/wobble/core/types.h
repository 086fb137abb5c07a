// Fixed-capacity Eigen types for a body's positions q and velocities q̇ (Eq. 4.4; group.h has
// the layout of both dimensions: at most 7 + kMaxModes positions, 6 + kMaxModes velocities).
//
// Sizes are dynamic but bounded, so per-step vectors and matrices live on the stack: a step
// of the 11-point table must not touch the heap. Every dynamics routine is a template on the
// scalar T so that the same code runs with double and with ceres::Jet (fitting through
// simulations differentiates it).
#pragma once

#include <Eigen/Core>

namespace wobble {

constexpr int kRigidDofs = 3;   // tx, ty, θ of a 2D body (Group<2>::kRigidDofs)
constexpr int kMaxModes = 12;   // deformation modes per body
constexpr int kMaxQ = 7 + kMaxModes;  // a 3D body's positions: t, a unit quaternion, γ

template <class T> using Vec2 = Eigen::Matrix<T, 2, 1>;
template <class T> using Mat2 = Eigen::Matrix<T, 2, 2>;
template <class T> using VecQ = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, kMaxQ, 1>;
template <class T> using MatQ = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxQ, kMaxQ>;
template <class T> using VecD = Eigen::Matrix<T, Eigen::Dynamic, 1, 0, kMaxModes, 1>;
template <class T> using MatD = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxModes, kMaxModes>;
template <class T, int Dim> using MatND = Eigen::Matrix<T, Dim, Eigen::Dynamic, 0, Dim, kMaxModes>;
template <class T> using Mat2D = MatND<T, 2>;

template <class T> using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T> using Mat3 = Eigen::Matrix<T, 3, 3>;
template <class T> using Mat3D = MatND<T, 3>;

// R(θ) of Eq. 4.3.
template <class T> Mat2<T> Rotation(const T& theta) {
  using std::cos;
  using std::sin;
  const T c = cos(theta), s = sin(theta);
  Mat2<T> r;
  r << c, -s, s, c;
  return r;
}

// S = [[0,-1],[1,0]]: dR/dθ = R S, and S v is v turned a quarter to the left.
template <class T> Vec2<T> Perp(const Vec2<T>& v) { return Vec2<T>(-v.y(), v.x()); }

}  // namespace wobble

namespace wobble {
// The plain value of a scalar: itself for double, the value part of a ceres::Jet (without
// making lib depend on Ceres). Used for checks and branches, never for arithmetic.
inline double ScalarValue(double x) { return x; }
template <class J> auto ScalarValue(const J& x) -> decltype(double(x.a)) { return x.a; }
}  // namespace wobble
