// One 3D FFD body: its state, forces and the integrators that advance it (the 3D Eq. 4.21 of
// kinematics3.h, M v̇ = Q − w), with the orientation kept on SO(3) as a unit quaternion.
//
// Forces: gravity, mode potentials V = K γ² with damping (and PD targets, chapter 5), damped
// springs to world anchors (Fig. 4.4), and the penalty ground of §4.9 (Eq. 4.24/4.25) on a plane of any normal, its friction capped in the
// whole tangent plane (|f_t| ≤ tan θ f_n: the 2D cap, isotropic in the plane's two directions).
//
// Integrators (the 2D set, carried to the group):
//   thesis            v' = v + Δt a(g, v), then g' = g·exp(Δt v')  (Eq. 4.22/4.23's Störmer form)
//   symplectic        g' = g·exp(Δt v), then v' = v + Δt a(g', v)  (position first, as in 2D)
//   rk4               Runge–Kutta–Munthe-Kaas: the classical tableau on (t, Θ, γ, v) with
//                     R = R0 exp(Θ̂), Θ̇ = dexp⁻¹_{−Θ}(ω), so every stage stays on SO(3)
//   implicit_euler    v' = v + Δt a(g·exp(Δt v'), v'), by Newton
//   variational       the discrete Euler–Poincaré equations of L_d = Δt L(g_k, ξ_k) with
//                     g_{k+1} = g_k·cay(Δt ξ_k) (Kobilarov & Marsden 2011; Bou-Rabee &
//                     Marsden 2009): symplectic, and it keeps linear and angular momentum
//                     exactly (to the Newton tolerance) when no external force acts
// where g·exp(Δt v) moves t by Δt ṫ, γ by Δt γ̇ and turns R by exp(Δt ω̂) on the right.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>
#include <type_traits>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/heightfield.h"
#include "wobble/dynamics/kinematics3.h"
#include "wobble/dynamics/step.h"

namespace wobble {

// The 3D ground: a plane of any normal, or a heightfield in its place (heightfield.h), with the
// ground constants of the 2D Ground (forces.h).
struct GroundPlane {
  bool enabled = false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit, pointing out of the ground
  double stiffness = 4500.0, normal_damping = 550.0, friction_damping = 50.0, friction_cap = 0.1;
  std::shared_ptr<const Heightfield> heightfield;  // when set, the ground (point and normal unused)
  template <class T> T Height(const Vec3<T>& x) const { return normal.cast<T>().dot(x - point.cast<T>()); }
  // Face f's plane near x with its constants: the plane itself (face 0) or a heightfield face
  // (with its cell's own constants, where set).
  // Built field by field, not copied: a copy would touch the shared_ptr's atomic count once
  // per (point, face) per force evaluation.
  GroundPlane Face(int f, const Eigen::Vector3d& x) const {
    GroundPlane p;
    p.enabled = enabled;
    p.stiffness = stiffness;
    p.normal_damping = normal_damping;
    p.friction_damping = friction_damping;
    p.friction_cap = friction_cap;
    if (heightfield) {
      heightfield->FacePlane(f, x, &p.point, &p.normal);
      if (const SurfaceOverrides* own = heightfield->FaceOverrides(f)) {  // the cell's own constants
        if (!std::isnan(own->stiffness)) p.stiffness = own->stiffness;
        if (!std::isnan(own->normal_damping)) p.normal_damping = own->normal_damping;
        if (!std::isnan(own->friction_damping)) p.friction_damping = own->friction_damping;
        if (!std::isnan(own->friction_cap)) p.friction_cap = own->friction_cap;
      }
    } else {
      p.point = point;
      p.normal = normal;
    }
    return p;
  }
};

// A damped spring from a world anchor to a point of the body given by lattice coordinates
// (the 2D Spring of forces.h, Fig. 4.4). MakeSpring3 fills in the point's b0 and B.
struct Spring3 {
  Eigen::Vector3d lattice_coords = Eigen::Vector3d::Constant(0.5);
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();
  double stiffness = 0.0, damping = 0.0, rest_length = 0.0;
  Eigen::Vector3d rest_local = Eigen::Vector3d::Zero();
  Mat3D<double> mode_matrix;
};
inline Spring3 MakeSpring3(const BodyModel3& body, const Eigen::Vector3d& lattice_coords, const Eigen::Vector3d& anchor,
                           double stiffness, double damping = 0.0, double rest_length = 0.0) {
  Spring3 s;
  s.lattice_coords = lattice_coords;
  s.anchor = anchor;
  s.stiffness = stiffness;
  s.damping = damping;
  s.rest_length = rest_length;
  body.LocalBasis(lattice_coords, &s.rest_local, &s.mode_matrix);
  return s;
}

struct WorldParams3 {
  bool gravity_on = true;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, -9.81, 0.0);  // y up, as in 2D
  GroundPlane ground;
  std::vector<Spring3> springs;
  double max_condition = 1e12;  // runs stop when cond₂(M) is estimated above this
};

