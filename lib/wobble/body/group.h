// The rotation group of a body of dimension Dim, and everything the dynamics needs from it.
// What differs between a 2D and a 3D body lives here and in the mass moments (body_model.h);
// the state, the forces, the contacts and the integrators are written once over Dim.
//
// A body's positions q and velocities q̇ follow MuJoCo's qpos/qvel: the positions hold the
// rotation's parameters, the velocities its tangent (the body-frame angular velocity ω):
//   2D (SO(2)): q = [t (2), θ, γ],            q̇ = [ṫ, ω = θ̇, γ̇]   (Eq. 4.4: q̇ is dq/dt)
//   3D (SO(3)): q = [t (3), x y z w, γ],      q̇ = [ṫ, ω (body), γ̇] (a unit quaternion, so
//               no Euler-angle singularity; Ṙ = R ω̂)
// so a point is x = t + R l and ẋ = ṫ + R (ω × l + B γ̇) in both, with "ω × l" the planar
// ω S l in 2D. Advance(q, v, h) is q·exp(h v) on the group.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "wobble/core/rotation3.h"
#include "wobble/core/types.h"

namespace wobble {

template <int Dim> struct Group;

template <> struct Group<2> {
  static constexpr int kRotationParams = 1;  // θ
  static constexpr int kRotationDofs = 1;    // ω
  static constexpr int kRigidParams = 2 + kRotationParams;
  static constexpr int kRigidDofs = 2 + kRotationDofs;

  // R of the rotation parameters at q[2].
  template <class T> static Mat2<T> RotationOf(const VecQ<T>& q) { return Rotation(q[2]); }
  // ω × l: the velocity of body point l turning at ω (planar: ω S l).
  template <class T> static Vec2<T> Turn(const VecQ<T>& qd, const Vec2<T>& l) { return Perp(l) * qd[2]; }
  // (ω × l)·f as a function of ω: the angular rows of Jᵀ f (the torque of f about the origin).
  template <class T> static void AddTorque(const Vec2<T>& l, const Vec2<T>& f_local, VecQ<T>* Q) {
    (*Q)[2] += Perp(l).dot(f_local);
  }
  // q ← q·exp(h v): an abelian group, so plain addition on every coordinate. A plain loop: at
  // this size Eigen's run-time sized expression is an out-of-line call per step (callgrind).
  template <class T> static void Advance(const VecQ<T>& v, const T& h, VecQ<T>* q) {
    for (int i = 0; i < int(v.size()); ++i) (*q)[i] += h * v[i];
  }
  // q0·exp(Θ) for a tangent increment dy = [δt, Θ, δγ] (a Runge–Kutta–Munthe-Kaas stage).
  template <class T> static void Retract(const VecQ<T>& q0, const VecQ<T>& dy, VecQ<T>* q) { *q = q0 + dy; }
  // Θ̇ of the stage coordinates for the velocity v at the stage offset dy: dexp⁻¹ is 1 on SO(2).
  template <class T> static VecQ<T> StageRate(const VecQ<T>&, const VecQ<T>& v) { return v; }
};

template <> struct Group<3> {
  static constexpr int kRotationParams = 4;  // a unit quaternion, x y z w
  static constexpr int kRotationDofs = 3;    // ω in the body frame
  static constexpr int kRigidParams = 3 + kRotationParams;
  static constexpr int kRigidDofs = 3 + kRotationDofs;

  template <class T> static Eigen::Quaternion<T> OrientationOf(const VecQ<T>& q) {
    return Eigen::Quaternion<T>(q[6], q[3], q[4], q[5]);
  }
  template <class T> static void SetOrientation(const Eigen::Quaternion<T>& r, VecQ<T>* q) {
    q->template segment<4>(3) = r.coeffs();  // Eigen stores x y z w
  }
  template <class T> static Mat3<T> RotationOf(const VecQ<T>& q) { return OrientationOf(q).toRotationMatrix(); }
  template <class T> static Vec3<T> Turn(const VecQ<T>& qd, const Vec3<T>& l) {
    return Vec3<T>(qd.template segment<3>(3)).cross(l);
  }
  template <class T> static void AddTorque(const Vec3<T>& l, const Vec3<T>& f_local, VecQ<T>* Q) {
    Q->template segment<3>(3) += l.cross(f_local);
  }
  // t += h ṫ, R ← R exp(h ω̂), γ += h γ̇.
  template <class T> static void Advance(const VecQ<T>& v, const T& h, VecQ<T>* q) {
    const int D = int(v.size()) - kRigidDofs;
    q->template head<3>() += h * v.template head<3>();
    SetOrientation(Eigen::Quaternion<T>(OrientationOf(*q) * ExpRotation<T>(Vec3<T>(h * v.template segment<3>(3))))
                       .normalized(),
                   q);
    q->tail(D) += h * v.tail(D);
  }
  // q = q0·exp(dy) with dy = [δt, Θ, δγ] in the tangent coordinates about q0.
  template <class T> static void Retract(const VecQ<T>& q0, const VecQ<T>& dy, VecQ<T>* q) {
    const int D = int(dy.size()) - kRigidDofs;
    q->resize(kRigidParams + D);
    q->template head<3>() = q0.template head<3>() + dy.template head<3>();
    SetOrientation(Eigen::Quaternion<T>(OrientationOf(q0) * ExpRotation<T>(Vec3<T>(dy.template segment<3>(3))))
                       .normalized(),
                   q);
    q->tail(D) = q0.tail(D) + dy.tail(D);
  }
  // Θ̇ = dexp⁻¹_{−Θ}(ω) (rotation3.h) on the rotation rows, v elsewhere.
  template <class T> static VecQ<T> StageRate(const VecQ<T>& dy, const VecQ<T>& v) {
    VecQ<T> rate = v;
    rate.template segment<3>(3) =
        RotationVectorRate<T>(Vec3<T>(dy.template segment<3>(3)), Vec3<T>(v.template segment<3>(3)));
    return rate;
  }
  template <class T> static void Normalize(VecQ<T>* q) {
    SetOrientation(OrientationOf(*q).normalized(), q);
  }
};

// Sizes of a body with D modes: positions (q) and velocities (q̇, the size of M).
template <int Dim> constexpr int NumPositions(int num_modes) { return Group<Dim>::kRigidParams + num_modes; }
template <int Dim> constexpr int NumVelocities(int num_modes) { return Group<Dim>::kRigidDofs + num_modes; }

}  // namespace wobble
