// Pose fits: q so that the body matches a target shape, for 2D and 3D bodies alike (q as in
// targets.h: [tx, ty, θ, γ] in 2D (Eq. 4.4), [t, r, γ] in 3D with r the rotation vector).
//
//   FitPose           with correspondences: body points (mass points or lattice points, e.g. of
//                     the drawing) and where each should be. Either dimension.
//   FitPoseToCurve    2D, without correspondences: the target is a set of polylines and/or an
//                     unordered point cloud; the residual of each body sample is its distance
//                     to the nearest target segment (ICP-like, see the function).
//   FitPoseToSurface  3D, without correspondences: the target is a triangle mesh and/or an
//                     unordered point cloud (e.g. a scan); every body sample is pulled to the
//                     nearest target triangle or point.
//
// All minimise Σ ρ(w_i |x_i(q) − target_i|²) + w_prior |γ|² with Ceres (automatic
// derivatives through the templated kinematics), γ_d bounded to [lower_d, upper_d]. The
// result says how well the targets determine q: see Conditioning. A 3D orientation is solved
// on SO(3) (R = R0 exp(δ̂) about the start, re-centred when δ grows past a radian), so there
// is no Euler-angle singularity; the conditioning's rotation coordinates are then body-frame
// turns rx ry rz (radians).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/fit/targets.h"

