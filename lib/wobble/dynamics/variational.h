// The variational integrators: each dimension's discrete Lagrangian, with the forces Q
// (gravity, modes, ground, springs) entering by the discrete Lagrange–d'Alembert principle.
// StepBody (step.h) calls VariationalStep for Integrator::kVariational; the step's contacts are
// updated by the caller.
#pragma once

#include <vector>

#include "wobble/core/cholesky.h"
#include "wobble/core/rotation3.h"
#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/newton.h"
#include "wobble/dynamics/status.h"

namespace wobble {

// 2D: the midpoint rule on the coordinates, L_d(q0, q1) = Δt L((q0+q1)/2, (q1−q0)/Δt). With
// p_n = M(q_n) q̇_n, solve for the mean velocity v:
//   M(m) v − ½Δt (∂T/∂q(m, v) + Q(m, v)) = p_n,   m = q_n + ½Δt v,
// then q_{n+1} = q_n + Δt v, p_{n+1} = M(m) v + ½Δt (∂T/∂q + Q), q̇_{n+1} = M(q_{n+1})⁻¹ p_{n+1}.
// Symplectic for any M(q).
template <class T, class Extra>
StepStatus VariationalStep(const BodyModel& body, const WorldParams& w, int body_index, const T& h, BodyState<2, T>* s,
                           const Extra& extra) {
  const VecQ<T> q0 = s->q;
  MatQ<T> M0;
  MassMatrix(body.moments(), q0, &M0);
  const VecQ<T> p0 = M0 * s->qd;
  auto momentum_parts = [&](const VecQ<T>& v, VecQ<T>* Mv, VecQ<T>* half_force) {
    const VecQ<T> m = q0 + T(0.5) * h * v;
    MatQ<T> Mm;
    MassMatrix(body.moments(), m, &Mm);
    VecQ<T> dT;
    KineticGradient(body.moments(), m, v, &dT);
    ForceBreakdown<2, T> f;
    s->q = m;
    s->qd = v;
    EvaluateForces(body, w, body_index, *s, &f, ContactSet::kFrozen);
    extra(*s, &f.total);
    *Mv = Mm * v;
    *half_force = T(0.5) * h * (dT + f.total);
  };
  VecQ<T> v = s->qd, Mv, half_force;
  StepStatus st;
  for (int pass = 0; pass < 4; ++pass) {  // active set, as for implicit Euler
    st = SolveNewton<T>(
        [&](const VecQ<T>& x, VecQ<T>* r) {
          momentum_parts(x, &Mv, &half_force);
          *r = Mv - half_force - p0;
          return StepStatus{};
        },
        &v);
    if (!st.ok()) return st;
    s->q = q0 + h * v;
    s->qd = v;
    if (AddMissingContacts(body, w.ground, s) == 0) break;
  }
  momentum_parts(v, &Mv, &half_force);
  s->q = q0 + h * v;
  MatQ<T> M1;
  MassMatrix(body.moments(), s->q, &M1);
  if (!CholeskyInPlace(&M1)) return {StatusCode::kSingularMass, 0.0};
  s->qd = Mv + half_force;
  CholeskySolveInPlace(M1, &s->qd);
  return {};
}

// 3D: the discrete Euler–Poincaré equations of L_d = Δt L(g_k, ξ_k) with
// g_{k+1} = g_k·cay(Δt ξ_k) (Kobilarov & Marsden 2011; Bou-Rabee & Marsden 2009): symplectic,
// and it keeps linear and angular momentum exactly (to the Newton tolerance) when no external
// force acts. With p_k = M(g_k) v_k, solve for ξ:
//   A(Δt ξ)ᵀ M(g_k) ξ − Δt (∂T/∂g + Q)(g_k, ξ) = p_k,
// A the Cayley momentum map on the ω rows and the identity elsewhere (translations and modes);
// then g_{k+1} = g_k·cay(Δt ξ) and p_{k+1} = A(−Δt ξ)ᵀ M(g_k) ξ.
template <class T, class Extra>
StepStatus VariationalStep(const BodyModelN<3>& body, const WorldParamsN<3>& w, int body_index, const T& h,
                           BodyState<3, T>* s, const Extra& extra) {
  using G = Group<3>;
  const int D = body.num_modes();
  const VecQ<T> q0 = s->q, v0 = s->qd;
  const Frame<3, T> frame(q0);
  const ShapeMoments<T> sm(body.moments(), VecD<T>(q0.tail(D)));
  MatQ<T> M0;
  MassMatrix(body.moments(), sm, frame.R, &M0);
  const VecQ<T> p0 = M0 * v0;
  auto residual = [&](const VecQ<T>& xi, VecQ<T>* r) {
    s->q = q0;
    s->qd = xi;
    ForceBreakdown<3, T> f;
    EvaluateForces(body, w, body_index, *s, frame, &f, ContactSet::kDetect);
    extra(*s, &f.total);
    VecQ<T> dT;
    KineticGradient(body.moments(), sm, frame.R, xi, &dT);
    VecQ<T> mu = M0 * xi;
    mu.template segment<3>(3) =
        CayleyMomentumMap<T>(Vec3<T>(h * xi.template segment<3>(3)), Vec3<T>(mu.template segment<3>(3)));
    *r = mu - h * (dT + f.total) - p0;
    return StepStatus{};
  };
  VecQ<T> xi = v0;
  StepStatus st;
  if (!(st = SolveNewton<T>(residual, &xi)).ok()) return st;
  VecQ<T> p1 = M0 * xi;
  p1.template segment<3>(3) =
      CayleyMomentumMap<T>(Vec3<T>(-h * xi.template segment<3>(3)), Vec3<T>(p1.template segment<3>(3)));
  s->q = q0;
  s->q.template head<3>() += h * xi.template head<3>();
  G::SetOrientation(
      Eigen::Quaternion<T>(G::OrientationOf(q0) * CayleyRotation<T>(Vec3<T>(h * xi.template segment<3>(3)))).normalized(),
      &s->q);
  s->q.tail(D) += h * xi.tail(D);
  const Frame<3, T> frame1(s->q);
  const ShapeMoments<T> sm1(body.moments(), VecD<T>(s->q.tail(D)));
  MatQ<T> M1;
  MassMatrix(body.moments(), sm1, frame1.R, &M1);
  if (!CholeskyInPlace(&M1)) return {StatusCode::kSingularMass, 0.0};
  CholeskySolveInPlace(M1, &p1);
  s->qd = p1;
  return {};
}

}  // namespace wobble
