// The World's bodies, the per-body step (no constraint enabled), the checks and the energies.
// Constraints, the multiplier step and impulses are in world_constraints.cc.
#include "wobble/world/world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "wobble/core/errors.h"
#include "wobble/dynamics/kinematics.h"

namespace wobble {

World::World(WorldOptions options) : options_(std::move(options)) {
  if (!(options_.dt > 0.0) || !std::isfinite(options_.dt)) throw std::invalid_argument("world: dt must be positive and finite");
}

// ---------------------------------------------------------------- bodies

int World::AddLinearBody(std::shared_ptr<const LinearBodyModel> model, AffineMaterial material) {
  if (!model) throw std::invalid_argument("AddLinearBody: no model");
  LinearEntry e;
  const int model_dim = model->dim();
  WorldData::Linear x;
  x.R = model->RestState();
  x.R_dot = Eigen::MatrixXd::Zero(x.R.rows(), x.R.cols());
  x.applied = x.R_dot;
  e.model = std::move(model);
  e.material = material;
  e.scale = LinearScale(*e.model, material);
  linear_.push_back(std::move(e));
  data_.linear.push_back(std::move(x));
  slots_.push_back({BodyKind::kLinear, model_dim, int(linear_.size()) - 1});
  return num_bodies() - 1;
}

void World::ThrowBadBody(int body, BodyKind wanted, int wanted_dim) const {
  if (body < 0 || body >= num_bodies())
    throw std::invalid_argument("unknown body " + std::to_string(body) + " (the world has " +
                                std::to_string(num_bodies()) + " bodies)");
  throw std::invalid_argument("body " + std::to_string(body) + " is not " +
                              (wanted == BodyKind::kLinear ? std::string("a linear body")
                               : wanted_dim == 0           ? std::string("an FFD body")
                                                           : "a " + std::to_string(wanted_dim) + "D FFD body"));
}

int World::dim(int body) const {
  CheckBody(body);
  return slots_[size_t(body)].dim;
}

int World::num_q(int body) const {
  if (kind(body) == BodyKind::kLinear) return Linear(body).model->num_q();
  return dim(body) == 3 ? Ffd<3>(body).model->num_q() : Ffd<2>(body).model->num_q();
}

const std::string& World::body_name(int body) const {
  if (kind(body) == BodyKind::kLinear) return Linear(body).model->name();
  return dim(body) == 3 ? Ffd<3>(body).model->name() : Ffd<2>(body).model->name();
}

const World::LinearEntry& World::Linear(int body) const {
  if (kind(body) != BodyKind::kLinear) ThrowBadBody(body, BodyKind::kLinear);
  return linear_[slots_[body].index];
}

const WorldData::Linear& World::LinearData(int body) const {
  Linear(body);
  return data_.linear[size_t(slots_[body].index)];
}

const LinearBodyModel& World::linear_model(int body) const { return *Linear(body).model; }
const std::shared_ptr<const LinearBodyModel>& World::shared_linear_model(int body) const { return Linear(body).model; }

void World::SetLinearState(int body, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot) {
  const LinearBodyModel& m = linear_model(body);
  if (R.rows() != m.dim() || R.cols() != m.basis_size() || R_dot.rows() != m.dim() || R_dot.cols() != m.basis_size())
    throw std::invalid_argument("linear body '" + m.name() + "': R and R_dot must be " + std::to_string(m.dim()) + "x" +
                                std::to_string(m.basis_size()));
  if (!R.allFinite() || !R_dot.allFinite()) throw std::invalid_argument("linear body '" + m.name() + "': non-finite state");
  LinearEntry& e = linear_[slots_[body].index];
  WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  e.R_before = x.R;
  e.R_dot_before = x.R_dot;
  x.R = R;
  x.R_dot = R_dot;
  RefreshLinearContacts(body);
  if (EnergyFinite(body)) return;
  const std::string terms = EnergyTerms(ComputeEnergies(body));
  x.R = e.R_before;
  x.R_dot = e.R_dot_before;
  RefreshLinearContacts(body);
  throw InputError("linear body '" + m.name() + "': a state whose energy is not finite (" + terms + ")");
}

const Eigen::MatrixXd& World::linear_R(int body) const { return LinearData(body).R; }
const Eigen::MatrixXd& World::linear_R_dot(int body) const { return LinearData(body).R_dot; }

void World::SetMaterial(int body, const AffineMaterial& material) {
  linear_model(body);
  LinearEntry& e = linear_[slots_[body].index];
  e.material = material;
  e.scale = LinearScale(*e.model, material);
}

const AffineMaterial& World::material(int body) const { return Linear(body).material; }

void World::SetGroundContact(int body, bool on) {
  linear_model(body);
  linear_[slots_[body].index].ground_contact = on;
  // found at the next SetLinearState or step, not at a state about to be replaced
  data_.linear[size_t(slots_[body].index)].contacts.clear();
}

bool World::ground_contact(int body) const {
  return kind(body) != BodyKind::kLinear || Linear(body).ground_contact;
}

const LinearContacts& World::linear_contacts(int body) const { return LinearData(body).contacts; }

void World::RefreshLinearContacts(int body) {
  const LinearEntry& e = linear_[slots_[body].index];
  WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  if (e.ground_contact) UpdateLinearContacts(*e.model, linear_ground(), x.R, x.R_dot, &x.contacts);
}

int World::AddSpring(Spring spring) {
  if (dim(spring.body) == 3) AttachSpring(body<3>(spring.body), &spring);
  else AttachSpring(body<2>(spring.body), &spring);
  options_.params.springs.push_back(std::move(spring));
  return int(options_.params.springs.size()) - 1;
}

// ---------------------------------------------------------------- model and data

namespace {
template <int Dim, class Entries>
void CheckFfdData(const Entries& models, const std::vector<WorldData::Ffd<Dim>>& data) {
  if (data.size() != models.size())
    throw std::invalid_argument("World::SetData: the data has " + std::to_string(data.size()) + " " +
                                std::to_string(Dim) + "D FFD bodies, the world " + std::to_string(models.size()));
  for (size_t i = 0; i < data.size(); ++i) {
    const auto& m = *models[i].model;
    const BodyState<Dim, double>& s = data[i].state;
    bool ok = s.q.size() == m.num_positions() && s.qd.size() == m.num_q() && data[i].applied.size() == m.num_q() &&
              (s.mode_target.size() == 0 || s.mode_target.size() == m.num_modes());
    for (const Contact<Dim, double>& c : s.contacts) ok = ok && c.point >= 0 && c.point < m.num_points();
    if (!ok) throw std::invalid_argument("World::SetData: the state of body '" + m.name() + "' does not fit its model");
  }
}
}  // namespace

void World::SetData(WorldData data) {
  CheckFfdData<2>(FfdEntries<2>(), data.ffd_of<2>());
  CheckFfdData<3>(FfdEntries<3>(), data.ffd_of<3>());
  if (data.linear.size() != linear_.size())
    throw std::invalid_argument("World::SetData: the data has " + std::to_string(data.linear.size()) +
                                " linear bodies, the world " + std::to_string(linear_.size()));
  for (size_t i = 0; i < linear_.size(); ++i) {
    const LinearBodyModel& m = *linear_[i].model;
    const WorldData::Linear& x = data.linear[i];
    for (const Eigen::MatrixXd* R : {&x.R, &x.R_dot, &x.applied})
      if (R->rows() != m.dim() || R->cols() != m.basis_size())
        throw std::invalid_argument("World::SetData: the state of linear body '" + m.name() + "' does not fit its model");
  }
  if (data.multipliers.size() != constraints_.size())
    throw std::invalid_argument("World::SetData: the data has " + std::to_string(data.multipliers.size()) +
                                " constraints, the world " + std::to_string(constraints_.size()));
  data_ = std::move(data);
}

// ---------------------------------------------------------------- stepping

bool World::Step() {
  if (!data_.status.ok()) return false;
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
  WorldData& d = data_;
  if (options_.dt != d.origin_dt) {  // dt changed: count from here
    d.time_origin = d.time;
    d.origin_dt = options_.dt;
    d.origin_steps = 0;
  }
  ++d.steps;
  ++d.origin_steps;
  d.time = d.time_origin + d.origin_steps * options_.dt;
  d.status.step = d.steps;
  d.status.time = d.time;
}

// No constraint: each body on its own. FFD bodies on the templated StepBody (the fast path).
bool World::StepEachBody() {
  // linear bodies by the world's integrator: the Euler forms here, the others in stages
  const bool staged_linear = !linear_.empty() && options_.integrator != Integrator::kThesis &&
                             options_.integrator != Integrator::kVariational;
  if (staged_linear && !StepConstrainedStaged(/*linear_only=*/true)) return false;
  for (int body = 0; body < num_bodies(); ++body) {
    if (slots_[body].kinematic) continue;
    if (slots_[body].kind == BodyKind::kFfd) {
      if (!(slots_[body].dim == 3 ? StepFfdBody<3>(body) : StepFfdBody<2>(body))) return false;
      continue;
    }
    if (staged_linear) continue;
    Eigen::VectorXd& acc = acc_.empty() ? acc_.emplace_back() : acc_[0];
    LinearFreeAcceleration(body, &acc);
    if (!acc.allFinite()) return Fail(StatusCode::kNonFinite, body, "non-finite acceleration");
    if (!StepLinearBody(body, acc)) return false;
  }
  return true;
}

namespace {
constexpr double kLinearScreen = 1e30;  // AcceptLinearStep's bound on every factor of an energy term
}  // namespace

// Semi-implicit Euler, velocity first, of a linear body with R̈ given row by row. The new state
// goes into the scratch matrices and is swapped in (O(1)), so that a refused step swaps back.
// Plain loops (d ≤ 3, n ≤ 10), which also apply AcceptLinearStep's screen to R and Ṙ on the way.
bool World::StepLinearBody(int body, const Eigen::VectorXd& acc) {
  LinearEntry& e = linear_[slots_[body].index];
  WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  const double h = options_.dt;
  const int d = e.model->dim(), n = e.model->basis_size();
  e.R_before.resize(d, n);
  e.R_dot_before.resize(d, n);
  bool screened = true;  // every |R|, |Ṙ| ≤ kLinearScreen (false for NaN and inf too)
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < d; ++i) {
      const double rd = x.R_dot(i, j) + h * acc[i * n + j];
      const double r = x.R(i, j) + h * rd;
      e.R_dot_before(i, j) = rd;
      e.R_before(i, j) = r;
      screened &= std::abs(rd) <= kLinearScreen && std::abs(r) <= kLinearScreen;
    }
  x.R.swap(e.R_before);
  x.R_dot.swap(e.R_dot_before);
  return FinishLinearStep(body, screened);
}

