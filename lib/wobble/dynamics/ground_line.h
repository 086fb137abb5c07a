// The penalty ground of §4.9 for 2D bodies (Eq. 4.24, 4.25): which points are below the line
// or a terrain's faces (terrain.h), the spring–damper force of a contact with its friction
// cap, and the anchor's slide when the cap is hit. forces.h sums them into Q.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "wobble/dynamics/body_state.h"
#include "wobble/dynamics/kinematics.h"

namespace wobble {

// Ground force at a point x with velocity v tied to `anchor` (Eq. 4.24, 4.25 in the face's
// frame): f_n = −K_d Δn − C_dam v_n (never pulling), f_t = −K_d Δt − FR_dam v_t with
// |f_t| ≤ tanθ f_n. Sets *slipping when the friction cap was hit.
template <class T>
Vec2<T> GroundForce(const GroundFace& g, const Vec2<T>& x, const Vec2<T>& v, const Vec2<T>& anchor, bool* slipping) {
  const Vec2<T> n = g.n.cast<T>(), tau = g.tau.cast<T>();
  const Vec2<T> dl = x - anchor;
  T fn = -T(g.stiffness) * n.dot(dl) - T(g.normal_damping) * n.dot(v);
  if (fn < T(0.0)) fn = T(0.0);
  T ft = -T(g.stiffness) * tau.dot(dl) - T(g.friction_damping) * tau.dot(v);
  const T cap = T(g.friction_cap) * fn;
  *slipping = false;
  if (ft > cap) {
    ft = cap;
    *slipping = true;
  } else if (ft < -cap) {
    ft = -cap;
    *slipping = true;
  }
  return fn * n + ft * tau;
}

// Convex-hull test: true when every deformed control point is strictly above the ground, so no
// point of the body can be below it (Bernstein and B-spline weights are a partition of unity).
// On a terrain: the hull's bounding box is above the highest surface point under it.
template <class T> bool ClearOfGround(const BodyModel& body, const Ground& g, const VecQ<T>& q, const Frame<2, T>& frame) {
  const int D = body.num_modes();
  const GroundFace face = g.Face(0);
  const std::vector<Eigen::Vector2d>& rest = body.rest_control();
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (int c = 0; c < int(rest.size()); ++c) {
    Vec2<T> local = rest[c].cast<T>();
    for (int d = 0; d < D; ++d) local += body.modes()[d].displacement[c].cast<T>() * q[kRigidDofs + d];
    const Vec2<T> x = WorldFromLocal(frame, local);
    if (!g.terrain) {
      if (!(ScalarValue(face.Height(x)) > 0.0)) return false;
      continue;
    }
    const Eigen::Vector2d xd(ScalarValue(x[0]), ScalarValue(x[1]));
    lo = lo.cwiseMin(xd);
    hi = hi.cwiseMax(xd);
  }
  return !g.terrain || lo.y() > g.terrain->MaxHeight(lo.x(), hi.x());
}

// The faces a point at x below the ground feels, each visited as f(face, face_index, anchor, v):
// anchor is the point's contact on that face (contacts() gives [first, last) of the point's
// contacts, sorted by face) or, for a new contact, its foot on the face; v = velocity(). Both
// are asked only for a point below the ground: most points visited are above it.
// On the line: face 0 when x is below it. On a terrain: terrain.h's rules.
// Shared by FFD bodies (ForEachPointInContact) and linear ones (linear_ground.h).
template <class T, class V, class C, class F>
[[gnu::always_inline]] inline void ForEachFaceFelt(const Ground& g, const GroundFace& line, const Vec2<T>& x, V&& velocity,
                                                  C&& contacts, F&& f) {
  auto foot = [&x](const GroundFace& face) { return Vec2<T>(x - face.Height(x) * face.n.cast<T>()); };
  if (!g.terrain) {
    if (!(ScalarValue(line.Height(x)) < 0.0)) return;
    const auto range = contacts();
    f(line, 0, range.first != range.second ? Vec2<T>(range.first->anchor) : foot(line), Vec2<T>(velocity()));
    return;
  }
  const Eigen::Vector2d xd(ScalarValue(x[0]), ScalarValue(x[1]));
  if (!g.terrain->Inside(xd)) return;
  const auto range = contacts();
  const auto first = range.first, last = range.second;  // (lambdas cannot capture bindings in C++17)
  const Vec2<T> v = velocity();
  const Eigen::Vector2d vd(ScalarValue(v[0]), ScalarValue(v[1]));
  thread_local std::vector<int> faces;
  faces.clear();
  g.terrain->FacesFelt(xd, vd, [&](int i) { return std::any_of(first, last, [i](const auto& c) { return c.face == i; }); },
                       &faces);
  for (int i : faces) {
    const auto existing = std::find_if(first, last, [i](const auto& c) { return c.face == i; });
    const GroundFace face = g.Face(i);
    f(face, i, existing != last ? Vec2<T>(existing->anchor) : foot(face), v);
  }
}

// Visits every mass point below the ground as f(k, l, x, v, anchor, face, face_index): l local,
// x world, v velocity, anchor its contact's anchor (existing, or the entry point projected on
// the face for a new contact), face the ground face it feels (a point in a terrain's valley is
// visited once per face). Bodies clear of the ground by the hull test cost nothing. `frame` is
// Frame(s.q), made once by the caller. With `memo` (the state's own, by the once-a-step contact
// update) a large body on the line skips the point tree's walk while the last one still holds.
template <class T, class F>
void ForEachPointInContact(const BodyModel& body, const Ground& g, const BodyState<2, T>& s, const Frame<2, T>& frame, F&& f,
                           ContactSet set = ContactSet::kDetect, PlaneScanMemo<2>* memo = nullptr) {
  if (!g.enabled) return;
  const GroundFace line = g.Face(0);
  auto point_at = [&](int k, Vec2<T>* l, Vec2<T>* x) {
    *l = LocalPosition<T>(body.rest_local(k), body.mode_matrix(k), s.q);
    *x = WorldFromLocal(frame, *l);
  };
  if (set == ContactSet::kFrozen) {
    for (const Contact<2, T>& c : s.contacts) {
      Vec2<T> l, x;
      point_at(c.point, &l, &x);
      f(c.point, l, x, PointVelocity(frame, s.qd, l, body.mode_matrix(c.point)), c.anchor,
        g.terrain ? g.Face(c.face) : line, c.face);
    }
    return;
  }
  if (ClearOfGround(body, g, s.q, frame)) return;
  const int D = body.num_modes();
  const Eigen::Matrix2d R = frame.R.unaryExpr([](const T& v) { return double(ScalarValue(v)); });
  const Eigen::Vector2d t(ScalarValue(s.q[0]), ScalarValue(s.q[1]));
  const Eigen::Vector2d n_local = R.transpose() * line.n;
  const double offset = line.n.dot(t - line.point), scale = t.cwiseAbs().sum() + line.point.cwiseAbs().sum();
  double gamma_norm = 0.0;
  for (int d = 0; d < D; ++d) gamma_norm += std::abs(ScalarValue(s.q[kRigidDofs + d]));
  // On the line, most points of a body at rest are far above it: a bound first (as in 3D,
  // ground_plane.h), then the exact position. A terrain's faces are not one plane: no bound.
  const PointClearOfPlane<2> clear_of_line(body.rest_extent(), body.max_mode_reach(), n_local, offset, scale,
                                           gamma_norm);
  // One point: on the line, below it or not; on a terrain, every face it feels.
  auto visit = [&](int k) {
    if (!g.terrain && clear_of_line(body.rest_local(k), body.mode_reach(k))) return;
    Vec2<T> l, x;
    point_at(k, &l, &x);
    ForEachFaceFelt(
        g, line, x, [&] { return PointVelocity(frame, s.qd, l, body.mode_matrix(k)); }, [&] { return ContactsOfPoint(s.contacts, k); },
        [&](const GroundFace& face, int face_index, const Vec2<T>& anchor, const Vec2<T>& v) {
          f(k, l, x, v, anchor, face, face_index);
        });
  };
  if (body.clusters().size() <= 1) {
    for (int k = 0; k < body.num_points(); ++k) visit(k);
    return;
  }
  // Large bodies: only the points of the point tree's nodes (body_model.h) whose box reaches
  // below the ground. The box test is a decision, so it runs on plain values: on the line,
  // height = n·(t − p) + (Rᵀn)·l (PlaneReach); on a terrain, the box's world bounds against the
  // highest surface point under them, widened by PlaneReach's margin.
  const int L = body.point_tree().width;
  const PlaneReach<2> below_line(body.point_tree(), D, n_local, offset, scale,
                                 [&](int d) { return ScalarValue(s.q[kRigidDofs + d]); });
  if (!g.terrain) {
    if (memo) {
      body.ForEachPointInPlaneReach(below_line, memo, visit);
    } else {
      body.ForEachPointInReach(below_line, visit);
    }
    return;
  }
  body.ForEachPointInReach(
      [&](const double* box, bool /*leaf: one test serves every node*/) {
        Eigen::Vector2d centre(box[0], box[1]), half(box[L], box[L + 1]);
        for (int d = 0; d < D; ++d) {
          const double gamma = ScalarValue(s.q[kRigidDofs + d]);
          centre += gamma * Eigen::Vector2d(box[2 * (d + 1)], box[2 * (d + 1) + 1]);
          half += std::abs(gamma) * Eigen::Vector2d(box[L + 2 * (d + 1)], box[L + 2 * (d + 1) + 1]);
        }
        const Eigen::Vector2d world_centre = t + R * centre,
                              world_half = R.cwiseAbs() * half + Eigen::Vector2d::Constant(below_line.margin());
        return world_centre.y() - world_half.y() <=
               g.terrain->MaxHeight(world_centre.x() - world_half.x(), world_centre.x() + world_half.x());
      },
      visit);
}

// The anchor of a point whose friction hit the cap, moved so that −K Δt − FR v_t equals the
// capped friction f·τ, and the force it then exerts. Out of line and cold: sliding is rare,
// and with this in the loop GCC stopped inlining the contact scan into UpdateContacts (8 %
// more instructions per resting-table step under callgrind).
template <class T>
[[gnu::noinline, gnu::cold]] void SlipAnchor(const GroundFace& g, const Vec2<T>& x, const Vec2<T>& v, Vec2<T>* anchor,
                                             Vec2<T>* f) {
  const Vec2<T> tau = g.tau.cast<T>(), n = g.n.cast<T>();
  // no stiffness, no spring to the anchor: it sits on the ground (dividing by K = 0 made it NaN)
  const T dt = g.stiffness > 0.0 ? T(-(f->dot(tau) + T(g.friction_damping) * tau.dot(v)) / T(g.stiffness)) : T(0.0);
  const Vec2<T> on_ground = x - g.Height(x) * n;
  *anchor = on_ground - dt * tau;
  bool slipping;
  *f = GroundForce(g, x, v, *anchor, &slipping);  // what the moved anchor exerts
}

}  // namespace wobble
