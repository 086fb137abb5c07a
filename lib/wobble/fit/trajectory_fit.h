// Kinematic trajectory fit: reference positions of some body points over frames (a recorded
// simulation, keyframes, motion drawn by hand) → q(t) for every frame, as ONE sparse Ceres
// problem: the pose residuals of every frame plus a temporal smoothness term coupling each
// frame to its neighbours (the divided second difference of q, see SecondDifference).
#pragma once

#include <vector>

#include "wobble/fit/pose_fit.h"
#include "wobble/fit/targets.h"

namespace wobble::fit {

struct TrajectoryFitOptions {
  PoseFitOptions pose;      // bounds, loss, prior (per frame), max_iterations, full_report
  double smoothness = 1.0;  // w of ½ w Σ_f |L ∘ Δ²q_f|²; L turns θ and γ into lengths
};

struct TrajectoryFitResult {
  std::vector<double> times;
  std::vector<Eigen::VectorXd> q;  // one per frame
  FitReport report;
  std::vector<double> frame_rms;   // rms distance of each frame's points to their targets
  double rms_residual = 0;         // over all points of all frames
  std::string linear_solver;       // what Ceres used
};

// Length scales L that weigh the coordinates in the smoothness term: 1 for tx, ty; the rms
// distance of the mass points from their centroid for θ; the rms displacement of the mass
// points under a unit amplitude for each γ_d (1 when a mode moves no mass point).
VecQ<double> SmoothnessScales(const BodyModel& body);

// Fits q(t). Frames need not be evenly spaced. Without options.pose.initial_q each frame
// starts from its rigid Procrustes placement (angles unwrapped across frames), γ = 0.
// Throws std::invalid_argument for invalid options, no frames or unknown mass points.
TrajectoryFitResult FitKinematicTrajectory(const BodyModel& body, const std::vector<ReferenceFrame>& frames,
                                           const TrajectoryFitOptions& options);

// Reference frames from recorded states (a simulation, e.g. `wobble simulate`'s CSV): the
// positions of the listed mass points (all when empty) at every `every`-th state, weight 1.
std::vector<ReferenceFrame> FramesFromStates(const BodyModel& body, const std::vector<double>& times,
                                             const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                             int every = 1);

}  // namespace wobble::fit
