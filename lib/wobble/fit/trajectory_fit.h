// Kinematic trajectory fit: reference positions of some body points over frames (a recorded
// simulation, keyframes, motion drawn by hand) → q(t) for every frame, as ONE sparse Ceres
// problem: the pose residuals of every frame plus a temporal smoothness term coupling each
// frame to its neighbours (the divided second difference of q). 2D and 3D bodies alike (q as
// in targets.h); a 3D orientation's smoothness is the second difference on the group,
// c2 log(R_fᵀ R_f+1) − c0 log(R_f−1ᵀ R_f) (body-frame turns), solved in charts about the
// frames' orientations as the pose fits do (pose_fit.h).
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

// Length scales L that weigh the coordinates in the smoothness term: 1 for the translation;
// the rms distance of the mass points from their centroid for every rotation coordinate; the
// rms displacement of the mass points under a unit amplitude for each γ_d (1 when a mode moves
// no mass point).
template <int Dim> VecQ<double> SmoothnessScales(const BodyModelN<Dim>& body);
extern template VecQ<double> SmoothnessScales(const BodyModelN<2>&);
extern template VecQ<double> SmoothnessScales(const BodyModelN<3>&);

// Fits q(t). Frames need not be evenly spaced. Without options.pose.initial_q each frame
// starts from its rigid placement (FitPose's; 2D angles unwrapped across frames), γ = 0.
// Throws std::invalid_argument for invalid options, no frames, a frame without points,
// weights that are not > 0 or unknown mass points.
template <int Dim>
TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                           const TrajectoryFitOptions& options);
extern template TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                                           const TrajectoryFitOptions&);
extern template TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                                           const TrajectoryFitOptions&);

// Reference frames from recorded states (a simulation, e.g. `wobble simulate`'s CSV; q rows as
// the fits' q): the positions of the listed mass points (all when empty) at every `every`-th
// state, weight 1.
template <int Dim>
std::vector<ReferenceFrameN<Dim>> FramesFromStates(const BodyModelN<Dim>& body, const std::vector<double>& times,
                                                   const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                                   int every = 1);
extern template std::vector<ReferenceFrameN<2>> FramesFromStates(const BodyModelN<2>&, const std::vector<double>&,
                                                                 const std::vector<Eigen::VectorXd>&,
                                                                 const std::vector<int>&, int);
extern template std::vector<ReferenceFrameN<3>> FramesFromStates(const BodyModelN<3>&, const std::vector<double>&,
                                                                 const std::vector<Eigen::VectorXd>&,
                                                                 const std::vector<int>&, int);

}  // namespace wobble::fit
