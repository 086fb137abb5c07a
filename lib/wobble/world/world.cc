// The World's bodies, the per-body step (no constraint enabled), the checks and the energies.
// Constraints, the multiplier step and impulses are in world_constraints.cc.
#include "wobble/world/world.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "wobble/dynamics/kinematics.h"

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

std::string StatusCodeName(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return "ok";
    case StatusCode::kNonFinite: return "non-finite state";
    case StatusCode::kSingularMass: return "singular mass matrix";
    case StatusCode::kIllConditioned: return "ill-conditioned mass matrix";
    case StatusCode::kPenetration: return "runaway ground penetration";
    case StatusCode::kSolverFailed: return "implicit solver did not converge";
    case StatusCode::kSingularConstraints: return "singular constraints";
    case StatusCode::kBadPath: return "bad trajectory path";
  }
  return "?";
}

World::World(WorldOptions options) : options_(std::move(options)) {
  if (!(options_.dt > 0.0) || !std::isfinite(options_.dt)) throw std::invalid_argument("world: dt must be positive and finite");
}

// ---------------------------------------------------------------- bodies

int World::AddBody(std::shared_ptr<const BodyModel> model) {
  if (!model) throw std::invalid_argument("AddBody: no model");
  FfdEntry e;
  e.state.q.setZero(model->num_q());
  e.state.qd.setZero(model->num_q());
  e.applied = Eigen::VectorXd::Zero(model->num_q());
  e.model = std::move(model);
  ffd_.push_back(std::move(e));
  slots_.push_back({BodyKind::kFfd, int(ffd_.size()) - 1});
  return num_bodies() - 1;
}

int World::AddLinearBody(std::shared_ptr<const LinearBodyModel> model, AffineMaterial material) {
  if (!model) throw std::invalid_argument("AddLinearBody: no model");
  LinearEntry e;
  e.R = model->RestState();
  e.R_dot = Eigen::MatrixXd::Zero(e.R.rows(), e.R.cols());
  e.applied = e.R_dot;
  e.model = std::move(model);
  e.material = material;
  linear_.push_back(std::move(e));
  slots_.push_back({BodyKind::kLinear, int(linear_.size()) - 1});
  return num_bodies() - 1;
}

void World::ThrowBadBody(int body, BodyKind wanted) const {
  if (body < 0 || body >= num_bodies())
    throw std::invalid_argument("unknown body " + std::to_string(body) + " (the world has " +
                                std::to_string(num_bodies()) + " bodies)");
  throw std::invalid_argument("body " + std::to_string(body) + " is not " +
                              (wanted == BodyKind::kFfd ? "an FFD body" : "a linear body"));
}

int World::dim(int body) const { return kind(body) == BodyKind::kLinear ? Linear(body).model->dim() : 2; }

int World::num_q(int body) const { return kind(body) == BodyKind::kLinear ? Linear(body).model->num_q() : Ffd(body).model->num_q(); }

const std::string& World::body_name(int body) const {
  return kind(body) == BodyKind::kLinear ? Linear(body).model->name() : Ffd(body).model->name();
}

const World::LinearEntry& World::Linear(int body) const {
  if (kind(body) != BodyKind::kLinear) ThrowBadBody(body, BodyKind::kLinear);
  return linear_[slots_[body].index];
}

const std::shared_ptr<const BodyModel>& World::shared_body(int i) const { return Ffd(i).model; }

void World::SetModeTargets(int i, const Eigen::VectorXd& targets) {
  FfdEntry& e = Ffd(i);
  const int D = e.model->num_modes();
  if (targets.size() != 0 && targets.size() != D)
    throw std::invalid_argument("body '" + e.model->name() + "' has " + std::to_string(D) + " modes, got " +
                                std::to_string(targets.size()) + " targets");
  e.state.mode_target = targets;
}

const LinearBodyModel& World::linear_model(int body) const { return *Linear(body).model; }
const std::shared_ptr<const LinearBodyModel>& World::shared_linear_model(int body) const { return Linear(body).model; }