namespace wobble::fit {

enum class Loss { kSquared, kHuber, kCauchy };
std::string LossName(Loss loss);
bool ParseLoss(const std::string& text, Loss* loss);

struct PoseFitOptions {
  // Starting q (size num_q). Empty: a rigid start (see each fit), γ = 0.
  Eigen::VectorXd initial_q;
  // Bounds of every γ_d; per-mode vectors (size D) override the scalars when not empty.
  double gamma_lower = -1.0, gamma_upper = 1.0;
  std::vector<double> mode_lower, mode_upper;
  // Robust loss for outliers: ρ(s) of Ceres with this scale (a distance, in length units:
  // residuals beyond about `loss_scale` count linearly (Huber) or logarithmically (Cauchy)).
  Loss loss = Loss::kSquared;
  double loss_scale = 1.0;
  // Weight of the prior pulling every γ toward rest (0): adds prior_weight * Σ γ_d².
  double prior_weight = 0.0;
  int max_iterations = 200;
  bool full_report = false;  // also fill FitReport::full_report (long)
  // Curve fits: samples per segment of the drawing (besides the mass points), and the number
  // of closest-point/solve rounds.
  int samples_per_segment = 8;
  bool use_mass_points = true;
  int max_rounds = 30;
  // Also pull every target vertex to the nearest segment of the body's drawing (weighted so
  // that both directions weigh the same in total): without it the body may cover only part
  // of the target.
  bool two_sided = true;
  // Two-sided fits use at most this many target vertices (evenly spread) for the reverse
  // direction: enough to see partial coverage, and the reverse terms are the costly ones.
  int max_reverse_points = 200;
  // Every start runs this many rounds; then only the best start continues.
  int start_rounds = 3;
  // Curve fits: find the nearest segments inside every residual evaluation (one solve per
  // start) instead of alternating closest-point rounds and solves.
  bool joint_closest_points = true;
  // 3D surface fits: at most this many of the body mesh's vertices are the body samples
  // (0: the mass points are; see SurfaceSamples). use_mass_points is for 2D curve fits.
  int max_mesh_samples = 400;
  // Compute PoseFitResult::conditioning (an SVD of the data Jacobian at the solution).
  bool analyze_conditioning = true;
  // Called after every Ceres iteration with its number and cost (progress display).
  std::function<void(int iteration, double cost)> on_iteration;
};
// Empty when valid, otherwise what is wrong (for a body with `num_modes` modes and
// `num_rigid` rigid coordinates: 3 in 2D, 6 in 3D).
std::string ValidateOptions(const PoseFitOptions& options, int num_modes, int num_rigid = kRigidDofs);

// How well the data terms (not the prior, not the bounds) determine q at the solution, from
// the SVD of their Jacobian J. Coordinates have different units (length, radians,
// amplitudes), so besides cond(JᵀJ) of the raw J the weak directions are found after scaling
// every column to unit norm (Jacobi equilibration); a column that is (numerically) zero is a
// coordinate the targets cannot see at all.
struct WeakDirection {
  double relative_singular_value = 0;  // σ_i / σ_max of the column-scaled J
  std::vector<std::string> coordinates; // names of the coordinates with |v| > 0.3 in it
  Eigen::VectorXd vector;               // the right singular vector (scaled coordinates)
};
struct Conditioning {
  double condition_number = 0;         // cond(JᵀJ) = (σ_max/σ_min)², raw J; inf if singular
  double scaled_condition_number = 0;  // the same for the column-scaled J, over seen columns
  std::vector<double> column_norms;    // |∂residuals/∂q_i|: how strongly the data sees q_i
  std::vector<WeakDirection> weak;     // σ_i/σ_max < kPoorlyDetermined, weakest first
  std::vector<std::string> undetermined;        // modes the data cannot see (σ_rel < kUndetermined or zero column)
  std::vector<std::string> poorly_determined;   // modes in a weak direction, not undetermined
  static constexpr double kUndetermined = 1e-7;
  static constexpr double kPoorlyDetermined = 1e-3;
};

// Common result of every fit.
struct FitReport {
  bool usable = false;             // Ceres' Summary::IsSolutionUsable()
  std::string termination;         // e.g. "CONVERGENCE"
  std::string brief_report, full_report;
  double initial_cost = 0, final_cost = 0;  // Ceres' cost ½ Σ ρ(|r|²), prior included
  std::vector<double> cost_per_iteration;    // iteration 0 = start; all rounds of a curve fit
  int iterations = 0;
  double solve_seconds = 0;
};

struct PoseFitResult {
  Eigen::VectorXd q;
  FitReport report;
  // Unweighted distance of every body point to its target (or nearest target segment), in
  // the order of the targets (curve fits: the body samples, mass points first).
  std::vector<double> point_residuals;
  double rms_residual = 0;
  std::vector<std::string> at_bound;  // modes that ended on a bound
  Conditioning conditioning;
  int rounds = 0;  // curve fits: closest-point rounds of the best start
};

// The names of q's coordinates: tx, ty, theta (2D) or tx ty tz, rx ry rz (3D), then the mode
// names.
template <int Dim> std::vector<std::string> CoordinateNames(const BodyModelN<Dim>& body);
extern template std::vector<std::string> CoordinateNames(const BodyModelN<2>&);
extern template std::vector<std::string> CoordinateNames(const BodyModelN<3>&);

// Fits q to point correspondences. Without options.initial_q the start is the best rigid
// placement of the rest shape onto the targets (weighted Procrustes in 2D, Kabsch in 3D: SVD,
// no reflection), γ = 0. Throws std::invalid_argument for invalid options, no targets, a
// weight that is not > 0 or a mass point index the body does not have.
template <int Dim>
PoseFitResult FitPose(const BodyModelN<Dim>& body, const std::vector<CorrespondenceN<Dim>>& targets,
                      const PoseFitOptions& options);
extern template PoseFitResult FitPose(const BodyModelN<2>&, const std::vector<CorrespondenceN<2>>&, const PoseFitOptions&);
extern template PoseFitResult FitPose(const BodyModelN<3>&, const std::vector<CorrespondenceN<3>>&, const PoseFitOptions&);

// Body samples of a curve fit: the mass points (if options.use_mass_points) and
// options.samples_per_segment + 1 points along every segment of the drawing; `segments`
// joins consecutive drawing samples (indices into `points`) into the body's curve.
struct CurveSamples {
  std::vector<PointBasis> points;
  std::vector<std::pair<int, int>> segments;
  static CurveSamples Of(const BodyModel& body, const PoseFitOptions& options);
};

// Fits q to a curve target without correspondences. The residuals are the distances of every
// body sample to its nearest target segment and (two-sided) of up to max_reverse_points
// target vertices to the nearest drawn body segment.
//   Jointly (options.joint_closest_points, the default): one solve per start, the nearest
//   segments chosen anew at every residual evaluation.
//   Alternated (ICP-like): every round fixes the nearest segments at the current q and solves
//   with point-to-segment residuals on them, until the assignment stops changing, a round no
//   longer lowers the cost by a relative 1e-6, or options.max_rounds; every start runs
//   options.start_rounds rounds, then only the lowest-cost one continues.
// Start (without options.initial_q): the rest shape's sample centroid moved onto the target's
// (length-weighted) centroid, its principal axis turned onto the target's; both orientations
// of the axis are tried (four quarter turns when either shape is nearly isotropic) and the
// lowest final cost wins; γ = 0. point_residuals are those of the body samples.
PoseFitResult FitPoseToCurve(const BodyModel& body, const CurveTarget& target, const PoseFitOptions& options);

// Body samples of a 3D surface fit: up to options.max_mesh_samples of the body mesh's vertices,
// evenly spread over its vertex list; the mass points when there are none (no mesh, or
// max_mesh_samples = 0). Not both: mass points sampled in the volume lie inside the skin,
// and pulling them onto the target's surface would squeeze the body.
std::vector<PointBasisN<3>> SurfaceSamples(const BodyModelN<3>& body, const PoseFitOptions& options);

// Fits a 3D body to a surface target without correspondences: the residual of every body
// sample is its distance to the nearest target triangle or cloud point, chosen anew at every
// evaluation (the distance is continuous in q; inside a face it moves the point along the
// normal, as point-to-plane ICP). Two-sided (options.two_sided): up to
// options.max_reverse_points target points (evenly spread) are also pulled to the nearest body
// sample, weighted so that both directions weigh the same.
// Starts (without options.initial_q): the samples' centroid onto the target's (area-weighted)
// centroid with the principal axes aligned (area-weighted on meshes, on both sides), in any
// order and with any signs (24 rotations); the four that fit best before solving are solved,
// best first, until one meets the target exactly (cost down by 1e12); the lowest cost wins.
// point_residuals are those of the body samples.
PoseFitResult FitPoseToSurface(const BodyModelN<3>& body, const SurfaceTarget& target, const PoseFitOptions& options);

}  // namespace wobble::fit
