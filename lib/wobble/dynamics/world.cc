#include "wobble/dynamics/world.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace wobble {

std::string IntegratorName(Integrator integrator) {
  switch (integrator) {
    case Integrator::kThesis: return "thesis";
    case Integrator::kSymplecticEuler: return "symplectic";
    case Integrator::kRK4: return "rk4";
    case Integrator::kImplicitEuler: return "implicit";
    case Integrator::kVariational: return "variational";
  }
  return "?";
}

bool ParseIntegrator(const std::string& text, Integrator* integrator) {
  for (Integrator i : {Integrator::kThesis, Integrator::kSymplecticEuler, Integrator::kRK4, Integrator::kImplicitEuler,
                               Integrator::kVariational})
    if (IntegratorName(i) == text) {
      *integrator = i;
      return true;
    }
  return false;
}

std::string StatusCodeName(StepStatus::Code code) {
  switch (code) {
    case StepStatus::Code::kOk: return "ok";
    case StepStatus::Code::kNonFinite: return "non-finite state";
    case StepStatus::Code::kSingularMass: return "singular mass matrix";
    case StepStatus::Code::kIllConditioned: return "ill-conditioned mass matrix";
    case StepStatus::Code::kPenetration: return "runaway ground penetration";
    case StepStatus::Code::kSolverFailed: return "implicit solver did not converge";
  }
  return "?";
}

int World::AddBody(std::shared_ptr<const BodyModel> body) {
  BodyState<double> s;
  s.q.setZero(body->num_q());
  s.qd.setZero(body->num_q());
  bodies_.push_back(std::move(body));
  states_.push_back(std::move(s));
  return num_bodies() - 1;
}

void World::SetState(int i, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  const int nq = bodies_.at(i)->num_q();
  if (q.size() != nq || qd.size() != nq)
    throw std::invalid_argument("body '" + bodies_[i]->name() + "' has " + std::to_string(nq) +
                                " generalized coordinates (tx ty theta and one per mode), got q of " +
                                std::to_string(q.size()) + " and qdot of " + std::to_string(qd.size()));
  states_[i].q = q;
  states_[i].qd = qd;
  UpdateContacts(*bodies_[i], options_.params.ground, &states_[i]);
}

void World::SetModeTargets(int i, const Eigen::VectorXd& targets) {
  const int D = bodies_.at(i)->num_modes();
  if (targets.size() != 0 && targets.size() != D)
    throw std::invalid_argument("body '" + bodies_[i]->name() + "' has " + std::to_string(D) + " modes, got " +
                                std::to_string(targets.size()) + " targets");
  states_[i].mode_target = targets;
}

void World::AddSpring(Spring spring) {
  const BodyModel& b = *bodies_.at(spring.body);
  b.LocalBasis(spring.lattice_coords, &spring.rest_local, &spring.mode_matrix);
  options_.params.springs.push_back(std::move(spring));
}

double World::PenetrationLimit(int i) const {
  const Ground& g = options_.params.ground;
  if (g.max_penetration > 0) return g.max_penetration;
  const Lattice& lat = bodies_[i]->lattice();
  return 0.5 * std::min(lat.axis_s().norm(), lat.axis_t().norm());
}

bool World::Fail(int i, StepStatus st, const std::string& detail) {
  status_.code = st.code;
  status_.step = steps_ + 1;
  status_.time = time_;
  status_.body = i;
  std::ostringstream msg;
  msg << StatusCodeName(st.code) << " at step " << status_.step << " (t = " << time_ << ") in body '"
      << bodies_[i]->name() << "'";
  if (st.code == StepStatus::Code::kIllConditioned) msg << ": condition estimate " << st.value;
  if (!detail.empty()) msg << ": " << detail;
  status_.message = msg.str();
  return false;
}

