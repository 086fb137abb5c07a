// Dynamic trajectory fit: parameters of the SIMULATION are fitted so that the simulated
// motion matches a reference (positions of body points over frames), with exact gradients
// from automatic differentiation through the templated dynamics (Ceres Jets through
// MassMatrix, VelocityTerms, EvaluateForces and the thesis integrator, Eq. 4.21–4.23).
//
// Fitted: the initial state (q0, q̇0), the stiffness K_d (V = K γ²) and damping c_d of every
// mode — also the PD gains of chapter 5 (C = 2K, D = c) —, and a pose-graph controller's poses
// (targets of the active modes) and transition times. Each is its own Ceres parameter block.
// The simulation is the world's own step (StepBody, thesis integrator) on the body with its mode
// forces switched off; the mode and PD forces −2K(γ − γ0(t)) − c γ̇, whose K, c and γ0 are Jets,
// enter as StepBody's extra generalized force.
//
// Every function takes a 2D or a 3D body (one template over the dimension): in 3D q0 = [t, r, γ]
// with r a rotation vector and q̇0 = [ṫ, body ω, γ̇], as the 3D CLI; the solver holds q0's
// orientation as chart · exp(δ̂) (as the pose fits, pose_fit.h), the world is
// DynamicFitOptionsN<3>::world.
//
// Transition times are made differentiable by a smoothed pose switch: the targets are
//     γ0(t) = P_0 + Σ_k (P_{k mod n} − P_{(k−1) mod n}) σ((t − S_k)/w),  S_k = τ_0 + … + τ_{k−1},
// σ the logistic function and w the switch width (DynamicFitOptionsN::switch_width). A hard switch
// (the pose graph of lib/wobble/control) has a cost that is piecewise constant in the times
// between steps, with zero gradient almost everywhere; the smoothed one is a controller in its
// own right (a PD servo whose set point moves in about 4w) and tends to the hard one as w → 0.
// The fit models a controller with smoothed switches: control::SmoothPoseTargets, which scripts
// run with `set switch_width W` (and anyone with World::SetModeTargets before each step).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "wobble/control/control.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::fit {

struct DynamicParameters {
  Eigen::VectorXd q0, qd0;             // initial state (num_q each)
  Eigen::VectorXd stiffness, damping;  // per mode: K_d > 0, c_d >= 0
  // Pose-graph controller of the active modes (DeformationMode::active); empty: no controller,
  // every mode is pulled to 0. Transition times > 0.
  control::PoseGraph graph;
};

// How a dynamic fit gets its derivatives (issue 18).
//   kJets:    forward-mode Jets give every residual's Jacobian; Ceres' Levenberg–Marquardt
//             (bounds exact). A Jacobian costs about one simulation per parameter.
//   kAdjoint: the adjoint (fit/adjoint.h) gives the cost's gradient for a few simulations
//             whatever the number of parameters; Ceres' line search (BFGS, L-BFGS past 400
//             unknowns). ζ ≥ 0 is held by ζ = u² and the transition times' bounds by a
//             logistic map. 2D and 3D bodies (fit/adjoint.h; 3D q0's δ through J_r).
enum class FitGradient { kJets, kAdjoint };

template <int Dim> struct DynamicFitOptionsN {
  WorldParams world;  // gravity, the ground of the body's dimension, springs
  double dt = 0.01;   // thesis integrator (Eq. 4.22/4.23), as `wobble simulate --integrator thesis`
  bool fit_q0 = true, fit_qd0 = true, fit_stiffness = true, fit_damping = true;
  bool fit_poses = false, fit_times = false;  // the controller's (needs a non-empty graph)
  double switch_width = 0.05;  // w of the smoothed pose switch, seconds (> 0 to fit times)
  double min_time = 0.05, max_time = 10.0;  // bounds of the transition times
  FitGradient gradient = FitGradient::kJets;
  int max_iterations = 50;  // solver iterations (L-BFGS takes more, cheaper ones: say 500)
  bool full_report = false;
  std::function<void(int iteration, double cost)> on_iteration;  // progress display
};
using DynamicFitOptions = DynamicFitOptionsN<2>;

struct DynamicFitResult {
  DynamicParameters params;
  FitReport report;
  double rms_residual = 0;  // distance of the simulated points to the reference, all frames
  long simulations = 0;     // simulations run (with Jets for Jacobians, plain for costs)
};

// The reference's frame times as step counts from its first frame; throws
// std::invalid_argument when a time is not a whole number of steps of dt.
template <int Dim> std::vector<int> FrameSteps(const std::vector<ReferenceFrameN<Dim>>& frames, double dt);

// Runs the simulation with `p` (the body's own K and c are replaced by p's) and calls
// on_frame(f, q) at every frame step (q as the fits' q). Returns false on numerical trouble
// (singular M, non-finite state).
template <int Dim>
bool SimulateWithParameters(const BodyModelN<Dim>& body, const DynamicFitOptionsN<Dim>& options, const DynamicParameters& p,
                            const std::vector<int>& frame_steps,
                            const std::function<void(int, const Eigen::VectorXd&)>& on_frame);

// Fits the parameters, starting from `initial`. An empty initial q0 / q̇0 is estimated from
// pose fits of the first two frames. Stiffness starts must be > 0 (it is fitted as log K);
// damping is fitted as the ratio ζ_d = c_d / (2 sqrt(2 K_d G_dd)) (G_dd the mode's
// generalized mass), bounded below by 0.
template <int Dim>
DynamicFitResult FitDynamicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                      const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& options);

// Baseline: simulated annealing on the same parameters and the same cost (½ Σ |x − target|²),
// given a budget of simulations. Returns the best parameters and cost found.
struct AnnealingResult {
  DynamicParameters params;
  double cost = 0;
  long simulations = 0;
};
// Simulated annealing of the controller (lib/wobble/synth, Fig. 5.2) on the same cost: the
// poses and/or times (options.fit_poses/fit_times) of initial.graph, the rest of `initial`
// fixed, with `simulation_budget` simulations (batch 1). The best graph is in result.params.
template <int Dim>
AnnealingResult AnnealPoseGraph(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& options,
                                long simulation_budget, std::uint64_t seed = 1);
template <int Dim>
AnnealingResult AnnealDynamicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                        const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& options,
                                        long simulation_budget, unsigned seed = 1);

// ½ Σ w |x − target|² of a parameter set (one plain simulation); +inf on numerical trouble.
template <int Dim>
double DynamicCost(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                   const DynamicParameters& p, const DynamicFitOptionsN<Dim>& options);

// (Each is instantiated for Dim = 2 and 3 in dynamic_fit.cc.)

}  // namespace wobble::fit
