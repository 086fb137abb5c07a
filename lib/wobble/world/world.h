// THE world: every kind of body (FFD bodies of the thesis, Witkin & Welch linear bodies in 2D
// and 3D), the ground, springs, constraints and impulses, one clock and one status.
//
// Usage (tests/constraints_test.cc, HelloPendulum; tests/physics_test.cc for FFD bodies):
//   World w({.params = ..., .dt = 0.002});
//   int table = w.AddBody(ffd_model);                     // an FFD body, at q = 0, at rest
//   int link = w.AddLinearBody(model, material);          // a linear body, at its rest state
//   int nail = w.AddNail({link, top_u});                  // nailed where the point is now
//   while (w.time() < 5) if (!w.Step()) report(w.status().message);
//   w.SetEnabled(nail, false);                            // the link falls; refactors once
//
// One body numbering for both kinds. FFD bodies of either dimension (2D: q = [tx, ty, θ,
// γ1..γD], Eq. 4.4; 3D: q = [t, unit quaternion, γ]) share their accessors (q, qd, SetState,
// SetModeTargets, ComputeEnergies, ...; body<Dim>, state<Dim> for the typed model and state);
// linear bodies x = R p(u) have R and Ṙ (linear_model, linear_R, SetLinearState).
//
// Stepping. While no constraint is enabled, every FFD body is advanced on its own by the
// templated StepBody (wobble/dynamics/step.h) with the world's integrator: the per-body fast
// path of the thesis, which the fits differentiate with Ceres Jets, and whose cost is O(D²)
// from the mass moments (ARCHITECTURE.md). Linear bodies take the same integrator on their
// constant, pre-inverted mass matrix (thesis and variational: velocity-first Euler, which is
// the variational integrator of a constant M). While a constraint is enabled, every body is
// advanced together through the multipliers (world_constraints.cc), with the same integrator:
// the constrained accelerations
//   J W Jᵀ λ = −(J W Q + J̇ q̇ − n̈ + α c + β ċ),   q̈ = W (Q + Jᵀ λ)   (Witkin & Welch Eq. 6–10)
// are a stage, evaluated wherever the integrator evaluates q̈: thesis (velocity-first Euler
// q̇ₙ₊₁ = q̇ₙ + Δt q̈, qₙ₊₁ = qₙ·exp(Δt q̇ₙ₊₁), Eq. 4.22/4.23's Störmer form), symplectic, rk4 and
// implicit. The variational integrator's discrete Lagrangian has no constraint forces: a
// constrained variational step is refused (StatusCode::kUnsupported). c̈ = −α c − β ċ makes a
// violation decay like a critically damped spring instead of drifting.
//
// Linear bodies: ∂x/∂R = δ_ir p_s (§3.3) is constant, so J is constant and J̇ = 0, and A = J W Jᵀ
// is factored once per change of the enabled set (dense inverse or sparse LDLT,
// MultiplierSolver). While a constraint touches an FFD body, A is rebuilt from M(q) per step.
//
// Every accepted state is checked; the first trouble stops the world with a status naming the
// step, the time, the body and the cause (never a silent NaN).
#pragma once

#include <memory>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "wobble/body/affine_energy.h"
#include "wobble/core/interrupt.h"
#include "wobble/body/linear_body.h"
#include "wobble/dynamics/linear_ground.h"
#include "wobble/dynamics/step.h"
#include "wobble/world/controller.h"
#include "wobble/world/multiplier_solver.h"
#include "wobble/world/point_path.h"

