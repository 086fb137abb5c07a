// Gradients of a trajectory cost through a whole 3D simulation, by the adjoint method: the 3D
// FFD body's counterpart of adjoint.h (issue 18).
//
// A rollout is StepBody3 (step3.h; thesis or symplectic Euler integrator) of one 3D FFD body
// whose mode forces are −2K_d (γ_d − γ0_d(n)) − c_d γ̇_d (§4.7, chapter 5's PD control): per-mode
// gains K, c and a PD target γ0(n) for every step n. Its cost is a sum of stage costs
// ℓ_n(state_n), n = 0 … steps. One forward run and one backward sweep give the gradient with
// respect to the start state, K, c and all steps × modes targets at once:
//     λ_N = ∂ℓ_N/∂z_N,   λ_n = ∂ℓ_n/∂z_n + (∂z_{n+1}/∂z_n)ᵀ λ_{n+1}.
//
// The orientation is on SO(3), not a vector: gradients with respect to a state are taken in its
// tangent coordinates z = (δt, ε, δγ, δv) with the state moved to (t + δt, R exp(ε̂), γ + δγ,
// v + δv) — ε a rotation vector in the body frame, the perturbation of step3.h's g·exp(h v).
// With these, λ_n is a plain vector of 12 + 2D numbers whatever the quaternion's sign.
//
// Each step's vector–Jacobian product is derived by hand (internal/step3_vjp.h): one mass
// solve, the mass-moment formulas' derivatives in O(D²) and each contact's and spring's force by
// its partials, so a gradient costs a few plain steps per step whatever the number of parameters.
// Contact decisions are taken on plain values, as in every Jet run: one-sided at a contact's
// onset.
//
// Memory (checkpoints.h): by default the forward run keeps every step's state and tape when they
// fit in kWholeRunMemoryBudget (about 7 kB a step: a 3,334-step chair run takes 23 MiB, runs
// up to about 9,000 steps fit), so nothing is taken twice; beyond it, a checkpoint every
// ⌈√steps⌉ steps, one interval recomputed at a time (a 10,000-step run: about 200 states).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/checkpoints.h"

namespace wobble::fit {

struct ControlledRollout3 {
  WorldParamsN<3> world;  // gravity, ground (plane or heightfield), springs
  Integrator integrator = Integrator::kThesis;  // kThesis or kSymplecticEuler
  double dt = 0.01;
  BodyState<3, double> start;            // t, orientation (normalized here), γ, v; contacts are found
  Eigen::VectorXd stiffness, damping;  // K_d, c_d per mode (replace the body's own)
  Eigen::MatrixXd targets;             // modes × steps: γ0 during step n is column n
  int steps() const { return int(targets.cols()); }
};

// The number of tangent coordinates of a state, 12 + 2D: δt (3), ε (3), δγ (D), δv (6 + D).
int StateTangentSize3(const BodyModel3& body);

// ℓ_n at state s: returns its value and adds ∂ℓ_n/∂z (tangent coordinates above) to *dz
// (sized StateTangentSize3, zero on entry).
using StageCost3 = std::function<double(int n, const BodyState<3, double>& s, Eigen::VectorXd* dz)>;

struct RolloutGradient3 {
  bool ok = false;
  std::string message;  // why not, when !ok
  double cost = 0.0;
  Eigen::VectorXd start;                // ∂cost/∂z_0 in tangent coordinates
  Eigen::VectorXd stiffness, damping;   // ∂cost/∂K, ∂cost/∂c
  Eigen::MatrixXd targets;              // ∂cost/∂γ0(n), modes × steps
  int states_held = 0;                  // the most body states held at once
};

// The cost of a rollout, one plain simulation; +inf when a step fails.
double RolloutCost3(const BodyModel3& body, const ControlledRollout3& rollout, const StageCost3& cost);

// The cost and its gradient with respect to every parameter. Throws std::invalid_argument on
// inconsistent sizes, non-finite numbers or another integrator. checkpoint_interval: an
// interval, kCheckpointAuto or kCheckpointSqrt (checkpoints.h).
RolloutGradient3 RolloutCostGradient3(const BodyModel3& body, const ControlledRollout3& rollout, const StageCost3& cost,
                                      int checkpoint_interval = 0);

}  // namespace wobble::fit
