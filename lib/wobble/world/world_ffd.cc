// The FFD bodies of the World, one code for both dimensions: added, set and stepped by the
// templated StepBody (dynamics/step.h), their checks and energies, and their ends of nails,
// attachments, trajectories and impulses: x = t + R l, J = [1 | R (ω × l)/∂ω | R B],
// J̇ q̇ = R (ω × (ω × l) + 2 ω × B γ̇) (Eq. 4.6–4.8; planar ω × l = ω S l). What differs
// between the dimensions is in group.h (Turn), the mass solve and the energies' moment
// formulas (the overloads at the top).
//
// In a file of its own, as the per-body step was before the worlds were merged, so that the
// compiler inlines the contact scan into the step (measured with callgrind on
// BM_TableRestingOnGround: in the larger world.cc GCC kept ForEachPointInContact out of line,
// 10 % more instructions per step).
#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "wobble/core/errors.h"
#include "wobble/world/world.h"

namespace wobble {

namespace {

// ---- the dimension's own formulas ----

// Eq. 4.9's kinetic energy ½ q̇ᵀ M q̇ and gravity's potential −g·(m t + R c(γ)).
double KineticEnergyOf(const BodyModelN<2>& m, const BodyState<2, double>& s, const Frame<2, double>& frame) {
  return KineticEnergy(m.moments(), s.q, s.qd, frame.R);
}
double KineticEnergyOf(const BodyModelN<3>& m, const BodyState<3, double>& s, const Frame<3, double>& frame) {
  return KineticEnergy(m.moments(), ShapeMoments<double>(m.moments(), s.gamma()), frame.R, s.qd);
}
double GravityEnergyOf(const BodyModelN<2>& m, const BodyState<2, double>& s, const Frame<2, double>&,
                       const Eigen::Vector2d& g) {
  return GravityEnergy(m.moments(), s.q, g);
}
double GravityEnergyOf(const BodyModelN<3>& m, const BodyState<3, double>& s, const Frame<3, double>& frame,
                       const Eigen::Vector3d& g) {
  return GravityEnergy(m.moments(), ShapeMoments<double>(m.moments(), s.gamma()), frame, g);
}

// x = M(q)⁻¹ Q, about the centre of mass in both (SolveMassSystem; M is never formed).
bool SolveMass(const BodyModelN<2>& m, const BodyState<2, double>& s, const VecQ<double>& Q, VecQ<double>* x) {
  double cond = 0;
  return SolveMassSystem(m.moments(), s.q, Rotation(s.q[2]), Q, x, &cond);
}
bool SolveMass(const BodyModelN<3>& m, const BodyState<3, double>& s, const VecQ<double>& Q, VecQ<double>* x) {
  double cond = 0;
  return SolveMassSystem(m.moments(), ShapeMoments<double>(m.moments(), s.gamma()),
                         Mat3<double>(s.orientation().toRotationMatrix()), Q, x, &cond);
}

// The largest |number| of the moments (NaN fails every comparison with the screen).
template <class Matrix> void TakeScale(const Matrix& x, double* scale) {
  if (x.size() > 0) *scale = std::max(*scale, double(x.cwiseAbs().maxCoeff()));
}
double MomentScale(const MassMomentsN<2>& m) {
  double scale = std::max({std::abs(m.m), std::abs(m.I0), m.c0.cwiseAbs().maxCoeff()});
  for (const MatD<double>* x : {&m.G, &m.P}) TakeScale(*x, &scale);
  TakeScale(m.C, &scale);
  TakeScale(m.e0, &scale);
  TakeScale(m.h0, &scale);
  return scale;
}
double MomentScale(const MassMomentsN<3>& m) {
  double scale = std::max({std::abs(m.m), m.c0.cwiseAbs().maxCoeff(), m.S0.cwiseAbs().maxCoeff()});
  TakeScale(m.C, &scale);
  TakeScale(m.H0, &scale);
  TakeScale(m.e0, &scale);
  TakeScale(m.G, &scale);
  for (const Eigen::Matrix3d& x : m.E) TakeScale(x, &scale);
  for (const Eigen::Matrix3d& x : m.F) TakeScale(x, &scale);
  for (const Eigen::Vector3d& x : m.X) TakeScale(x, &scale);
  return scale;
}

// The point forces of ApplyPointForce as StepBody's extra generalized force; none (null) on
// almost every step. One functor type for both cases: one instantiation of the step.
template <int Dim> struct AppliedForce {
  const Eigen::VectorXd* force = nullptr;
  void operator()(const BodyState<Dim, double>&, VecQ<double>* Q) const {
    if (force) *Q += *force;
  }
};

}  // namespace

template <int Dim> double ModelScale(const BodyModelN<Dim>& b) {
  double scale = MomentScale(b.moments());
  for (int k = 0; k < b.num_points(); ++k) {
    TakeScale(b.rest_local(k), &scale);
    TakeScale(b.mode_matrix(k), &scale);
  }
  for (const DeformationModeN<Dim>& d : b.modes()) scale = std::max(scale, std::abs(d.stiffness));
  return std::isfinite(scale) ? scale : std::numeric_limits<double>::infinity();
}
template double ModelScale(const BodyModelN<2>&);
template double ModelScale(const BodyModelN<3>&);

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

// ---------------------------------------------------------------- bodies

template <int Dim> int World::AddFfdBody(std::shared_ptr<const BodyModelN<Dim>> model) {
  if (!model) throw std::invalid_argument("AddBody: no model");
  FfdEntry<Dim> e;
  WorldData::Ffd<Dim> x;
  x.state = RestState<Dim, double>(*model);
  x.applied = Eigen::VectorXd::Zero(model->num_q());
  UpdateContacts(*model, GroundFor<Dim>(), &x.state);
  e.scale = ModelScale(*model);
  e.model = std::move(model);
  std::vector<FfdEntry<Dim>>& entries = FfdEntries<Dim>();
  entries.push_back(std::move(e));
  data_.ffd_of<Dim>().push_back(std::move(x));
  slots_.push_back({BodyKind::kFfd, Dim, int(entries.size()) - 1});
  return num_bodies() - 1;
}
template int World::AddFfdBody(std::shared_ptr<const BodyModelN<2>>);
template int World::AddFfdBody(std::shared_ptr<const BodyModelN<3>>);

void World::SetState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  if (dim(body) == 3) SetFfdState<3>(body, q, qd);
  else SetFfdState<2>(body, q, qd);
}

