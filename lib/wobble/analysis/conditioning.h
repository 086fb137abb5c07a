// Conditioning of the mass matrix (thesis §4.10.3): the condition number in the 2-norm with its
// singular values, a cheap 1-norm estimate for large systems, the angle sweep of Fig. 4.7/4.8,
// and the check the thesis wished for: how close the deformation modes of a set are to each
// other and to the rigid motions, under the body's mass inner product.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/step.h"

namespace wobble::analysis {

// cond₂(M) = σ_max / σ_min (thesis: cond(M) = ‖M‖ ‖M⁻¹‖). M counts as singular when
// σ_min ≤ n·ε·σ_max, the usual numerical-rank tolerance: its "condition number" would then be
// rounding noise, so `cond` is +∞ and `singular` says why.
struct ConditionNumber {
  bool singular = false;
  double cond = 0.0;                // +∞ when singular
  Eigen::VectorXd singular_values;  // descending
  // cond₂ of the Jacobi-scaled S M S, S = diag(M)^(-1/2): independent of units (pixels vs
  // metres, mass vs inertia), so it measures how alike the degrees of freedom are.
  double cond_scaled = 0.0;
};
ConditionNumber Condition(const Eigen::MatrixXd& M);
// M(q) of a body (from its mass moments).
ConditionNumber MassMatrixCondition(const BodyModel& body, const Eigen::VectorXd& q);
// M of a 3D body at state s.
ConditionNumber MassMatrixCondition(const BodyModelN<3>& body, const BodyState<3, double>& s);

// Estimate of cond₁(A) = ‖A‖₁ ‖A⁻¹‖₁ by Hager's method (Higham's refinement of the iteration):
// a few solves with an LU factorization, never A⁻¹ itself. A lower bound of cond₁, usually
// within a small factor. Returns +∞ when A is singular.
double Cond1Estimate(const Eigen::MatrixXd& A);

// ---- the angle sweep of Fig. 4.7 -------------------------------------------------------------

// A linear squash about an anchor point: displacement u(p) = A (p − anchor) with
// A(φ) = R(φ) diag(−compress, expand) R(φ)ᵀ: squeezed along the direction at angle φ from the
// x axis, bulging across it. φ = 0 is a horizontal squash, φ = π/2 a vertical squash. Rotating
// the squash's axis (not merely its displacement vectors, which would turn it into a shear) is
// what makes the two modes of Fig. 4.7 coincide at φ = π/2.
struct Squash {
  double compress = 1.0;  // d_y = −100 t on the 300 x 100 table at φ = π/2, as data/vsquash.def
  double expand = 0.5;    // d_x = 0.5 (x − 150), as data/vsquash.def
  // The fixed point, in lattice coordinates; (0.5, 0) keeps the middle of the bottom in place.
  Eigen::Vector2d anchor_st = Eigen::Vector2d(0.5, 0.0);
};
// The squash as a deformation mode on `lattice`: the linear field sampled at the control points
// (the lattice reproduces a linear field exactly). Stiffness and damping are left at zero. In 3D
// the squash's axis turns about z from x (φ = 0) to y and it bulges in both other directions,
// A(φ) = R_z(φ) diag(−compress, expand, expand) R_z(φ)ᵀ, anchored at (anchor_st, ½): the middle of
// the bottom face.
template <int Dim>
DeformationModeN<Dim> SquashMode(const LatticeN<Dim>& lattice, double phi, const Squash& squash,
                                 const std::string& name);

struct SweepSample {
  double phi = 0.0;
  ConditionNumber cond;
};
// Fig. 4.7: for each φ, the body with two modes — the vertical squash and the squash at angle φ
// (horizontal at φ = 0, vertical again at φ = π/2) — and cond(M) at state q.
std::vector<SweepSample> AngleSweep(const BodyDef& def, const std::vector<double>& phis, const Squash& squash,
                                    const Eigen::VectorXd& q);

// The sweep for a 3D body at rest (SquashMode's 3D squash).
std::vector<SweepSample> AngleSweep(const BodyDefN<3>& def, const std::vector<double>& phis, const Squash& squash);

// ---- how close the modes of a set are -----------------------------------------------------------

// One degree of freedom's share in a (near) dependency.
struct Participant {
  std::string dof;  // "translation x", "translation y", "rotation" or a mode's name
  double weight;    // signed, in the unit-free scaled coordinates; the largest has |weight| = 1
};

struct ModeFinding {
  std::string mode;
  // Mass-weighted RMS displacement at the mass points over the RMS displacement of the lattice
  // points: near 0 when the mass distribution cannot see the mode (§4.10.3, the vertical rod).
  double visibility = 0.0;
  // Angle between the mode's field and the span of every other degree of freedom (rigid motions
  // at the checked state and the other modes), under the mass inner product ⟨u, v⟩ = Σ m_k u_k·v_k.
  double angle_to_others_deg = 0.0;
  // The combination of other degrees of freedom that comes closest to it.
  std::vector<Participant> closest_combination;
};

struct ModeCheckOptions {
  double warn_angle_deg = 5.0;    // warn below this angle between a mode and the rest
  double warn_visibility = 0.05;  // warn when a mode moves this little of its lattice motion
};

struct ModeSetReport {
  enum class Level { kOk, kWarning, kError };
  Level level = Level::kOk;
  std::vector<std::string> messages;  // one line each, most severe first
  std::vector<std::string> dofs;      // "translation x", "translation y", "rotation", modes...
  // Angles between pairs of modes' displacement fields (degrees, D x D, 0..90; the sign of a
  // mode is arbitrary so parallel and anti-parallel are both 0).
  Eigen::MatrixXd pair_angle_deg;
  std::vector<ModeFinding> modes;
  // The closest dependency of the whole set: the smallest angle, the mode it belongs to, and
  // the combination it is nearly equal to.
  double smallest_angle_deg = 90.0;
  std::string smallest_mode;
  ConditionNumber condition;  // of M at the checked state
};
// Checks the body's mode set at state q (rest when q is empty).
ModeSetReport CheckModeSet(const BodyModel& body, const Eigen::VectorXd& q = Eigen::VectorXd(),
                           const ModeCheckOptions& options = {});
// The same check for a 3D body at rest (dofs: translations x, y, z, rotations x, y, z, modes).
ModeSetReport CheckModeSet(const BodyModelN<3>& body, const ModeCheckOptions& options = {});
std::string LevelName(ModeSetReport::Level level);

}  // namespace wobble::analysis
