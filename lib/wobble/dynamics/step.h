// Equations of motion (Eq. 4.21) and the integrators that advance one body, 2D or 3D, by one
// step:
//
//   M(q) q̈ = Q(q, q̇) − w(q, q̇),   w = Σ m_k J_kᵀ J̇_k q̇
//
// with the dimension's own mass solve (SolveAccelerations: about the centre of mass in 2D,
// Cholesky in 3D) and the integrators written once on the group (group.h).
#pragma once

#include <cmath>

#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/newton.h"
#include "wobble/dynamics/status.h"
#include "wobble/dynamics/variational.h"
#include "wobble/core/cholesky.h"

namespace wobble {

// q̈ of Eq. 4.21, M q̈ = Q − w (the dimension's own mass solve: SolveAccelerations). Fails with
// kIllConditioned when the solve's pivot ratio, a lower bound of cond₂(M), exceeds
// w.max_condition. `extra` is added to Q (and to forces->total).
template <int Dim, class T, class Extra = NoExtraForce>
StepStatus Accelerations(const BodyModelN<Dim>& body, const WorldParams& w, int body_index,
                         const BodyState<Dim, T>& s, VecQ<T>* qdd, ForceBreakdown<Dim, T>* forces = nullptr,
                         ContactSet contact_set = ContactSet::kDetect, const Extra& extra = Extra()) {
  ForceBreakdown<Dim, T> local;
  ForceBreakdown<Dim, T>& f = forces ? *forces : local;
  const Frame<Dim, T> frame(s.q);
  EvaluateForces(body, w, body_index, s, frame, &f, contact_set);
  extra(s, &f.total);
  double cond_estimate = 0.0;
  if (!SolveAccelerations(body.moments(), s.q, s.qd, frame.R, f.total, qdd, &cond_estimate)) {
    // an infinite force is not a singular M (a stiffness of 1e300 is not the mass's fault)
    for (int i = 0; i < f.total.size(); ++i)
      if (!std::isfinite(double(ScalarValue(f.total[i])))) return {StepStatus::Code::kOverflowingForce, 0.0};
    return {StepStatus::Code::kSingularMass, 0.0};
  }
  if (cond_estimate > w.max_condition) return {StepStatus::Code::kIllConditioned, cond_estimate};
  return {};
}

// Advances one body by dt with contacts held fixed, then updates its contacts, with the
// integrators written once on the group (group.h: q·exp(h v) moves the positions):
//   thesis        v' = v + Δt a(q, v), q' = q·exp(Δt v')  (Eq. 4.22/4.23's Störmer form: in 2D
//                 q_{n+1} = 2q_n − q_{n−1} + Δt² q̈_n with q̇_n = (q_n − q_{n−1})/Δt)
//   symplectic    q' = q·exp(Δt v), v' = v + Δt a(q', v)  (position first)
//   rk4           Runge–Kutta–Munthe-Kaas: the classical tableau on the tangent coordinates
//                 about q (dexp⁻¹ = 1 on SO(2): classical RK4 in 2D), every stage on the group
//   implicit      v' = v + Δt a(q·exp(Δt v'), v'), by Newton, with an active set of contacts
//   variational   the dimension's own discrete Lagrangian (variational.h)
// `extra`: an extra generalized force (see NoExtraForce).
template <int Dim, class T, class Extra = NoExtraForce>
StepStatus StepBody(const BodyModelN<Dim>& body, const WorldParams& w, int body_index, Integrator integrator,
                    double dt, BodyState<Dim, T>* s, const Extra& extra = Extra()) {
  using G = Group<Dim>;
  const T h(dt);
  VecQ<T> a;
  StepStatus st;
  // stage evaluations reuse *s (q and q̇ overwritten, contacts kept): no copies, no heap
  auto accel = [&](VecQ<T>* out, ContactSet set = ContactSet::kDetect) {
    return Accelerations(body, w, body_index, *s, out, static_cast<ForceBreakdown<Dim, T>*>(nullptr), set, extra);
  };
  switch (integrator) {
    case Integrator::kThesis: {
      if (!(st = accel(&a)).ok()) return st;
      for (int i = 0; i < int(a.size()); ++i) s->qd[i] += h * a[i];  // a loop: see Group<2>::Advance
      G::Advance(s->qd, h, &s->q);
      break;
    }
    case Integrator::kSymplecticEuler: {
      G::Advance(s->qd, h, &s->q);
      if (!(st = accel(&a)).ok()) return st;
      s->qd += h * a;
      break;
    }
    case Integrator::kRK4: {
      // stage i at q0·exp(dy_i), v0 + dv_i; rate[i]: the stage's rate of the tangent coordinates
      const VecQ<T> q0 = s->q, v0 = s->qd;
      VecQ<T> rate[4], k[4];
      auto stage = [&](int i, const VecQ<T>& dy, const VecQ<T>& dv) {
        G::Retract(q0, dy, &s->q);
        s->qd = v0 + dv;
        rate[i] = G::StageRate(dy, s->qd);
        const StepStatus rs = accel(&k[i]);
        return rs;
      };
      const VecQ<T> zero = VecQ<T>::Zero(v0.size());
      if (!(st = stage(0, zero, zero)).ok()) return st;
      if (!(st = stage(1, T(0.5) * h * rate[0], T(0.5) * h * k[0])).ok()) return st;
      if (!(st = stage(2, T(0.5) * h * rate[1], T(0.5) * h * k[1])).ok()) return st;
      if (!(st = stage(3, h * rate[2], h * k[2])).ok()) return st;
      G::Retract(q0, VecQ<T>(h / T(6.0) * (rate[0] + T(2.0) * rate[1] + T(2.0) * rate[2] + rate[3])), &s->q);
      s->qd = v0 + h / T(6.0) * (k[0] + T(2.0) * k[1] + T(2.0) * k[2] + k[3]);
      break;
    }
    case Integrator::kImplicitEuler: {
      // solve r(v) = v − q̇_n − Δt q̈(q_n·exp(Δt v), v) = 0 for v = q̇_{n+1}
      const VecQ<T> q0 = s->q, v0 = s->qd;
      if (!(st = accel(&a)).ok()) return st;
      VecQ<T> v = v0 + h * a;  // explicit Euler guess
      // active set: points that end the step below the ground join the contacts and the step
      // is solved again, so contact forces act during the step a point enters the ground
      for (int pass = 0; pass < 4; ++pass) {
        st = SolveNewton<T>(
            [&](const VecQ<T>& x, VecQ<T>* r) {
              s->q = q0;
              G::Advance(x, h, &s->q);
              s->qd = x;
              VecQ<T> acc;
              const StepStatus rs = accel(&acc, ContactSet::kFrozen);
              if (rs.ok()) *r = x - v0 - h * acc;
              return rs;
            },
            &v);
        if (!st.ok()) return st;
        s->q = q0;
        G::Advance(v, h, &s->q);
        s->qd = v;
        if (AddMissingContacts(body, GroundFor<Dim>(w), s) == 0) break;
      }
      break;
    }
    case Integrator::kVariational: {
      if (!(st = VariationalStep(body, w, body_index, h, s, extra)).ok()) return st;
      break;
    }
  }
  for (int i = 0; i < s->q.size(); ++i)
    if (!std::isfinite(double(ScalarValue(s->q[i])))) return {StatusCode::kNonFinite, 0.0};
  for (int i = 0; i < s->qd.size(); ++i)
    if (!std::isfinite(double(ScalarValue(s->qd[i])))) return {StatusCode::kNonFinite, 0.0};
  UpdateContacts(body, GroundFor<Dim>(w), s);
  return {};
}

// The plain (double) step is compiled once, in step_instances.cc, not in every unit that steps
// a body (each copy cost several seconds of compile time); Jet steps are instantiated where used.
#define WOBBLE_DOUBLE_STEP(prefix, Dim)                                                                     \
  prefix template StepStatus Accelerations<Dim, double, NoExtraForce>(                                              \
      const BodyModelN<Dim>&, const WorldParams&, int, const BodyState<Dim, double>&, VecQ<double>*,          \
      ForceBreakdown<Dim, double>*, ContactSet, const NoExtraForce&);                                               \
  prefix template StepStatus StepBody<Dim, double, NoExtraForce>(const BodyModelN<Dim>&, const WorldParams&,  \
                                                                 int, Integrator, double, BodyState<Dim, double>*,  \
                                                                 const NoExtraForce&);                              \
  prefix template void UpdateContacts<Dim, double>(const BodyModelN<Dim>&, const GroundOf<Dim>&,                    \
                                                   BodyState<Dim, double>*)
WOBBLE_DOUBLE_STEP(extern, 2);
WOBBLE_DOUBLE_STEP(extern, 3);

}  // namespace wobble
