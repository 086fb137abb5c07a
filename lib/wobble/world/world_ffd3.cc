// The 3D FFD bodies of the World: added, set and stepped with StepBody (dynamics/step.h) on
// the world's 3D gravity and ground plane, and the 3D FFD ends of nails, attachments,
// trajectories and impulses: x = t + R l, J = [1 | −R[l]× | R B], J̇v = R(ω×(ω×l) + 2ω×Bγ̇)
// (kinematics3.h). A constrained world steps them by semi-implicit Euler, velocity first, on
// the group, as it steps every other body.
#include <algorithm>
#include <sstream>

#include "wobble/core/errors.h"
#include "wobble/world/world.h"

namespace wobble {

int World::AddBody(std::shared_ptr<const BodyModel3> model) {
  if (!model) throw std::invalid_argument("AddBody: no model");
  Ffd3Entry e;
  e.state = RestState<3, double>(*model);
  e.applied = Eigen::VectorXd::Zero(model->num_q());
  e.model = std::move(model);
  ffd3_.push_back(std::move(e));
  slots_.push_back({BodyKind::kFfd3, int(ffd3_.size()) - 1});
  UpdateContacts(*ffd3_.back().model, options_.ground_3d, &ffd3_.back().state);
  return num_bodies() - 1;
}

const World::Ffd3Entry& World::Ffd3(int body) const {
  if (unsigned(body) >= slots_.size() || slots_[size_t(body)].kind != BodyKind::kFfd3) ThrowBadBody(body, BodyKind::kFfd3);
  return ffd3_[slots_[size_t(body)].index];
}
const BodyModel3& World::body3(int i) const { return *Ffd3(i).model; }
const std::shared_ptr<const BodyModel3>& World::shared_body3(int i) const { return Ffd3(i).model; }

GroundPlane GroundPlaneOf(const Ground& g) {
  if (g.terrain)
    throw InputError("a 3D body stands on a ground plane; a terrain profile is 2D only (turn it off with 'terrain off')");
  GroundPlane p;
  p.enabled = g.enabled;
  p.point = Eigen::Vector3d(g.point.x(), g.point.y(), 0.0);
  p.normal = Eigen::Vector3d(g.normal().x(), g.normal().y(), 0.0);
  p.stiffness = g.stiffness;
  p.normal_damping = g.normal_damping;
  p.friction_damping = g.friction_damping;
  p.friction_cap = g.friction_cap;
  p.heightfield = g.heightfield;
  return p;
}

double World::Penetration(int body) const {
  if (kind(body) == BodyKind::kFfd) return state(body).penetration;
  if (kind(body) == BodyKind::kLinear) return Linear(body).contacts.penetration;
  const BodyModel3& m = body3(body);
  const BodyState<3, double>& s = state3(body);
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  double deepest = 0.0;
  for (const Contact<3, double>& c : s.contacts) {
    const Eigen::Vector3d x = s.translation() + R * (m.rest_local(c.point) + m.mode_matrix(c.point) * s.gamma());
    deepest = std::max(deepest, -options_.ground_3d.Face(c.face, x).Height(x));
  }
  return deepest;
}
const BodyState<3, double>& World::state3(int i) const { return Ffd3(i).state; }

WorldParamsN<3> Params3Of(const WorldOptions& options) {
  WorldParamsN<3> p;
  p.gravity_on = options.params.gravity_on;
  p.gravity = options.gravity_3d;
  p.ground = options.ground_3d;
  p.springs = options.springs_3d;
  p.max_condition = options.params.max_condition;
  return p;
}

void World::SetState3(int body, const Eigen::Vector3d& t, const Eigen::Quaterniond& orientation,
                      const Eigen::VectorXd& gamma, const Eigen::VectorXd& v) {
  Ffd3(body);  // checks the body and its kind
  Ffd3Entry& e = ffd3_[slots_[size_t(body)].index];
  const BodyModel3& m = *e.model;
  if (gamma.size() != m.num_modes() || v.size() != m.num_q())
    throw InputError("body '" + m.name() + "' has " + std::to_string(m.num_modes()) + " modes and " +
                     std::to_string(m.num_q()) + " velocities (t-dot, omega and one per mode), got " +
                     std::to_string(gamma.size()) + " and " + std::to_string(v.size()));
  if (!t.allFinite() || !orientation.coeffs().allFinite() || !gamma.allFinite() || !v.allFinite())
    throw InputError("body '" + m.name() + "': the state must be finite");
  if (!(orientation.norm() > 1e-12)) throw InputError("body '" + m.name() + "': the orientation quaternion is zero");
  const BodyState<3, double> before = e.state;
  e.state = RestState<3, double>(m);
  e.state.translation() = t;
  Group<3>::SetOrientation(orientation.normalized(), &e.state.q);
  e.state.gamma() = gamma;
  e.state.qd = v;
  e.state.contacts.clear();
  UpdateContacts(m, options_.ground_3d, &e.state);
  const Energies energies = Ffd3Energies(body);
  if (std::isfinite(energies.total())) return;
  e.state = before;
  throw InputError("body '" + m.name() + "': a state whose energy is not finite (" + EnergyTerms(energies) + ")");
}

namespace {
// The point forces of ApplyPointForce as StepBody's extra generalized force; none (null) on
// almost every step. One functor type for both cases: one instantiation of the step.
struct AppliedForce3 {
  const Eigen::VectorXd* force = nullptr;
  void operator()(const BodyState<3, double>&, VecQ<double>* Q) const {
    if (force) *Q += *force;
  }
};
}  // namespace

bool World::StepFfd3Body(int body) {
  Ffd3Entry& e = ffd3_[slots_[body].index];
  const BodyState<3, double> before = e.state;
  const bool pushed = !e.applied.isZero(0.0);
  const StepStatus st = StepBody(*e.model, Params3Of(options_), 0, options_.integrator, options_.dt, &e.state,
                                  AppliedForce3{pushed ? &e.applied : nullptr});
  if (pushed) e.applied.setZero();
  if (st.ok() && std::isfinite(Ffd3Energies(body).total())) return true;
  const Energies energies = st.ok() ? Ffd3Energies(body) : Energies();
  e.state = before;  // a refused step leaves the state before it
  if (!st.ok()) return Fail(st.code, body, "", st.value);
  return Fail(StatusCode::kNonFiniteEnergy, body, EnergyTerms(energies) + " after the step (refused)");
}

// Kinetic ½ vᵀMv, gravity −g·(m t + R c), modes K (γ − γ0)², and the ground's penalty ½ K |Δ|²
// of every contact spring.
Energies World::Ffd3Energies(int body) const {
  const Ffd3Entry& e = Ffd3(body);
  const BodyModel3& m = *e.model;
  const BodyState<3, double>& s = e.state;
  const ShapeMoments<double> sm(m.moments(), s.gamma());
  const Frame<3, double> frame(s.q);
  Energies out;
  out.kinetic = wobble::KineticEnergy(m.moments(), sm, frame.R, s.qd);
  if (options_.params.gravity_on) out.gravity = GravityEnergy(m.moments(), sm, frame, options_.gravity_3d);
  for (int d = 0; d < m.num_modes(); ++d) {
    const double offset = s.gamma()[d] - (s.mode_target.size() == m.num_modes() ? s.mode_target[d] : 0.0);
    out.per_mode.push_back(m.modes()[d].stiffness * offset * offset);
    out.modes += out.per_mode.back();
  }
  for (const Contact<3, double>& c : s.contacts) {
    const Eigen::Vector3d x = frame.t + frame.R * LocalPosition<double>(m.rest_local(c.point), m.mode_matrix(c.point), s.q);
    out.ground += 0.5 * options_.ground_3d.Face(c.face, x).stiffness * (x - c.anchor).squaredNorm();
  }
  // springs: ½ K (|x − anchor| − L)², the potential of step3.h's force
  for (const SpringN<3>& sp : options_.springs_3d) {
    const Eigen::Vector3d x = frame.t + frame.R * LocalPosition<double>(sp.rest_local, sp.mode_matrix, s.q);
    const double stretch = (x - sp.anchor).norm() - sp.rest_length;
    out.springs += 0.5 * sp.stiffness * stretch * stretch;
  }
  return out;
}

// ---------------------------------------------------------------- constraint ends

void World::Ffd3Resolve(const MaterialPoint& point, End* e) const {
  const BodyModel3& m = *Ffd3(point.body).model;
  Eigen::Vector3d u;
  if (point.mass_point >= 0) {
    if (point.mass_point >= m.num_points())
      throw std::invalid_argument("body '" + m.name() + "' has " + std::to_string(m.num_points()) +
                                  " mass points, no point " + std::to_string(point.mass_point));
    u = m.lattice_coords(point.mass_point);
  } else {
    if (point.u.size() != 3 || !point.u.allFinite())
      throw std::invalid_argument("a point of 3D FFD body '" + m.name() + "' needs 3 lattice coordinates (s, t, u)");
    u = point.u;
    const double tol = 1e-9;
    if (u.minCoeff() < -tol || u.maxCoeff() > 1.0 + tol)
      throw std::invalid_argument("lattice coordinates of 3D FFD body '" + m.name() + "' are outside [0, 1]^3");
  }
  m.LocalBasis(u, &e->b0_3, &e->B3);
}

World::PointVec World::Ffd3EndPosition(const End& e) const {
  const BodyState<3, double>& s = Ffd3(e.body).state;
  const Frame<3, double> frame(s.q);
  return frame.t + frame.R * LocalPosition<double>(e.b0_3, e.B3, s.q);
}

World::PointVec World::Ffd3EndVelocity(const End& e) const {
  const BodyState<3, double>& s = Ffd3(e.body).state;
  const Frame<3, double> frame(s.q);
  return wobble::PointVelocity(frame, s.qd, LocalPosition<double>(e.b0_3, e.B3, s.q), e.B3);
}

World::PointVec World::Ffd3EndJdotQdot(const End& e) const {
  const BodyState<3, double>& s = Ffd3(e.body).state;
  const Frame<3, double> frame(s.q);
  const Eigen::Vector3d l = LocalPosition<double>(e.b0_3, e.B3, s.q);
  const Eigen::Vector3d omega = s.qd.segment<3>(3);
  const Eigen::Vector3d Bgd = e.B3 * s.qd.tail(e.B3.cols());
  return frame.R * (omega.cross(omega.cross(l)) + 2.0 * omega.cross(Bgd));
}

Eigen::MatrixXd World::Ffd3EndJacobian(const End& e) const {
  const BodyState<3, double>& s = Ffd3(e.body).state;
  const Frame<3, double> frame(s.q);
  const Eigen::Vector3d l = LocalPosition<double>(e.b0_3, e.B3, s.q);
  Eigen::MatrixXd J(3, s.qd.size());
  J.leftCols(3).setIdentity();
  J.block<3, 3>(0, 3) = -frame.R * Skew<double>(l);
  if (e.B3.cols() > 0) J.rightCols(e.B3.cols()) = frame.R * e.B3;
  return J;
}

void World::Ffd3AddEndForce(const End& e, const Eigen::VectorXd& f, Eigen::VectorXd* Q) const {
  const BodyState<3, double>& s = Ffd3(e.body).state;
  const Frame<3, double> frame(s.q);
  VecQ<double> q = *Q;
  AddGeneralizedForce(frame, LocalPosition<double>(e.b0_3, e.B3, s.q), e.B3, Eigen::Vector3d(f), &q);
  *Q = q;
}

void World::Ffd3ApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const {
  const Ffd3Entry& e = Ffd3(body);
  const ShapeMoments<double> sm(e.model->moments(), e.state.gamma());
  MatQ<double> M;
  MassMatrix(e.model->moments(), sm, Mat3<double>(e.state.orientation().toRotationMatrix()), &M);
  if (!CholeskyInPlace(&M)) {
    *acc = Eigen::VectorXd::Constant(acc->size(), std::nan(""));  // caught by the finite checks
    return;
  }
  VecQ<double> x = Q;
  CholeskySolveInPlace(M, &x);
  *acc += x;
}

bool World::Ffd3FreeAcceleration(int body, Eigen::VectorXd* acc, StepStatus* st) const {
  VecQ<double> a;
  *st = wobble::Accelerations(*Ffd3(body).model, Params3Of(options_), 0, Ffd3(body).state, &a);
  if (!st->ok()) return false;
  *acc = a;
  if (!Ffd3(body).applied.isZero(0.0)) Ffd3ApplyGeneralized(body, Ffd3(body).applied, acc);
  return true;
}

bool World::Ffd3AcceptConstrainedStep(int body, const Eigen::VectorXd& acc) {
  Ffd3Entry& e = ffd3_[slots_[body].index];
  const BodyState<3, double> before = e.state;
  e.applied.setZero();  // acc holds it
  e.state.qd += options_.dt * acc;
  Group<3>::Advance(e.state.qd, options_.dt, &e.state.q);
  UpdateContacts(*e.model, options_.ground_3d, &e.state);
  if (e.state.qd.allFinite() && e.state.translation().allFinite() && e.state.gamma().allFinite() &&
      std::isfinite(Ffd3Energies(body).total()))
    return true;
  e.state = before;
  return Fail(StatusCode::kNonFinite, body, "the constrained step left a non-finite state (refused)");
}

}  // namespace wobble