namespace wobble {

enum class BodyKind { kLinear, kFfd };  // an FFD body of either dimension: World::dim
enum class ConstraintKind { kNail, kAttachment, kTrajectory };
const char* ConstraintKindName(ConstraintKind kind);

// Energy terms of one body. Linear bodies: kinetic, gravity and their affine energy in `modes`.
struct Energies {
  double kinetic = 0, gravity = 0, modes = 0, ground = 0, springs = 0;
  std::vector<double> per_mode;  // each FFD mode's K (γ − γ0)²; `modes` is their sum
  double total() const { return kinetic + gravity + modes + ground + springs; }
};

// Why the world stopped, and where. The cause is one StatusCode for per-body and world trouble.
struct WorldStatus {
  using Code = StatusCode;
  Code code = Code::kOk;
  long step = 0;      // the step that failed (1-based), or steps taken
  double time = 0.0;  // simulated time at the start of that step
  int body = -1;      // -1: not one body's (the constraints)
  std::string message;  // one line for people
  bool ok() const { return code == Code::kOk; }
};

// The largest |number| of a model's moments, points and mode stiffnesses (inf for a NaN).
template <int Dim> double ModelScale(const BodyModelN<Dim>& b);
double LinearScale(const LinearBodyModel& m, const AffineMaterial& material);  // the same, linear

// "kinetic K, gravity G, ..." of a refused step, for its status message.
std::string EnergyTerms(const Energies& e);

struct WorldOptions {
  // Gravity (one vector; 2D bodies feel its x and y), the ground of each dimension (2D: the
  // line or terrain `ground`; 3D: `ground_plane`), the springs of every FFD body and
  // max_condition: one set for bodies of both dimensions, which their steps read as it is.
  WorldParams params;
  // Every body's integrator, constraints a stage of it (variational: refused with constraints).
  Integrator integrator = Integrator::kThesis;
  double dt = 0.01;
  // Default constraint feedback: α = (rate/Δt)², β = 2 rate/Δt (critically damped).
  double feedback_rate = 0.1;
  // Dense pre-inverted A up to this many constraint rows, sparse LDLT above (kAuto). Measured
  // (bench/constraints_bench): per step the two are equal within 5 % up to 200 rows and the
  // dense solve grows quadratically beyond; refactoring is cheaper sparse from about 20 rows on.
  MultiplierMethod method = MultiplierMethod::kAuto;
  int dense_max_rows = 24;
};

// A material point of a body. Linear bodies: u in undeformed coordinates (any point, inside
// or outside the mass points). FFD bodies: u = lattice coordinates (s, t) in [0, 1]². Or
// mass_point = k ≥ 0: the body's k-th mass point (u is then ignored).
struct MaterialPoint {
  int body = -1;
  Eigen::VectorXd u;
  int mass_point = -1;
};
inline MaterialPoint At(int body, Eigen::VectorXd u) { return {body, std::move(u), -1}; }
inline MaterialPoint MassPointOf(int body, int k) { return {body, Eigen::VectorXd(), k}; }

// Drift feedback of one constraint: c̈ = −α c − β ċ. Negative means the world's default.
struct Feedback {
  double alpha = -1.0, beta = -1.0;
};

// A velocity goal for ApplyImpulse: after the jump, v(a) − v(b) = v (b.body < 0: v(a) = v).
struct VelocityGoal {
  MaterialPoint a;
  MaterialPoint b;  // body −1: none
  Eigen::VectorXd v;
};

// The 3D ground of a 2D ground line (the `set` parameters and the CLI's ground flags): the
// plane through its point with its normal, extended along z, with its stiffness, damping and
// friction.
GroundPlane GroundPlaneOf(const Ground& ground);

// What a run changes (MuJoCo's mjData): each body's state with its ground contacts and the
// point forces waiting for the next step, the constraints' multipliers, the clock and the
// status. Everything else a World holds is its model (MuJoCo's mjModel), which steps do not
// change: the body models and materials, the options (gravity, ground, springs, integrator),
// the constraint topology, the kinematic flags and the controllers. A replay, trials from one
// start or an undo copies this and puts it back (World::data, World::SetData), not the world.
struct WorldData {
  template <int Dim> struct Ffd {
    BodyState<Dim, double> state;
    Eigen::VectorXd applied;  // Σ Jᵀ f of ApplyPointForce for the next step
  };
  struct Linear {
    Eigen::MatrixXd R, R_dot;
    Eigen::MatrixXd applied;  // Σ f pᵀ of ApplyPointForce for the next step
    LinearContacts contacts;
  };
  // the FFD bodies by dimension and the linear bodies, each in the order added
  std::tuple<std::vector<Ffd<2>>, std::vector<Ffd<3>>> ffd;
  std::vector<Linear> linear;
  std::vector<Eigen::VectorXd> multipliers;  // λ of each constraint id at the last step
  // the clock: time = time_origin + origin_steps dt (no drift from summing dt) since the clock
  // was set or dt changed
  double time = 0.0, time_origin = 0.0, origin_dt = 0.0;
  long origin_steps = 0;
  long steps = 0;
  WorldStatus status;

