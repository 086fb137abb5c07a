// A world of Witkin–Welch linear bodies (2D and 3D) and FFD bodies (2D) joined by constraints
// solved with Lagrange multipliers (§3, Eq. 6–10), with impulses (§3.2, Eq. 9).
//
// Usage (see tests/constraints_test.cc, HelloPendulum):
//   ConstrainedWorld w;                                   // gravity −y, dt 0.002
//   int link = w.AddLinearBody(model, material);          // or AddFfdBody(ffd_model)
//   int nail = w.AddNail({link, top_u});                  // nailed where the point is now
//   while (w.time() < 5) if (!w.Step()) report(w.status().message);
//   w.SetEnabled(nail, false);                            // the link falls; refactors once
//
// Constraints. Every constraint is c = x_a − x_b = 0 on material points (d rows):
//   nail        x_b = a fixed place,   trajectory  x_b = n(t) of a PointPath,
//   attachment  x_b = a point of another (or the same) body.
// The multipliers solve (Eq. 8, with the feedback put into the acceleration condition)
//   J W Jᵀ λ = −(J W Q + J̇ q̇ − n̈ + α c + β ċ),   q̈ = W (Q + Jᵀ λ),
// i.e. c̈ = −α c − β ċ: any violation decays like a critically damped spring (β = 2√α)
// instead of drifting. The paper adds the same two terms as a force along ∂c/∂q; in the
// acceleration equation they do not depend on the bodies' masses. Both vanish when c = ċ = 0.
//
// Linear bodies: ∂x/∂R = δ_ir p_s (§3.3) does not depend on R, so J is constant and J̇ = 0;
// W is constant too, hence A = J W Jᵀ is constant while the set of enabled constraints is
// unchanged: it is factored once (dense inverse or sparse LDLT, MultiplierSolver) and every
// step reuses it; adding, removing or switching a constraint refactors at the next step
// (counted by factorizations()). For two ends on one linear body the block of A is
// (p_aᵀ W p_b) I_d, so assembling A is cheap. Moving a nail or changing a path keeps A.
//
// FFD bodies: J = [I | R S l | R B] of a lattice point depends on q, and W = M(q)⁻¹ is applied
// through the body's own solve about the centre of mass (SolveMassSystem); when an enabled
// constraint touches an FFD body, A is rebuilt and factored every step (counted separately
// in per_step_factorizations()). Their unconstrained accelerations, gravity, mode forces,
// ground contacts and energies come from the FFD World (wobble/dynamics), not a copy.
//
// Integrator: semi-implicit (symplectic) Euler, velocity first:
//   q̇ₙ₊₁ = q̇ₙ + Δt q̈(qₙ, q̇ₙ),  qₙ₊₁ = qₙ + Δt q̇ₙ₊₁,
// which is exactly the Störmer form of the thesis integrator (Eq. 4.22/4.23) for FFD bodies.
// It is symplectic for the constant mass matrix of linear bodies, so a frictionless nailed
// pendulum keeps its energy within O(Δt) without secular drift; for linear constraints c is
// linear in q, so with c = ċ = 0 at the start the discrete c stays at round-off (the α, β
// feedback only has to remove round-off, path discretization and FFD curvature drift).
// Explicit methods with several stages would need the multiplier solve per stage for no gain
// in constraint accuracy.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "wobble/body/affine_energy.h"
#include "wobble/body/linear_body.h"
#include "wobble/constraints/multiplier_solver.h"
#include "wobble/constraints/point_path.h"
#include "wobble/dynamics/world.h"

