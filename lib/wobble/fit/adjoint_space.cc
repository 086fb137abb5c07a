// The 3D body's step piece of the adjoint (adjoint.h): internal::AdjointStep<3>, whose product
// is the hand-derived one of internal/step_vjp_space.h, kept on the forward step's tape.
#include <cmath>
#include <stdexcept>
#include <vector>

#include "wobble/fit/adjoint.h"
#include "wobble/fit/internal/adjoint_sweep.h"
#include "wobble/fit/internal/mode_force.h"
#include "wobble/fit/internal/step_vjp_space.h"

namespace wobble::fit {

namespace internal {

// The rollout's step, plain and differentiated (internal/step_vjp_space.h), on the body with
// its own mode forces off (adjoint_sweep.h says what a piece holds).
template <> class AdjointStep<3> {
 public:
  static constexpr const char* kWhat = "3D rollout";
  static constexpr bool kTaped = true;
  using Tape = StepTape;

  template <class Fail> static void CheckStartSizes(const BodyModelN<3>& body, const BodyState<3, double>& s, Fail fail) {
    const int D = body.num_modes();
    if (s.gamma().size() != D || s.qd.size() != body.num_q())
      fail("the start needs " + std::to_string(D) + " mode amplitudes and " + std::to_string(body.num_q()) +
           " velocities (t dot, omega, gamma dot)");
  }
  static bool StartFinite(const BodyState<3, double>& s) {
    return s.translation().allFinite() && s.gamma().allFinite() && s.qd.allFinite() &&
           std::isfinite(s.orientation().norm());
  }
  template <class Fail> static void CheckStartValid(const BodyState<3, double>& s, Fail fail) {
    if (!(s.orientation().norm() > 1e-12)) fail("the orientation quaternion must not be zero");
  }
  // a kept step: its state and its tape (which holds two more), with the start's number of
  // contacts in each (an estimate)
  static size_t StepBytes(const BodyState<3, double>& start) {
    return sizeof(StepTape) + sizeof(start) + 3 * start.contacts.size() * sizeof(Contact<3, double>);
  }

  AdjointStep(const BodyModelN<3>& body, const ControlledRolloutN<3>& r) : passive_(body.WithoutModeGains()), r_(r) {
    params_.K = r.stiffness;
    params_.c = r.damping;
  }

  BodyState<3, double> Start() const {
    BodyState<3, double> s;
    s.q = r_.start.q;
    Group<3>::Normalize(&s.q);
    s.qd = r_.start.qd;
    UpdateContacts(passive_, r_.world.ground_plane, &s);
    return s;
  }

  bool Advance(int n, BodyState<3, double>* s, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st =
        StepBody(passive_, r_.world, 0, r_.integrator, r_.dt, s, ModeForce<double>{&params_, &target});
    if (!st.ok()) return StepFailed(n, StatusCodeName(st.code), why);
    return true;
  }

  // Step n from *s like Advance, keeping its tape for Vjp.
  bool Record(int n, BodyState<3, double>* s, StepTape* tape, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st = RecordStep(Model(), target, *s, tape, s);
    if (!st.ok()) return StepFailed(n, StatusCodeName(st.code), why);
    return true;
  }

  // λ_n from λ_{n+1} = `out` through step n from state s, whose tape is `tape` (null: taken
  // again here); adds the step's part of the gains' gradient to *g and sets its targets' column.
  bool Vjp(int n, const BodyState<3, double>& s, const BodyState<3, double>&, const StepTape* tape,
           const StateAdjoint<3>& out, StateAdjoint<3>* in, RolloutGradient* g, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    StepTape fresh;
    if (!tape) {
      BodyState<3, double> next;
      const StepStatus st = RecordStep(Model(), target, s, &fresh, &next);
      if (!st.ok()) return StepFailed(n, StatusCodeName(st.code) + " (differentiated step)", why);
      tape = &fresh;
    }
    ControlAdjoint controls{{}, &g->stiffness, &g->damping};
    StepVjp(Model(), target, s, *tape, out, in, &controls);
    g->targets.col(n) = controls.target;
    return true;
  }

  // The first state's anchors come from its contact update (a point below the ground at the
  // start is anchored at its foot): their adjoint passes on to the start state.
  void StartVjp(const StateAdjoint<3>& start, Eigen::VectorXd* dz0) const {
    if (!start.anchor.empty()) StartContactsVjp(passive_, r_.world.ground_plane, Start(), start.anchor, dz0);
  }

 private:
  StepModel Model() const { return {passive_, r_.world, r_.integrator, r_.dt, params_}; }

  const BodyModelN<3> passive_;
  const ControlledRolloutN<3>& r_;
  ModeParams<double> params_;
};

}  // namespace internal

template <>
double RolloutCost<3>(const BodyModelN<3>& body, const ControlledRolloutN<3>& rollout, const StageCostN<3>& cost) {
  return internal::RolloutCostOf<internal::AdjointStep<3>>(body, rollout, cost);
}

template <>
RolloutGradient RolloutCostGradient<3>(const BodyModelN<3>& body, const ControlledRolloutN<3>& rollout,
                                       const StageCostN<3>& cost, int checkpoint_interval) {
  return internal::RolloutGradientOf<internal::AdjointStep<3>>(body, rollout, cost, checkpoint_interval);
}

}  // namespace wobble::fit