template <int Dim> void World::SetFfdState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  const BodyModelN<Dim>& m = *Ffd<Dim>(body).model;
  WorldData::Ffd<Dim>& e = FfdData<Dim>(body);
  if (q.size() != m.num_positions() || qd.size() != m.num_q())
    throw InputError("body '" + m.name() + "' has " + std::to_string(m.num_positions()) + " positions (" +
                     (Dim == 2 ? "tx ty theta" : "tx ty tz, quaternion x y z w") + " and one per mode) and " +
                     std::to_string(m.num_q()) + " velocities, got q of " + std::to_string(q.size()) + " and qdot of " +
                     std::to_string(qd.size()));
  if (!q.allFinite() || !qd.allFinite()) throw InputError("body '" + m.name() + "': the state must be finite");
  BodyState<Dim, double> s = RestState<Dim, double>(m);
  s.q = q;
  s.qd = qd;
  s.mode_target = e.state.mode_target;
  if constexpr (Dim == 3) {
    if (!(s.orientation().norm() > 1e-12)) throw InputError("body '" + m.name() + "': the orientation quaternion is zero");
    Group<3>::Normalize(&s.q);
  }
  std::swap(e.state, s);  // s: the state before, restored when the energy is not finite
  UpdateContacts(m, GroundFor<Dim>(), &e.state);
  if (EnergyFinite(body)) return;
  const std::string terms = EnergyTerms(FfdEnergies<Dim>(body, ContactSet::kDetect, false));
  e.state = std::move(s);
  throw InputError("body '" + m.name() + "': a state whose energy is not finite (" + terms + ")");
}

Eigen::VectorXd World::coordinates(int i) const {
  return dim(i) == 3 ? CoordinatesOf(state<3>(i)) : Eigen::VectorXd(state<2>(i).q);
}

void World::SetCoordinates(int i, const Eigen::VectorXd& coordinates, const Eigen::VectorXd& qd) {
  if (dim(i) == 2) return SetFfdState<2>(i, coordinates, qd);
  const BodyModelN<3>& m = body<3>(i);
  if (coordinates.size() != m.num_q())
    throw InputError("body '" + m.name() + "' has " + std::to_string(m.num_q()) +
                     " coordinates (tx ty tz, rotation vector rx ry rz and one per mode), got " +
                     std::to_string(coordinates.size()));
  SetFfdState<3>(i, StateFromCoordinates<3>(coordinates, qd).q, qd);
}

