// The per-body fast path of the World (no constraint enabled): one FFD body stepped by the
// templated StepBody, its checks, and its ground contacts. In a file of its own, as it was
// before the worlds were merged, so that the compiler inlines the contact scan into the step
// as it did then (measured with callgrind on BM_TableRestingOnGround: in the larger world.cc
// GCC kept ForEachPointInContact out of line, 10 % more instructions per step).
#include <sstream>
#include <stdexcept>

#include "wobble/world/world.h"

#include "wobble/core/errors.h"

namespace wobble {

void World::SetState(int i, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  FfdEntry& e = Ffd(i);
  const int nq = e.model->num_q();
  if (q.size() != nq || qd.size() != nq)
    throw InputError("body '" + e.model->name() + "' has " + std::to_string(nq) +
                                " generalized coordinates (tx ty theta and one per mode), got q of " +
                                std::to_string(q.size()) + " and qdot of " + std::to_string(qd.size()));
  if (!q.allFinite() || !qd.allFinite())
    throw InputError("body '" + e.model->name() + "': the state must be finite");
  const VecQ<double> q_before = e.state.q, qd_before = e.state.qd;
  e.state.q = q;
  e.state.qd = qd;
  UpdateContacts(*e.model, options_.params.ground, &e.state);
  if (EnergyFinite(i)) return;
  const std::string terms = EnergyTerms(FfdEnergies(i, ContactSet::kDetect, false));
  e.state.q = q_before;
  e.state.qd = qd_before;
  UpdateContacts(*e.model, options_.params.ground, &e.state);
  throw InputError("body '" + e.model->name() + "': a state whose energy is not finite (" + terms + ")");
}

namespace {
// The point forces of ApplyPointForce as StepBody's extra generalized force; none (null) on
// almost every step. One functor type for both cases: one instantiation of the step.
struct AppliedForce {
  const Eigen::VectorXd* force = nullptr;
  void operator()(const BodyState<2, double>&, VecQ<double>* Q) const {
    if (force) *Q += *force;
  }
};
}  // namespace

bool World::StepFfdBody(int body) {
  FfdEntry& e = ffd_[slots_[body].index];
  BodyState<2, double>& s = e.state;
  const VecQ<double> q_before = s.q, qd_before = s.qd;
  const bool pushed = !e.applied.isZero(0.0);
  const StepStatus st = StepBody(*e.model, options_.params, body, options_.integrator, options_.dt, &s,
                                 AppliedForce{pushed ? &e.applied : nullptr});
  if (pushed) e.applied.setZero();
  // the screen implies a finite state; past it, the state and the energies are checked in full
  if (st.ok() && s.penetration <= PenetrationLimit(*e.model) &&
      (EnergySurelyFinite(e) || (s.q.allFinite() && s.qd.allFinite() && EnergyFinite(body))))
    return true;
  return RefuseFfdStep(body, q_before, qd_before, st);
}

// Refuses a step that failed, left a non-finite state or energy, or sank a point too deep; the
// body keeps its state before the step for whoever reports the failure.
bool World::RefuseFfdStep(int body, const VecQ<double>& q_before, const VecQ<double>& qd_before, StepStatus st) {
  FfdEntry& e = ffd_[slots_[body].index];
  BodyState<2, double>& s = e.state;
  const bool finite = s.q.allFinite() && s.qd.allFinite();
  const double limit = PenetrationLimit(*e.model);
  const double depth = s.penetration;
  const bool too_deep = depth > limit;
  const Energies energies = finite && !too_deep ? FfdEnergies(body, ContactSet::kFrozen, false) : Energies();
  s.q = q_before;
  s.qd = qd_before;
  UpdateContacts(*e.model, options_.params.ground, &s);
  // a state that overflowed because its forces did: the force is the cause to name (the step
  // reports only that its state is not finite)
  if (!st.ok() && st.code != StatusCode::kNonFinite) return Fail(st.code, body, "", st.value);
  if (!finite) return ForcesFinite(body) ? Fail(StatusCode::kNonFinite, body) : Fail(StatusCode::kOverflowingForce, body);
  if (!too_deep)
    return Fail(StatusCode::kNonFiniteEnergy, body, EnergyTerms(energies) + " after the step (refused: the state is the one before it)");
  std::ostringstream d;
  d << "a point is " << depth << " below the ground (limit " << limit
    << "); reduce dt, or use a stiffer ground with the implicit integrator";
  return Fail(StatusCode::kPenetration, body, d.str(), depth);
}

bool World::ForcesFinite(int body) const {
  const FfdEntry& e = ffd_[slots_[body].index];
  ForceBreakdown<2, double> f;
  EvaluateForces(*e.model, options_.params, body, e.state, Frame<2, double>(e.state.q), &f, ContactSet::kDetect);
  return f.total.allFinite();
}

std::string EnergyTerms(const Energies& e) {
  std::ostringstream d;
  d << "kinetic " << e.kinetic << ", gravity " << e.gravity << ", modes " << e.modes << ", ground " << e.ground
    << ", springs " << e.springs;
  return d.str();
}

void World::RefreshContacts(FfdEntry& e) const { UpdateContacts(*e.model, options_.params.ground, &e.state); }

double World::PenetrationLimit(const BodyModel& model) const {
  const Ground& g = options_.params.ground;
  if (g.max_penetration > 0) return g.max_penetration;
  const Lattice& lat = model.lattice();
  return 0.5 * std::min(lat.axis_s().norm(), lat.axis_t().norm());
}

}  // namespace wobble
