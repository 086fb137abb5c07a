// Fits of a 3D FFD body: q = [tx ty tz, rx ry rz, γ1..γD] with r the rotation vector of the
// orientation R (the turn by |r| about r, as `--q` of the 3D CLI) and
//     x(q) = t + R (b0 + B γ)                                   (Eq. 4.2, in 3D)
// for every body point.
//
//   FitPose3                 with correspondences: mass points or lattice points (s, t, u)
//                            and where each should be.
//   FitPoseToSurface3        without correspondences: the target is a triangle mesh and/or an
//                            unordered point cloud (e.g. a scan); every body sample is pulled
//                            to the nearest target triangle or point.
//   FitKinematicTrajectory3  frames of correspondences → q(t), one sparse problem with a
//                            smoothness term (trajectory_fit.h in 3D).
//
// The orientation lives on SO(3): every solve writes R = R0 exp(δ̂) with R0 the start and δ
// a body-frame rotation vector that starts at 0, so there is no Euler-angle singularity and
// no unit-norm constraint; δ stays small in a local fit, and a solve whose δ grew past
// kRecentreAngle is restarted from its result (R0 ← R0 exp(δ̂)). The objective, options,
// report and conditioning are those of the 2D fits (pose_fit.h); the conditioning's
// coordinates are tx ty tz, rx ry rz (body-frame turns, radians) and the modes.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/targets.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble::fit {

// tx ty tz rx ry rz, then the mode names.
std::vector<std::string> CoordinateNames3(const BodyModel3& body);

// A local solve turns by at most this much (radians) before it is re-centred.
constexpr double kRecentreAngle = 1.0;

// With correspondences. Without options.initial_q the start is the best rigid placement of
// the rest shape onto the targets (weighted Kabsch: SVD, no reflection), γ = 0. Throws
// std::invalid_argument for invalid options, no targets or a mass point the body lacks.
PoseFitResult FitPose3(const BodyModel3& body, const std::vector<Correspondence3>& targets,
                       const PoseFitOptions& options);

// Body samples of a surface fit: up to options.max_mesh_samples of the body mesh's vertices,
// evenly spread over its vertex list; the mass points when there are none (no mesh, or
// max_mesh_samples = 0). Not both: mass points sampled in the volume lie inside the skin,
// and pulling them onto the target's surface would squeeze the body.
std::vector<PointBasis3> SurfaceSamples3(const BodyModel3& body, const PoseFitOptions& options);

// Without correspondences: the residual of every body sample is its distance to the nearest
// target triangle or cloud point, chosen anew at every evaluation (the distance is continuous
// in q; inside a face it moves the point along the normal, as point-to-plane ICP). Two-sided
// (options.two_sided): up to options.max_reverse_points target points (evenly spread) are
// also pulled to the nearest body sample, weighted so that both directions weigh the same.
// Starts (without options.initial_q): the samples' centroid onto the target's (area-weighted)
// centroid with the principal axes aligned (area-weighted on meshes, on both sides), in any
// order and with any signs (24 rotations); the four that fit best before solving are solved,
// best first, until one meets the target exactly (cost down by 1e12); the lowest cost wins. point_residuals are those of the body samples.
PoseFitResult FitPoseToSurface3(const BodyModel3& body, const SurfaceTarget3& target, const PoseFitOptions& options);

// Length scales of the smoothness term, as SmoothnessScales in 2D: 1 for t, the rms radius
// of the mass points for the rotation, the rms mass point displacement of each mode.
VecQ<double> SmoothnessScales3(const BodyModel3& body);

// q(t) for every frame, as FitKinematicTrajectory in 2D. The smoothness of the orientation
// is the second difference on the group, c2 log(R_fᵀ R_f+1) − c0 log(R_f−1ᵀ R_f) (body-frame
// turns), that of t and γ the divided second difference; every frame starts from its Kabsch
// placement (or options.pose.initial_q), γ = 0.
TrajectoryFitResult FitKinematicTrajectory3(const BodyModel3& body, const std::vector<ReferenceFrame3>& frames,
                                            const TrajectoryFitOptions& options);

// Reference frames from recorded 3D states (q = [t, r, γ] rows): the positions of the listed
// mass points (all when empty) at every `every`-th state.
std::vector<ReferenceFrame3> FramesFromStates3(const BodyModel3& body, const std::vector<double>& times,
                                               const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                               int every = 1);

}  // namespace wobble::fit