const VecQ<double>& World::q(int i) const { return dim(i) == 3 ? state<3>(i).q : state<2>(i).q; }
const VecQ<double>& World::qd(int i) const { return dim(i) == 3 ? state<3>(i).qd : state<2>(i).qd; }
int World::num_modes(int i) const { return dim(i) == 3 ? body<3>(i).num_modes() : body<2>(i).num_modes(); }
const VecD<double>& World::mode_targets(int i) const {
  return dim(i) == 3 ? state<3>(i).mode_target : state<2>(i).mode_target;
}

double World::Penetration(int body) const {
  if (kind(body) == BodyKind::kLinear) return LinearData(body).contacts.penetration;
  return dim(body) == 3 ? state<3>(body).penetration : state<2>(body).penetration;
}

void World::SetModeTargets(int i, const Eigen::VectorXd& targets) {
  const int D = num_modes(i);
  if (targets.size() != 0 && targets.size() != D)
    throw std::invalid_argument("body '" + body_name(i) + "' has " + std::to_string(D) + " modes, got " +
                                std::to_string(targets.size()) + " targets");
  if (dim(i) == 3) FfdData<3>(i).state.mode_target = targets;
  else FfdData<2>(i).state.mode_target = targets;
}

template <int Dim> ForceBreakdown<Dim, double> World::Forces(int i) const {
  ForceBreakdown<Dim, double> f;
  EvaluateForces(body<Dim>(i), options_.params, i, state<Dim>(i), &f);
  return f;
}
template ForceBreakdown<2, double> World::Forces<2>(int) const;
template ForceBreakdown<3, double> World::Forces<3>(int) const;

Eigen::VectorXd World::Accelerations(int i) const {
  Eigen::VectorXd a;
  StepStatus st;
  const bool ok = dim(i) == 3 ? FfdFreeAcceleration<3>(i, &a, &st) : FfdFreeAcceleration<2>(i, &a, &st);
  if (!ok) return Eigen::VectorXd::Constant(dim(i) == 3 ? body<3>(i).num_q() : body<2>(i).num_q(), std::nan(""));
  return a;
}

template <int Dim> std::vector<Eigen::Matrix<double, Dim, 1>> World::PointPositions(int i) const {
  const BodyModelN<Dim>& b = body<Dim>(i);
  const BodyState<Dim, double>& s = state<Dim>(i);
  std::vector<Eigen::Matrix<double, Dim, 1>> x(size_t(b.num_points()));
  const Frame<Dim, double> frame(s.q);
  for (int k = 0; k < b.num_points(); ++k)
    x[size_t(k)] = WorldFromLocal(frame, LocalPosition<double>(b.rest_local(k), b.mode_matrix(k), s.q));
  return x;
}
template std::vector<Eigen::Vector2d> World::PointPositions<2>(int) const;
template std::vector<Eigen::Vector3d> World::PointPositions<3>(int) const;

// ---------------------------------------------------------------- stepping

template <int Dim> bool World::StepFfdBody(int body) {
  const size_t index = size_t(slots_[size_t(body)].index);
  const BodyModelN<Dim>& model = *FfdEntries<Dim>()[index].model;
  WorldData::Ffd<Dim>& e = data_.ffd_of<Dim>()[index];
  const VecQ<double> q_before = e.state.q, qd_before = e.state.qd;  // contacts are found again on refusal
  const bool pushed = !e.applied.isZero(0.0);
  const StepStatus st = StepBody(model, options_.params, body, options_.integrator, options_.dt, &e.state,
                                 AppliedForce<Dim>{pushed ? &e.applied : nullptr});
  if (pushed) e.applied.setZero();
  if (st.ok() && AcceptFfdState<Dim>(body)) return true;
  return RefuseFfdStep<Dim>(body, q_before, qd_before, st);
}
template bool World::StepFfdBody<2>(int);
template bool World::StepFfdBody<3>(int);

// The screen implies a finite state; past it, the state and the energies are checked in full.
template <int Dim> bool World::AcceptFfdState(int body) {
  const size_t index = size_t(slots_[size_t(body)].index);
  const BodyState<Dim, double>& s = data_.ffd_of<Dim>()[index].state;
  return s.penetration <= PenetrationLimit(*FfdEntries<Dim>()[index].model) &&
         (EnergySurelyFinite<Dim>(body) || (s.q.allFinite() && s.qd.allFinite() && EnergyFinite(body)));
}