bool World::AcceptLinearState(int body, const Eigen::MatrixXd& R_before, const Eigen::MatrixXd& R_dot_before) {
  LinearEntry& e = linear_[slots_[body].index];
  const WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  e.R_before = R_before;
  e.R_dot_before = R_dot_before;
  // NaN fails both comparisons, so a non-finite state is not screened
  const bool screened = (x.R.array().abs() <= kLinearScreen).all() && (x.R_dot.array().abs() <= kLinearScreen).all();
  return FinishLinearStep(body, screened);
}

bool World::FinishLinearStep(int body, bool screened) {
  LinearEntry& e = linear_[slots_[body].index];
  WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  x.applied.setZero();
  if (!AcceptLinearStep(body, screened)) return false;
  if (!e.ground_contact) return true;
  // the contacts of the accepted state; a point deeper than half the body's thickness went
  // through the ground (a step too long for its stiffness): refused, as for FFD bodies
  e.contacts_before = x.contacts;  // copy-assigned: reuses its storage from step to step
  RefreshLinearContacts(body);
  const double limit = options_.params.ground.max_penetration > 0 ? options_.params.ground.max_penetration
                                                                  : e.model->half_thickness();
  if (!(x.contacts.penetration > limit)) return true;
  std::ostringstream detail;
  detail << "a point is " << x.contacts.penetration << " below the ground (limit " << limit
         << "); reduce dt, or the ground's stiffness or damping";
  x.R.swap(e.R_before);
  x.R_dot.swap(e.R_dot_before);
  x.contacts.lists.swap(e.contacts_before.lists);
  x.contacts.penetration = e.contacts_before.penetration;
  return Fail(StatusCode::kPenetration, body, detail.str());
}

