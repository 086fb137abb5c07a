// The mode forces of the fits and of the adjoint (not public): the body's own mode potentials
// switched off (BodyModelN::WithoutModeGains) and replaced by StepBody's extra generalized
// force, whose gains and PD targets are of the scalar type being differentiated (Jets, double).
#pragma once

#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/step.h"

namespace wobble::fit {

template <class T> struct ModeParams {
  VecD<T> K, c;
};

// StepBody's extra generalized force: the mode forces −2K_d (γ_d − γ0_d) − c_d γ̇_d (§4.7, and
// the PD controller of chapter 5) with K, c and γ0 of scalar T; the body's own are switched off.
template <class T> struct ModeForce {
  const ModeParams<T>* p;
  const VecD<T>* target;
  template <int Dim> void operator()(const BodyState<Dim, T>& s, VecQ<T>* Q) const {
    constexpr int kRigid = Group<Dim>::kRigidDofs, kRigidParams = Group<Dim>::kRigidParams;
    for (int d = 0; d < p->K.size(); ++d)
      (*Q)[kRigid + d] += -T(2.0) * p->K[d] * (s.q[kRigidParams + d] - (*target)[d]) - p->c[d] * s.qd[kRigid + d];
  }
};

}  // namespace wobble::fit