template <int Dim>
bool World::RefuseFfdStep(int body, const VecQ<double>& q_before, const VecQ<double>& qd_before, StepStatus st) {
  const size_t index = size_t(slots_[size_t(body)].index);
  const FfdEntry<Dim>& e = FfdEntries<Dim>()[index];
  BodyState<Dim, double>& s = data_.ffd_of<Dim>()[index].state;
  const bool finite = s.q.allFinite() && s.qd.allFinite();
  const double limit = PenetrationLimit(*e.model);
  const double depth = s.penetration;
  const bool too_deep = depth > limit;
  const Energies energies = finite && !too_deep ? FfdEnergies<Dim>(body, ContactSet::kFrozen, false) : Energies();
  s.q = q_before;
  s.qd = qd_before;
  UpdateContacts(*e.model, GroundFor<Dim>(), &s);
  // a state that overflowed because its forces did: the force is the cause to name (the step
  // reports only that its state is not finite)
  if (!st.ok() && st.code != StatusCode::kNonFinite) return Fail(st.code, body, "", st.value);
  if (!finite)
    return ForcesFinite<Dim>(body) ? Fail(StatusCode::kNonFinite, body) : Fail(StatusCode::kOverflowingForce, body);
  if (!too_deep)
    return Fail(StatusCode::kNonFiniteEnergy, body,
                EnergyTerms(energies) + " after the step (refused: the state is the one before it)");
  std::ostringstream d;
  d << "a point is " << depth << " below the ground (limit " << limit
    << "); reduce dt, or use a stiffer ground with the implicit integrator";
  return Fail(StatusCode::kPenetration, body, d.str(), depth);
}

template <int Dim> bool World::ForcesFinite(int body) const {
  const BodyState<Dim, double>& s = state<Dim>(body);
  ForceBreakdown<Dim, double> f;
  EvaluateForces(*Ffd<Dim>(body).model, options_.params, body, s, Frame<Dim, double>(s.q), &f, ContactSet::kDetect);
  return f.total.allFinite();
}

std::string EnergyTerms(const Energies& e) {
  std::ostringstream d;
  d << "kinetic " << e.kinetic << ", gravity " << e.gravity << ", modes " << e.modes << ", ground " << e.ground
    << ", springs " << e.springs;
  return d.str();
}

// Half the shortest lattice side, unless the ground sets its own limit.
template <int Dim> double World::PenetrationLimit(const BodyModelN<Dim>& model) const {
  const double own = Dim == 2 ? options_.params.ground.max_penetration : 0.0;
  if (own > 0) return own;
  double shortest = model.lattice().axis(0).norm();
  for (int a = 1; a < Dim; ++a) shortest = std::min(shortest, model.lattice().axis(a).norm());
  return 0.5 * shortest;
}

// ---------------------------------------------------------------- energies

// Eq. 4.9's kinetic, gravity, K (γ − γ0)², the ground's penalty and the springs. The step's
// finiteness check takes the contacts the step left (kFrozen: no scan of every point) and no
// per-mode breakdown (no heap).
template <int Dim> Energies World::FfdEnergies(int i, ContactSet contacts, bool per_mode) const {
  using Vector = Eigen::Matrix<double, Dim, 1>;
  Energies e;
  const auto& p = options_.params;
  const BodyModelN<Dim>& b = body<Dim>(i);
  const BodyState<Dim, double>& s = state<Dim>(i);
  const Frame<Dim, double> frame(s.q);
  e.kinetic = KineticEnergyOf(b, s, frame);
  if (p.gravity_on) e.gravity = GravityEnergyOf(b, s, frame, GravityFor<Dim>(p));
  // K (γ − γ0)²: the potential whose gradient is the mode force, PD target γ0 included
  const bool targeted = s.mode_target.size() == b.num_modes();
  for (int d = 0; d < b.num_modes(); ++d) {
    const double offset = s.gamma()[d] - (targeted ? s.mode_target[d] : 0.0);
    const double term = b.modes()[size_t(d)].stiffness * offset * offset;
    if (per_mode) e.per_mode.push_back(term);
    e.modes += term;
  }
  ForEachPointInContact(b, GroundFor<Dim>(), s, frame,
                        [&](int, const Vector&, const Vector& x, const Vector&, const Vector& anchor, const auto& face,
                            int) { e.ground += 0.5 * face.stiffness * (x - anchor).squaredNorm(); },
                        contacts);
  for (const Spring& sp : p.springs) {
    if (sp.body != i) continue;
    const Vector x = WorldFromLocal(frame, LocalPosition<double>(sp.RestLocal<Dim>(), sp.ModeMatrix<Dim>(), s.q));
    const double stretch = (x - sp.Anchor<Dim>()).norm() - sp.rest_length;
    e.springs += 0.5 * sp.stiffness * stretch * stretch;
  }
  return e;
}
template Energies World::FfdEnergies<2>(int, ContactSet, bool) const;
template Energies World::FfdEnergies<3>(int, ContactSet, bool) const;