bool World::Step() {
  if (!status_.ok()) return false;
  for (int i = 0; i < num_bodies(); ++i) {
    BodyState<double>& s = states_[i];
    const VecQ<double> q_before = s.q, qd_before = s.qd;
    const StepStatus st = StepBody(*bodies_[i], options_.params, i, options_.integrator, options_.dt, &s);
    const bool finite = s.q.allFinite() && s.qd.allFinite();
    if (!st.ok() || !finite || s.penetration > PenetrationLimit(i)) {
      // keep the last good state for whoever reports the failure
      const double depth = s.penetration;
      s.q = q_before;
      s.qd = qd_before;
      UpdateContacts(*bodies_[i], options_.params.ground, &s);
      if (!st.ok()) return Fail(i, st);
      if (!finite) return Fail(i, {StepStatus::Code::kNonFinite, 0.0});
      std::ostringstream d;
      d << "a point is " << depth << " below the ground (limit " << PenetrationLimit(i)
        << "); reduce dt, or use a stiffer ground with the implicit integrator";
      return Fail(i, {StepStatus::Code::kPenetration, depth}, d.str());
    }
  }
  ++steps_;
  time_ = time_origin_ + steps_ * options_.dt;
  status_.step = steps_;
  status_.time = time_;
  return true;
}

Energies World::ComputeEnergies(int i) const {
  const BodyModel& b = *bodies_[i];
  const BodyState<double>& s = states_[i];
  const WorldParams& p = options_.params;
  Energies e;
  MatQ<double> M;
  MassMatrix(b.moments(), s.q, &M);
  e.kinetic = 0.5 * s.qd.dot(M * s.qd);  // Eq. 4.9
  if (p.gravity_on) e.gravity = GravityEnergy(b.moments(), s.q, p.gravity);
  // K (γ − γ0)²: the potential whose gradient is the mode force, PD target γ0 included
  const bool targeted = s.mode_target.size() == b.num_modes();
  for (int d = 0; d < b.num_modes(); ++d) {
    const double offset = s.q[kRigidDofs + d] - (targeted ? s.mode_target[d] : 0.0);
    e.per_mode.push_back(b.modes()[d].stiffness * offset * offset);
    e.modes += e.per_mode.back();
  }
  ForEachPointInContact(b, p.ground, s, Frame<double>(s.q), [&](int, const Vec2<double>&, const Vec2<double>& x, const Vec2<double>&,
                                            const Vec2<double>& anchor) {
    e.ground += 0.5 * p.ground.stiffness * (x - anchor).squaredNorm();
  });
  for (const Spring& sp : p.springs) {
    if (sp.body != i) continue;
    const Vec2<double> x = WorldFromLocal(Frame<double>(s.q), LocalPosition<double>(sp.rest_local, sp.mode_matrix, s.q));
    const double stretch = (x - sp.anchor).norm() - sp.rest_length;
    e.springs += 0.5 * sp.stiffness * stretch * stretch;
  }
  return e;
}

ForceBreakdown<double> World::Forces(int i) const {
  ForceBreakdown<double> f;
  EvaluateForces(*bodies_[i], options_.params, i, states_[i], &f);
  return f;
}

Eigen::VectorXd World::Accelerations(int i) const {
  VecQ<double> a;
  const StepStatus st = wobble::Accelerations(*bodies_[i], options_.params, i, states_[i], &a);
  if (!st.ok()) return Eigen::VectorXd::Constant(bodies_[i]->num_q(), std::nan(""));
  return a;
}

std::vector<Eigen::Vector2d> World::PointPositions(int i) const {
  const BodyModel& b = *bodies_[i];
  std::vector<Eigen::Vector2d> x(b.num_points());
  const Frame<double> frame(states_[i].q);
  for (int k = 0; k < b.num_points(); ++k)
    x[k] = WorldFromLocal(frame, LocalPosition<double>(b.rest_local(k), b.mode_matrix(k), states_[i].q));
  return x;
}

}  // namespace wobble
