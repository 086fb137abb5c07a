// The 3D body's piece of the adjoint (adjoint.h): its per-step vector–Jacobian product, derived
// by hand (not public; adjoint_space.cc puts it behind internal::AdjointStep<3>).
//
// A step of StepBody<3> (thesis or symplectic integrator) maps a state s, its contacts' anchors A
// and the step's controls u = (PD targets, K, c) to s' and A'. Given λ' = ∂cost/∂(s', A'), this
// gives ∂cost/∂(s, A, u) = (∂(s', A')/∂(s, A, u))ᵀ λ' in the tangent coordinates of adjoint.h,
// for about the price of two plain steps, whatever the number of contacts:
//  - the mass solve a = M⁻¹ (Q − w) is pulled back through one solve λ_r = M⁻¹ λ_a and the
//    scalar ψ = λ_rᵀ (Q − w − M a) at fixed a and λ_r, whose gradient is that of λ_aᵀ a;
//  - ψ's mass-moment terms (M, w, gravity: spatial_inertia.h) are differentiated by hand, in O(D²)
//    whatever the number of mass points;
//  - a contact's force (Eq. 4.24/4.25: its one-sided normal force and capped friction) and its
//    anchor's update (SlipAnchor) by their partials in the point's x, ẋ and anchor, from the
//    parts the forward force keeps (GroundForcePartsOf), and a spring's the same way; x and ẋ
//    are pulled back to the state by x = t + R l, ẋ = ṫ + R (ω × l + B γ̇);
//  - the turn R' = R exp(Δt ω̂) moves ε by exp(−Δt ω̂) and ω by Δt J_r(Δt ω) (rotation3.h).
// tests/adjoint3_test.cc checks whole runs against forward-mode Jets and central differences.
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <utility>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/spatial_inertia.h"
#include "wobble/dynamics/step.h"
#include "wobble/fit/internal/adjoint_sweep.h"
#include "wobble/fit/internal/mode_force.h"

namespace wobble::fit::internal {

// What a step is: the body (its own mode gains off), the world, the integrator, the step and
// the mode forces' gains.
struct StepModel {
  const BodyModelN<3>& passive;
  const WorldParams& world;
  Integrator integrator;  // kThesis or kSymplecticEuler
  double dt;
  const ModeParams<double>& gains;
};

// ∂cost/∂(one step's controls).
struct ControlAdjoint {
  VecD<double> target;                  // this step's PD targets (set)
  Eigen::VectorXd *stiffness, *damping;  // the gains' (added to, across steps)
};

// What the product needs of the forward step from s (StepBody<3>'s thesis or symplectic step,
// the same operations in the same order): where the accelerations were evaluated, the frame and
// shape moments there, the accelerations, and the state after the step before its contact
// update. The adjoint's recompute keeps one per step of an interval, so the product does not
// evaluate the step's forces a second time.
struct StepTape {
  BodyState<3, double> eval, after;
  std::optional<Frame<3, double>> frame;
  std::optional<ShapeMoments<double>> moments;
  SpatialMassFactor<double> factor;  // the step's elimination about the centre of mass (spatial_inertia.h)
  VecQ<double> a;
};

// One step from s with PD targets `target`, as StepBody<3> takes it, keeping its tape: *next is
// StepBody<3>'s result (contacts updated). Fails as StepBody<3> does.
StepStatus RecordStep(const StepModel& m, const VecD<double>& target, const BodyState<3, double>& s,
                       StepTape* tape, BodyState<3, double>* next);

// in = λ of state s from out = λ of the state after the step taken from s with PD targets
// `target` (whose tape RecordStep kept); adds the gains' part to controls->stiffness/damping
// and sets controls->target.
void StepVjp(const StepModel& m, const VecD<double>& target, const BodyState<3, double>& s, const StepTape& tape,
              const StateAdjoint<3>& out, StateAdjoint<3>* in, ControlAdjoint* controls);

// The start's contact update (UpdateContacts on `s`, whose contacts are ignored): adds the
// part of ∂cost/∂z that reaches s through the anchors it gives.
void StartContactsVjp(const BodyModelN<3>& passive, const GroundPlane& ground, BodyState<3, double> s,
                       const std::map<ContactKey, Eigen::Vector3d>& anchor, Eigen::VectorXd* dz);

}  // namespace wobble::fit::internal