// A screen with a proof, so that the step need not compute its energies (a quarter of a step's
// work): when every factor is at most kScreen (the state, the PD targets, the contact anchors,
// the model's moments, points and stiffnesses, the world's gravity, ground and springs), each
// energy term is a sum of at most ~10^6 products of at most five factors (γᵀGγ θ̇², k |x − a|²
// with x = t + R(b0 + Bγ)), so below 10^6 · 15^4 · kScreen^5, far from the largest double. A
// normal step passes; one that does not has its energies computed (EnergyFinite).
namespace {
constexpr double kScreen = 1e30;
// Every |x| ≤ kScreen: a plain loop (maxCoeff is an out-of-line reduction per call here, and
// its result for a NaN is unspecified; !(|x| ≤ bound) is true for a NaN).
template <class V> bool Screened(const V& v) {
  for (int i = 0; i < int(v.size()); ++i)
    if (!(std::abs(v.data()[i]) <= kScreen)) return false;
  return true;
}
}  // namespace

template <int Dim> bool World::EnergySurelyFinite(int body) const {
  const FfdEntry<Dim>& e = Ffd<Dim>(body);
  const BodyState<Dim, double>& s = state<Dim>(body);
  const auto& p = options_.params;
  if (!(e.scale <= kScreen && Screened(s.q) && Screened(s.qd))) return false;
  if (!Screened(s.mode_target)) return false;
  // a terrain's or a heightfield region's own stiffnesses are at most 1e30 (their makers)
  const GroundOf<Dim>& ground = GroundFor<Dim>();
  if (!(Screened(GravityFor<Dim>(p)) && std::abs(ground.stiffness) <= kScreen)) return false;
  if constexpr (Dim == 3) {
    if (!Screened(ground.point)) return false;
  }
  for (const Contact<Dim, double>& c : s.contacts)
    if (!Screened(c.anchor)) return false;
  for (const Spring& sp : p.springs)
    if (!(std::abs(sp.stiffness) <= kScreen && std::abs(sp.rest_length) <= kScreen && Screened(sp.anchor) &&
          Screened(sp.rest_local) && Screened(sp.mode_matrix)))
      return false;
  return true;
}

// ---------------------------------------------------------------- constraint ends

template <int Dim> void World::ResolveFfd(const MaterialPoint& point, End* e) const {
  using Point = Eigen::Matrix<double, Dim, 1>;
  const BodyModelN<Dim>& m = body<Dim>(point.body);
  const char* coords = Dim == 2 ? "(s, t)" : "(s, t, u)";
  Point u;
  if (point.mass_point >= 0) {
    if (point.mass_point >= m.num_points())
      throw std::invalid_argument("body '" + m.name() + "' has " + std::to_string(m.num_points()) +
                                  " mass points, no point " + std::to_string(point.mass_point));
    u = m.lattice_coords(point.mass_point);
  } else {
    if (point.u.size() != Dim || !point.u.allFinite())
      throw std::invalid_argument("a point of FFD body '" + m.name() + "' needs " + std::to_string(Dim) +
                                  " lattice coordinates " + coords);
    u = point.u;
    const double tol = 1e-9;
    if (u.minCoeff() < -tol || u.maxCoeff() > 1.0 + tol) {
      std::ostringstream msg;
      msg << "lattice coordinates (" << u.transpose() << ") of FFD body '" << m.name() << "' are outside [0, 1]^"
          << Dim;
      throw std::invalid_argument(msg.str());
    }
  }
  Point b0;
  typename BodyModelN<Dim>::ModeMatrix B;
  m.LocalBasis(u, &b0, &B);
  e->b0.setZero();
  e->b0.head<Dim>() = b0;
  e->B.setZero(3, B.cols());
  e->B.topRows<Dim>() = B;
}

