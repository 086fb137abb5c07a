// The mutable half of a body (MuJoCo's mjData) and the world constants its step reads, written
// once for both dimensions: positions and velocities in group.h's layout, contacts with the
// ground, the springs that hold points (Fig. 4.4) and the gravity.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <type_traits>
#include <utility>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/body/group.h"
#include "wobble/core/types.h"
#include "wobble/dynamics/ground.h"

namespace wobble {

// A damped spring from a world anchor to a point of a body given by lattice coordinates
// (Fig. 4.4). MakeSpring (or World::AddSpring) fills in the point's b0 and B. One type for both
// dimensions, stored in three: a 2D spring reads its first two rows (the z row stays zero), as
// the world's constraint ends do, so that one list holds the springs of every body.
struct Spring {
  int body = 0;  // the body it holds: the world's body index (0 in a one-body rollout)
  Eigen::Vector3d lattice_coords = Eigen::Vector3d::Constant(0.5);
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double stiffness = 0.0, damping = 0.0, rest_length = 0.0;
  Eigen::Vector3d rest_local = Eigen::Vector3d::Zero();
  Mat3D<double> mode_matrix;
  template <int Dim> Eigen::Matrix<double, Dim, 1> Anchor() const { return anchor.head<Dim>(); }
  template <int Dim> Eigen::Matrix<double, Dim, 1> RestLocal() const { return rest_local.head<Dim>(); }
  template <int Dim> MatND<double, Dim> ModeMatrix() const { return mode_matrix.topRows<Dim>(); }
  template <int Dim> Eigen::Matrix<double, Dim, 1> LatticeCoords() const { return lattice_coords.head<Dim>(); }
};

// Fills in b0 and B of the spring's point on `body` (its lattice coordinates of the body's
// dimension; 2D: the z entries are ignored and stay zero).
template <int Dim> void AttachSpring(const BodyModelN<Dim>& body, Spring* s) {
  Eigen::Matrix<double, Dim, 1> b0;
  MatND<double, Dim> B;
  body.LocalBasis(Eigen::Matrix<double, Dim, 1>(s->lattice_coords.head<Dim>()), &b0, &B);
  if constexpr (Dim == 2) s->lattice_coords.z() = 0.0;
  s->rest_local.setZero();
  s->rest_local.head<Dim>() = b0;
  s->mode_matrix.setZero(3, B.cols());
  s->mode_matrix.topRows<Dim>() = B;
}

// (Dim is the body's: the points are taken as BodyModelN<Dim>::Point, not deduced from them.)
template <int Dim>
Spring MakeSpring(const BodyModelN<Dim>& body, const typename BodyModelN<Dim>::Point& lattice_coords,
                  const typename BodyModelN<Dim>::Point& anchor, double stiffness, double damping = 0.0,
                  double rest_length = 0.0) {
  Spring s;
  s.lattice_coords.setZero();
  s.lattice_coords.head<Dim>() = lattice_coords;
  s.anchor.setZero();
  s.anchor.head<Dim>() = anchor;
  s.stiffness = stiffness;
  s.damping = damping;
  s.rest_length = rest_length;
  AttachSpring(body, &s);
  return s;
}

// The world constants a body's step reads, one set for both dimensions: gravity (y up; a 2D
// body, in the x-y plane, feels its x and y), the ground each dimension stands on, the springs
// of every body, and the condition number of M past which a run stops.
struct WorldParams {
  bool gravity_on = true;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, -9.81, 0.0);
  Ground ground;              // 2D bodies: the line or terrain (on by default)
  GroundPlane ground_plane;   // 3D bodies: the plane or heightfield (off by default; GroundPlaneOf)
  std::vector<Spring> springs;
  double max_condition = 1e12;
};