void World::LinearFreeAcceleration(int body, Eigen::VectorXd* acc) {
  LinearEntry& e = linear_[slots_[body].index];
  const WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  const WorldParams& params = options_.params;
  const LinearBodyModel& m = *e.model;
  const int d = m.dim(), n = m.basis_size();
  Eigen::MatrixXd& Q = e.Q;
  Q = x.applied;
  AddAffineForce(e.material, x.R, x.R_dot, &Q);
  if (params.gravity_on) {  // Σ m_k g p_kᵀ
    const double* g = params.gravity.data();  // a 2D body reads x and y
    const Eigen::VectorXd& mu = m.first_moment();
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < d; ++i) Q(i, j) += g[i] * mu[j];
  }
  if (e.ground_contact) AddLinearGroundForce(m, linear_ground(), x.R, x.R_dot, x.contacts, &Q);
  // R̈ = Q W (Eq. 5), flattened row by row; plain loops, as TimesBasis in world_constraints.cc
  acc->resize(m.num_q());
  const Eigen::MatrixXd& W = m.inverse_mass_matrix();
  for (int i = 0; i < d; ++i)
    for (int k = 0; k < n; ++k) {
      double sum = 0.0;
      for (int j = 0; j < n; ++j) sum += Q(i, j) * W(j, k);
      (*acc)[i * n + k] = sum;
    }
}

