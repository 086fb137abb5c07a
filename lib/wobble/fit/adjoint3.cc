#include "wobble/fit/adjoint3.h"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "wobble/fit/internal/adjoint_sweep.h"
#include "wobble/fit/internal/mode_force.h"
#include "wobble/fit/internal/step3_vjp.h"

namespace wobble::fit {

namespace {

using internal::StateAdjoint3;

void CheckRollout3(const BodyModel3& body, const ControlledRollout3& r) {
  const int D = body.num_modes();
  auto fail = [](const std::string& what) { throw std::invalid_argument("3D rollout: " + what); };
  if (r.integrator != Integrator::kThesis && r.integrator != Integrator::kSymplecticEuler)
    fail("the adjoint takes the thesis and symplectic integrators, not " + IntegratorName(r.integrator));
  if (!(r.dt > 0.0) || !std::isfinite(r.dt)) fail("dt must be positive and finite");
  if (r.start.gamma().size() != D || r.start.qd.size() != body.num_q())
    fail("the start needs " + std::to_string(D) + " mode amplitudes and " + std::to_string(body.num_q()) +
         " velocities (t dot, omega, gamma dot)");
  if (r.stiffness.size() != D || r.damping.size() != D) fail("stiffness and damping need one value per mode");
  if (r.targets.rows() != D) fail("targets need one row per mode (" + std::to_string(D) + ")");
  const double q_norm = r.start.orientation().norm();
  if (!r.start.translation().allFinite() || !r.start.gamma().allFinite() || !r.start.qd.allFinite() || !std::isfinite(q_norm) ||
      !r.stiffness.allFinite() || !r.damping.allFinite() || !r.targets.allFinite())
    fail("every number must be finite");
  if (!(q_norm > 1e-12)) fail("the orientation quaternion must not be zero");
}

// The rollout's step, plain and differentiated (internal/step3_vjp.h), on the body with its
// own mode forces off.
class Rollout3 {
 public:
  Rollout3(const BodyModel3& body, const ControlledRollout3& r) : passive_(body.WithoutModeGains()), r_(r) {
    params_.K = r.stiffness;
    params_.c = r.damping;
  }
  int modes() const { return passive_.num_modes(); }
  int tangent() const { return StateTangentSize3(passive_); }

  BodyState<3, double> Start() const {
    BodyState<3, double> s;
    s.q = r_.start.q;
    Group<3>::Normalize(&s.q);
    s.qd = r_.start.qd;
    UpdateContacts(passive_, r_.world.ground, &s);
    return s;
  }

  bool Step(int n, BodyState<3, double>* s, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st =
        StepBody(passive_, r_.world, 0, r_.integrator, r_.dt, s, ModeForce<double>{&params_, &target});
    if (!st.ok()) return internal::StepFailed(n, StatusCodeName(st.code), why);
    return true;
  }

  // Step n from *s like Step, keeping its tape (internal/step3_vjp.h) for StepVjp.
  bool Record(int n, BodyState<3, double>* s, internal::StepTape3* tape, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st = internal::RecordStep3(Model(), target, *s, tape, s);
    if (!st.ok()) return internal::StepFailed(n, StatusCodeName(st.code), why);
    return true;
  }

  // λ_n from λ_{n+1} = `out` through step n from state s, whose tape is `tape` (null: taken
  // again here); adds the step's part of the gains' gradient to *g and sets its targets' column.
  bool StepVjp(int n, const BodyState<3, double>& s, const internal::StepTape3* tape, const StateAdjoint3& out,
               StateAdjoint3* in, RolloutGradient3* g, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    internal::StepTape3 fresh;
    if (!tape) {
      BodyState<3, double> next;
      const StepStatus st = internal::RecordStep3(Model(), target, s, &fresh, &next);
      if (!st.ok()) return internal::StepFailed(n, StatusCodeName(st.code) + " (differentiated step)", why);
      tape = &fresh;
    }
    internal::ControlAdjoint3 controls{{}, &g->stiffness, &g->damping};
    internal::StepVjp3(Model(), target, s, *tape, out, in, &controls);
    g->targets.col(n) = controls.target;
    return true;
  }

