// Gradients of a trajectory cost through a whole simulation, by the adjoint method (issue 18).
//
// A rollout is the world's own step (StepBody, thesis or symplectic Euler integrator) of one
// 2D FFD body whose mode forces are −2K_d (γ_d − γ0_d(n)) − c_d γ̇_d (§4.7 and the PD control
// of chapter 5): per-mode gains K, c and a PD target γ0(n) for every step n, the per-step
// controls. Its cost is a sum of stage costs ℓ_n(q_n, q̇_n), n = 0 … steps, given with their
// gradients (the fits' residual sums, a final-state cost, ...).
//
// The gradient with respect to every parameter at once — q0, q̇0, K, c and all steps × modes
// targets — comes from one forward run and one backward sweep:
//     λ_N = ∂ℓ_N/∂z_N,   λ_n = ∂ℓ_n/∂z_n + (∂z_{n+1}/∂z_n)ᵀ λ_{n+1},
//     ∂/∂γ0(n) = (∂z_{n+1}/∂γ0(n))ᵀ λ_{n+1},   ∂/∂(K, c) = Σ_n (∂z_{n+1}/∂(K, c))ᵀ λ_{n+1},
// with z_n the step's whole state: q, q̇ and the anchor of every ground contact (the friction
// springs of Eq. 4.24/4.25 remember where a contact began), matched from step to step by
// (point, face). Each step's vector–Jacobian product is hand-derived (one mass solve, the
// moment formulas, and each contact point's force and anchor update through the point's
// position and velocity); springs, and a terrain under the symplectic step, take
// forward-mode Jets over the step's whole input (2 nq + 2 × contacts + 3 D numbers, chunks of
// 16). So the cost of a gradient does not grow with the number of steps' controls, unlike
// Jets over every parameter. Contact decisions are taken on plain values, as in every Jet
// run: the gradient is one-sided at a contact's onset, as the fits' are.
//
// Memory (checkpoints.h): by default the forward run keeps every state when they fit in
// kWholeRunMemoryBudget, and nothing is recomputed. Beyond it (or with kCheckpointSqrt or an
// interval), the forward run keeps a checkpoint every `checkpoint_interval` steps (⌈√steps⌉);
// the backward sweep recomputes one interval at a time from its checkpoint, so a gradient
// holds about 2√steps states (200 for 10,000 steps) for one extra plain simulation.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>

#include "wobble/body/body_model.h"
#include "wobble/control/control.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/checkpoints.h"

namespace wobble::fit {

struct ControlledRollout {
  WorldParams world;  // gravity, ground (line or terrain), springs
  Integrator integrator = Integrator::kThesis;  // kThesis or kSymplecticEuler
  double dt = 0.01;
  Eigen::VectorXd q0, qd0;             // num_q each
  Eigen::VectorXd stiffness, damping;  // K_d, c_d per mode (replace the body's own)
  Eigen::MatrixXd targets;             // modes × steps: γ0 during step n is column n
  int steps() const { return int(targets.cols()); }
};

// ℓ_n at (q_n, q̇_n): returns its value and adds ∂ℓ_n/∂q to *dq and ∂ℓ_n/∂q̇ to *dqd (both
// sized num_q, zero on entry).
using StageCost = std::function<double(int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                       Eigen::VectorXd* dq, Eigen::VectorXd* dqd)>;

struct RolloutGradient {
  bool ok = false;
  std::string message;  // why not, when !ok (a step failed: singular mass, non-finite state, ...)
  double cost = 0.0;
  Eigen::VectorXd q0, qd0, stiffness, damping;  // ∂cost/∂ each
  Eigen::MatrixXd targets;                      // ∂cost/∂γ0(n), modes × steps
  int states_held = 0;  // the most body states held at once (checkpoints + one interval)
};

// The cost of a rollout, one plain simulation (the baseline the gradient's cost is quoted
// against). +inf when a step fails.
double RolloutCost(const BodyModel& body, const ControlledRollout& rollout, const StageCost& cost);

// The cost and its gradient with respect to every parameter of the rollout. Throws
// std::invalid_argument on inconsistent sizes, non-finite numbers or another integrator.
// checkpoint_interval: an interval, kCheckpointAuto or kCheckpointSqrt (checkpoints.h).
RolloutGradient RolloutCostGradient(const BodyModel& body, const ControlledRollout& rollout, const StageCost& cost,
                                    int checkpoint_interval = 0);

// A smoothed pose-graph controller (control::SmoothPoseTargets, switch width w > 0) as
// per-step targets: column n is γ0(n dt), the dynamic fit's convention. 2D or 3D body.
Eigen::MatrixXd PoseGraphTargets(const BodyModel& body, const control::PoseGraph& graph, double dt, int steps,
                                 double width);
Eigen::MatrixXd PoseGraphTargets(const BodyModel3& body, const control::PoseGraph& graph, double dt, int steps,
                                 double width);

// The chain rule through PoseGraphTargets: from ∂cost/∂γ0(n) (RolloutGradient::targets) to
// ∂cost/∂(each pose's entries) and ∂cost/∂(each duration, i.e. the smoothed switch times).
struct PoseGraphGradient {
  std::vector<Eigen::VectorXd> poses;
  std::vector<double> durations;
};
PoseGraphGradient PoseGraphGradientOf(const BodyModel& body, const control::PoseGraph& graph, double dt,
                                      double width, const Eigen::MatrixXd& target_gradient);
PoseGraphGradient PoseGraphGradientOf(const BodyModel3& body, const control::PoseGraph& graph, double dt,
                                      double width, const Eigen::MatrixXd& target_gradient);

}  // namespace wobble::fit