  template <int Dim> std::vector<Ffd<Dim>>& ffd_of() { return std::get<Dim - 2>(ffd); }
  template <int Dim> const std::vector<Ffd<Dim>>& ffd_of() const { return std::get<Dim - 2>(ffd); }
};

class World {
 public:
  explicit World(WorldOptions options = {});

  // ---- bodies (one numbering for both kinds) ----
  // An FFD body of either dimension starts in its lattice's pose (t = 0, no turn, γ = 0), at
  // rest. Both step on options().params with options().integrator.
  int AddBody(std::shared_ptr<const BodyModelN<2>> model) { return AddFfdBody<2>(std::move(model)); }
  int AddBody(std::shared_ptr<const BodyModelN<3>> model) { return AddFfdBody<3>(std::move(model)); }
  // A linear body starts at its rest state R = [I | 0 | 0], at rest.
  int AddLinearBody(std::shared_ptr<const LinearBodyModel> model, AffineMaterial material = {});
  int num_bodies() const { return int(slots_.size()); }
  BodyKind kind(int body) const;
  int dim(int body) const;  // 2 or 3
  bool IsFfd(int body, int dim) const { return kind(body) == BodyKind::kFfd && slots_[size_t(body)].dim == dim; }
  const std::string& body_name(int body) const;

  // FFD bodies of either dimension (std::invalid_argument for another kind, the other
  // dimension or a wrong size; InputError for a state that is not finite or whose energy is
  // not). The model and state of dimension Dim: body<2>(i), state<3>(i), ...
  template <int Dim> const BodyModelN<Dim>& body(int i) const { return *Ffd<Dim>(i).model; }
  // for whoever outlives the world
  template <int Dim> const std::shared_ptr<const BodyModelN<Dim>>& shared_body(int i) const { return Ffd<Dim>(i).model; }
  template <int Dim> const BodyState<Dim, double>& state(int i) const { return FfdData<Dim>(i).state; }
  // Either dimension: positions q (2D [t, θ, γ]; 3D [t, unit quaternion x y z w, γ]) and
  // velocities q̇ (2D dq/dt; 3D [ṫ, body ω, γ̇]), as body_state.h lays them out.
  const VecQ<double>& q(int i) const;
  const VecQ<double>& qd(int i) const;
  int num_modes(int i) const;
  // The PD targets γ0 of its modes (empty: all zero).
  const VecD<double>& mode_targets(int i) const;
  // How deep the body's deepest contact point is below the ground now (0 without contacts).
  double Penetration(int body) const;
  // Sets positions and velocities in the layout of q() and qd(); a 3D quaternion is
  // normalized (a zero one is refused). Does not enforce constraints: follow with
  // ProjectVelocities() or let the feedback pull it in.
  void SetState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
  // The coordinates people read and write (files, the command line's --q, Python's World.q):
  // the positions in 2D; [t, Θ, γ] in 3D with Θ the orientation's rotation vector
  // (StateFromCoordinates, body_state.h). Velocities as qd().
  Eigen::VectorXd coordinates(int body) const;
  void SetCoordinates(int body, const Eigen::VectorXd& coordinates, const Eigen::VectorXd& qd);
  // PD targets γ0 of the body's modes (one per mode; empty: all zero). See wobble/control.
  void SetModeTargets(int body, const Eigen::VectorXd& targets);
  template <int Dim> ForceBreakdown<Dim, double> Forces(int body) const;
  Eigen::VectorXd Accelerations(int body) const;  // free q̈ (no constraint forces)
  // world positions of its mass points
  template <int Dim> std::vector<Eigen::Matrix<double, Dim, 1>> PointPositions(int body) const;