namespace wobble {

enum class BodyKind { kLinear, kFfd };
enum class ConstraintKind { kNail, kAttachment, kTrajectory };

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

struct ConstrainedWorldOptions {
  // Gravity (params.gravity for 2D bodies, gravity_3d for 3D ones, both off with
  // params.gravity_on), the ground, springs and max_condition of the FFD bodies.
  WorldParams params;
  Eigen::Vector3d gravity_3d = Eigen::Vector3d(0.0, -9.81, 0.0);
  double dt = 0.002;
  // Default feedback: α = (rate/Δt)², β = 2 rate/Δt (critically damped, time constant Δt/rate).
  double feedback_rate = 0.1;
  // Dense pre-inverted A up to this many constraint rows, sparse LDLT above (kAuto). Measured
  // (bench/constraints_bench): per step the two are equal within 5 % up to 200 rows and the
  // dense solve grows quadratically beyond; refactoring is cheaper sparse from about 20 rows on.
  MultiplierMethod method = MultiplierMethod::kAuto;
  int dense_max_rows = 24;
};

struct ConstrainedStatus {
  enum class Code { kOk, kSingularConstraints, kBodyFailed, kNonFinite, kBadPath };
  Code code = Code::kOk;
  long step = 0;
  double time = 0.0;
  int body = -1;
  std::string message;
  bool ok() const { return code == Code::kOk; }
};

// A velocity goal for ApplyImpulse: after the jump, v(a) − v(b) = v (b.body < 0: v(a) = v).
struct VelocityGoal {
  MaterialPoint a;
  MaterialPoint b;  // body −1: none
  Eigen::VectorXd v;
};

class ConstrainedWorld {
 public:
  explicit ConstrainedWorld(ConstrainedWorldOptions options = {});

  // ---- bodies (one numbering for both kinds) ----
  // A linear body starts at its rest state R = [I | 0 | 0], at rest.
  int AddLinearBody(std::shared_ptr<const LinearBodyModel> model, AffineMaterial material = {});
  // An FFD body starts at q = 0, at rest.
  int AddFfdBody(std::shared_ptr<const BodyModel> model);
  int num_bodies() const { return int(bodies_.size()); }
  BodyKind kind(int body) const;
  int dim(int body) const;  // 2 or 3
  const std::string& body_name(int body) const;
  const LinearBodyModel& linear_model(int body) const;
  const BodyModel& ffd_model(int body) const;

  // States. Linear: R and Ṙ (d×n). FFD: q and q̇ (3 + D). Throw std::invalid_argument on a
  // wrong body kind or size. Setting a state does not enforce constraints: follow with
  // ProjectVelocities() (and start in a legal place) or let the feedback pull it in.
  void SetLinearState(int body, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot);
  const Eigen::MatrixXd& linear_R(int body) const;
  const Eigen::MatrixXd& linear_R_dot(int body) const;
  void SetFfdState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
  const BodyState<double>& ffd_state(int body) const;
  void SetMaterial(int body, const AffineMaterial& material);
  const AffineMaterial& material(int body) const;
  // The FFD bodies' world (energies, forces, PD targets via SetModeTargets). Its body index i
  // is ffd_index(body); do not Step() it directly.
  World& ffd_world() { return ffd_; }
  const World& ffd_world() const { return ffd_; }
  int ffd_index(int body) const;

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
  int num_constraints() const { return int(constraints_.size()); }  // ids are 0..n−1
  // c = x_a − x_b (or x_a − n(t)) now, and its largest norm over the enabled constraints.
  Eigen::VectorXd ConstraintError(int id) const;
  Eigen::VectorXd ConstraintVelocityError(int id) const;
  double MaxViolation() const;
  // The multiplier λ (the constraint force on point a, world units) of the last step.
  Eigen::VectorXd Multiplier(int id) const;

  // ---- impulses (§3.2, Eq. 9) ----
  // One velocity jump Δq̇ = W Jᵀ λ, with J W Jᵀ λ = (wanted − current velocity of each row):
  // every enabled constraint ends with ċ = 0 (a trajectory: the point moves with ṅ(t)), and
  // every goal is met exactly. Non-impulsive forces are ignored (§3.2). Stop dead: goal v = 0;
  // bounce: v = reflected velocity; Connect: a relative goal v(a) − v(b) = 0, then
  // AddAttachment. Returns false with *error (and nothing changed) when the goals conflict
  // with each other or with the constraints, or name an unknown body or point.
  bool ApplyImpulse(const std::vector<VelocityGoal>& goals, std::string* error = nullptr);
  // ApplyImpulse({}): makes the velocities legal (e.g. after SetLinearState or a path switch).
  bool ProjectVelocities(std::string* error = nullptr) { return ApplyImpulse({}, error); }