void World::SetLinearState(int body, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot) {
  const LinearBodyModel& m = linear_model(body);
  if (R.rows() != m.dim() || R.cols() != m.basis_size() || R_dot.rows() != m.dim() || R_dot.cols() != m.basis_size())
    throw std::invalid_argument("linear body '" + m.name() + "': R and R_dot must be " + std::to_string(m.dim()) + "x" +
                                std::to_string(m.basis_size()));
  if (!R.allFinite() || !R_dot.allFinite()) throw std::invalid_argument("linear body '" + m.name() + "': non-finite state");
  linear_[slots_[body].index].R = R;
  linear_[slots_[body].index].R_dot = R_dot;
}

const Eigen::MatrixXd& World::linear_R(int body) const { return Linear(body).R; }
const Eigen::MatrixXd& World::linear_R_dot(int body) const { return Linear(body).R_dot; }

void World::SetMaterial(int body, const AffineMaterial& material) {
  linear_model(body);
  linear_[slots_[body].index].material = material;
}

const AffineMaterial& World::material(int body) const { return Linear(body).material; }

void World::AddSpring(Spring spring) {
  const BodyModel& b = body(spring.body);
  b.LocalBasis(spring.lattice_coords, &spring.rest_local, &spring.mode_matrix);
  options_.params.springs.push_back(std::move(spring));
}

ForceBreakdown<double> World::Forces(int i) const {
  ForceBreakdown<double> f;
  EvaluateForces(body(i), options_.params, i, state(i), &f);
  return f;
}

Eigen::VectorXd World::Accelerations(int i) const {
  VecQ<double> a;
  const StepStatus st = wobble::Accelerations(body(i), options_.params, i, state(i), &a);
  if (!st.ok()) return Eigen::VectorXd::Constant(body(i).num_q(), std::nan(""));
  return a;
}

std::vector<Eigen::Vector2d> World::PointPositions(int i) const {
  const BodyModel& b = body(i);
  const BodyState<double>& s = state(i);
  std::vector<Eigen::Vector2d> x(b.num_points());
  const Frame<double> frame(s.q);
  for (int k = 0; k < b.num_points(); ++k) x[k] = WorldFromLocal(frame, LocalPosition<double>(b.rest_local(k), b.mode_matrix(k), s.q));
  return x;
}

// ---------------------------------------------------------------- stepping

bool World::Step() {
  if (!status_.ok()) return false;
  if (controllers_.empty()) {  // the fast path of a world nobody drives
    if (!(enabled_count_ == 0 ? StepEachBody() : StepConstrained())) return false;
    FinishStep();
  } else {
    // by index: a controller may add controllers; removals wait until the step is over (also
    // when a controller throws)
    struct Stepping {
      World& w;
      explicit Stepping(World& world) : w(world) { w.stepping_ = true; }
      ~Stepping() {
        w.stepping_ = false;
        if (!w.removed_while_stepping_) return;
        w.removed_while_stepping_ = false;
        w.controllers_.erase(std::remove(w.controllers_.begin(), w.controllers_.end(), nullptr), w.controllers_.end());
      }
    } stepping(*this);
    for (size_t i = 0; i < controllers_.size(); ++i)
      if (controllers_[i]) controllers_[i]->BeforeStep(*this);
    if (!(enabled_count_ == 0 ? StepEachBody() : StepConstrained())) return false;
    FinishStep();
    for (size_t i = 0; i < controllers_.size(); ++i)
      if (controllers_[i]) controllers_[i]->AfterStep(*this);
  }
  if (recorder_) recorder_->AfterStep(*this);
  return true;
}

void World::AddController(std::shared_ptr<Controller> controller) {
  if (!controller) throw std::invalid_argument("AddController: no controller");
  controllers_.push_back(std::move(controller));
}

void World::RemoveController(const Controller* controller) {
  for (size_t i = 0; i < controllers_.size(); ++i)
    if (controllers_[i].get() == controller) {
      if (stepping_) {
        controllers_[i] = nullptr;  // it may be running now: released when the step is over
        removed_while_stepping_ = true;
      } else {
        controllers_.erase(controllers_.begin() + long(i));
      }
      return;
    }
}

void World::SetKinematic(int body, bool on) {
  CheckBody(body);
  slots_[body].kinematic = on;
}

bool World::kinematic(int body) const {
  CheckBody(body);
  return slots_[body].kinematic;
}

