// Potential energies of linear bodies (§2.4), with their gradients ∂V/∂R.
//
// m = the first d columns of R (the deformation gradient at u = 0; for an affine body the whole
// linear part, §2.3):
//   rigidity   V_e = k_e |mᵀm − I|²_F           ∂V_e/∂m = 4 k_e m (mᵀm − I)
//   volume     V_c = k_c (det m − 1)²           ∂V_c/∂m = 2 k_c (det m − 1) cof(m)
//   bending    V_q = k_q Σ (quadratic columns of R)²   (ours: pulls a quadratic body back to
//              its affine shape; the paper leaves a quadratic body's energy open)
// and the damping force of §2.4, Q = −k_d V̇ ∂V/∂R with V̇ = ⟨∂V/∂R, Ṙ⟩, which removes energy
// at the rate k_d V̇² and vanishes at rest. Both energies are zero and stationary exactly at
// rotations (mᵀm = I, det m = 1), whatever the translation.
#pragma once

#include <Eigen/Core>

#include "wobble/body/linear_body.h"

namespace wobble {

// Stiffness and drag constants: from near-rigid (large k_e, k_c) to jello (small, with k_d).
struct AffineMaterial {
  double rigidity = 0.0;   // k_e
  double volume = 0.0;     // k_c
  double damping = 0.0;    // k_d (multiplies V̇ ∂V/∂R)
  double bending = 0.0;    // k_q, quadratic columns only
};

// V_e + V_c + V_q at R (d×n, d = 2 or 3, n ≥ d + 1).
double AffineEnergy(const AffineMaterial& mat, const Eigen::MatrixXd& R);
// ∂(V_e + V_c + V_q)/∂R, same shape as R.
Eigen::MatrixXd AffineEnergyGradient(const AffineMaterial& mat, const Eigen::MatrixXd& R);
// The generalized force of the energies with their damping: −∂V/∂R − k_d V̇ ∂V/∂R.
Eigen::MatrixXd AffineForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot);
// Q += AffineForce(mat, R, Ṙ) without heap allocations (the per-step form).
void AddAffineForce(const AffineMaterial& mat, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot, Eigen::MatrixXd* Q);

// Angular frequencies ω (ascending) of a linear body's small vibrations about its rest shape:
// H v = ω² (I_d ⊗ M) v, with H the Hessian of the energies at R = [I | 0 | 0] (central
// differences of the analytic gradient) in the row-major flattening of R. Rigid motions give 0.
Eigen::VectorXd VibrationFrequencies(const LinearBodyModel& model, const AffineMaterial& mat);
// A step the explicit integrator stays stable with: 1/ω_max (half the linear limit 2/ω_max,
// because V is quartic in R and stiffens under large deformation, and the damping term is
// explicit too). Infinity for a body without energies. Thin bodies are the stiff ones: their
// short axis carries little inertia.
double StableTimeStep(const LinearBodyModel& model, const AffineMaterial& mat);

}  // namespace wobble