  // Linear bodies: R and Ṙ (d×n).
  const LinearBodyModel& linear_model(int body) const;
  const std::shared_ptr<const LinearBodyModel>& shared_linear_model(int body) const;
  void SetLinearState(int body, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot);
  const Eigen::MatrixXd& linear_R(int body) const;
  const Eigen::MatrixXd& linear_R_dot(int body) const;
  void SetMaterial(int body, const AffineMaterial& material);
  const AffineMaterial& material(int body) const;
  // Whether a linear body feels the ground: a 2D one the 2D ground (line or terrain), a 3D one
  // params.ground_plane (linear_ground.h). Off by default, as in Witkin & Welch's scenes, which have no
  // ground; FFD bodies always feel it. Turning it on or off starts with no contacts.
  void SetGroundContact(int body, bool on);
  bool ground_contact(int body) const;
  // The linear body's contacts with their anchors (empty while ground_contact is off).
  const LinearContacts& linear_contacts(int body) const;
  // The ground of a linear body, for the linear_ground.h functions.
  LinearGround linear_ground() const { return {options_.params.ground, options_.params.ground_plane}; }

  // Springs hold a point of an FFD body (spring.body) given by lattice coordinates (Fig. 4.4);
  // into options().params.springs, with b0 and B of the body's point filled in. Returns its
  // index there.
  int AddSpring(Spring spring);

  // ---- material points ----
  // Throws std::invalid_argument: unknown body, wrong size, lattice coordinates outside
  // [0, 1]², or a mass point index out of range.
  Eigen::VectorXd PointPosition(const MaterialPoint& point) const;
  Eigen::VectorXd PointVelocity(const MaterialPoint& point) const;
  // A world force at a point during the next step only (Q = f pᵀ, or Jᵀ f for FFD bodies).
  void ApplyPointForce(const MaterialPoint& point, const Eigen::VectorXd& f);

  // ---- constraints: each returns an id, enabled at once ----
  // Nail the point at `where` (empty: where the point is now).
  int AddNail(const MaterialPoint& point, Eigen::VectorXd where = Eigen::VectorXd(), Feedback fb = {});
  int AddAttachment(const MaterialPoint& a, const MaterialPoint& b, Feedback fb = {});
  int AddTrajectory(const MaterialPoint& point, std::shared_ptr<const PointPath> path, Feedback fb = {});
  // Moving a nail or replacing a path keeps the factorization (J does not change).
  void SetNailPosition(int id, const Eigen::VectorXd& where);
  void SetPath(int id, std::shared_ptr<const PointPath> path);
  void SetFeedback(int id, Feedback fb);
  // Switching on or off (or removing) refactors A at the next step. Removed ids stay invalid.
  void SetEnabled(int id, bool enabled);
  void Remove(int id);
  bool enabled(int id) const;
  bool exists(int id) const;
  ConstraintKind constraint_kind(int id) const;
  // The bodies of its ends: {a, b}, b = −1 for a nail or a trajectory.
  std::pair<int, int> constraint_bodies(int id) const { return {Get(id).a.body, Get(id).b.body}; }
  int num_constraints() const { return int(constraints_.size()); }  // ids are 0..n−1
  int num_enabled_constraints() const { return enabled_count_; }
  // c = x_a − x_b (or x_a − n(t)) now, and its largest norm over the enabled constraints.
  Eigen::VectorXd ConstraintError(int id) const;
  Eigen::VectorXd ConstraintVelocityError(int id) const;
  double MaxViolation() const;
  // The multiplier λ (the constraint force on point a, world units) of the last step.
  Eigen::VectorXd Multiplier(int id) const;

