// External and internal forces of a body as generalized forces Q = Σ Jᵀ f (Eq. 4.20):
// gravity (§4.7), mode potentials V = K γ² with damping (§4.7), springs holding a point
// (Fig. 4.4), and the penalty ground of §4.9 (Eq. 4.24, 4.25) on a line of any slope or a
// terrain of straight faces (terrain.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <type_traits>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/dynamics/heightfield.h"
#include "wobble/dynamics/terrain.h"

namespace wobble {

// The ground line through `point` at angle `slope` (radians, counter-clockwise from +x).
// World y points up, gravity is −y.
struct Ground {
  bool enabled = true;
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  double slope = 0.0;
  double stiffness = 4500.0;       // K_d of Eq. 4.24/4.25 (appendix C: grconst)
  double normal_damping = 550.0;   // C_dam, damping along the normal (grdam)
  double friction_damping = 50.0;  // FR_dam, damping along the tangent (frconst)
  double friction_cap = 0.1;       // tan θ: |friction / normal force| never exceeds it
  // A point deeper than this stops the run (runaway penetration). 0 means automatic: half
  // the shorter lattice side of the body.
  double max_penetration = 0.0;
  // A terrain of straight faces (terrain.h) in place of the line through `point`; the
  // parameters above are those of every face that has none of its own.
  std::shared_ptr<const Terrain> terrain;
  // The 3D bodies' ground in place of the plane of this line (GroundPlaneOf in world.h); 2D
  // bodies never feel it.
  std::shared_ptr<const Heightfield> heightfield;