// The ground and gravity a body of dimension Dim feels.
template <int Dim> const GroundOf<Dim>& GroundFor(const WorldParams& w) {
  if constexpr (Dim == 2) return w.ground;
  else return w.ground_plane;
}
template <int Dim> GroundOf<Dim>& GroundFor(WorldParams& w) {
  if constexpr (Dim == 2) return w.ground;
  else return w.ground_plane;
}
template <int Dim> Eigen::Matrix<double, Dim, 1> GravityFor(const WorldParams& w) { return w.gravity.head<Dim>(); }

// A point below the ground is tied to its entry point `anchor` on face `face` (0 for the
// ground line or plane; terrain.h and heightfield.h say which faces a point feels) by the
// spring–damper unit of Fig. 4.5(a) until it leaves the ground. A point in a valley has one
// contact per face.
template <int Dim, class T> struct Contact {
  int point;
  Eigen::Matrix<T, Dim, 1> anchor;
  int face = 0;
};
template <int Dim, class T> bool ContactBefore(const Contact<Dim, T>& a, const Contact<Dim, T>& b) {
  return a.point < b.point || (a.point == b.point && a.face < b.face);
}

// The contacts of point k in contacts sorted by (point, face), as a range [first, last).
template <int Dim, class T> auto ContactsOfPoint(const std::vector<Contact<Dim, T>>& contacts, int k) {
  const auto first = std::lower_bound(contacts.begin(), contacts.end(), k,
                                      [](const Contact<Dim, T>& a, int point) { return a.point < point; });
  auto last = first;
  while (last != contacts.end() && last->point == k) ++last;
  return std::make_pair(first, last);
}

// The mutable half of a body (MuJoCo's mjData): positions q and velocities q̇ in group.h's
// layout (2D: q = [tx, ty, θ, γ...], q̇ = dq/dt; 3D: q = [t, quaternion, γ], q̇ = [ṫ, ω, γ̇]),
// and its contacts (sorted by point index, then face).
template <int Dim, class T> struct BodyState {
  VecQ<T> q, qd;
  std::vector<Contact<Dim, T>> contacts;
  double penetration = 0.0;  // deepest contact at the last contact update
  // The generalized ground force of `contacts` at exactly (q, qd) under `ground`, left by
  // UpdateContacts. The next explicit step evaluates forces at that same state, so it reuses
  // this instead of visiting every point a second time (half the cost of a resting body).
  // Keyed by value: any change of q, q̇ or the ground makes it miss, never go stale.
  struct GroundForceCache {
    bool valid = false;
    VecQ<T> q, qd, force;
    GroundOf<Dim> ground;
  } ground_cache;
  // What UpdateContacts' last walk of a large body's point tree found (body_model.h): a body at
  // rest then scans the same few leaves without walking the tree. Any state is valid with any
  // memo (it keeps the plane test's numbers and checks how far they moved), so copying or
  // replacing q never makes it wrong, only slower once.
  PlaneScanMemo<Dim> scan_memo;
  // PD targets γ0 of the modes (chapter 5: Q_r = −(C(q − q0) + D q̇)); empty means all zero,
  // i.e. every mode is passive and pulled back to its rest shape. Set by wobble/control.
  VecD<T> mode_target;

  int num_modes() const { return int(q.size()) - Group<Dim>::kRigidParams; }
  auto translation() const { return q.template head<Dim>(); }
  auto translation() { return q.template head<Dim>(); }
  auto gamma() const { return q.tail(num_modes()); }
  auto gamma() { return q.tail(num_modes()); }
  // 3D only: the unit quaternion of the positions
  auto orientation() const { return Group<Dim>::OrientationOf(q); }
  template <class Rotation> void set_orientation(const Rotation& r) {
    Group<Dim>::SetOrientation(Eigen::Quaternion<T>(r), &q);
  }
};

// A state at rest in the lattice's own pose.
template <int Dim, class T> BodyState<Dim, T> RestState(const BodyModelN<Dim>& body) {
  BodyState<Dim, T> s;
  s.q.setZero(NumPositions<Dim>(body.num_modes()));
  if constexpr (Dim == 3) s.q[6] = T(1.0);  // the identity quaternion's w
  s.qd.setZero(NumVelocities<Dim>(body.num_modes()));
  return s;
}