  // ---- impulses (§3.2, Eq. 9) ----
  // One velocity jump Δq̇ = W Jᵀ λ, with J W Jᵀ λ = (wanted − current velocity of each row):
  // every enabled constraint ends with ċ = 0 (a trajectory: the point moves with ṅ(t)), and
  // every goal is met exactly. Non-impulsive forces are ignored (§3.2). Returns false with
  // *error (and nothing changed) when the goals conflict with each other or with the
  // constraints, or name an unknown body or point.
  bool ApplyImpulse(const std::vector<VelocityGoal>& goals, std::string* error = nullptr);
  // ApplyImpulse({}): makes the velocities legal (e.g. after SetLinearState or a path switch).
  bool ProjectVelocities(std::string* error = nullptr) { return ApplyImpulse({}, error); }

  // ---- controllers (controller.h) and the recorder ----
  // Every Step calls the controllers in the order added, then the recorder (one, or none:
  // wobble/record's Recorder). The world shares their ownership.
  void AddController(std::shared_ptr<Controller> controller);
  void RemoveController(const Controller* controller);  // no-op when absent
  void ClearControllers() {
    for (auto& c : controllers_) c = nullptr;
    if (stepping_) removed_while_stepping_ = true;
    else controllers_.clear();
  }
  void SetRecorder(std::shared_ptr<Controller> recorder) { recorder_ = std::move(recorder); }
  Controller* recorder() const { return recorder_.get(); }
  // A kinematic body is not moved by Step (Box2D's kinematic bodies): controllers set its
  // state, as keyframes do. It is not moved by constraint forces either.
  void SetKinematic(int body, bool kinematic);
  bool kinematic(int body) const;

  // ---- stepping ----
  // One step of every body. Returns false and keeps status() at the first trouble (the body's
  // state before the step is kept); later calls return false until ClearStatus().
  bool Step();
  // Steps until time >= t_end or trouble; calls on_step(world) after every accepted step.
  // Ctrl-C (core/interrupt.h) between two steps throws Interrupted saying where.
  template <class F> bool RunUntil(double t_end, F&& on_step) {
    while (data_.time + 0.5 * options_.dt < t_end) {
      if (InterruptRequested()) ThrowInterrupted();
      if (!Step()) return false;
      on_step(*this);
    }
    return true;
  }
  bool RunUntil(double t_end) {
    return RunUntil(t_end, [](World&) {});
  }
  [[noreturn]] void ThrowInterrupted() const;  // "stopped by Ctrl-C at t = T (step N)"
  const WorldStatus& status() const { return data_.status; }
  // Stops the world after the step now (a controller's or the recorder's call: a record row
  // that overflowed); the state stays. body -1: not one body's trouble.
  void Stop(StatusCode code, int body, const std::string& detail) { Fail(code, body, detail); }
  void ClearStatus() { data_.status = WorldStatus(); }
  // Sets the clock (replays of recorded states, scenes that start later); steps continue from t.
  void SetTime(double t) {
    data_.time = data_.time_origin = t;
    data_.origin_steps = 0;
  }
  double time() const { return data_.time; }
  long steps() const { return data_.steps; }
  const WorldOptions& options() const { return options_; }
  // Changing dt, gravity, the ground, springs or the integrator between steps is allowed
  // (scripts and the viewer do).
  WorldOptions& mutable_options() { return options_; }

  // ---- model and data (WorldData) ----
  // Everything a step changes. SetData puts back a copy taken of this world (or of a world
  // with the same bodies and constraints): std::invalid_argument when its bodies, sizes or
  // constraints do not match. Controllers and the recorder are not called.
  const WorldData& data() const { return data_; }
  void SetData(WorldData data);

  // ---- energies ----
  // Every term of one body (Energies); kinetic ½ q̇ᵀ M q̇ (FFD, Eq. 4.9) or ½ tr(Ṙ M Ṙᵀ) (linear).
  Energies ComputeEnergies(int body) const;
  double KineticEnergy(int body) const { return ComputeEnergies(body).kinetic; }
  double PotentialEnergy(int body) const;
  double TotalEnergy() const;

  // ---- statistics ----
  // Factorizations of the constant A (linear bodies only): one per change of the enabled set.
  long factorizations() const { return constant_solver_.factorizations(); }
  // Factorizations made because an enabled constraint touches an FFD body (one per step).
  long per_step_factorizations() const { return dynamic_solver_.factorizations(); }
  // The method of the last factorization (dense or sparse) and A's size.
  MultiplierMethod last_method() const { return last_method_; }
  int constraint_rows() const;

