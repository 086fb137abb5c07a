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

// The Cayley map on SE(3) and its momentum map, for the 3D step below. A twist x = [x_v, x_ω]
// (body-frame translation first, as in a body's velocities) is the 4x4 X = [x̂_ω x_v; 0 0], and
// cay(X) = (1 − X/2)⁻¹ (1 + X/2) = [cay(x_ω), (1 − x̂_ω/2)⁻¹ x_v; 0 1] (Kobilarov & Marsden 2011,
// §3.2): g·cay(X) turns R by cay(x_ω) and moves t by R (1 − x̂_ω/2)⁻¹ x_v. Since
// cay(A X A⁻¹) = A cay(X) A⁻¹, the step it makes does not depend on where the body frame's
// origin is (a change of origin is a conjugation), unlike a step on R³ × SO(3).
// (1 − x̂/2)⁻¹ y = y + (½ x × y + ¼ x × (x × y)) / (1 + |x|²/4).
template <class T> Vec3<T> CayleyTranslation(const Vec3<T>& x_omega, const Vec3<T>& x_v) {
  const Vec3<T> xy = x_omega.cross(x_v);
  return x_v + (T(0.5) * xy + T(0.25) * x_omega.cross(xy)) / (T(1.0) + T(0.25) * x_omega.squaredNorm());
}
// (dcay⁻¹_x)ᵀ μ on se(3)*, with the right-trivialized dcay⁻¹ of Kobilarov & Marsden 2011, §3.2:
//   dcay⁻¹_x = [ 1 − x̂_ω/2                  −½ (1 − x̂_ω/2) x̂_v       ]   (rows v, ω)
//              [ 0                          1 − x̂_ω/2 + x_ω x_ωᵀ/4   ]
// so that, for μ = [μ_v, μ_ω],
//   v-rows:  μ_v + ½ x_ω × μ_v
//   ω-rows:  μ_ω + ½ x_ω × μ_ω + ¼ x_ω (x_ω·μ_ω) + ½ x_v × (μ_v + ½ x_ω × μ_v).
// The ω-rows with x_v = 0 are CayleyMomentumMap (rotation3.h). variational3_test checks the
// whole map against finite differences of cay.
template <class T> void CayleyMomentumMapSE3(const Vec3<T>& x_v, const Vec3<T>& x_omega, Vec3<T>* mu_v, Vec3<T>* mu_omega) {
  const Vec3<T> v_rows = *mu_v + T(0.5) * x_omega.cross(*mu_v);
  *mu_omega = CayleyMomentumMap<T>(x_omega, *mu_omega) + T(0.5) * x_v.cross(v_rows);
  *mu_v = v_rows;
}