template <int Dim, class T> struct ForceBreakdown {
  VecQ<T> gravity, modes, ground, springs, total;
};

// Positions q (group.h's layout) from a translation, a rotation and the amplitudes γ: the
// angle θ in 2D; a quaternion (or anything Eigen makes one of: an angle-axis) in 3D.
inline VecQ<double> PositionsOf(const Eigen::Vector2d& t, double theta, const Eigen::VectorXd& gamma) {
  VecQ<double> q(Group<2>::kRigidParams + gamma.size());
  q << t, theta, gamma;
  return q;
}
template <class Rotation>
VecQ<double> PositionsOf(const Eigen::Vector3d& t, const Rotation& rotation, const Eigen::VectorXd& gamma) {
  VecQ<double> q(Group<3>::kRigidParams + gamma.size());
  q.head<3>() = t;
  Group<3>::SetOrientation(Eigen::Quaterniond(rotation).normalized(), &q);
  q.tail(gamma.size()) = gamma;
  return q;
}

// The cached ground force of s, when it was computed at s's current state on ground g.
template <int Dim, class T> const VecQ<T>* CachedGroundForce(const BodyState<Dim, T>& s, const GroundOf<Dim>& g) {
  if constexpr (!std::is_same_v<T, double>) {
    return nullptr;  // derivative parts are not keyed; Jets always recompute
  } else {
    const auto& c = s.ground_cache;
    if (!c.valid || !(c.ground == g) || c.q.size() != s.q.size()) return nullptr;
    for (int i = 0; i < s.q.size(); ++i)
      if (c.q[i] != s.q[i]) return nullptr;
    for (int i = 0; i < s.qd.size(); ++i)
      if (c.qd[i] != s.qd[i]) return nullptr;
    return &c.force;
  }
}

// Which points the ground acts on during a force evaluation.
enum class ContactSet {
  kDetect,  // every point below the ground (explicit integrators)
  kFrozen,  // exactly the listed contacts, even a point a little above the ground: implicit
            // solves need a residual without the jump that a point crossing the surface (and
            // its damping force) would add. A listed point above the ground feels only what
            // damping pushes, never a pull (f_n >= 0).
};

// A state from the coordinates users read and write (World::q, files, the command line's --q)
// and velocities q̇, without contacts; and the coordinates of a state. In 2D the coordinates
// are the positions; in 3D they are [t, Θ, γ] with Θ the orientation's rotation vector
// (|Θ| ≤ π), where the positions hold a unit quaternion.
template <int Dim>
BodyState<Dim, double> StateFromCoordinates(const Eigen::VectorXd& coordinates, const Eigen::VectorXd& qd) {
  BodyState<Dim, double> s;
  s.qd = qd;
  if constexpr (Dim == 2) {
    s.q = coordinates;
  } else {
    const int D = int(coordinates.size()) - Group<3>::kRigidDofs;
    s.q.resize(NumPositions<3>(D));
    s.q.template head<3>() = coordinates.template head<3>();
    Group<3>::SetOrientation(ExpRotation<double>(Eigen::Vector3d(coordinates.template segment<3>(3))), &s.q);
    s.q.tail(D) = coordinates.tail(D);
  }
  return s;
}
template <int Dim> Eigen::VectorXd CoordinatesOf(const BodyState<Dim, double>& s) {
  if constexpr (Dim == 2) {
    return s.q;
  } else {
    const int D = s.num_modes();
    Eigen::VectorXd c(Group<3>::kRigidDofs + D);
    c << s.q.template head<3>(), LogRotation<double>(Group<3>::OrientationOf(s.q)), s.q.tail(D);
    return c;
  }
}

}  // namespace wobble
