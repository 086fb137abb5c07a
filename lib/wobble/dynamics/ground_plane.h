// The penalty ground of §4.9 for 3D bodies: which points are below a plane of any normal or a
// heightfield's faces (heightfield.h), the spring–damper force of a contact (Eq. 4.24/4.25 in
// the plane's frame, its friction capped in the whole tangent plane: |f_t| ≤ tan θ f_n, the 2D
// cap made isotropic), and the anchor's slide when the cap is hit. forces.h sums them into Q.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "wobble/dynamics/body_state.h"
#include "wobble/dynamics/kinematics.h"

namespace wobble {

// The faces a point x of the body feels, f(face, plane, anchor) with the face's plane: on a
// plane, the plane when x is below it; on a heightfield, Heightfield::FacesFelt's. The anchor
// is that of the point's contact on the face — contacts_of_k() gives the range of the point's
// contacts, asked for only when x is below the ground — or, on a face the point had no contact
// with, the anchor of the face it leaves projected onto the new one (friction holds across the
// edges between triangles), else the point's foot on the face. Shared by FFD and linear bodies.
template <class T, class ContactsOf, class F>
void ForEachFaceFelt(const GroundPlane& g, const Vec3<T>& x, ContactsOf&& contacts_of_k, F&& f) {
  if (!g.heightfield) {
    const T h = g.Height(x);
    if (!(ScalarValue(h) < 0.0)) return;
    const auto [first, last] = contacts_of_k();
    f(0, g, first != last ? first->anchor : Vec3<T>(x - h * g.normal.cast<T>()));
    return;
  }
  const Heightfield& field = *g.heightfield;
  const Eigen::Vector3d xd(ScalarValue(x.x()), ScalarValue(x.y()), ScalarValue(x.z()));
  if (!(xd.y() < field.max_height())) return;
  thread_local std::vector<int> faces;
  faces.clear();
  field.FacesFelt(xd, &faces);
  if (faces.empty()) return;
  const auto [first, last] = contacts_of_k();
  for (int face : faces) {
    const GroundPlane plane = g.Face(face, xd);
    const Vec3<T> n = plane.normal.template cast<T>();
    const auto same = std::find_if(first, last, [face](const auto& c) { return c.face == face; });
    if (same != last) {
      f(face, plane, same->anchor);
    } else if (first != last) {
      f(face, plane, Vec3<T>(first->anchor - n * plane.Height(first->anchor)));
    } else {
      f(face, plane, Vec3<T>(x - n * plane.Height(x)));
    }
  }
}

// The (point, face) pairs the ground acts on during an evaluation (ContactSet of the 2D body):
// f(k, l, x, v, anchor, plane, face) with the face's plane (the 2D visitor's order). `memo`: as
// in 2D, the walk of a large body's point tree skipped while the last one still holds.
template <class T, class F>
void ForEachPointInContact(const BodyModelN<3>& body, const GroundPlane& g, const BodyState<3, T>& s,
                            const Frame<3, T>& frame, F&& f, ContactSet set = ContactSet::kDetect,
                            PlaneScanMemo<3>* memo = nullptr) {
  if (!g.enabled) return;
  if (set == ContactSet::kFrozen) {
    for (const Contact<3, T>& c : s.contacts) {
      const auto B = body.mode_matrix(c.point);
      const Vec3<T> l = LocalPosition<T>(body.rest_local(c.point), B, s.q);
      const Vec3<T> x = frame.t + frame.R * l;
      const Eigen::Vector3d xd(ScalarValue(x.x()), ScalarValue(x.y()), ScalarValue(x.z()));
      if (g.heightfield) {
        f(c.point, l, x, PointVelocity(frame, s.qd, l, B), c.anchor, g.Face(c.face, xd), c.face);
      } else {
        f(c.point, l, x, PointVelocity(frame, s.qd, l, B), c.anchor, g, c.face);
      }
    }
    return;
  }
  // decisions on plain values: height = n·(t − p) + (Rᵀn)·l; over a heightfield the plane is
  // the level one through its highest node (nothing above it can touch)
  const Eigen::Vector3d normal = g.heightfield ? Eigen::Vector3d::UnitY() : g.normal;
  const Eigen::Vector3d through = g.heightfield ? Eigen::Vector3d(0.0, g.heightfield->max_height(), 0.0) : g.point;
  const Eigen::Vector3d n_local =
      Mat3<double>(frame.R.unaryExpr([](const T& x) { return double(ScalarValue(x)); })).transpose() * normal;
  const Eigen::Vector3d t(ScalarValue(s.q[0]), ScalarValue(s.q[1]), ScalarValue(s.q[2]));
  const double offset = normal.dot(t - through);
  const int D = body.num_modes();
  // convex-hull test: every deformed control point above the plane means every point is
  bool clear = true;
  const std::vector<Eigen::Vector3d>& rest = body.rest_control();
  for (int c = 0; clear && c < int(rest.size()); ++c) {
    double h = offset + n_local.dot(rest[c]);
    for (int d = 0; d < D; ++d) h += ScalarValue(s.q[Group<3>::kRigidParams + d]) * n_local.dot(body.modes()[d].displacement[c]);
    clear = h > 0.0;
  }
  if (clear) return;
  double gamma_norm = 0.0;
  for (int d = 0; d < D; ++d) gamma_norm += std::abs(ScalarValue(s.q[Group<3>::kRigidParams + d]));
  const PointClearOfPlane<3> clear_of_plane(body.rest_extent(), body.max_mode_reach(), n_local, offset,
                                            t.cwiseAbs().sum() + through.cwiseAbs().sum(), gamma_norm);
  auto visit = [&](int k) {
    // most points of a body at rest are far above: a bound first, then the exact position
    if (clear_of_plane(body.rest_local(k), body.mode_reach(k))) return;
    const auto B = body.mode_matrix(k);
    const Vec3<T> l = LocalPosition<T>(body.rest_local(k), B, s.q);
    const Vec3<T> x = frame.t + frame.R * l;
    ForEachFaceFelt(g, x, [&] { return ContactsOfPoint(s.contacts, k); },
                     [&](int face, const GroundPlane& plane, const Vec3<T>& anchor) {
                       f(k, l, x, PointVelocity(frame, s.qd, l, B), anchor, plane, face);
                     });
  };
  if (body.clusters().size() <= 1) {
    for (int k = 0; k < body.num_points(); ++k) visit(k);
    return;
  }
  // large bodies: only the points of the point tree's nodes whose box reaches below the plane
  // (as in 2D, ground_line.h)
  const PlaneReach<3> below_plane(body.point_tree(), D, n_local, offset, t.cwiseAbs().sum() + through.cwiseAbs().sum(),
                                  [&](int d) { return ScalarValue(s.q[Group<3>::kRigidParams + d]); });
  if (memo) {
    body.ForEachPointInPlaneReach(below_plane, memo, visit);
  } else {
    body.ForEachPointInReach(below_plane, visit);
  }
}

// Eq. 4.24/4.25 in the plane's frame: f_n = −K Δn − C_dam v_n (never pulling),
// f_t = −K Δt − FR_dam v_t (tangent-plane vectors), scaled back onto |f_t| ≤ tan θ f_n. The
// parts are kept for the 3D adjoint's partials (fit/internal/step_vjp_space.cc).
template <class T> struct GroundForceParts {
  T fn;             // the normal force, after the clamp at 0
  bool pressing;    // the spring-damper pushed (fn was not clamped)
  Vec3<T> ft;       // the tangential force before the cap, and its norm
  T ft_norm;
  bool slipping;    // |f_t| above the cap
  Vec3<T> f;        // the force
};
template <class T>
GroundForceParts<T> GroundForcePartsOf(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, const Vec3<T>& anchor) {
  using std::sqrt;
  GroundForceParts<T> p;
  const Vec3<T> n = g.normal.cast<T>();
  const Vec3<T> dl = x - anchor;
  p.fn = -T(g.stiffness) * n.dot(dl) - T(g.normal_damping) * n.dot(v);
  p.pressing = !(p.fn < T(0.0));
  if (!p.pressing) p.fn = T(0.0);
  const Vec3<T> dl_t = dl - n * n.dot(dl), v_t = v - n * n.dot(v);
  p.ft = -T(g.stiffness) * dl_t - T(g.friction_damping) * v_t;
  const T cap = T(g.friction_cap) * p.fn;
  p.ft_norm = sqrt(p.ft.squaredNorm() + T(1e-300));
  p.slipping = p.ft_norm > cap;
  p.f = p.fn * n + (p.slipping ? Vec3<T>(p.ft * (cap / p.ft_norm)) : p.ft);
  return p;
}
template <class T>
Vec3<T> GroundForce(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, const Vec3<T>& anchor, bool* slipping) {
  const GroundForceParts<T> p = GroundForcePartsOf(g, x, v, anchor);
  *slipping = p.slipping;
  return p.f;
}

// The anchor of a point whose friction hit the cap, moved so that the tangential spring holds
// exactly the capped force f_t, and the force it then exerts (SlipAnchor of forces.h in 3D).
template <class T>
void SlipAnchor(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, Vec3<T>* anchor, Vec3<T>* f) {
  if (!(g.stiffness > 0.0)) return;  // no spring to the anchor: nothing to move
  // −K Δt − FR v_t = f_t  ⇒  Δt = −(f_t + FR v_t)/K, measured from the point's foot
  const Vec3<T> n = g.normal.cast<T>();
  const Vec3<T> ft = *f - n * n.dot(*f), v_t = v - n * n.dot(v);
  const Vec3<T> dt = -(ft + T(g.friction_damping) * v_t) / T(g.stiffness);
  *anchor = x - g.Height(x) * n - dt;
  bool slipping;
  *f = GroundForce(g, x, v, *anchor, &slipping);  // what the moved anchor exerts
}

}  // namespace wobble
