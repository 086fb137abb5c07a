// Gradients of a trajectory cost through a whole simulation, by the adjoint method (issue 18),
// for the 2D and the 3D FFD body alike.
//
// A rollout is the world's own step (StepBody, thesis or symplectic Euler integrator) of one
// FFD body whose mode forces are −2K_d (γ_d − γ0_d(n)) − c_d γ̇_d (§4.7 and the PD control of
// chapter 5): per-mode gains K, c and a PD target γ0(n) for every step n, the per-step
// controls. Its cost is a sum of stage costs ℓ_n(state_n), n = 0 … steps, given with their
// gradients (the fits' residual sums, a final-state cost, ...).
//
// The gradient with respect to every parameter at once — the start state, K, c and all
// steps × modes targets — comes from one forward run and one backward sweep:
//     λ_N = ∂ℓ_N/∂z_N,   λ_n = ∂ℓ_n/∂z_n + (∂z_{n+1}/∂z_n)ᵀ λ_{n+1},
//     ∂/∂γ0(n) = (∂z_{n+1}/∂γ0(n))ᵀ λ_{n+1},   ∂/∂(K, c) = Σ_n (∂z_{n+1}/∂(K, c))ᵀ λ_{n+1},
// with z_n the step's whole state: the body's state and the anchor of every ground contact
// (the friction springs of Eq. 4.24/4.25 remember where a contact began), matched from step to
// step by (point, face).
//
// Gradients with respect to a state are taken in its tangent coordinates, 2 num_q numbers
// (StateTangentSize): the state moved to (q + δq, q̇ + δq̇) with δ = (δq, δq̇).
//   2D: the coordinates themselves, z = (q, q̇) = (t, θ, γ, ṫ, θ̇, γ̇).
//   3D: the orientation is on SO(3), not a vector: z = (δt, ε, δγ, δv) with the state moved to
//       (t + δt, R exp(ε̂), γ + δγ, v + δv) — ε a rotation vector in the body frame, the
//       perturbation of step.h's g·exp(h v) — so λ_n is a plain vector of 12 + 2D numbers
//       whatever the quaternion's sign.
//
// Each step's vector–Jacobian product is the dimension's own piece behind one interface
// (internal/adjoint_sweep.h; what the sweep, the checks and the costs do is one code path):
//   2D (adjoint_plane.cc): hand-derived (one mass solve, the moment formulas, and each contact
//       point's force and anchor update through the point's position and velocity); springs,
//       and a terrain under the symplectic step, take forward-mode Jets over the step's whole
//       input (2 nq + 2 × contacts + 3 D numbers, chunks of 16).
//   3D (adjoint_space.cc, internal/step_vjp_space.h): hand-derived, the mass-moment formulas'
//       derivatives in O(D²) and each contact's and spring's force by its partials, from the
//       forward step's tape.
// So the cost of a gradient does not grow with the number of steps' controls, unlike Jets over
// every parameter. Contact decisions are taken on plain values, as in every Jet run: the
// gradient is one-sided at a contact's onset, as the fits' are.
//
// Memory (checkpoints.h): by default the forward run keeps every state (3D: and every step's
// tape, about 7 kB a step) when they fit in kWholeRunMemoryBudget, and nothing is recomputed.
// Beyond it (or with kCheckpointSqrt or an interval), the forward run keeps a checkpoint every
// `checkpoint_interval` steps (⌈√steps⌉); the backward sweep recomputes one interval at a time
// from its checkpoint, so a gradient holds about 2√steps states (200 for 10,000 steps) for one
// extra plain simulation.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/control/control.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/checkpoints.h"