  Eigen::Vector2d tangent() const { return {std::cos(slope), std::sin(slope)}; }
  Eigen::Vector2d normal() const { return {-std::sin(slope), std::cos(slope)}; }
  bool operator==(const Ground& o) const {
    return enabled == o.enabled && point == o.point && slope == o.slope && stiffness == o.stiffness &&
           normal_damping == o.normal_damping && friction_damping == o.friction_damping &&
           friction_cap == o.friction_cap && max_penetration == o.max_penetration &&
           (terrain == o.terrain || (terrain && o.terrain && *terrain == *o.terrain)) &&
           (heightfield == o.heightfield || (heightfield && o.heightfield && *heightfield == *o.heightfield));
  }
  // Face i of the ground (0 for the line) with its parameters resolved.
  GroundFace Face(int i) const {
    if (terrain) return terrain->Face(i, stiffness, normal_damping, friction_damping, friction_cap);
    GroundFace f;
    f.point = point;
    f.n = normal();
    f.tau = tangent();
    f.stiffness = stiffness;
    f.normal_damping = normal_damping;
    f.friction_damping = friction_damping;
    f.friction_cap = friction_cap;
    return f;
  }
};

// A damped spring from a world anchor to a point of a body given by lattice coordinates.
struct Spring {
  int body = 0;
  Eigen::Vector2d lattice_coords = Eigen::Vector2d(0.5, 0.5);
  Eigen::Vector2d anchor = Eigen::Vector2d::Zero();
  double stiffness = 0.0, damping = 0.0, rest_length = 0.0;
  // b0 and B of the held point, filled in by World::AddSpring.
  Eigen::Vector2d rest_local = Eigen::Vector2d::Zero();
  Mat2D<double> mode_matrix;
};

struct WorldParams {
  bool gravity_on = true;
  Eigen::Vector2d gravity = Eigen::Vector2d(0.0, -9.81);
  Ground ground;
  std::vector<Spring> springs;
  // Runs stop when the estimated condition number of M exceeds this.
  double max_condition = 1e12;
};

// A point below the ground is tied to its entry point `anchor` on face `face` (0 for the
// ground line; terrain.h says which faces of a terrain a point feels) by the spring–damper unit
// of Fig. 4.5(a) until it leaves the ground. A point in a valley has one contact per face.
template <class T> struct Contact {
  int point;
  Vec2<T> anchor;
  int face = 0;
};
template <class T> bool ContactBefore(const Contact<T>& a, const Contact<T>& b) {
  return a.point < b.point || (a.point == b.point && a.face < b.face);
}

// The mutable half of a body (MuJoCo's mjData): q = [tx, ty, θ, γ...], q̇, and its contacts
// (sorted by point index, then face).
template <class T> struct BodyState {
  VecQ<T> q, qd;
  std::vector<Contact<T>> contacts;
  double penetration = 0.0;  // deepest contact at the last contact update
  // The generalized ground force of `contacts` at exactly (q, qd) under `ground`, left by
  // UpdateContacts. The next explicit step evaluates forces at that same state, so it reuses
  // this instead of visiting every point a second time (half the cost of a resting body).
  // Keyed by value: any change of q, q̇ or the ground makes it miss, never go stale.
  struct GroundForceCache {
    bool valid = false;
    VecQ<T> q, qd, force;
    Ground ground;
  } ground_cache;
  // PD targets γ0 of the modes (chapter 5: Q_r = −(C(q − q0) + D q̇)); empty means all zero,
  // i.e. every mode is passive and pulled back to its rest shape. Set by wobble/control.
  VecD<T> mode_target;
};

// The cached ground force of s, when it was computed at s's current state on ground g.
template <class T> const VecQ<T>* CachedGroundForce(const BodyState<T>& s, const Ground& g) {
  if constexpr (!std::is_same_v<T, double>) {
    return nullptr;  // derivative parts are not keyed; Jets always recompute
  } else {
    const auto& c = s.ground_cache;
    if (!c.valid || !(c.ground == g) || c.q.size() != s.q.size()) return nullptr;
    for (int i = 0; i < s.q.size(); ++i)
      if (c.q[i] != s.q[i] || c.qd[i] != s.qd[i]) return nullptr;
    return &c.force;
  }
}

template <class T> struct ForceBreakdown {
  VecQ<T> gravity, modes, ground, springs, total;
};

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
template <class T> bool ClearOfGround(const BodyModel& body, const Ground& g, const VecQ<T>& q, const Frame<T>& frame) {
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

// Which points the ground acts on during a force evaluation.
enum class ContactSet {
  kDetect,  // every point below the ground (explicit integrators)
  kFrozen,  // exactly the listed contacts, even a point a little above the ground: implicit
            // solves need a residual without the jump that a point crossing the surface (and
            // its damping force) would add. A listed point above the ground feels only what
            // damping pushes, never a pull (f_n >= 0).
};

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
// Frame(s.q), made once by the caller.
template <class T, class F>
void ForEachPointInContact(const BodyModel& body, const Ground& g, const BodyState<T>& s, const Frame<T>& frame, F&& f,
                           ContactSet set = ContactSet::kDetect) {
  if (!g.enabled) return;
  const GroundFace line = g.Face(0);
  auto point_at = [&](int k, Vec2<T>* l, Vec2<T>* x) {
    *l = LocalPosition<T>(body.rest_local(k), body.mode_matrix(k), s.q);
    *x = WorldFromLocal(frame, *l);
  };
  if (set == ContactSet::kFrozen) {
    for (const Contact<T>& c : s.contacts) {
      Vec2<T> l, x;
      point_at(c.point, &l, &x);
      f(c.point, l, x, PointVelocity(frame, s.qd, l, body.mode_matrix(c.point)), c.anchor,
        g.terrain ? g.Face(c.face) : line, c.face);
    }
    return;
  }
  // The contacts of point k: [first, last) of the sorted list.
  auto contacts_of = [&](int k) {
    const auto first = std::lower_bound(s.contacts.begin(), s.contacts.end(), k,
                                        [](const Contact<T>& a, int point) { return a.point < point; });
    auto last = first;
    while (last != s.contacts.end() && last->point == k) ++last;
    return std::make_pair(first, last);
  };
  // One point: on the line, below it or not; on a terrain, every face it feels.
  auto visit = [&](int k) {
    Vec2<T> l, x;
    point_at(k, &l, &x);
    ForEachFaceFelt(
        g, line, x, [&] { return PointVelocity(frame, s.qd, l, body.mode_matrix(k)); }, [&] { return contacts_of(k); },
        [&](const GroundFace& face, int face_index, const Vec2<T>& anchor, const Vec2<T>& v) {
          f(k, l, x, v, anchor, face, face_index);
        });
  };
  if (ClearOfGround(body, g, s.q, frame)) return;
  const std::vector<PointCluster>& clusters = body.clusters();
  if (clusters.size() <= 1) {
    for (int k = 0; k < body.num_points(); ++k) visit(k);
    return;
  }
  // Large bodies: only groups whose bounding box reaches below the ground. The box test is a
  // decision, so it runs on plain values: on the line, height = n·(t − p) + (Rᵀn)·l; on a
  // terrain, the box's world bounds against the highest surface point under them.
  const int D = body.num_modes();
  const Eigen::Matrix2d R = frame.R.unaryExpr([](const T& v) { return double(ScalarValue(v)); });
  const Eigen::Vector2d n_local = R.transpose() * line.n;
  const Eigen::Vector2d t(ScalarValue(s.q[0]), ScalarValue(s.q[1]));
  const double offset = line.n.dot(t - line.point);
  for (const PointCluster& c : clusters) {
    Eigen::Vector2d centre = c.centre0, half = c.half0;
    for (int d = 0; d < D; ++d) {
      const double gamma = ScalarValue(s.q[kRigidDofs + d]);
      centre += gamma * c.centre_modes.col(d);
      half += std::abs(gamma) * c.half_modes.col(d);
    }
    if (!g.terrain) {
      if (offset + n_local.dot(centre) - n_local.cwiseAbs().dot(half) >= 0.0) continue;
    } else {
      const Eigen::Vector2d world_centre = t + R * centre, world_half = R.cwiseAbs() * half;
      if (world_centre.y() - world_half.y() >
          g.terrain->MaxHeight(world_centre.x() - world_half.x(), world_centre.x() + world_half.x()))
        continue;
    }
    for (int k : c.points) visit(k);
  }
}

// All generalized forces on a body, by source.
// `frame` is Frame(s.q), made once by the caller.
template <class T>
void EvaluateForces(const BodyModel& body, const WorldParams& w, int body_index, const BodyState<T>& s,
                    const Frame<T>& frame, ForceBreakdown<T>* out, ContactSet contact_set = ContactSet::kDetect) {
  const int nq = body.num_q(), D = body.num_modes();
  // gravity, exactly from the moments
  if (w.gravity_on) {
    GravityForce(body.moments(), s.q, frame.R, w.gravity, &out->gravity);
  } else {
    out->gravity.setZero(nq);
  }
  // mode potentials V = K γ² → Q = −2Kγ, and damping −c γ̇ (§4.7); with a PD target γ0 this
  // is the controller of chapter 5, Q_r = −(C(γ − γ0) + D γ̇) with C = 2K, D = c
  out->modes.setZero(nq);
  const bool targeted = s.mode_target.size() == D;
  for (int d = 0; d < D; ++d) {
    const DeformationMode& m = body.modes()[d];
    const T offset = targeted ? T(s.q[kRigidDofs + d] - s.mode_target[d]) : T(s.q[kRigidDofs + d]);
    out->modes[kRigidDofs + d] = -T(2.0 * m.stiffness) * offset - T(m.damping) * s.qd[kRigidDofs + d];
  }
  // penalty ground, only over points below it
  const VecQ<T>* cached = contact_set == ContactSet::kDetect ? CachedGroundForce(s, w.ground) : nullptr;
  if (cached) {
    out->ground = *cached;
  } else {
    out->ground.setZero(nq);
    ForEachPointInContact(body, w.ground, s, frame, [&](int k, const Vec2<T>& l, const Vec2<T>& x, const Vec2<T>& v,
                                                 const Vec2<T>& anchor, const GroundFace& face, int) {
      bool slipping;
      AddGeneralizedForce(frame, l, body.mode_matrix(k), GroundForce(face, x, v, anchor, &slipping), &out->ground);
    }, contact_set);
  }
  // springs holding a point
  out->springs.setZero(nq);
  for (const Spring& sp : w.springs) {
    if (sp.body != body_index) continue;
    const Vec2<T> l = LocalPosition<T>(sp.rest_local, sp.mode_matrix, s.q);
    const Vec2<T> x = WorldFromLocal(frame, l);
    const Vec2<T> v = PointVelocity(frame, s.qd, l, sp.mode_matrix);
    const Vec2<T> delta = x - sp.anchor.cast<T>();
    using std::sqrt;
    const T len = sqrt(delta.squaredNorm() + T(1e-300));
    const Vec2<T> dir = delta / len;
    const Vec2<T> f = -(T(sp.stiffness) * (len - T(sp.rest_length)) + T(sp.damping) * dir.dot(v)) * dir;
    AddGeneralizedForce(frame, l, sp.mode_matrix, f, &out->springs);
  }
  out->total = out->gravity + out->modes + out->ground + out->springs;
}
template <class T>
void EvaluateForces(const BodyModel& body, const WorldParams& w, int body_index, const BodyState<T>& s,
                    ForceBreakdown<T>* out, ContactSet contact_set = ContactSet::kDetect) {
  EvaluateForces(body, w, body_index, s, Frame<T>(s.q), out, contact_set);
}

// Adds a contact for every point below the ground that has none (anchor: its projection on
// the ground). Returns how many were added. Implicit steps call it to grow their active set.
template <class T> int AddMissingContacts(const BodyModel& body, const Ground& g, BodyState<T>* s) {
  std::vector<Contact<T>> added;
  const BodyState<T>& view = *s;
  ForEachPointInContact(body, g, view, Frame<T>(view.q), [&](int k, const Vec2<T>&, const Vec2<T>&, const Vec2<T>&,
                                            const Vec2<T>& anchor, const GroundFace&, int face) {
    for (const Contact<T>& c : view.contacts)
      if (c.point == k && c.face == face) return;
    added.push_back({k, anchor, face});
  });
  if (added.empty()) return 0;
  s->contacts.insert(s->contacts.end(), added.begin(), added.end());
  std::sort(s->contacts.begin(), s->contacts.end(), ContactBefore<T>);
  return int(added.size());
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

// After a step is accepted: points that went below the ground get an anchor at their entry
// point, points that left it lose theirs, and an anchor whose friction hit the cap slides
// along the ground so the tangential spring holds exactly the capped force (Coulomb slip).
// The same pass sums the ground's generalized force at this state into s->ground_cache.
template <class T> void UpdateContacts(const BodyModel& body, const Ground& g, BodyState<T>* s) {
  // reuse storage across steps: no heap traffic while a body rests on the ground
  thread_local std::vector<Contact<T>> next;
  next.clear();
  s->penetration = 0.0;
  const Frame<T> frame(s->q);
  auto& cache = s->ground_cache;
  cache.force.setZero(s->q.size());
  ForEachPointInContact(body, g, *s, frame, [&](int k, const Vec2<T>& l, const Vec2<T>& x, const Vec2<T>& v,
                                         Vec2<T> anchor, const GroundFace& face, int face_index) {
    bool slipping;
    Vec2<T> f = GroundForce(face, x, v, anchor, &slipping);
    if (slipping) SlipAnchor(face, x, v, &anchor, &f);
    AddGeneralizedForce(frame, l, body.mode_matrix(k), f, &cache.force);
    next.push_back({k, anchor, face_index});
    s->penetration = std::max(s->penetration, -double(ScalarValue(face.Height(x))));
  });
  if (body.clusters().size() > 1)  // groups are visited in lattice order, not point order
    std::sort(next.begin(), next.end(), ContactBefore<T>);
  s->contacts.swap(next);
  cache.q = s->q;
  cache.qd = s->qd;
  cache.ground = g;
  cache.valid = true;
}

}  // namespace wobble