 private:
  struct Slot {
    BodyKind kind;
    int dim;    // 2 or 3
    int index;  // into ffd_ (by dim) or linear_, and the same in data_
    bool kinematic = false;
  };
  // A point or constraint value (d ≤ 3) on the stack: the per-step loops allocate nothing.
  using PointVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
  // The model of an FFD body of dimension Dim (its state: data_.ffd_of<Dim>(), same index).
  template <int Dim> struct FfdEntry {
    std::shared_ptr<const BodyModelN<Dim>> model;
    double scale = 0.0;  // the largest |number| of the model (ModelScale), for EnergySurelyFinite
  };
  // The model of a linear body (its state: data_.linear, same index) and its per-step work.
  struct LinearEntry {
    std::shared_ptr<const LinearBodyModel> model;
    AffineMaterial material;
    double scale = 0.0;  // the largest |number| of the mass matrix, first moment and material
    bool ground_contact = false;
    // per-step work, not state: the generalized force, and what a refused step restores
    Eigen::MatrixXd Q, R_before, R_dot_before;
    LinearContacts contacts_before;
  };
  // A resolved material point: linear bodies keep p(u) and W p; FFD bodies b0 and B (their
  // first dim(body) rows: one layout for both dimensions).
  struct End {
    int body = -1;
    Eigen::VectorXd p, Wp;  // linear
    Eigen::Vector3d b0 = Eigen::Vector3d::Zero();  // FFD
    Mat3D<double> B;                               // FFD
  };
  struct Constraint {
    ConstraintKind kind;
    End a, b;  // b.body < 0: nail/trajectory
    Eigen::VectorXd where;
    std::shared_ptr<const PointPath> path;
    Feedback fb;
    bool enabled = true, removed = false;
    int row = -1;  // first row in A while enabled
  };