  // The first state's anchors come from its contact update (a point below the ground at the
  // start is anchored at its foot): their adjoint passes on to the start state.
  void StartVjp(const StateAdjoint3& start, Eigen::VectorXd* dz0) const {
    if (!start.anchor.empty()) internal::StartContactsVjp3(passive_, r_.world.ground, Start(), start.anchor, dz0);
  }

 private:
  internal::StepModel3 Model() const { return {passive_, r_.world, r_.integrator, r_.dt, params_}; }

  const BodyModel3 passive_;
  const ControlledRollout3& r_;
  ModeParams<double> params_;
};

}  // namespace

int StateTangentSize3(const BodyModel3& body) { return 12 + 2 * body.num_modes(); }

double RolloutCost3(const BodyModel3& body, const ControlledRollout3& rollout, const StageCost3& cost) {
  CheckRollout3(body, rollout);
  const Rollout3 r(body, rollout);
  Eigen::VectorXd dz(r.tangent());
  std::string why;
  return internal::PlainRolloutCost(
      rollout.steps(), r.Start(), [&](int n, BodyState<3, double>* s) { return r.Step(n, s, &why); },
      [&](int n, const BodyState<3, double>& s) {
        dz.setZero();
        return cost(n, s, &dz);
      });
}

RolloutGradient3 RolloutCostGradient3(const BodyModel3& body, const ControlledRollout3& rollout, const StageCost3& cost,
                                      int checkpoint_interval) {
  CheckRollout3(body, rollout);
  const Rollout3 r(body, rollout);
  const int D = r.modes(), nz = r.tangent(), N = rollout.steps();
  RolloutGradient3 g;
  g.stiffness = Eigen::VectorXd::Zero(D);
  g.damping = Eigen::VectorXd::Zero(D);
  g.targets = Eigen::MatrixXd::Zero(D, N);
  Eigen::VectorXd dz(nz);
  auto stage = [&](int n, const BodyState<3, double>& s, StateAdjoint3* lambda) {
    dz.setZero();
    g.cost += cost(n, s, &dz);
    lambda->z += dz;
  };
  auto step = [&](int n, BodyState<3, double>* s) { return r.Step(n, s, &g.message); };
  // The recompute of an interval keeps each step's tape (slot n mod interval; `taped` says
  // which step a slot holds), so the product does not evaluate the step a third time: about
  // one simulation less per gradient (the interval's last step has none and is taken again,
  // except when the interval is the whole run, whose forward run keeps every tape).
  const BodyState<3, double> start = r.Start();
  // a kept step: its state and its tape (which holds two more), with the start's number of
  // contacts in each (an estimate)
  const size_t step_bytes =
      sizeof(internal::StepTape3) + sizeof(start) + 3 * start.contacts.size() * sizeof(Contact<3, double>);
  const int interval = CheckpointInterval(N, checkpoint_interval, step_bytes);
  std::vector<internal::StepTape3> tapes(size_t(std::min(interval, std::max(N, 1))));
  std::vector<int> taped(tapes.size(), -1);
  auto recompute = [&](int n, BodyState<3, double>* s) {
    const size_t slot = size_t(n % int(tapes.size()));
    taped[slot] = n;
    return r.Record(n, s, &tapes[slot], &g.message);
  };
  auto vjp = [&](int n, const BodyState<3, double>& state, const BodyState<3, double>&, const StateAdjoint3& out,
                 StateAdjoint3* in) {
    const size_t slot = size_t(n % int(tapes.size()));
    return r.StepVjp(n, state, taped[slot] == n ? &tapes[slot] : nullptr, out, in, &g, &g.message);
  };
  StateAdjoint3 lambda{Eigen::VectorXd::Zero(nz), {}};
  if (!internal::CheckpointedAdjointSweep(N, interval, start, &lambda, step, recompute, vjp, stage,
                                          &g.states_held))
    return g;
  g.start = lambda.z;
  r.StartVjp(lambda, &g.start);
  if (!std::isfinite(g.cost)) {
    g.message = "the cost is not finite";
    return g;
  }
  g.ok = true;
  return g;
}

}  // namespace wobble::fit
