// Dynamic trajectory fit: parameters of the SIMULATION are fitted so that the simulated
// motion matches a reference (positions of body points over frames), with exact gradients
// from automatic differentiation through the templated dynamics (Ceres Jets through
// MassMatrix, VelocityTerms, EvaluateForces and the thesis integrator, Eq. 4.21–4.23).
//
// Fitted now: the initial state (q0, q̇0) and the passive mode stiffness K_d (V = K γ²) and
// damping c_d of every mode. Each is its own Ceres parameter block, so that the controller
// parameters of issue 5 (PD gains, pose-graph poses and timings) can join later as further
// blocks: add them to DynamicParameters, to the block list in dynamic_fit.cc (Blocks) and
// their generalized force to ModeForces.
#pragma once

#include <functional>
#include <vector>

#include "wobble/dynamics/step.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::fit {

struct DynamicParameters {
  Eigen::VectorXd q0, qd0;             // initial state (num_q each)
  Eigen::VectorXd stiffness, damping;  // per mode: K_d > 0, c_d >= 0
};

struct DynamicFitOptions {
  WorldParams world;  // gravity, ground, springs
  double dt = 0.01;   // thesis integrator (Eq. 4.22/4.23), as `wobble simulate --integrator thesis`
  bool fit_q0 = true, fit_qd0 = true, fit_stiffness = true, fit_damping = true;
  int max_iterations = 50;
  bool full_report = false;
  std::function<void(int iteration, double cost)> on_iteration;  // progress display
};

struct DynamicFitResult {
  DynamicParameters params;
  FitReport report;
  double rms_residual = 0;  // distance of the simulated points to the reference, all frames
  long simulations = 0;     // simulations run (with Jets for Jacobians, plain for costs)
};

// The reference's frame times as step counts from its first frame; throws
// std::invalid_argument when a time is not a whole number of steps of dt.
std::vector<int> FrameSteps(const std::vector<io::TargetFrame>& frames, double dt);

// Runs the simulation with `p` (the body's own K and c are replaced by p's) and calls
// on_frame(f, q) at every frame step. Returns false on numerical trouble (singular M,
// non-finite state).
bool SimulateWithParameters(const BodyModel& body, const DynamicFitOptions& options, const DynamicParameters& p,
                            const std::vector<int>& frame_steps,
                            const std::function<void(int, const Eigen::VectorXd&)>& on_frame);

// Fits the parameters, starting from `initial`. An empty initial q0 / q̇0 is estimated from
// pose fits of the first two frames. Stiffness starts must be > 0 (it is fitted as log K);
// damping is fitted as the ratio ζ_d = c_d / (2 sqrt(2 K_d G_dd)) (G_dd the mode's
// generalized mass), bounded below by 0.
DynamicFitResult FitDynamicTrajectory(const BodyModel& body, const std::vector<io::TargetFrame>& frames,
                                      const DynamicParameters& initial, const DynamicFitOptions& options);

// Baseline: simulated annealing on the same parameters and the same cost (½ Σ |x − target|²),
// given a budget of simulations. Returns the best parameters and cost found.
struct AnnealingResult {
  DynamicParameters params;
  double cost = 0;
  long simulations = 0;
};
AnnealingResult AnnealDynamicTrajectory(const BodyModel& body, const std::vector<io::TargetFrame>& frames,
                                        const DynamicParameters& initial, const DynamicFitOptions& options,
                                        long simulation_budget, unsigned seed = 1);

// ½ Σ w |x − target|² of a parameter set (one plain simulation); +inf on numerical trouble.
double DynamicCost(const BodyModel& body, const std::vector<io::TargetFrame>& frames, const DynamicParameters& p,
                   const DynamicFitOptions& options);

}  // namespace wobble::fit
