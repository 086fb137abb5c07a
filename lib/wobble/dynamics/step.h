// Equations of motion (Eq. 4.21) and the integrators that advance one body by one step.
//
//   M(q) q̈ = Q(q, q̇) − w(q, q̇),   w = Σ m_k J_kᵀ J̇_k q̇
//
// solved by Cholesky (M is symmetric positive definite for a well-posed mode set).
#pragma once

#include <Eigen/LU>
#include <string>

#include "wobble/dynamics/forces.h"
#include "wobble/core/cholesky.h"

namespace wobble {

enum class Integrator {
  kThesis,           // Eq. 4.22/4.23: q_{n+1} = 2q_n − q_{n−1} + Δt² q̈_n, q̇ = (q_{n+1} − q_n)/Δt
  kSymplecticEuler,  // position first: q_{n+1} = q_n + Δt q̇_n, q̇_{n+1} = q̇_n + Δt q̈(q_{n+1}, q̇_n)
  kRK4,              // classical fourth-order Runge–Kutta
  kImplicitEuler,    // backward Euler, Newton on q̇_{n+1}: for stiff ground contact
  kVariational,      // midpoint variational integrator: symplectic for any M(q)
};
std::string IntegratorName(Integrator integrator);
bool ParseIntegrator(const std::string& text, Integrator* integrator);
std::string IntegratorNames();  // "thesis, symplectic, ...": every name ParseIntegrator takes

// Why a run stopped: one list of causes for a body's step (StepStatus) and the world's
// (WorldStatus, wobble/world). Never a silent NaN: the step loop checks every accepted state.
enum class StatusCode {
  kOk,
  kNonFinite,
  kSingularMass,
  kIllConditioned,
  kPenetration,
  kSolverFailed,
  kSingularConstraints,  // redundant or conflicting constraints (J W Jᵀ singular)
  kBadPath,              // a trajectory's path returned a non-finite or wrongly sized sample
  kOverflowingForce,     // a generalized force past the largest double (huge stiffness, speed, ...)
  kNonFiniteEnergy,      // a finite state whose energy is not (q̇ = 1e160 squares to inf)
};
std::string StatusCodeName(StatusCode code);

struct StepStatus {
  using Code = StatusCode;
  Code code = Code::kOk;
  double value = 0.0;  // the offending number (condition estimate, depth, ...)
  bool ok() const { return code == Code::kOk; }
};

// An extra generalized force added to Q at every force evaluation, as extra(s, &Q) with s the
// state being evaluated (every stage of a multi-stage integrator). The World adds none; the
// dynamic fit (lib/wobble/fit) adds mode and PD-control forces whose gains and targets are
// Ceres Jets, so that it steps with exactly this code. The default costs nothing (inlined away).
// The same hook serves the 3D body (step3.h: extra(BodyState3, &Q)).
struct NoExtraForce {
  template <class State, class Force> void operator()(const State&, Force*) const {}
};

// q̈ of Eq. 4.21, M q̈ = Q − w, solved about the centre of mass (SolveMassSystem). Fails with
// kIllConditioned when the elimination's pivot ratio, a lower bound of cond₂(M), exceeds
// w.max_condition. `extra` is added to Q (and to forces->total).
template <class T, class Extra = NoExtraForce>
StepStatus Accelerations(const BodyModel& body, const WorldParams& w, int body_index, const BodyState<T>& s,
                         VecQ<T>* qdd, ForceBreakdown<T>* forces = nullptr,
                         ContactSet contact_set = ContactSet::kDetect, const Extra& extra = Extra()) {
  VecQ<T> vel;
  ForceBreakdown<T> local;
  ForceBreakdown<T>& f = forces ? *forces : local;
  const Frame<T> frame(s.q);
  VelocityTerms(body.moments(), s.q, s.qd, frame.R, &vel);
  EvaluateForces(body, w, body_index, s, frame, &f, contact_set);
  extra(s, &f.total);
  double cond_estimate = 0.0;
  if (!SolveMassSystem(body.moments(), s.q, frame.R, VecQ<T>(f.total - vel), qdd, &cond_estimate)) {
    // an infinite force is not a singular M (a stiffness of 1e300 is not the mass's fault)
    for (int i = 0; i < f.total.size(); ++i)
      if (!std::isfinite(double(ScalarValue(f.total[i])))) return {StepStatus::Code::kOverflowingForce, 0.0};
    return {StepStatus::Code::kSingularMass, 0.0};
  }
  if (cond_estimate > w.max_condition) return {StepStatus::Code::kIllConditioned, cond_estimate};
  return {};
}

// Newton's method with a forward-difference Jacobian and backtracking on |r|, for the implicit
// integrators. x holds the initial guess and receives the solution.
// Vec is VecQ<T> (2D bodies) or VecQ3<T> (3D).
template <class T, class Residual, class Vec> StepStatus SolveNewton(Residual&& residual, Vec* x) {
  const int n = int(x->size());
  auto norm = [](const Vec& r) {
    double m = 0.0;
    for (int i = 0; i < r.size(); ++i) m = std::max(m, std::abs(double(ScalarValue(r[i]))));
    return m;
  };
  using Jacobian = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, 0, Vec::MaxRowsAtCompileTime, Vec::MaxRowsAtCompileTime>;
  Vec r, r_probe, trial;
  StepStatus st;
  if (!(st = residual(*x, &r)).ok()) return st;
  const double scale = 1.0 + norm(r);
  for (int iter = 0; iter < 30; ++iter) {
    const double r_norm = norm(r);
    if (r_norm <= 1e-12 * scale) return {};
    Jacobian jac(n, n);
    for (int i = 0; i < n; ++i) {
      const double eps = 1e-7 * std::max(1.0, std::abs(double(ScalarValue((*x)[i]))));
      Vec xp = *x;
      xp[i] += T(eps);
      if (!(st = residual(xp, &r_probe)).ok()) return st;
      jac.col(i) = (r_probe - r) / T(eps);
    }
    const Vec dx = jac.partialPivLu().solve(r);
    // backtrack until the residual decreases (contact forces are only piecewise smooth)
    double step = 1.0;
    for (int k = 0; k < 12; ++k, step *= 0.5) {
      trial = *x - T(step) * dx;
      if (!(st = residual(trial, &r_probe)).ok()) return st;
      if (norm(r_probe) < r_norm) break;
    }
    const double dx_norm = step * norm(dx);
    *x = trial;
    r = r_probe;
    if (dx_norm <= 1e-13 * (1.0 + norm(*x))) return {};
  }
  return norm(r) <= 1e-8 * scale ? StepStatus{} : StepStatus{StepStatus::Code::kSolverFailed, norm(r)};
}

// Advances one body by dt with contacts held fixed, then updates its contacts. `extra`: an
// extra generalized force (see NoExtraForce).
template <class T, class Extra = NoExtraForce>
StepStatus StepBody(const BodyModel& body, const WorldParams& w, int body_index, Integrator integrator, double dt,
                    BodyState<T>* s, const Extra& extra = Extra()) {
  const T h(dt);
  VecQ<T> a;
  StepStatus st;
  // stage evaluations reuse *s (q and q̇ overwritten, contacts kept): no copies, no heap
  auto accel = [&](const VecQ<T>& q, const VecQ<T>& qd, VecQ<T>* out, ContactSet set = ContactSet::kDetect) {
    s->q = q;
    s->qd = qd;
    return Accelerations(body, w, body_index, *s, out, static_cast<ForceBreakdown<T>*>(nullptr), set, extra);
  };
  switch (integrator) {
    case Integrator::kThesis: {
      // Störmer form of Eq. 4.22/4.23 with q̇_n = (q_n − q_{n−1})/Δt kept as the state
      if (!(st = Accelerations(body, w, body_index, *s, &a, static_cast<ForceBreakdown<T>*>(nullptr),
                               ContactSet::kDetect, extra)).ok())
        return st;
      const VecQ<T> q_prev = s->q - h * s->qd;
      const VecQ<T> q_next = T(2.0) * s->q - q_prev + h * h * a;
      s->qd = (q_next - s->q) / h;
      s->q = q_next;
      break;
    }
    case Integrator::kSymplecticEuler: {
      s->q += h * s->qd;
      if (!(st = Accelerations(body, w, body_index, *s, &a, static_cast<ForceBreakdown<T>*>(nullptr),
                               ContactSet::kDetect, extra)).ok())
        return st;
      s->qd += h * a;
      break;
    }
    case Integrator::kRK4: {
      VecQ<T> k1, k2, k3, k4;
      const VecQ<T> q0 = s->q, v0 = s->qd;
      if (!(st = accel(q0, v0, &k1)).ok()) return st;
      if (!(st = accel(q0 + T(0.5) * h * v0, v0 + T(0.5) * h * k1, &k2)).ok()) return st;
      const VecQ<T> v2 = v0 + T(0.5) * h * k1;
      if (!(st = accel(q0 + T(0.5) * h * v2, v0 + T(0.5) * h * k2, &k3)).ok()) return st;
      const VecQ<T> v3 = v0 + T(0.5) * h * k2;
      if (!(st = accel(q0 + h * v3, v0 + h * k3, &k4)).ok()) return st;
      const VecQ<T> v4 = v0 + h * k3;
      s->q = q0 + h / T(6.0) * (v0 + T(2.0) * v2 + T(2.0) * v3 + v4);
      s->qd = v0 + h / T(6.0) * (k1 + T(2.0) * k2 + T(2.0) * k3 + k4);
      break;
    }
    case Integrator::kImplicitEuler: {
      // solve r(v) = v − q̇_n − Δt q̈(q_n + Δt v, v) = 0 for v = q̇_{n+1}
      const VecQ<T> q0 = s->q, v0 = s->qd;
      if (!(st = accel(q0, v0, &a)).ok()) return st;
      VecQ<T> v = v0 + h * a;  // explicit Euler guess
      // active set: points that end the step below the ground join the contacts and the step
      // is solved again, so contact forces act during the step a point enters the ground
      for (int pass = 0; pass < 4; ++pass) {
        st = SolveNewton<T>(
            [&](const VecQ<T>& x, VecQ<T>* r) {
              VecQ<T> acc;
              const StepStatus rs = accel(q0 + h * x, x, &acc, ContactSet::kFrozen);
              if (rs.ok()) *r = x - v0 - h * acc;
              return rs;
            },
            &v);
        if (!st.ok()) return st;
        s->q = q0 + h * v;
        s->qd = v;
        if (AddMissingContacts(body, w.ground, s) == 0) break;
      }
      break;
    }
    case Integrator::kVariational: {
      // Discrete Lagrangian L_d(q0, q1) = Δt L((q0+q1)/2, (q1−q0)/Δt) with the forces Q (gravity,
      // modes, ground, springs) entering by the discrete Lagrange–d'Alembert principle at the
      // midpoint. With p_n = M(q_n) q̇_n, solve for the mean velocity v:
      //   M(m) v − ½Δt (∂T/∂q(m, v) + Q(m, v)) = p_n,   m = q_n + ½Δt v,
      // then q_{n+1} = q_n + Δt v, p_{n+1} = M(m) v + ½Δt (∂T/∂q + Q), q̇_{n+1} = M(q_{n+1})⁻¹ p_{n+1}.
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
        ForceBreakdown<T> f;
        s->q = m;
        s->qd = v;
        EvaluateForces(body, w, body_index, *s, &f, ContactSet::kFrozen);
        extra(*s, &f.total);
        *Mv = Mm * v;
        *half_force = T(0.5) * h * (dT + f.total);
      };
      VecQ<T> v = s->qd, Mv, half_force;
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
      if (!CholeskyInPlace(&M1)) return {StepStatus::Code::kSingularMass, 0.0};
      s->qd = Mv + half_force;
      CholeskySolveInPlace(M1, &s->qd);
      break;
    }
  }
  UpdateContacts(body, w.ground, s);
  return {};
}

// The plain (double) step is compiled once, in step_instances.cc, not in every unit that steps
// a body (each copy cost several seconds of compile time); Jet steps are instantiated where used.
extern template StepStatus Accelerations<double, NoExtraForce>(const BodyModel&, const WorldParams&, int,
                                                               const BodyState<double>&, VecQ<double>*,
                                                               ForceBreakdown<double>*, ContactSet, const NoExtraForce&);
extern template StepStatus StepBody<double, NoExtraForce>(const BodyModel&, const WorldParams&, int, Integrator, double,
                                                          BodyState<double>*, const NoExtraForce&);
extern template void UpdateContacts<double>(const BodyModel&, const Ground&, BodyState<double>*);

}  // namespace wobble