template <class T> struct Contact3 {
  int point;
  Vec3<T> anchor;  // where the point entered the ground (slides when friction is capped)
  int face = 0;    // which face (a heightfield's; 0 on a plane): one contact per (point, face)
};
template <class T> bool ContactBefore3(const Contact3<T>& a, const Contact3<T>& b) {
  return a.point < b.point || (a.point == b.point && a.face < b.face);
}

// The mutable half of a 3D body: translation, orientation, mode amplitudes, v = [ṫ, ω, γ̇].
template <class T> struct BodyState3 {
  Vec3<T> t = Vec3<T>::Zero();
  Eigen::Quaternion<T> orientation = Eigen::Quaternion<T>::Identity();
  VecD<T> gamma;
  VecQ3<T> v;
  std::vector<Contact3<T>> contacts;  // sorted by point
  VecD<T> mode_target;                // PD targets γ0; empty: all zero
  // The ground's generalized force at exactly this state, left by UpdateContacts3 for the next
  // explicit step (which evaluates forces at the same state): one contact scan per step, not
  // two. Keyed by value, as BodyState::ground_cache in 2D, so it can miss but never be stale.
  struct GroundForceCache {
    bool valid = false;
    Vec3<T> t;
    Eigen::Quaternion<T> orientation;
    VecD<T> gamma;
    VecQ3<T> v, force;
  } ground_cache;
};

// A state from q = [t, Θ, γ] (Θ the orientation's rotation vector: World's q3 coordinates) and
// q̇ = v, without contacts; and the q of a state (|Θ| ≤ π).
inline BodyState3<double> State3FromQ(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  BodyState3<double> s;
  s.t = q.head<3>();
  s.orientation = ExpRotation<double>(q.segment<3>(3));
  s.gamma = q.tail(q.size() - kRigidDofs3);
  s.v = qd;
  return s;
}
inline Eigen::VectorXd QOfState3(const BodyState3<double>& s) {
  Eigen::VectorXd q(kRigidDofs3 + s.gamma.size());
  q << s.t, LogRotation<double>(s.orientation), s.gamma;
  return q;
}

// The cached ground force of s, when it was computed at s's current state (doubles only).
template <class T> const VecQ3<T>* CachedGroundForce3(const BodyState3<T>& s) {
  if constexpr (!std::is_same_v<T, double>) {
    return nullptr;
  } else {
    const auto& c = s.ground_cache;
    if (!c.valid || c.t != s.t || c.orientation.coeffs() != s.orientation.coeffs() || c.gamma != s.gamma || c.v != s.v)
      return nullptr;
    return &c.force;
  }
}

// A state at rest in the lattice's own pose.
template <class T> BodyState3<T> RestState3(const BodyModel3& body) {
  BodyState3<T> s;
  s.gamma.setZero(body.num_modes());
  s.v.setZero(body.num_q());
  return s;
}

template <class T> struct ForceBreakdown3 {
  VecQ3<T> gravity, modes, ground, springs, total;
};

