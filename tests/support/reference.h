// The direct per-point evaluation of the thesis' formulas, kept as the reference that the
// moment-based fast path (kinematics.h) is tested against. O(N·D²) per call: never use it
// in a step loop.
#pragma once

#include <Eigen/Core>

#include "wobble/body/body_model.h"

namespace wobble::reference {

using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;

// J_k = ∂x_k/∂q of mass point k (Eq. 4.6–4.8), 2 x nq.
Matrix Jacobian(const BodyModel& body, int k, const Vector& q);
// ∂J_k/∂q_j (Eq. 4.14–4.19), 2 x nq.
Matrix JacobianDerivative(const BodyModel& body, int k, const Vector& q, int j);
// M = Σ_k m_k J_kᵀ J_k (Eq. 4.10).
Matrix MassMatrix(const BodyModel& body, const Vector& q);
// ∂M/∂q_j = Σ_k m_k [(J_kᵀ ∂J_k/∂q_j)ᵀ + J_kᵀ ∂J_k/∂q_j] (Eq. 4.13).
Matrix MassMatrixDerivative(const BodyModel& body, const Vector& q, int j);
// The velocity-dependent terms moved to the left of Eq. 4.21:
//   w_k = (Σ_l ∂M_kj/∂q_l q̇_l) q̇_j − ½ q̇ᵀ (∂M/∂q_k) q̇, so that M q̈ = Q − w.
Vector VelocityTerms(const BodyModel& body, const Vector& q, const Vector& qd);
// Σ_k J_kᵀ (m_k g) (Eq. 4.20 applied to gravity, §4.7).
Vector GravityForce(const BodyModel& body, const Vector& q, const Eigen::Vector2d& g);

}  // namespace wobble::reference