namespace {
// b0 and B of an end, in the body's dimension.
template <int Dim> Eigen::Matrix<double, Dim, 1> EndRest(const Eigen::Vector3d& b0) { return b0.head<Dim>(); }
}  // namespace

template <int Dim> World::PointVec World::FfdEndPosition(const End& e) const {
  const BodyState<Dim, double>& s = state<Dim>(e.body);
  const Frame<Dim, double> frame(s.q);
  return WorldFromLocal(frame, LocalPosition<double>(EndRest<Dim>(e.b0), e.B.topRows<Dim>(), s.q));
}

template <int Dim> World::PointVec World::FfdEndVelocity(const End& e) const {
  const BodyState<Dim, double>& s = state<Dim>(e.body);
  const Frame<Dim, double> frame(s.q);
  return wobble::PointVelocity(frame, s.qd, LocalPosition<double>(EndRest<Dim>(e.b0), e.B.topRows<Dim>(), s.q),
                               e.B.topRows<Dim>());
}

// J̇ q̇ = R (ω × (ω × l) + 2 ω × B γ̇) (from Eq. 4.21's velocity terms; planar: −θ̇² l + 2 θ̇ S B γ̇).
template <int Dim> World::PointVec World::FfdEndJdotQdot(const End& e) const {
  using Vector = Eigen::Matrix<double, Dim, 1>;
  const BodyState<Dim, double>& s = state<Dim>(e.body);
  const Frame<Dim, double> frame(s.q);
  const Vector l = LocalPosition<double>(EndRest<Dim>(e.b0), e.B.topRows<Dim>(), s.q);
  const Vector Bgd = e.B.topRows<Dim>() * s.qd.tail(e.B.cols());
  return frame.R * (Group<Dim>::Turn(s.qd, Vector(Group<Dim>::Turn(s.qd, l))) + 2.0 * Group<Dim>::Turn(s.qd, Bgd));
}

// J = [I | R ∂(ω × l)/∂ω | R B] (Eq. 4.6–4.8), Dim × num_q.
template <int Dim> Eigen::MatrixXd World::FfdEndJacobian(const End& e) const {
  using Vector = Eigen::Matrix<double, Dim, 1>;
  const BodyState<Dim, double>& s = state<Dim>(e.body);
  const Frame<Dim, double> frame(s.q);
  const Vector l = LocalPosition<double>(EndRest<Dim>(e.b0), e.B.topRows<Dim>(), s.q);
  Eigen::MatrixXd J(Dim, s.qd.size());
  J.leftCols(Dim).setIdentity();
  for (int k = 0; k < Group<Dim>::kRotationDofs; ++k) {
    VecQ<double> unit = VecQ<double>::Zero(s.qd.size());
    unit[Dim + k] = 1.0;
    J.col(Dim + k) = frame.R * Group<Dim>::Turn(unit, l);
  }
  if (e.B.cols() > 0) J.rightCols(e.B.cols()) = frame.R * e.B.topRows<Dim>();
  return J;
}

template <int Dim> void World::FfdAddEndForce(const End& e, const Eigen::VectorXd& f, Eigen::VectorXd* Q) const {
  using Vector = Eigen::Matrix<double, Dim, 1>;
  const BodyState<Dim, double>& s = state<Dim>(e.body);
  const Frame<Dim, double> frame(s.q);
  VecQ<double> q = *Q;
  AddGeneralizedForce(frame, LocalPosition<double>(EndRest<Dim>(e.b0), e.B.topRows<Dim>(), s.q), e.B.topRows<Dim>(),
                      Vector(f), &q);  // Jᵀ f (Eq. 4.20)
  *Q = q;
}

template <int Dim> void World::FfdApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const {
  VecQ<double> x;
  if (!SolveMass(*Ffd<Dim>(body).model, state<Dim>(body), VecQ<double>(Q), &x)) {
    *acc = Eigen::VectorXd::Constant(acc->size(), std::nan(""));  // caught by the finite checks
    return;
  }
  *acc += x;
}

