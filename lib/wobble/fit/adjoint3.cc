#include "wobble/fit/adjoint3.h"

#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

#include "wobble/core/rotation3.h"
#include "wobble/fit/internal/adjoint_sweep.h"
#include "wobble/fit/internal/mode_force.h"

namespace wobble::fit {

namespace {

using internal::Pull;
using internal::Seed;
using Jet = internal::AdjointJet;
constexpr int kChunk = internal::kAdjointChunk;

using ContactKey = std::pair<int, int>;  // (point, face): a contact's identity across steps

// λ of one state: ∂cost/∂z (tangent coordinates) and ∂cost/∂(each contact's anchor).
struct Adjoint3 {
  Eigen::VectorXd z;
  std::map<ContactKey, Eigen::Vector3d> anchor;
};

void CheckRollout3(const BodyModel3& body, const ControlledRollout3& r) {
  const int D = body.num_modes();
  auto fail = [](const std::string& what) { throw std::invalid_argument("3D rollout: " + what); };
  if (r.integrator != Integrator::kThesis && r.integrator != Integrator::kSymplecticEuler)
    fail("the adjoint takes the thesis and symplectic integrators, not " + IntegratorName(r.integrator));
  if (!(r.dt > 0.0) || !std::isfinite(r.dt)) fail("dt must be positive and finite");
  if (r.start.gamma.size() != D || r.start.v.size() != body.num_q())
    fail("the start needs " + std::to_string(D) + " mode amplitudes and " + std::to_string(body.num_q()) +
         " velocities (t dot, omega, gamma dot)");
  if (r.stiffness.size() != D || r.damping.size() != D) fail("stiffness and damping need one value per mode");
  if (r.targets.rows() != D) fail("targets need one row per mode (" + std::to_string(D) + ")");
  const double q_norm = r.start.orientation.norm();
  if (!r.start.t.allFinite() || !r.start.gamma.allFinite() || !r.start.v.allFinite() || !std::isfinite(q_norm) ||
      !r.stiffness.allFinite() || !r.damping.allFinite() || !r.targets.allFinite())
    fail("every number must be finite");
  if (!(q_norm > 1e-12)) fail("the orientation quaternion must not be zero");
}

// The rollout's step, plain and differentiated, on the body with its own mode forces off.
class Rollout3 {
 public:
  Rollout3(const BodyModel3& body, const ControlledRollout3& r) : passive_(body.WithoutModeGains()), r_(r) {
    params_.K = r.stiffness;
    params_.c = r.damping;
  }
  int modes() const { return passive_.num_modes(); }
  int tangent() const { return StateTangentSize3(passive_); }

  BodyState3<double> Start() const {
    BodyState3<double> s;
    s.t = r_.start.t;
    s.orientation = r_.start.orientation.normalized();
    s.gamma = r_.start.gamma;
    s.v = r_.start.v;
    UpdateContacts3(passive_, r_.world.ground, &s);
    return s;
  }

  bool Step(int n, BodyState3<double>* s, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st =
        StepBody3(passive_, r_.world, r_.integrator, r_.dt, s, ModeForce<double>{&params_, &target});
    if (!st.ok()) return internal::StepFailed(n, StatusCodeName(st.code), why);
    return true;
  }

  // λ_n from λ_{n+1} = `out` through step n from state s; adds the step's part of the gains'
  // gradient to *g and sets its targets' column.
  bool StepVjp(int n, const BodyState3<double>& s, const Adjoint3& out, Adjoint3* in, RolloutGradient3* g,
               std::string* why) const {
    const int D = modes(), nz = tangent(), nc = int(s.contacts.size());
    const int controls = nz + 3 * nc, width = controls + 3 * D;
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(width);
    for (int offset = 0; offset < width; offset += kChunk) {
      BodyState3<Jet> sj = Seeded(s, offset);
      ModeParams<Jet> mp;
      mp.K.resize(D);
      mp.c.resize(D);
      VecD<Jet> target(D);
      for (int d = 0; d < D; ++d) {
        target[d] = Seed(r_.targets(d, n), controls + d, offset);
        mp.K[d] = Seed(params_.K[d], controls + D + d, offset);
        mp.c[d] = Seed(params_.c[d], controls + 2 * D + d, offset);
      }
      const StepStatus st = StepBody3(passive_, r_.world, r_.integrator, r_.dt, &sj, ModeForce<Jet>{&mp, &target});
      if (!st.ok()) return internal::StepFailed(n, StatusCodeName(st.code) + " (differentiated step)", why);
      PullState(sj, out, offset, &grad);
    }
    in->z = grad.head(nz);
    in->anchor.clear();
    for (int c = 0; c < nc; ++c)
      in->anchor[{s.contacts[size_t(c)].point, s.contacts[size_t(c)].face}] = grad.segment(nz + 3 * c, 3);
    g->targets.col(n) = grad.segment(controls, D);
    g->stiffness += grad.segment(controls + D, D);
    g->damping += grad.segment(controls + 2 * D, D);
    return true;
  }

