// What the 2D and 3D gradient bindings share (gradients.cc, gradients3.cc; not public): Python
// stage costs, the rollout's keyword arguments and the spacetime fit's options.
#pragma once

#include <memory>
#include <string>

#include "support.h"
#include "wobble/fit/spacetime.h"

namespace wobble::python {

// A Python callable kept by C++ copies of a stage cost: dropped with the GIL taken, since the
// library drops std::functions on threads that do not hold it.
std::shared_ptr<py::function> HoldWithGil(py::function fn);

// A Python stage cost's result (value, dq, dqd) at step n, each gradient `size` finite numbers or
// None (zero); the value must be finite. InputError otherwise.
double StageResult(const py::object& result, int n, long size, Eigen::VectorXd* dq, Eigen::VectorXd* dqd);

// The keyword arguments every rollout takes: the integrator (thesis or symplectic), the targets
// (modes, steps) and the gains (the body's own when None).
void CheckGradientIntegrator(Integrator integrator);
Eigen::MatrixXd TargetsOf(const py::object& targets, int modes);
template <class Body>
void GainsOf(const Body& body, const py::object& stiffness, const py::object& damping, Eigen::VectorXd* K,
             Eigen::VectorXd* c) {
  const int D = body.num_modes();
  Eigen::VectorXd own_K, own_c;
  body.ModeGains(&own_K, &own_c);
  *K = VectorOr(stiffness, D, own_K, "stiffness");
  *c = VectorOr(damping, D, own_c, "damping");
}

// fit_spacetime's and fit_spacetime3's bounds (every target within ±bound), control weight and
// options.
template <class Problem> void SetSpacetimeBounds(int modes, double bound, double control_weight, Problem* p) {
  if (!(bound > 0) || !std::isfinite(bound)) throw InputError("bound must be a finite number > 0");
  if (!(control_weight >= 0) || !std::isfinite(control_weight)) throw InputError("control_weight must be >= 0");
  p->lower = Eigen::VectorXd::Constant(modes, -bound);
  p->upper = Eigen::VectorXd::Constant(modes, bound);
  p->control_weight = control_weight;
}
fit::SpacetimeOptions SpacetimeOptionsOf(int max_iterations, int starts, double start_spread, unsigned seed, int threads);

}  // namespace wobble::python
