// Equations of motion (Eq. 4.21) and the integrators that advance one body by one step.
//
//   M(q) q̈ = Q(q, q̇) − w(q, q̇),   w = Σ m_k J_kᵀ J̇_k q̇
//
// solved by Cholesky (M is symmetric positive definite for a well-posed mode set).
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <string>

#include "wobble/dynamics/forces.h"

namespace wobble {

enum class Integrator {
  kThesis,           // Eq. 4.22/4.23: q_{n+1} = 2q_n − q_{n−1} + Δt² q̈_n, q̇ = (q_{n+1} − q_n)/Δt
  kSymplecticEuler,  // position first: q_{n+1} = q_n + Δt q̇_n, q̇_{n+1} = q̇_n + Δt q̈(q_{n+1}, q̇_n)
  kRK4,              // classical fourth-order Runge–Kutta
  kImplicitEuler,    // backward Euler, Newton on q̇_{n+1}: for stiff ground contact
};
std::string IntegratorName(Integrator integrator);
bool ParseIntegrator(const std::string& text, Integrator* integrator);

// Why a run stopped. Never a silent NaN: the step loop checks every accepted state.
struct StepStatus {
  enum class Code { kOk, kNonFinite, kSingularMass, kIllConditioned, kPenetration, kSolverFailed };
  Code code = Code::kOk;
  double value = 0.0;  // the offending number (condition estimate, depth, ...)
  bool ok() const { return code == Code::kOk; }
};
std::string StatusCodeName(StepStatus::Code code);

// q̈ of Eq. 4.21. Also returns a cheap lower bound of cond₂(M) from the Cholesky factor
// (the squared ratio of its largest to smallest diagonal entry).
template <class T>
StepStatus Accelerations(const BodyModel& body, const WorldParams& w, int body_index, const BodyState<T>& s,
                         VecQ<T>* qdd, ForceBreakdown<T>* forces = nullptr) {
  MatQ<T> M;
  VecQ<T> vel;
  ForceBreakdown<T> local;
  ForceBreakdown<T>& f = forces ? *forces : local;
  MassMatrix(body.moments(), s.q, &M);
  VelocityTerms(body.moments(), s.q, s.qd, &vel);
  EvaluateForces(body, w, body_index, s, &f);
  const Eigen::LLT<MatQ<T>> llt(M);
  if (llt.info() != Eigen::Success) return {StepStatus::Code::kSingularMass, 0.0};
  const auto diag = llt.matrixLLT().diagonal();
  double lo = ScalarValue(diag[0]), hi = lo;
  for (int i = 1; i < diag.size(); ++i) {
    lo = std::min(lo, double(ScalarValue(diag[i])));
    hi = std::max(hi, double(ScalarValue(diag[i])));
  }
  const double cond_estimate = (hi / lo) * (hi / lo);
  if (!(lo > 0.0)) return {StepStatus::Code::kSingularMass, 0.0};
  if (cond_estimate > w.max_condition) return {StepStatus::Code::kIllConditioned, cond_estimate};
  *qdd = llt.solve(f.total - vel);
  return {};
}

// Advances one body by dt with contacts held fixed, then updates its contacts.
template <class T>
StepStatus StepBody(const BodyModel& body, const WorldParams& w, int body_index, Integrator integrator, double dt,
                    BodyState<T>* s) {
  const T h(dt);
  VecQ<T> a;
  StepStatus st;
  auto accel = [&](const VecQ<T>& q, const VecQ<T>& qd, VecQ<T>* out) {
    BodyState<T> probe{q, qd, s->contacts};
    return Accelerations(body, w, body_index, probe, out);
  };
  switch (integrator) {
    case Integrator::kThesis: {
      // Störmer form of Eq. 4.22/4.23 with q̇_n = (q_n − q_{n−1})/Δt kept as the state
      if (!(st = Accelerations(body, w, body_index, *s, &a)).ok()) return st;
      const VecQ<T> q_prev = s->q - h * s->qd;
      const VecQ<T> q_next = T(2.0) * s->q - q_prev + h * h * a;
      s->qd = (q_next - s->q) / h;
      s->q = q_next;
      break;
    }
    case Integrator::kSymplecticEuler: {
      s->q += h * s->qd;
      if (!(st = Accelerations(body, w, body_index, *s, &a)).ok()) return st;
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
      // solve r(v) = v − q̇_n − Δt q̈(q_n + Δt v, v) = 0 for v = q̇_{n+1} by Newton's method
      // with a finite-difference Jacobian
      const int nq = body.num_q();
      const VecQ<T> q0 = s->q, v0 = s->qd;
      auto residual = [&](const VecQ<T>& v, VecQ<T>* r) {
        VecQ<T> acc;
        const StepStatus rs = accel(q0 + h * v, v, &acc);
        if (rs.ok()) *r = v - v0 - h * acc;
        return rs;
      };
      VecQ<T> v = v0, r, r_probe;
      if (!(st = accel(q0, v0, &a)).ok()) return st;
      v = v0 + h * a;  // explicit Euler guess
      bool converged = false;
      for (int iter = 0; iter < 20 && !converged; ++iter) {
        if (!(st = residual(v, &r)).ok()) return st;
        MatQ<T> jac(nq, nq);
        for (int i = 0; i < nq; ++i) {
          const double eps = 1e-7 * std::max(1.0, std::abs(double(ScalarValue(v[i]))));
          VecQ<T> vp = v;
          vp[i] += T(eps);
          if (!(st = residual(vp, &r_probe)).ok()) return st;
          jac.col(i) = (r_probe - r) / T(eps);
        }
        const VecQ<T> dv = jac.partialPivLu().solve(r);
        v -= dv;
        double dv_norm = 0.0, v_norm = 0.0;
        for (int i = 0; i < nq; ++i) {
          dv_norm = std::max(dv_norm, std::abs(double(ScalarValue(dv[i]))));
          v_norm = std::max(v_norm, std::abs(double(ScalarValue(v[i]))));
        }
        converged = dv_norm <= 1e-10 * (1.0 + v_norm);
      }
      if (!converged) return {StepStatus::Code::kSolverFailed, 0.0};
      s->q = q0 + h * v;
      s->qd = v;
      break;
    }
  }
  UpdateContacts(body, w.ground, s);
  return {};
}

}  // namespace wobble
