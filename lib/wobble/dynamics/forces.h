// External and internal forces of a body as generalized forces Q = Σ Jᵀ f (Eq. 4.20), written
// once for 2D and 3D bodies: gravity (§4.7), mode potentials V = K γ² with damping (§4.7),
// springs holding a point (Fig. 4.4), and the penalty ground of §4.9 (Eq. 4.24, 4.25), whose
// geometry is the dimension's own (ground_line.h: a line or terrain; ground_plane.h: a plane
// or heightfield).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "wobble/dynamics/body_state.h"
#include "wobble/dynamics/ground_line.h"
#include "wobble/dynamics/ground_plane.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/dynamics/spatial_inertia.h"

namespace wobble {

// A damped spring's pull on its point at x moving at v: f = −(K (|Δ| − L) + C v·Δ̂) Δ̂ along
// Δ = x − anchor.
template <int Dim, class T>
Eigen::Matrix<T, Dim, 1> SpringForce(const Spring& sp, const Eigen::Matrix<T, Dim, 1>& x,
                                     const Eigen::Matrix<T, Dim, 1>& v) {
  using std::sqrt;
  const Eigen::Matrix<T, Dim, 1> delta = x - sp.Anchor<Dim>().template cast<T>();
  const T len = sqrt(delta.squaredNorm() + T(1e-300));
  const Eigen::Matrix<T, Dim, 1> dir = delta / len;
  return -(T(sp.stiffness) * (len - T(sp.rest_length)) + T(sp.damping) * dir.dot(v)) * dir;
}

// All generalized forces on a body, by source. `frame` is Frame(s.q), made once by the caller.
template <int Dim, class T>
void EvaluateForces(const BodyModelN<Dim>& body, const WorldParams& w, int body_index, const BodyState<Dim, T>& s,
                    const Frame<Dim, T>& frame, ForceBreakdown<Dim, T>* out, ContactSet contact_set = ContactSet::kDetect) {
  using Vector = Eigen::Matrix<T, Dim, 1>;
  constexpr int kRigidParams = Group<Dim>::kRigidParams, kRigid = Group<Dim>::kRigidDofs;
  const int nv = body.num_q(), D = body.num_modes();
  // gravity, exactly from the moments
  if (w.gravity_on) {
    GravityForce(body.moments(), s.q, frame.R, GravityFor<Dim>(w), &out->gravity);
  } else {
    out->gravity.setZero(nv);
  }
  // mode potentials V = K γ² → Q = −2Kγ, and damping −c γ̇ (§4.7); with a PD target γ0 this
  // is the controller of chapter 5, Q_r = −(C(γ − γ0) + D γ̇) with C = 2K, D = c
  out->modes.setZero(nv);
  const bool targeted = s.mode_target.size() == D;
  for (int d = 0; d < D; ++d) {
    const DeformationModeN<Dim>& m = body.modes()[d];
    const T offset = targeted ? T(s.q[kRigidParams + d] - s.mode_target[d]) : T(s.q[kRigidParams + d]);
    out->modes[kRigid + d] = -T(2.0 * m.stiffness) * offset - T(m.damping) * s.qd[kRigid + d];
  }
  // penalty ground, only over points below it
  const VecQ<T>* cached = contact_set == ContactSet::kDetect ? CachedGroundForce(s, GroundFor<Dim>(w)) : nullptr;
  if (cached) {
    out->ground = *cached;
  } else {
    out->ground.setZero(nv);
    ForEachPointInContact(body, GroundFor<Dim>(w), s, frame, [&](int k, const Vector& l, const Vector& x, const Vector& v,
                                                        const Vector& anchor, const auto& face, int) {
      bool slipping;
      AddGeneralizedForce(frame, l, body.mode_matrix(k), GroundForce(face, x, v, anchor, &slipping), &out->ground);
    }, contact_set);
  }
  // springs holding a point
  out->springs.setZero(nv);
  for (const Spring& sp : w.springs) {
    if (sp.body != body_index) continue;
    const MatND<double, Dim> B = sp.ModeMatrix<Dim>();
    const Vector l = LocalPosition<T>(sp.RestLocal<Dim>(), B, s.q);
    const Vector x = WorldFromLocal(frame, l);
    const Vector v = PointVelocity(frame, s.qd, l, B);
    AddGeneralizedForce(frame, l, B, SpringForce<Dim>(sp, x, v), &out->springs);
  }
  out->total = out->gravity + out->modes + out->ground + out->springs;
}
template <int Dim, class T>
void EvaluateForces(const BodyModelN<Dim>& body, const WorldParams& w, int body_index, const BodyState<Dim, T>& s,
                    ForceBreakdown<Dim, T>* out, ContactSet contact_set = ContactSet::kDetect) {
  EvaluateForces(body, w, body_index, s, Frame<Dim, T>(s.q), out, contact_set);
}

// Adds a contact for every point below the ground that has none (anchor: its projection on
// the ground). Returns how many were added. Implicit steps call it to grow their active set.
template <int Dim, class T> int AddMissingContacts(const BodyModelN<Dim>& body, const GroundOf<Dim>& g, BodyState<Dim, T>* s) {
  using Vector = Eigen::Matrix<T, Dim, 1>;
  std::vector<Contact<Dim, T>> added;
  const BodyState<Dim, T>& view = *s;
  ForEachPointInContact(body, g, view, Frame<Dim, T>(view.q), [&](int k, const Vector&, const Vector&, const Vector&,
                                                                  const Vector& anchor, const auto&, int face) {
    for (const Contact<Dim, T>& c : view.contacts)
      if (c.point == k && c.face == face) return;
    added.push_back({k, anchor, face});
  });
  if (added.empty()) return 0;
  s->contacts.insert(s->contacts.end(), added.begin(), added.end());
  std::sort(s->contacts.begin(), s->contacts.end(), ContactBefore<Dim, T>);
  return int(added.size());
}

// After a step is accepted: points that went below the ground get an anchor at their entry
// point, points that left it lose theirs, and an anchor whose friction hit the cap slides
// along the ground so the tangential spring holds exactly the capped force (Coulomb slip).
// The same pass sums the ground's generalized force at this state into s->ground_cache.
template <int Dim, class T> void UpdateContacts(const BodyModelN<Dim>& body, const GroundOf<Dim>& g, BodyState<Dim, T>* s) {
  using Vector = Eigen::Matrix<T, Dim, 1>;
  // reuse storage across steps: no heap traffic while a body rests on the ground
  thread_local std::vector<Contact<Dim, T>> next;
  next.clear();
  s->penetration = 0.0;
  const Frame<Dim, T> frame(s->q);
  auto& cache = s->ground_cache;
  cache.force.setZero(s->qd.size());
  ForEachPointInContact(body, g, *s, frame, [&](int k, const Vector& l, const Vector& x, const Vector& v,
                                                Vector anchor, const auto& face, int face_index) {
    bool slipping;
    Vector f = GroundForce(face, x, v, anchor, &slipping);
    if (slipping) SlipAnchor(face, x, v, &anchor, &f);
    AddGeneralizedForce(frame, l, body.mode_matrix(k), f, &cache.force);
    next.push_back({k, anchor, face_index});
    s->penetration = std::max(s->penetration, -double(ScalarValue(face.Height(x))));
  }, ContactSet::kDetect, &s->scan_memo);
  // groups are visited in lattice order, not point order; a resting body's few contacts
  // usually come out sorted already
  if (body.clusters().size() > 1 && !std::is_sorted(next.begin(), next.end(), ContactBefore<Dim, T>))
    std::sort(next.begin(), next.end(), ContactBefore<Dim, T>);
  s->contacts.swap(next);
  cache.q = s->q;
  cache.qd = s->qd;
  cache.ground = g;
  cache.valid = true;
}

}  // namespace wobble