// The faces a point x of the body feels, f(face, plane, anchor) with the face's plane: on a
// plane, the plane when x is below it; on a heightfield, Heightfield::FacesFelt's. The anchor
// is that of the point's contact on the face — contacts_of_k() gives the range of the point's
// contacts, asked for only when x is below the ground — or, on a face the point had no contact
// with, the anchor of the face it leaves projected onto the new one (friction holds across the
// edges between triangles), else the point's foot on the face. Shared by FFD and linear bodies.
template <class T, class ContactsOf, class F>
void ForEachFaceFelt3(const GroundPlane& g, const Vec3<T>& x, ContactsOf&& contacts_of_k, F&& f) {
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

// The contacts of point k in contacts sorted by (point, face), as a range.
template <class T> auto ContactsOfPoint3(const std::vector<Contact3<T>>& contacts, int k) {
  const auto first = std::lower_bound(contacts.begin(), contacts.end(), k,
                                      [](const Contact3<T>& a, int point) { return a.point < point; });
  auto last = first;
  while (last != contacts.end() && last->point == k) ++last;
  return std::make_pair(first, last);
}

// The (point, face) pairs the ground acts on during an evaluation (ContactSet of the 2D body):
// f(k, face, plane, l, x, v, anchor) with the face's plane.
template <class T, class F>
void ForEachPointInContact3(const BodyModel3& body, const GroundPlane& g, const BodyState3<T>& s,
                            const Frame3<T>& frame, F&& f, ContactSet set) {
  if (!g.enabled) return;
  if (set == ContactSet::kFrozen) {
    for (const Contact3<T>& c : s.contacts) {
      const auto B = body.mode_matrix(c.point);
      const Vec3<T> l = LocalPosition3<T>(body.rest_local(c.point), B, s.gamma);
      const Vec3<T> x = frame.t + frame.R * l;
      const Eigen::Vector3d xd(ScalarValue(x.x()), ScalarValue(x.y()), ScalarValue(x.z()));
      if (g.heightfield) {
        f(c.point, c.face, g.Face(c.face, xd), l, x, PointVelocity3(frame, s.v, l, B), c.anchor);
      } else {
        f(c.point, c.face, g, l, x, PointVelocity3(frame, s.v, l, B), c.anchor);
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
  const Eigen::Vector3d t(ScalarValue(s.t.x()), ScalarValue(s.t.y()), ScalarValue(s.t.z()));
  const double offset = normal.dot(t - through);
  const int D = body.num_modes();
  // convex-hull test: every deformed control point above the plane means every point is
  bool clear = true;
  const std::vector<Eigen::Vector3d>& rest = body.rest_control();
  for (int c = 0; clear && c < int(rest.size()); ++c) {
    double h = offset + n_local.dot(rest[c]);
    for (int d = 0; d < D; ++d) h += ScalarValue(s.gamma[d]) * n_local.dot(body.modes()[d].displacement[c]);
    clear = h > 0.0;
  }
  if (clear) return;
  auto visit = [&](int k) {
    const auto B = body.mode_matrix(k);
    const Vec3<T> l = LocalPosition3<T>(body.rest_local(k), B, s.gamma);
    const Vec3<T> x = frame.t + frame.R * l;
    ForEachFaceFelt3(g, x, [&] { return ContactsOfPoint3(s.contacts, k); },
                     [&](int face, const GroundPlane& plane, const Vec3<T>& anchor) {
                       f(k, face, plane, l, x, PointVelocity3(frame, s.v, l, B), anchor);
                     });
  };
  const std::vector<PointClusterN<3>>& clusters = body.clusters();
  if (clusters.size() <= 1) {
    for (int k = 0; k < body.num_points(); ++k) visit(k);
    return;
  }
  // large bodies: only point groups whose bounding box reaches below the plane (as in 2D)
  for (const PointClusterN<3>& c : clusters) {
    Eigen::Vector3d centre = c.centre0, half = c.half0;
    for (int d = 0; d < D; ++d) {
      const double gamma = ScalarValue(s.gamma[d]);
      centre += gamma * c.centre_modes.col(d);
      half += std::abs(gamma) * c.half_modes.col(d);
    }
    if (offset + n_local.dot(centre) - n_local.cwiseAbs().dot(half) >= 0.0) continue;
    for (int k : c.points) visit(k);
  }
}

// Eq. 4.24/4.25 in the plane's frame: f_n = −K Δn − C_dam v_n (never pulling),
// f_t = −K Δt − FR_dam v_t (tangent-plane vectors), scaled back onto |f_t| ≤ tan θ f_n. The
// parts are kept for the 3D adjoint's partials (fit/internal/step3_vjp.cc).
template <class T> struct GroundForceParts3 {
  T fn;             // the normal force, after the clamp at 0
  bool pressing;    // the spring-damper pushed (fn was not clamped)
  Vec3<T> ft;       // the tangential force before the cap, and its norm
  T ft_norm;
  bool slipping;    // |f_t| above the cap
  Vec3<T> f;        // the force
};
template <class T>
GroundForceParts3<T> GroundForcePartsOf3(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, const Vec3<T>& anchor) {
  using std::sqrt;
  GroundForceParts3<T> p;
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
Vec3<T> GroundForce3(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, const Vec3<T>& anchor, bool* slipping) {
  const GroundForceParts3<T> p = GroundForcePartsOf3(g, x, v, anchor);
  *slipping = p.slipping;
  return p.f;
}

// A damped spring's pull on its point at x moving at v: f = −(K (|Δ| − L) + C v·Δ̂) Δ̂ along
// Δ = x − anchor.
template <class T> Vec3<T> SpringForce3(const Spring3& sp, const Vec3<T>& x, const Vec3<T>& v) {
  using std::sqrt;
  const Vec3<T> delta = x - sp.anchor.cast<T>();
  const T len = sqrt(delta.squaredNorm() + T(1e-300));
  const Vec3<T> dir = delta / len;
  return -(T(sp.stiffness) * (len - T(sp.rest_length)) + T(sp.damping) * dir.dot(v)) * dir;
}

template <class T>
void EvaluateForces3(const BodyModel3& body, const WorldParams3& w, const BodyState3<T>& s, const Frame3<T>& frame,
                     const ShapeMoments3<T>& sm, ForceBreakdown3<T>* out, ContactSet set = ContactSet::kDetect) {
  const int n = body.num_q(), D = body.num_modes();
  if (w.gravity_on) {
    GravityForce3(body.moments(), sm, frame.R, w.gravity, &out->gravity);
  } else {
    out->gravity.setZero(n);
  }
  // V = K γ² → −2K(γ − γ0), damping −c γ̇ (§4.7, chapter 5's PD form)
  out->modes.setZero(n);
  const bool targeted = s.mode_target.size() == D;
  for (int d = 0; d < D; ++d) {
    const DeformationMode3& m = body.modes()[d];
    const T offset = targeted ? T(s.gamma[d] - s.mode_target[d]) : s.gamma[d];
    out->modes[kRigidDofs3 + d] = -T(2.0 * m.stiffness) * offset - T(m.damping) * s.v[kRigidDofs3 + d];
  }
  const VecQ3<T>* cached = set == ContactSet::kDetect ? CachedGroundForce3(s) : nullptr;
  if (cached) {
    out->ground = *cached;
  } else {
    out->ground.setZero(n);
    ForEachPointInContact3(body, w.ground, s, frame, [&](int k, int, const GroundPlane& plane, const Vec3<T>& l,
                                                         const Vec3<T>& x, const Vec3<T>& v, const Vec3<T>& anchor) {
      bool slipping;
      AddGeneralizedForce3(frame, l, body.mode_matrix(k), GroundForce3(plane, x, v, anchor, &slipping), &out->ground);
    }, set);
  }
  out->springs.setZero(n);
  for (const Spring3& sp : w.springs) {
    const Vec3<T> l = LocalPosition3<T>(sp.rest_local, sp.mode_matrix, s.gamma);
    const Vec3<T> x = frame.t + frame.R * l;
    const Vec3<T> f = SpringForce3(sp, x, PointVelocity3(frame, s.v, l, sp.mode_matrix));
    AddGeneralizedForce3(frame, l, sp.mode_matrix, f, &out->springs);
  }
  out->total = out->gravity + out->modes + out->ground + out->springs;
}

// v̇ of M v̇ = Q − w. Fails with kIllConditioned when the Cholesky pivot ratio (a lower bound
// of cond₂(M)) exceeds w.max_condition.
// `extra` is added to Q (and to forces->total), as in 2D (step.h: NoExtraForce).
template <class T, class Extra = NoExtraForce>
StepStatus Accelerations3(const BodyModel3& body, const WorldParams3& w, const BodyState3<T>& s, VecQ3<T>* a,
                          ForceBreakdown3<T>* forces = nullptr, ContactSet set = ContactSet::kDetect,
                          const Extra& extra = Extra()) {
  ForceBreakdown3<T> local;
  ForceBreakdown3<T>& f = forces ? *forces : local;
  const Frame3<T> frame(s.t, s.orientation);
  const ShapeMoments3<T> sm(body.moments(), s.gamma);
  VecQ3<T> vel;
  VelocityTerms3(body.moments(), sm, frame.R, s.v, &vel);
  EvaluateForces3(body, w, s, frame, sm, &f, set);
  extra(s, &f.total);
  MatQ3<T> M;
  MassMatrix3(body.moments(), sm, frame.R, &M);
  if (!CholeskyInPlace(&M)) {
    for (int i = 0; i < f.total.size(); ++i)
      if (!std::isfinite(double(ScalarValue(f.total[i])))) return {StatusCode::kOverflowingForce, 0.0};
    return {StatusCode::kSingularMass, 0.0};
  }
  double lo = HUGE_VAL, hi = 0.0;
  CholeskyPivotRange(M, &lo, &hi);
  *a = f.total - vel;
  CholeskySolveInPlace(M, a);
  if (hi / lo > w.max_condition) return {StatusCode::kIllConditioned, hi / lo};
  return {};
}

// The anchor of a point whose friction hit the cap, moved so that the tangential spring holds
// exactly the capped force f_t, and the force it then exerts (SlipAnchor of forces.h in 3D).
template <class T>
void SlipAnchor3(const GroundPlane& g, const Vec3<T>& x, const Vec3<T>& v, Vec3<T>* anchor, Vec3<T>* f) {
  if (!(g.stiffness > 0.0)) return;  // no spring to the anchor: nothing to move
  // −K Δt − FR v_t = f_t  ⇒  Δt = −(f_t + FR v_t)/K, measured from the point's foot
  const Vec3<T> n = g.normal.cast<T>();
  const Vec3<T> ft = *f - n * n.dot(*f), v_t = v - n * n.dot(v);
  const Vec3<T> dt = -(ft + T(g.friction_damping) * v_t) / T(g.stiffness);
  *anchor = x - g.Height(x) * n - dt;
  bool slipping;
  *f = GroundForce3(g, x, v, *anchor, &slipping);  // what the moved anchor exerts
}

// After an accepted step: anchors for points that entered the ground, none for those that
// left, and an anchor whose friction hit the cap moved so the tangential spring holds exactly
// the capped force (Coulomb slip), as UpdateContacts does in 2D.
template <class T> void UpdateContacts3(const BodyModel3& body, const GroundPlane& g, BodyState3<T>* s) {
  thread_local std::vector<Contact3<T>> next;  // no heap traffic while a body rests
  next.clear();
  const Frame3<T> frame(s->t, s->orientation);
  auto& cache = s->ground_cache;
  cache.force.setZero(body.num_q());
  ForEachPointInContact3(body, g, *s, frame, [&](int k, int face, const GroundPlane& plane, const Vec3<T>& l,
                                                 const Vec3<T>& x, const Vec3<T>& v, Vec3<T> anchor) {
    bool slipping;
    Vec3<T> f = GroundForce3(plane, x, v, anchor, &slipping);
    if (slipping) SlipAnchor3(plane, x, v, &anchor, &f);
    AddGeneralizedForce3(frame, l, body.mode_matrix(k), f, &cache.force);
    next.push_back({k, anchor, face});
  }, ContactSet::kDetect);
  if (body.clusters().size() > 1)  // groups are visited in lattice order, not point order
    std::sort(next.begin(), next.end(), ContactBefore3<T>);
  s->contacts.swap(next);
  cache.t = s->t;
  cache.orientation = s->orientation;
  cache.gamma = s->gamma;
  cache.v = s->v;
  cache.valid = true;
}

// Adds a contact (anchor: its foot on the plane) for every point below the ground that has
// none; returns how many. The implicit step grows its active set with it.
template <class T> int AddMissingContacts3(const BodyModel3& body, const GroundPlane& g, BodyState3<T>* s) {
  std::vector<Contact3<T>> added;
  const BodyState3<T>& view = *s;
  ForEachPointInContact3(body, g, view, Frame3<T>(view.t, view.orientation),
                         [&](int k, int face, const GroundPlane&, const Vec3<T>&, const Vec3<T>&, const Vec3<T>&,
                             const Vec3<T>& anchor) {
                           for (const Contact3<T>& c : view.contacts)
                             if (c.point == k && c.face == face) return;
                           added.push_back({k, anchor, face});
                         }, ContactSet::kDetect);
  if (added.empty()) return 0;
  s->contacts.insert(s->contacts.end(), added.begin(), added.end());
  std::sort(s->contacts.begin(), s->contacts.end(), ContactBefore3<T>);
  return int(added.size());
}

// g·exp(h v) of the header comment, in place.
template <class T> void AdvanceConfiguration3(const VecQ3<T>& v, const T& h, BodyState3<T>* s) {
  const int D = int(s->gamma.size());
  s->t += h * v.template head<3>();
  s->orientation = (s->orientation * ExpRotation<T>(Vec3<T>(h * v.template segment<3>(3)))).normalized();
  s->gamma += h * v.tail(D);
}

// Kinetic-energy gradient ∂T/∂g at fixed ξ, left-trivialized on SO(3) (δR = R ε̂), for the
// variational integrator. With a = ω × c + C γ̇ (so that M_tω ω + M_tγ γ̇ = R a):
//   ∂T/∂t = 0,  ∂T/∂R = a × Rᵀṫ,
//   ∂T/∂γ_d = ṫ·R(ω × C_d) + e_d|ω|² − ωᵀ L_d ω + ω·Σ_e γ̇_e X_de
// (∂K/∂γ_d = L_d + L_dᵀ, ∂I/∂γ_d = 2 e_d 1 − L_d − L_dᵀ, ∂N_e/∂γ_d = X_de).
template <class T>
void KineticGradient3(const MassMoments3& mm, const ShapeMoments3<T>& sm, const Mat3<T>& R, const VecQ3<T>& xi,
                      VecQ3<T>* out) {
  const int D = int(sm.e.size());
  const Vec3<T> t_dot = xi.template head<3>(), omega = xi.template segment<3>(3);
  const auto gamma_dot = xi.tail(D);
  const Vec3<T> a = omega.cross(sm.c) + mm.C.cast<T>() * gamma_dot;
  const Vec3<T> t_local = R.transpose() * t_dot;
  out->setZero(kRigidDofs3 + D);
  out->template segment<3>(3) = a.cross(t_local);
  const T omega2 = omega.squaredNorm();
  for (int d = 0; d < D; ++d) {
    Vec3<T> X_gd = Vec3<T>::Zero();
    for (int e = 0; e < D; ++e) X_gd += mm.X[size_t(d) * D + e].cast<T>() * gamma_dot[e];
    (*out)[kRigidDofs3 + d] = t_local.dot(omega.cross(mm.C.col(d).cast<T>())) + sm.e[d] * omega2 -
                              omega.dot(sm.L[d] * omega) + omega.dot(X_gd);
  }
}

// Advances one 3D body by dt, then updates its contacts. `extra`: a generalized force added at
// every force evaluation (NoExtraForce; the dynamic fit's mode forces with Jet gains).
template <class T, class Extra = NoExtraForce>
StepStatus StepBody3(const BodyModel3& body, const WorldParams3& w, Integrator integrator, double dt,
                     BodyState3<T>* s, const Extra& extra = Extra()) {
  const T h(dt);
  const int D = body.num_modes();
  VecQ3<T> a;
  StepStatus st;
  auto accelerations = [&](const BodyState3<T>& x, VecQ3<T>* out) {
    return Accelerations3(body, w, x, out, static_cast<ForceBreakdown3<T>*>(nullptr), ContactSet::kDetect, extra);
  };
  switch (integrator) {
    case Integrator::kThesis: {
      if (!(st = accelerations(*s, &a)).ok()) return st;
      s->v += h * a;
      AdvanceConfiguration3(s->v, h, s);
      break;
    }
    case Integrator::kSymplecticEuler: {
      AdvanceConfiguration3(s->v, h, s);
      if (!(st = accelerations(*s, &a)).ok()) return st;
      s->v += h * a;
      break;
    }
    case Integrator::kRK4: {
      // stage y = (t, Θ, γ, v) about the start; R = R0 exp(Θ̂)
      const BodyState3<T> start = *s;
      VecQ3<T> rate[4];  // per stage: configuration rate (ṫ, Θ̇, γ̇)
      auto stage = [&](int i, const VecQ3<T>& dy_config, const VecQ3<T>& dv) {
        BodyState3<T>& x = *s;
        x.t = start.t + dy_config.template head<3>();
        const Vec3<T> theta = dy_config.template segment<3>(3);
        x.orientation = (start.orientation * ExpRotation<T>(theta)).normalized();
        x.gamma = start.gamma + dy_config.tail(D);
        x.v = start.v + dv;
        rate[i] = x.v;
        rate[i].template segment<3>(3) = RotationVectorRate<T>(theta, Vec3<T>(x.v.template segment<3>(3)));
        return accelerations(x, &a);
      };
      VecQ3<T> k[4];
      const VecQ3<T> zero = VecQ3<T>::Zero(body.num_q());
      if (!(st = stage(0, zero, zero)).ok()) return st;
      k[0] = a;
      if (!(st = stage(1, T(0.5) * h * rate[0], T(0.5) * h * k[0])).ok()) return st;
      k[1] = a;
      if (!(st = stage(2, T(0.5) * h * rate[1], T(0.5) * h * k[1])).ok()) return st;
      k[2] = a;
      if (!(st = stage(3, h * rate[2], h * k[2])).ok()) return st;
      k[3] = a;
      const VecQ3<T> dy = h / T(6.0) * (rate[0] + T(2.0) * rate[1] + T(2.0) * rate[2] + rate[3]);
      const VecQ3<T> dv = h / T(6.0) * (k[0] + T(2.0) * k[1] + T(2.0) * k[2] + k[3]);
      s->t = start.t + dy.template head<3>();
      s->orientation = (start.orientation * ExpRotation<T>(Vec3<T>(dy.template segment<3>(3)))).normalized();
      s->gamma = start.gamma + dy.tail(D);
      s->v = start.v + dv;
      break;
    }
    case Integrator::kImplicitEuler: {
      const BodyState3<T> start = *s;
      if (!(st = accelerations(start, &a)).ok()) return st;
      VecQ3<T> v = start.v + h * a;
      for (int pass = 0; pass < 4; ++pass) {  // active set, as in 2D
        st = SolveNewton<T>(
            [&](const VecQ3<T>& x, VecQ3<T>* r) {
              BodyState3<T> trial = start;
              trial.contacts = s->contacts;
              AdvanceConfiguration3(x, h, &trial);
              trial.v = x;
              VecQ3<T> acc;
              const StepStatus rs = Accelerations3(body, w, trial, &acc, static_cast<ForceBreakdown3<T>*>(nullptr),
                                                   ContactSet::kFrozen, extra);
              if (rs.ok()) *r = x - start.v - h * acc;
              return rs;
            },
            &v);
        if (!st.ok()) return st;
        std::vector<Contact3<T>> contacts = s->contacts;
        *s = start;
        s->contacts = contacts;
        AdvanceConfiguration3(v, h, s);
        s->v = v;
        if (!AddMissingContacts3(body, w.ground, s)) break;
      }
      break;
    }
    case Integrator::kVariational: {
      // p_k = M(g_k) v_k; solve for ξ:  A(Δt ξ)ᵀ M(g_k) ξ − Δt (∂T/∂g + Q)(g_k, ξ) = p_k, with A
      // the Cayley momentum map on the ω rows and the identity elsewhere (translations and
      // modes); then g_{k+1} = g_k·cay(Δt ξ) and p_{k+1} = A(−Δt ξ)ᵀ M(g_k) ξ.
      const BodyState3<T> start = *s;
      const Frame3<T> frame(start.t, start.orientation);
      const ShapeMoments3<T> sm(body.moments(), start.gamma);
      MatQ3<T> M0;
      MassMatrix3(body.moments(), sm, frame.R, &M0);
      const VecQ3<T> p0 = M0 * start.v;
      auto residual = [&](const VecQ3<T>& xi, VecQ3<T>* r) {
        BodyState3<T> at = start;
        at.v = xi;
        ForceBreakdown3<T> f;
        EvaluateForces3(body, w, at, frame, sm, &f, ContactSet::kDetect);
        extra(at, &f.total);
        VecQ3<T> dT;
        KineticGradient3(body.moments(), sm, frame.R, xi, &dT);
        VecQ3<T> mu = M0 * xi;
        mu.template segment<3>(3) = CayleyMomentumMap<T>(Vec3<T>(h * xi.template segment<3>(3)),
                                                         Vec3<T>(mu.template segment<3>(3)));
        *r = mu - h * (dT + f.total) - p0;
        return StepStatus{};
      };
      VecQ3<T> xi = start.v;
      if (!(st = SolveNewton<T>(residual, &xi)).ok()) return st;
      VecQ3<T> p1 = M0 * xi;
      p1.template segment<3>(3) = CayleyMomentumMap<T>(Vec3<T>(-h * xi.template segment<3>(3)),
                                                       Vec3<T>(p1.template segment<3>(3)));
      s->t = start.t + h * xi.template head<3>();
      s->orientation = (start.orientation * CayleyRotation<T>(Vec3<T>(h * xi.template segment<3>(3)))).normalized();
      s->gamma = start.gamma + h * xi.tail(D);
      const Frame3<T> frame1(s->t, s->orientation);
      const ShapeMoments3<T> sm1(body.moments(), s->gamma);
      MatQ3<T> M1;
      MassMatrix3(body.moments(), sm1, frame1.R, &M1);
      if (!CholeskyInPlace(&M1)) return {StatusCode::kSingularMass, 0.0};
      CholeskySolveInPlace(M1, &p1);
      s->v = p1;
      break;
    }
  }
  auto finite = [](const auto& x) {
    for (int i = 0; i < x.size(); ++i)
      if (!std::isfinite(double(ScalarValue(x[i])))) return false;
    return true;
  };
  if (!finite(s->v) || !finite(s->t) || !finite(s->gamma) || !finite(s->orientation.coeffs()))
    return {StatusCode::kNonFinite, 0.0};
  UpdateContacts3(body, w.ground, s);
  return {};
}

// compiled once, in step_instances.cc (see step.h)
extern template StepStatus StepBody3<double, NoExtraForce>(const BodyModel3&, const WorldParams3&, Integrator, double,
                                                           BodyState3<double>*, const NoExtraForce&);
extern template void UpdateContacts3<double>(const BodyModel3&, const GroundPlane&, BodyState3<double>*);

}  // namespace wobble
