// The names of step.h's enums: integrators (as the CLI, scripts and Python spell them) and
// status codes. Here, beside their declarations, so that the dynamics layer links on its own.
#include "wobble/dynamics/status.h"

namespace wobble {

std::string IntegratorName(Integrator integrator) {
  switch (integrator) {
    case Integrator::kThesis: return "thesis";
    case Integrator::kSymplecticEuler: return "symplectic";
    case Integrator::kRK4: return "rk4";
    case Integrator::kImplicitEuler: return "implicit";
    case Integrator::kVariational: return "variational";
  }
  return "?";
}

namespace {
constexpr Integrator kIntegrators[] = {Integrator::kThesis, Integrator::kSymplecticEuler, Integrator::kRK4,
                                       Integrator::kImplicitEuler, Integrator::kVariational};
}  // namespace

bool ParseIntegrator(const std::string& text, Integrator* integrator) {
  for (Integrator i : kIntegrators)
    if (IntegratorName(i) == text) {
      *integrator = i;
      return true;
    }
  return false;
}

std::string IntegratorNames() {
  std::string names;
  for (Integrator i : kIntegrators) names += (names.empty() ? "" : ", ") + IntegratorName(i);
  return names;
}

std::string StatusCodeName(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kNonFinite: return "non-finite state";
    case StatusCode::kSingularMass: return "singular mass matrix";
    case StatusCode::kIllConditioned: return "ill-conditioned mass matrix";
    case StatusCode::kPenetration: return "runaway ground penetration";
    case StatusCode::kSolverFailed: return "implicit solver did not converge";
    case StatusCode::kSingularConstraints: return "singular constraints";
    case StatusCode::kBadPath: return "bad trajectory path";
    case StatusCode::kOverflowingForce: return "overflowing force";
    case StatusCode::kNonFiniteEnergy: return "non-finite energy";
    case StatusCode::kUnsupported: return "unsupported";
  }
  return "?";
}

}  // namespace wobble