void World::FinishStep() {
  if (options_.dt != origin_dt_) {  // dt changed: count from here
    time_origin_ = time_;
    origin_dt_ = options_.dt;
    origin_steps_ = 0;
  }
  ++steps_;
  ++origin_steps_;
  time_ = time_origin_ + origin_steps_ * options_.dt;
  status_.step = steps_;
  status_.time = time_;
}

// No constraint: each body on its own. FFD bodies on the templated StepBody (the fast path).
bool World::StepEachBody() {
  const double h = options_.dt;
  for (int body = 0; body < num_bodies(); ++body) {
    if (slots_[body].kinematic) continue;
    if (slots_[body].kind == BodyKind::kFfd) {
      if (!StepFfdBody(body)) return false;
      continue;
    }
    LinearEntry& e = linear_[slots_[body].index];
    Eigen::VectorXd& acc = acc_.empty() ? acc_.emplace_back() : acc_[0];
    LinearFreeAcceleration(e, &acc);
    if (!acc.allFinite()) return Fail(StatusCode::kNonFinite, body, "non-finite acceleration");
    const int d = e.model->dim(), n = e.model->basis_size();
    e.R_dot += h * Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(acc.data(), d, n);
    e.R += h * e.R_dot;
    e.applied.setZero();
  }
  return true;
}

void World::LinearFreeAcceleration(LinearEntry& e, Eigen::VectorXd* acc) const {
  const WorldParams& params = options_.params;
  const LinearBodyModel& m = *e.model;
  Eigen::MatrixXd& Q = e.Q;
  Q = e.applied;
  AddAffineForce(e.material, e.R, e.R_dot, &Q);
  if (params.gravity_on) {  // Σ m_k g p_kᵀ
    if (m.dim() == 2)
      Q.noalias() += params.gravity * m.first_moment().transpose();
    else
      Q.noalias() += options_.gravity_3d * m.first_moment().transpose();
  }
  acc->resize(m.num_q());
  // R̈ = Q W (Eq. 5), flattened row by row
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(acc->data(), m.dim(), m.basis_size())
      .noalias() = Q * m.inverse_mass_matrix();
}

bool World::Fail(StatusCode code, int body, const std::string& detail, double value) {
  status_.code = code;
  status_.step = steps_ + 1;
  status_.time = time_;
  status_.body = body;
  std::ostringstream msg;
  msg << StatusCodeName(code) << " at step " << status_.step << " (t = " << time_ << ")";
  if (body >= 0) msg << " in body '" << body_name(body) << "'";
  if (code == StatusCode::kIllConditioned) msg << ": condition estimate " << value;
  if (!detail.empty()) msg << ": " << detail;
  status_.message = msg.str();
  return false;
}

// ---------------------------------------------------------------- energies

Energies World::ComputeEnergies(int i) const {
  Energies e;
  const WorldParams& p = options_.params;
  if (kind(i) == BodyKind::kLinear) {
    const LinearEntry& l = Linear(i);
    e.kinetic = 0.5 * (l.R_dot * l.model->mass_matrix() * l.R_dot.transpose()).trace();  // ½ Ṙ_ij Ṙ_ik M_jk
    e.modes = AffineEnergy(l.material, l.R);
    if (p.gravity_on) {
      const Eigen::VectorXd g = l.model->dim() == 2 ? Eigen::VectorXd(p.gravity) : Eigen::VectorXd(options_.gravity_3d);
      e.gravity = -g.dot(l.R * l.model->first_moment());
    }
    return e;
  }
  const BodyModel& b = body(i);
  const BodyState<double>& s = state(i);
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
  ForEachPointInContact(b, p.ground, s, Frame<double>(s.q),
                        [&](int, const Vec2<double>&, const Vec2<double>& x, const Vec2<double>&, const Vec2<double>& anchor) {
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

double World::PotentialEnergy(int body) const {
  const Energies e = ComputeEnergies(body);
  return e.total() - e.kinetic;
}

double World::TotalEnergy() const {
  double e = 0.0;
  for (int body = 0; body < num_bodies(); ++body) e += ComputeEnergies(body).total();
  return e;
}

}  // namespace wobble