// 3D: a symmetric (second-order) discrete Lagrangian on SE(3) × R^D. The body's velocities in
// its own frame, ξ = [v = Rᵀṫ, ω, γ̇], make the kinetic energy T = ½ ξᵀ M̃(γ) ξ independent of
// the pose (M̃ is M of spatial_inertia.h at R = 1), and a step moves g_{k+1} = g_k·cay(Δt ξ_k)
// on SE(3) (above), γ_{k+1} = γ_k + Δt γ̇_k. With the trapezoidal discrete Lagrangian
//   L_d(g_k, g_{k+1}) = ½Δt [L(g_k, ξ_k) + L(g_{k+1}, ξ_k)]
// (Marsden & West 2001, §2.6: the symmetric L_d that gives Störmer–Verlet; on a Lie group
// Bou-Rabee & Marsden 2009 and Kobilarov & Marsden 2011, §3) and the forces by the discrete
// Lagrange–d'Alembert principle, f_d^± = ½Δt Q(g_{k|k+1}, ξ_k) (all of Q: gravity, modes,
// ground, springs, as in 2D; Q's translation rows taken to the body frame, Rᵀ Q_t), the
// discrete Euler–Poincaré equations are, with π = ½ (M̃(γ_k) + M̃(γ_{k+1})) ξ and the body
// momentum p_k = M̃(γ_k) ξ̃_k of the state,
//   p_k     = A(Δt ξ)ᵀ π − ½Δt (∂T/∂γ + Q)(g_k, ξ)          (solved for ξ by Newton)
//   p_{k+1} = A(−Δt ξ)ᵀ π + ½Δt (∂T/∂γ + Q)(g_{k+1}, ξ)     (explicit)
// A(x)ᵀ = (dcay⁻¹_x)ᵀ on the SE(3) rows (CayleyMomentumMapSE3) and the identity on the modes,
// ∂T/∂γ only on the mode rows (the pose derivative of T is zero); then q̇_{k+1} from
// M̃(γ_{k+1}) ξ_{k+1} = p_{k+1}. The 2D step's structure (variational.h above) with the
// trapezoid in place of the midpoint: the pose derivative vanishes, and the forces at the two
// ends need no pull-back from a midpoint. Symmetric, hence second order; symplectic; it keeps
// linear and angular momentum exactly (to the Newton tolerance) when no external force acts,
// integrates a constant force exactly, and, being independent of the body origin, keeps a
// mirror-symmetric motion in its plane. Only the force at g_k depends on ξ in the solve: the
// one at g_{k+1} is evaluated once, with the contacts found there (ContactSet::kDetect).
template <class T, class Extra>
StepStatus VariationalStep(const BodyModelN<3>& body, const WorldParams& w, int body_index, const T& h,
                           BodyState<3, T>* s, const Extra& extra) {
  using G = Group<3>;
  constexpr int kRigid = G::kRigidDofs;
  const MassMomentsN<3>& mm = body.moments();
  const int D = body.num_modes();
  const Mat3<T> identity = Mat3<T>::Identity();
  const VecQ<T> q0 = s->q;
  const Frame<3, T> frame0(q0);
  const ShapeMoments<T> sm0(mm, VecD<T>(q0.tail(D)));
  MatQ<T> M0;
  MassMatrix(mm, sm0, identity, &M0);  // M̃(γ_k)
  VecQ<T> xi = s->qd;
  xi.template head<3>() = frame0.R.transpose() * s->qd.template head<3>();
  const VecQ<T> p0 = M0 * xi;
  // g·cay(Δt ξ) and γ + Δt γ̇
  auto advance = [&](const VecQ<T>& x, VecQ<T>* q1) {
    const Vec3<T> x_omega = h * x.template segment<3>(3);
    *q1 = q0;
    q1->template head<3>() +=
        frame0.R * CayleyTranslation<T>(x_omega, Vec3<T>(h * x.template head<3>()));
    G::SetOrientation(Eigen::Quaternion<T>(G::OrientationOf(q0) * CayleyRotation<T>(x_omega)).normalized(), q1);
    q1->tail(D) += h * x.tail(D);
  };
  // ½Δt (∂T/∂γ + Q) at the pose q (frame `frame`, shape moments sm) for body velocities x,
  // Q's translation rows in the body frame
  auto half_force = [&](const VecQ<T>& q, const Frame<3, T>& frame, const ShapeMoments<T>& sm, const VecQ<T>& x,
                        VecQ<T>* out) {
    s->q = q;
    s->qd = x;
    s->qd.template head<3>() = frame.R * x.template head<3>();
    ForceBreakdown<3, T> f;
    EvaluateForces(body, w, body_index, *s, frame, &f, ContactSet::kDetect);
    extra(*s, &f.total);
    VecQ<T> dT;
    KineticGradient(mm, sm, identity, x, &dT);  // at R = 1: only its mode rows are ∂T/∂γ of T(γ, ξ)
    *out = f.total;
    out->template head<3>() = frame.R.transpose() * f.total.template head<3>();
    out->tail(D) += dT.tail(D);
    *out *= T(0.5) * h;
  };
  // π and A(±Δt ξ)ᵀ π
  auto momentum = [&](const VecQ<T>& x, const MatQ<T>& M1, T sign, VecQ<T>* out) {
    *out = T(0.5) * (M0 * x + M1 * x);
    Vec3<T> mu_v = out->template head<3>(), mu_omega = out->template segment<3>(3);
    CayleyMomentumMapSE3<T>(Vec3<T>(sign * h * x.template head<3>()), Vec3<T>(sign * h * x.template segment<3>(3)),
                            &mu_v, &mu_omega);
    out->template head<3>() = mu_v;
    out->template segment<3>(3) = mu_omega;
  };
  VecQ<T> q1, force0;
  MatQ<T> M1 = M0;  // M̃ depends on γ only: constant for a rigid body
  auto mass_at = [&](const VecQ<T>& q) {
    if (D == 0) return;
    const ShapeMoments<T> sm1(mm, VecD<T>(q.tail(D)));
    MassMatrix(mm, sm1, identity, &M1);
  };
  auto residual = [&](const VecQ<T>& x, VecQ<T>* r) {
    advance(x, &q1);
    mass_at(q1);
    half_force(q0, frame0, sm0, x, &force0);
    momentum(x, M1, T(1.0), r);
    *r -= force0 + p0;
    return StepStatus{};
  };
  StepStatus st = SolveNewton<T>(residual, &xi);
  if (!st.ok()) return st;
  advance(xi, &q1);
  mass_at(q1);
  const Frame<3, T> frame1(q1);
  const ShapeMoments<T> sm1(mm, VecD<T>(q1.tail(D)));
  VecQ<T> p1, force1;
  momentum(xi, M1, T(-1.0), &p1);
  half_force(q1, frame1, sm1, xi, &force1);
  p1 += force1;
  if (!CholeskyInPlace(&M1)) return {StatusCode::kSingularMass, 0.0};
  CholeskySolveInPlace(M1, &p1);  // ξ_{k+1}
  s->q = q1;
  s->qd = p1;
  s->qd.template head<3>() = frame1.R * p1.template head<3>();
  (void)kRigid;
  return {};
}

}  // namespace wobble