  // ---- stepping ----
  // One step of every body. Returns false and keeps status() at the first trouble (the state
  // before the step is kept); later calls return false until ClearStatus().
  bool Step();
  template <class F> bool RunUntil(double t_end, F&& on_step) {
    while (time_ + 0.5 * options_.dt < t_end) {
      if (!Step()) return false;
      on_step(*this);
    }
    return true;
  }
  bool RunUntil(double t_end) {
    return RunUntil(t_end, [](ConstrainedWorld&) {});
  }
  const ConstrainedStatus& status() const { return status_; }
  void ClearStatus() { status_ = ConstrainedStatus(); }
  double time() const { return time_; }
  void set_time(double t) { time_ = t; }
  long steps() const { return steps_; }
  ConstrainedWorldOptions& options() { return options_; }
  const ConstrainedWorldOptions& options() const { return options_; }

  // ---- energies ----
  // Kinetic ½ tr(Ṙ M Ṙᵀ) (linear) or ½ q̇ᵀ M q̇ (FFD); potential: gravity −g·(R μ), the affine
  // energies, and the FFD world's gravity, modes, ground and springs.
  double KineticEnergy(int body) const;
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
  struct Body {
    BodyKind kind;
    int index;  // into linear_ or the FFD world
  };
  // A point or constraint value (d ≤ 3) on the stack: the per-step loops allocate nothing.
  using PointVec = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;
  struct LinearEntry {
    std::shared_ptr<const LinearBodyModel> model;
    AffineMaterial material;
    Eigen::MatrixXd R, R_dot, applied;  // applied: Σ f pᵀ of ApplyPointForce for the next step
    Eigen::MatrixXd Q;                  // per-step work: the body's generalized force
  };
  // A resolved material point: linear bodies keep p(u) and W p; FFD bodies b0 and B.
  struct End {
    int body = -1;
    Eigen::VectorXd p, Wp;            // linear
    Eigen::Vector2d b0;               // FFD
    Mat2D<double> B;                  // FFD
  };
  struct Constraint {
    ConstraintKind kind;
    End a, b;  // b.body < 0: nail/trajectory
    Eigen::VectorXd where;
    std::shared_ptr<const PointPath> path;
    Feedback fb;
    bool enabled = true, removed = false;
    Eigen::VectorXd lambda;
    int row = -1;  // first row in A while enabled
  };

  End Resolve(const MaterialPoint& point) const;
  void CheckBody(int body) const;
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
  void Targets(const Constraint& c, double t, Eigen::VectorXd* n, Eigen::VectorXd* n_dot, Eigen::VectorXd* n_ddot) const;
  Eigen::VectorXd Alpha(const Constraint& c) const;
  double FeedbackAlpha(const Constraint& c) const;
  double FeedbackBeta(const Constraint& c) const;
  bool AnyFfdConstrained() const;
  int AssignRows();
  // A = J W Jᵀ over the enabled constraints plus `extra` rows (impulse goals).
  Eigen::SparseMatrix<double> AssembleA(const std::vector<const Constraint*>& rows) const;
  bool EnsureFactored(std::string* why);
  // Free accelerations of every body (flattened), or false with a body failure.
  bool FreeAccelerations(std::vector<Eigen::VectorXd>* a, int* failed_body, StepStatus* st);
  void ApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const;  // += W Q
  bool Fail(ConstrainedStatus::Code code, int body, const std::string& message);

  ConstrainedWorldOptions options_;
  World ffd_;
  std::vector<Body> bodies_;
  std::vector<LinearEntry> linear_;
  std::vector<Constraint> constraints_;
  std::vector<Eigen::VectorXd> ffd_applied_;  // Σ Jᵀ f per FFD body for the next step
  std::vector<Eigen::VectorXd> acc_, force_;   // per-step work, kept to reuse their storage
  MultiplierSolver constant_solver_, dynamic_solver_;
  bool structure_dirty_ = true;
  MultiplierMethod last_method_ = MultiplierMethod::kAuto;
  double time_ = 0.0;
  long steps_ = 0;
  ConstrainedStatus status_;
};

const char* ConstraintKindName(ConstraintKind kind);

}  // namespace wobble