  // world.cc: bodies, controllers, linear bodies, energies; world_ffd.cc: the FFD bodies of
  // either dimension (added, set, stepped, checked; their ends of constraints)
  void CheckBody(int body) const;
  template <int Dim> std::vector<FfdEntry<Dim>>& FfdEntries();
  template <int Dim> const std::vector<FfdEntry<Dim>>& FfdEntries() const;
  template <int Dim> int FfdIndex(int body) const;  // into FfdEntries<Dim> and data_.ffd_of<Dim>
  template <int Dim> const FfdEntry<Dim>& Ffd(int body) const { return FfdEntries<Dim>()[size_t(FfdIndex<Dim>(body))]; }
  template <int Dim> const WorldData::Ffd<Dim>& FfdData(int body) const {
    return data_.ffd_of<Dim>()[size_t(FfdIndex<Dim>(body))];
  }
  template <int Dim> WorldData::Ffd<Dim>& FfdData(int body) { return data_.ffd_of<Dim>()[size_t(FfdIndex<Dim>(body))]; }
  template <int Dim> int AddFfdBody(std::shared_ptr<const BodyModelN<Dim>> model);
  template <int Dim> const GroundOf<Dim>& GroundFor() const { return wobble::GroundFor<Dim>(options_.params); }
  [[noreturn]] void ThrowBadBody(int body, BodyKind wanted, int wanted_dim = 0) const;
  const LinearEntry& Linear(int body) const;
  const WorldData::Linear& LinearData(int body) const;
  bool StepEachBody();
  template <int Dim> void SetFfdState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
  template <int Dim> bool StepFfdBody(int body);
  // Refuses a step that failed, left a non-finite state or energy, or sank a point too deep;
  // the body gets `before` back.
  template <int Dim>
  bool RefuseFfdStep(int body, const VecQ<double>& q_before, const VecQ<double>& qd_before, StepStatus st);
  template <int Dim> bool AcceptFfdState(int body);  // the checks of StepFfdBody
  template <int Dim> bool ForcesFinite(int body) const;
  template <int Dim> double PenetrationLimit(const BodyModelN<Dim>& model) const;
  template <int Dim> Energies FfdEnergies(int body, ContactSet contacts, bool per_mode) const;
  // Every energy term of the body is finite: a finite state can hold an infinite energy (a
  // q̇ of 1e160 squares past the largest double), and no accepted step leaves one.
  bool EnergyFinite(int body) const;
  template <int Dim> bool EnergySurelyFinite(int body) const;
  template <int Dim> void ResolveFfd(const MaterialPoint& point, End* e) const;
  template <int Dim> PointVec FfdEndPosition(const End& e) const;
  template <int Dim> PointVec FfdEndVelocity(const End& e) const;
  template <int Dim> PointVec FfdEndJdotQdot(const End& e) const;
  template <int Dim> Eigen::MatrixXd FfdEndJacobian(const End& e) const;
  template <int Dim> void FfdAddEndForce(const End& e, const Eigen::VectorXd& f, Eigen::VectorXd* Q) const;
  template <int Dim> void FfdApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const;
  template <int Dim>
  bool FfdFreeAcceleration(int body, Eigen::VectorXd* acc, StepStatus* st, ContactSet contacts = ContactSet::kDetect) const;
  template <int Dim> bool FfdAcceptConstrainedStep(int body, const Eigen::VectorXd& acc);
  // The new state is in data_: contacts found, the checks of a step, or back to the state given.
  template <int Dim> bool FfdAcceptState(int body, const VecQ<double>& q_before, const VecQ<double>& qd_before);
  template <int Dim> void FfdMoveToStage(int body, const Eigen::VectorXd& q0, const Eigen::VectorXd& v0,
                                         const Eigen::VectorXd& dy, const Eigen::VectorXd& dv);
  template <int Dim> void FfdAddVelocity(int body, const Eigen::VectorXd& dv);
  void LinearFreeAcceleration(int body, Eigen::VectorXd* acc);
  void RefreshLinearContacts(int body);  // the contacts of its state now
  bool Fail(StatusCode code, int body, const std::string& detail = "", double value = 0.0);
  bool StepLinearBody(int body, const Eigen::VectorXd& acc);
  // The linear body's new state is in data_, the one before it in R_before and R_dot_before:
  // the checks and contacts of a step, or the state before it back.
  bool FinishLinearStep(int body, bool screened);
  bool AcceptLinearState(int body, const Eigen::MatrixXd& R_before, const Eigen::MatrixXd& R_dot_before);
  bool AcceptLinearStep(int body, bool screened);
  void FinishStep();