namespace wobble::fit {

template <int Dim> struct ControlledRolloutN {
  WorldParams world;  // gravity, ground (2D: line or terrain; 3D: ground_plane, a plane or heightfield), springs
  Integrator integrator = Integrator::kThesis;  // kThesis or kSymplecticEuler
  double dt = 0.01;
  // The start: 2D q, q̇ (num_q each); 3D t, orientation (normalized here), γ, v. Its contacts
  // are found here.
  BodyState<Dim, double> start;
  Eigen::VectorXd stiffness, damping;  // K_d, c_d per mode (replace the body's own)
  Eigen::MatrixXd targets;             // modes × steps: γ0 during step n is column n
  int steps() const { return int(targets.cols()); }
};
using ControlledRollout = ControlledRolloutN<2>;

// The number of tangent coordinates of a state: 2 num_q (2D: q, q̇; 3D: δt (3), ε (3), δγ (D),
// δv (6 + D)).
template <int Dim> int StateTangentSize(const BodyModelN<Dim>& body) { return 2 * body.num_q(); }

// ℓ_n at state s: returns its value and adds ∂ℓ_n/∂z (the state's tangent coordinates above;
// 2D: ∂ℓ_n/∂q then ∂ℓ_n/∂q̇) to *dz (sized StateTangentSize, zero on entry).
template <int Dim>
using StageCostN = std::function<double(int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz)>;
using StageCost = StageCostN<2>;

// The stage cost's parameter type, not deduced: Dim is the body's, and the cost may be any
// callable (a lambda, a function).
template <int Dim> using StageCostArg = typename std::enable_if<true, StageCostN<Dim>>::type;

struct RolloutGradient {
  bool ok = false;
  std::string message;  // why not, when !ok (a step failed: singular mass, non-finite state, ...)
  double cost = 0.0;
  Eigen::VectorXd start;               // ∂cost/∂z_0, the start's tangent coordinates (2D: q0 then q̇0)
  Eigen::VectorXd stiffness, damping;  // ∂cost/∂K, ∂cost/∂c
  Eigen::MatrixXd targets;             // ∂cost/∂γ0(n), modes × steps
  int states_held = 0;  // the most body states held at once (checkpoints + one interval)
};

// The cost of a rollout, one plain simulation (the baseline the gradient's cost is quoted
// against). +inf when a step fails. Dim = 2 or 3.
template <int Dim>
double RolloutCost(const BodyModelN<Dim>& body, const ControlledRolloutN<Dim>& rollout, const StageCostArg<Dim>& cost);

// The cost and its gradient with respect to every parameter of the rollout. Throws
// std::invalid_argument on inconsistent sizes, non-finite numbers or another integrator.
// checkpoint_interval: an interval, kCheckpointAuto or kCheckpointSqrt (checkpoints.h).
template <int Dim>
RolloutGradient RolloutCostGradient(const BodyModelN<Dim>& body, const ControlledRolloutN<Dim>& rollout,
                                    const StageCostArg<Dim>& cost, int checkpoint_interval = 0);

// Each dimension's RolloutCost and RolloutCostGradient are the one sweep of
// internal/adjoint_sweep.h over its step piece (adjoint_plane.cc, adjoint_space.cc).
template <> double RolloutCost<2>(const BodyModelN<2>&, const ControlledRolloutN<2>&, const StageCostN<2>&);
template <> double RolloutCost<3>(const BodyModelN<3>&, const ControlledRolloutN<3>&, const StageCostN<3>&);
template <>
RolloutGradient RolloutCostGradient<2>(const BodyModelN<2>&, const ControlledRolloutN<2>&, const StageCostN<2>&, int);
template <>
RolloutGradient RolloutCostGradient<3>(const BodyModelN<3>&, const ControlledRolloutN<3>&, const StageCostN<3>&, int);

// A smoothed pose-graph controller (control::SmoothPoseTargets, switch width w > 0) as
// per-step targets: column n is γ0(n dt), the dynamic fit's convention. Dim = 2 or 3.
template <int Dim>
Eigen::MatrixXd PoseGraphTargets(const BodyModelN<Dim>& body, const control::PoseGraph& graph, double dt, int steps,
                                 double width);

// The chain rule through PoseGraphTargets: from ∂cost/∂γ0(n) (RolloutGradient::targets) to
// ∂cost/∂(each pose's entries) and ∂cost/∂(each duration, i.e. the smoothed switch times).
struct PoseGraphGradient {
  std::vector<Eigen::VectorXd> poses;
  std::vector<double> durations;
};
template <int Dim>
PoseGraphGradient PoseGraphGradientOf(const BodyModelN<Dim>& body, const control::PoseGraph& graph, double dt,
                                      double width, const Eigen::MatrixXd& target_gradient);

}  // namespace wobble::fit