template <int Dim>
bool World::FfdFreeAcceleration(int body, Eigen::VectorXd* acc, StepStatus* st, ContactSet contacts) const {
  const WorldData::Ffd<Dim>& e = FfdData<Dim>(body);
  VecQ<double> a;
  *st = wobble::Accelerations(*Ffd<Dim>(body).model, options_.params, body, e.state, &a,
                              static_cast<ForceBreakdown<Dim, double>*>(nullptr), contacts);
  if (!st->ok()) return false;
  *acc = a;
  if (!e.applied.isZero(0.0)) FfdApplyGeneralized<Dim>(body, e.applied, acc);
  return true;
}

// Semi-implicit Euler, velocity first, on the group (the Störmer form of Eq. 4.22/4.23).
template <int Dim> bool World::FfdAcceptConstrainedStep(int body, const Eigen::VectorXd& acc) {
  WorldData::Ffd<Dim>& e = FfdData<Dim>(body);
  const VecQ<double> q_before = e.state.q, qd_before = e.state.qd;
  e.state.qd += options_.dt * acc;
  Group<Dim>::Advance(e.state.qd, options_.dt, &e.state.q);
  return FfdAcceptState<Dim>(body, q_before, qd_before);
}

template <int Dim>
bool World::FfdAcceptState(int body, const VecQ<double>& q_before, const VecQ<double>& qd_before) {
  const BodyModelN<Dim>& model = *Ffd<Dim>(body).model;
  WorldData::Ffd<Dim>& e = FfdData<Dim>(body);
  UpdateContacts(model, GroundFor<Dim>(), &e.state);
  e.applied.setZero();  // the step's accelerations held it
  if (e.state.q.allFinite() && e.state.qd.allFinite() && e.state.penetration <= PenetrationLimit(model) &&
      EnergyFinite(body))
    return true;
  return RefuseFfdStep<Dim>(body, q_before, qd_before, StepStatus{});
}

// A Runge–Kutta–Munthe-Kaas stage on the group (step.h): q0·exp(dy), v0 + dv; contacts kept.
template <int Dim>
void World::FfdMoveToStage(int body, const Eigen::VectorXd& q0, const Eigen::VectorXd& v0, const Eigen::VectorXd& dy,
                           const Eigen::VectorXd& dv) {
  BodyState<Dim, double>& s = FfdData<Dim>(body).state;
  Group<Dim>::Retract(VecQ<double>(q0), VecQ<double>(dy), &s.q);
  s.qd = v0 + dv;
}

template <int Dim> void World::FfdAddVelocity(int body, const Eigen::VectorXd& dv) {
  WorldData::Ffd<Dim>& e = FfdData<Dim>(body);
  e.state.qd += dv;
  UpdateContacts(*Ffd<Dim>(body).model, GroundFor<Dim>(), &e.state);
}

#define WOBBLE_WORLD_FFD(Dim)                                                                             \
  template void World::ResolveFfd<Dim>(const MaterialPoint&, End*) const;                               \
  template World::PointVec World::FfdEndPosition<Dim>(const End&) const;                               \
  template World::PointVec World::FfdEndVelocity<Dim>(const End&) const;                               \
  template World::PointVec World::FfdEndJdotQdot<Dim>(const End&) const;                               \
  template Eigen::MatrixXd World::FfdEndJacobian<Dim>(const End&) const;                               \
  template void World::FfdAddEndForce<Dim>(const End&, const Eigen::VectorXd&, Eigen::VectorXd*) const; \
  template void World::FfdApplyGeneralized<Dim>(int, const Eigen::VectorXd&, Eigen::VectorXd*) const;   \
  template bool World::FfdFreeAcceleration<Dim>(int, Eigen::VectorXd*, StepStatus*, ContactSet) const;  \
  template bool World::FfdAcceptConstrainedStep<Dim>(int, const Eigen::VectorXd&);                      \
  template bool World::FfdAcceptState<Dim>(int, const VecQ<double>&, const VecQ<double>&);              \
  template void World::FfdMoveToStage<Dim>(int, const Eigen::VectorXd&, const Eigen::VectorXd&,         \
                                           const Eigen::VectorXd&, const Eigen::VectorXd&);             \
  template void World::FfdAddVelocity<Dim>(int, const Eigen::VectorXd&);                                \
  template bool World::EnergySurelyFinite<Dim>(int) const;
WOBBLE_WORLD_FFD(2)
WOBBLE_WORLD_FFD(3)
#undef WOBBLE_WORLD_FFD

}  // namespace wobble