void World::ThrowInterrupted() const {
  std::ostringstream msg;
  msg << "stopped by Ctrl-C at t = " << data_.time << " (after step " << data_.steps << ")";
  throw Interrupted(msg.str());
}

bool World::Fail(StatusCode code, int body, const std::string& detail, double value) {
  WorldStatus& status = data_.status;
  status.code = code;
  status.step = data_.steps + 1;
  status.time = data_.time;
  status.body = body;
  std::ostringstream msg;
  msg << StatusCodeName(code) << " at step " << status.step << " (t = " << data_.time << ")";
  if (body >= 0) msg << " in body '" << body_name(body) << "'";
  if (code == StatusCode::kIllConditioned) msg << ": condition estimate " << value;
  if (!detail.empty()) msg << ": " << detail;
  status.message = msg.str();
  return false;
}

// ---------------------------------------------------------------- energies

Energies World::ComputeEnergies(int i) const {
  Energies e;
  const WorldParams& p = options_.params;
  if (kind(i) == BodyKind::kLinear) {
    const LinearEntry& l = Linear(i);
    const WorldData::Linear& x = LinearData(i);
    e.kinetic = 0.5 * (x.R_dot * l.model->mass_matrix() * x.R_dot.transpose()).trace();  // ½ Ṙ_ij Ṙ_ik M_jk
    e.modes = AffineEnergy(l.material, x.R);
    e.ground = LinearGroundEnergy(*l.model, linear_ground(), x.R, x.contacts);
    if (p.gravity_on) {
      const Eigen::VectorXd g = p.gravity.head(l.model->dim());
      e.gravity = -g.dot(x.R * l.model->first_moment());
    }
    return e;
  }
  return dim(i) == 3 ? FfdEnergies<3>(i, ContactSet::kDetect, true) : FfdEnergies<2>(i, ContactSet::kDetect, true);
}

// A finite acceleration can still overflow R, Ṙ or the energy: the step is refused then, and
// the body keeps its state before it (R_before, R_dot_before hold it: the step swapped them).
// `screened`: every entry of R and Ṙ is at most kLinearScreen in size.
bool World::AcceptLinearStep(int body, bool screened) {
  LinearEntry& e = linear_[slots_[body].index];
  WorldData::Linear& x = data_.linear[size_t(slots_[body].index)];
  // the screen of EnergySurelyFinite, for ½ tr(Ṙ M Ṙᵀ), −g·R m̄ and the affine energies (at
  // most seven factors deep: k_c (det A − 1)² with a 3×3 A)
  const double g = options_.params.gravity.head(e.model->dim()).cwiseAbs().maxCoeff();
  if (screened && e.scale <= kLinearScreen && g <= kLinearScreen) return true;
  const bool finite = x.R.allFinite() && x.R_dot.allFinite();
  if (finite && EnergyFinite(body)) return true;
  const Energies energies = finite ? ComputeEnergies(body) : Energies();
  x.R.swap(e.R_before);
  x.R_dot.swap(e.R_dot_before);
  return finite ? Fail(StatusCode::kNonFiniteEnergy, body, EnergyTerms(energies)) : Fail(StatusCode::kNonFinite, body);
}

bool World::EnergyFinite(int body) const {
  if (kind(body) == BodyKind::kFfd) {
    if (dim(body) == 3) {
      if (EnergySurelyFinite<3>(body)) return true;
      return std::isfinite(FfdEnergies<3>(body, ContactSet::kFrozen, false).total());
    }
    if (EnergySurelyFinite<2>(body)) return true;
    return std::isfinite(FfdEnergies<2>(body, ContactSet::kFrozen, false).total());
  }
  return std::isfinite(ComputeEnergies(body).total());
}

double LinearScale(const LinearBodyModel& m, const AffineMaterial& material) {
  const double scale = std::max({m.mass_matrix().cwiseAbs().maxCoeff(), m.first_moment().cwiseAbs().maxCoeff(),
                                 std::abs(material.rigidity), std::abs(material.volume), std::abs(material.bending),
                                 std::abs(material.damping)});
  return std::isfinite(scale) ? scale : std::numeric_limits<double>::infinity();
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