  // The first state's anchors come from its contact update (a point below the ground at the
  // start is anchored at its foot): their adjoint passes on to the start state.
  void StartVjp(const Adjoint3& start, Eigen::VectorXd* dz0) const {
    if (start.anchor.empty()) return;
    const int nz = tangent();
    Adjoint3 anchors_only{Eigen::VectorXd::Zero(nz), start.anchor};
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(nz);
    BodyState3<double> plain = Start();
    plain.contacts.clear();
    for (int offset = 0; offset < nz; offset += kChunk) {
      BodyState3<Jet> sj = Seeded(plain, offset);
      UpdateContacts3(passive_, r_.world.ground, &sj);
      PullState(sj, anchors_only, offset, &grad);
    }
    *dz0 += grad;
  }

 private:
  // s with its tangent coordinates z (inputs 0 … nz − 1) and its contacts' anchors (3 each,
  // from nz on) seeded for the chunk at `offset`: the orientation as R exp(ε̂) at ε = 0.
  BodyState3<Jet> Seeded(const BodyState3<double>& s, int offset) const {
    const int D = modes();
    BodyState3<Jet> sj;
    Vec3<Jet> epsilon;
    for (int i = 0; i < 3; ++i) {
      sj.t[i] = Seed(s.t[i], i, offset);
      epsilon[i] = Seed(0.0, 3 + i, offset);
    }
    sj.orientation = s.orientation.cast<Jet>() * ExpRotation<Jet>(epsilon);
    sj.gamma.resize(D);
    for (int d = 0; d < D; ++d) sj.gamma[d] = Seed(s.gamma[d], 6 + d, offset);
    sj.v.resize(s.v.size());
    for (int i = 0; i < s.v.size(); ++i) sj.v[i] = Seed(s.v[i], 6 + D + i, offset);
    const int nz = tangent();
    sj.contacts.resize(s.contacts.size());
    for (size_t c = 0; c < s.contacts.size(); ++c) {
      sj.contacts[c].point = s.contacts[c].point;
      sj.contacts[c].face = s.contacts[c].face;
      for (int k = 0; k < 3; ++k) sj.contacts[c].anchor[k] = Seed(s.contacts[c].anchor[k], nz + 3 * int(c) + k, offset);
    }
    return sj;
  }

  // g += (∂(state)/∂(chunk inputs))ᵀ λ over every output of a step; the orientation's output is
  // its tangent coordinate ε' = log(R'ᵀ R'(inputs)) about its own value.
  static void PullState(const BodyState3<Jet>& s, const Adjoint3& lambda, int offset, Eigen::VectorXd* g) {
    const int D = int(s.gamma.size());
    const Eigen::Quaterniond value(s.orientation.w().a, s.orientation.x().a, s.orientation.y().a,
                                   s.orientation.z().a);
    const Vec3<Jet> epsilon = LogRotation<Jet>(Eigen::Quaternion<Jet>(value.conjugate().cast<Jet>() * s.orientation));
    for (int i = 0; i < 3; ++i) {
      Pull(s.t[i], lambda.z[i], offset, g);
      Pull(epsilon[i], lambda.z[3 + i], offset, g);
    }
    for (int d = 0; d < D; ++d) Pull(s.gamma[d], lambda.z[6 + d], offset, g);
    for (int i = 0; i < s.v.size(); ++i) Pull(s.v[i], lambda.z[6 + D + i], offset, g);
    for (const Contact3<Jet>& c : s.contacts) {
      const auto it = lambda.anchor.find({c.point, c.face});
      if (it == lambda.anchor.end()) continue;
      for (int k = 0; k < 3; ++k) Pull(c.anchor[k], it->second[k], offset, g);
    }
  }


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
      rollout.steps(), r.Start(), [&](int n, BodyState3<double>* s) { return r.Step(n, s, &why); },
      [&](int n, const BodyState3<double>& s) {
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
  auto stage = [&](int n, const BodyState3<double>& s, Adjoint3* lambda) {
    dz.setZero();
    g.cost += cost(n, s, &dz);
    lambda->z += dz;
  };
  auto step = [&](int n, BodyState3<double>* s) { return r.Step(n, s, &g.message); };
  auto vjp = [&](int n, const BodyState3<double>& state, const BodyState3<double>&, const Adjoint3& out, Adjoint3* in) {
    return r.StepVjp(n, state, out, in, &g, &g.message);
  };
  Adjoint3 lambda{Eigen::VectorXd::Zero(nz), {}};
  if (!internal::CheckpointedAdjointSweep(N, internal::CheckpointInterval(N, checkpoint_interval), r.Start(), &lambda,
                                          step, vjp, stage, &g.states_held))
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