  // world_constraints.cc: points, constraints, the multiplier step, impulses
  End Resolve(const MaterialPoint& point) const;
  const Constraint& Get(int id) const;
  Constraint& Get(int id);
  int AddConstraint(Constraint c);
  PointVec EndPosition(const End& e) const;
  PointVec EndVelocity(const End& e) const;
  // Jᵀ f as the body's generalized force (flattened for linear bodies: row-major R).
  void AddEndForce(const End& e, const Eigen::VectorXd& f, std::vector<Eigen::VectorXd>* Q) const;
  PointVec EndJdotQdot(const End& e) const;  // J̇ q̇ (zero for linear bodies)
  // W Jᵀ e_i (nq × d) for an end, and J of another end times that.
  Eigen::MatrixXd EndWJt(const End& e) const;
  Eigen::MatrixXd EndJacobian(const End& e) const;  // d × nq of the body
  void Targets(const Constraint& c, double t, PointVec* n, PointVec* n_dot, PointVec* n_ddot) const;
  double FeedbackAlpha(const Constraint& c) const;
  double FeedbackBeta(const Constraint& c) const;
  bool AnyFfdConstrained() const;
  int AssignRows();
  // A = J W Jᵀ over the given rows.
  Eigen::SparseMatrix<double> AssembleA(const std::vector<const Constraint*>& rows) const;
  // Factors A when it changed (or always, when an FFD body is constrained: A depends on q);
  // *factored (if given) is the solver that holds it.
  bool EnsureFactored(std::string* why, const MultiplierSolver** factored = nullptr);
  // Free accelerations of every body (flattened), or false with the failing body and status.
  bool FreeAccelerations(std::vector<Eigen::VectorXd>* a, int* failed_body, StepStatus* st,
                         ContactSet contacts = ContactSet::kDetect);
  void ApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const;  // += W Q
  // The constrained q̈ = W (Q + Jᵀ λ) of every body at the state in data_ and time t (Eq. 6–10
  // with feedback), λ recorded in data_.multipliers. `lag`: how far the velocities lag the
  // positions (½Δt in the Euler forms, 0 at a Runge–Kutta stage). false: the status says why.
  bool ConstrainedAccelerations(double t, double lag, ContactSet contacts, std::vector<Eigen::VectorXd>* acc);
  bool StepConstrained();        // the world's integrator over every body through the multipliers
  bool StepConstrainedThesis();  // velocity-first Euler (Eq. 4.22/4.23's Störmer form)
  // symplectic, rk4, implicit: their stages at constrained q̈ (linear_only: the linear bodies of
  // a world without constraints, at their free q̈)
  bool StepConstrainedStaged(bool linear_only = false);
  // The start of a constrained step, every body flattened (FFD q and q̇; linear R and Ṙ row by
  // row), and the moves of its stages about it: q0·exp(dy), v0 + dv on the body's group.
  struct StepStart {
    std::vector<Eigen::VectorXd> q, v;
  };
  void SaveStart(StepStart* start) const;
  void RestoreStart(const StepStart& start);
  void MoveToStage(int body, const StepStart& start, const Eigen::VectorXd& dy, const Eigen::VectorXd& dv);
  // the rate of the stage's tangent coordinates dy at velocity v (dexp⁻¹; v itself but in 3D)
  Eigen::VectorXd StageRate(int body, const Eigen::VectorXd& dy, const Eigen::VectorXd& v) const;
  // Checks the new state in data_ as every step does; a refused body gets its start back.
  bool AcceptStagedState(int body, const StepStart& start);
  int num_q(int body) const;

  WorldOptions options_;
  std::vector<Slot> slots_;
  std::vector<std::shared_ptr<Controller>> controllers_;  // null: removed during this step
  std::shared_ptr<Controller> recorder_;
  bool stepping_ = false;
  bool removed_while_stepping_ = false;  // controllers_ has null entries to erase
  std::tuple<std::vector<FfdEntry<2>>, std::vector<FfdEntry<3>>> ffd_;  // the FFD bodies' models, by dimension
  std::vector<LinearEntry> linear_;
  std::vector<Constraint> constraints_;
  int enabled_count_ = 0;
  std::vector<Eigen::VectorXd> acc_, force_;  // per-step work, kept to reuse their storage
  Eigen::VectorXd rhs_, lambda_;             // per-step work of the multiplier solve
  MultiplierSolver constant_solver_, dynamic_solver_;
  bool structure_dirty_ = true;
  MultiplierMethod last_method_ = MultiplierMethod::kAuto;
  WorldData data_;
};

inline void World::CheckBody(int body) const {
  if (unsigned(body) >= slots_.size()) ThrowBadBody(body, BodyKind::kFfd);
}
inline BodyKind World::kind(int body) const {
  CheckBody(body);
  return slots_[size_t(body)].kind;
}
template <int Dim> std::vector<World::FfdEntry<Dim>>& World::FfdEntries() { return std::get<Dim - 2>(ffd_); }
template <int Dim> const std::vector<World::FfdEntry<Dim>>& World::FfdEntries() const { return std::get<Dim - 2>(ffd_); }
// inline: the per-step loops of controllers call body() and state()
template <int Dim> int World::FfdIndex(int body) const {
  if (unsigned(body) >= slots_.size() || slots_[size_t(body)].kind != BodyKind::kFfd || slots_[size_t(body)].dim != Dim)
    ThrowBadBody(body, BodyKind::kFfd, Dim);
  return slots_[size_t(body)].index;
}

}  // namespace wobble
