// What a step is asked to do and how it ended: the integrators' names, the causes that stop a
// run, and the hook through which the fits add their own generalized forces.
#pragma once

#include <string>

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
  kUnsupported,          // the integrator cannot step what the world holds (variational with constraints)
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
struct NoExtraForce {
  template <class State, class Force> void operator()(const State&, Force*) const {}
};

}  // namespace wobble
