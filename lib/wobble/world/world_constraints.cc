// The World's constraints (Witkin & Welch §3): material points, nails, attachments and
// trajectories, the multiplier step (Eq. 6–10 with feedback) and impulses (§3.2, Eq. 9).
#include "wobble/world/world.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "wobble/core/errors.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/dynamics/step.h"

namespace wobble {

namespace {
using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// A linear body's flattened coordinates are R row by row: index i·n + s holds R_is (§3.3).
Eigen::Map<RowMajor> AsMatrix(Eigen::VectorXd& v, int d, int n) { return {v.data(), d, n}; }
Eigen::Map<const RowMajor> AsMatrix(const Eigen::VectorXd& v, int d, int n) { return {v.data(), d, n}; }

// y = M p for a linear body's d×n matrix M (R, Ṙ or R̈) and a basis vector p: the position,
// velocity or acceleration of a material point. Plain loops: at d ≤ 3, n ≤ 10 Eigen's run-time
// sized products spend more on dispatch and alignment peeling than on the arithmetic (Fig. 2's
// step, bench/mujoco_bench).
using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;  // World::PointVec
template <class Matrix>
SmallVector TimesBasis(const Matrix& M, const Eigen::VectorXd& p) {
  const int d = int(M.rows()), n = int(M.cols());
  SmallVector y(d);
  for (int i = 0; i < d; ++i) {
    double sum = 0.0;
    for (int j = 0; j < n; ++j) sum += M(i, j) * p[j];
    y[i] = sum;
  }
  return y;
}
}  // namespace

const char* ConstraintKindName(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::kNail: return "nail";
    case ConstraintKind::kAttachment: return "attachment";
    case ConstraintKind::kTrajectory: return "trajectory";
  }
  return "?";
}

// ---------------------------------------------------------------- points

World::End World::Resolve(const MaterialPoint& point) const {
  CheckBody(point.body);
  End e;
  e.body = point.body;
  if (slots_[point.body].kind == BodyKind::kFfd) {
    if (slots_[point.body].dim == 3) ResolveFfd<3>(point, &e);
    else ResolveFfd<2>(point, &e);
  } else {
    const LinearBodyModel& m = *linear_[slots_[point.body].index].model;
    Eigen::VectorXd u = point.u;
    if (point.mass_point >= 0) {
      if (point.mass_point >= m.num_points())
        throw std::invalid_argument("body '" + m.name() + "' has " + std::to_string(m.num_points()) +
                                    " mass points, no point " + std::to_string(point.mass_point));
      u = m.def().points[point.mass_point];
    }
    if (u.size() != m.dim() || !u.allFinite())
      throw std::invalid_argument("a point of body '" + m.name() + "' needs " + std::to_string(m.dim()) +
                                  " finite undeformed coordinates, got " + std::to_string(u.size()));
    e.p = m.Basis(u);
    e.Wp = m.inverse_mass_matrix() * e.p;
  }
  return e;
}

World::PointVec World::EndPosition(const End& e) const {
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) return TimesBasis(data_.linear[size_t(b.index)].R, e.p);
  return b.dim == 3 ? FfdEndPosition<3>(e) : FfdEndPosition<2>(e);
}

World::PointVec World::EndVelocity(const End& e) const {
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) return TimesBasis(data_.linear[size_t(b.index)].R_dot, e.p);
  return b.dim == 3 ? FfdEndVelocity<3>(e) : FfdEndVelocity<2>(e);
}

Eigen::VectorXd World::PointPosition(const MaterialPoint& point) const { return EndPosition(Resolve(point)); }
Eigen::VectorXd World::PointVelocity(const MaterialPoint& point) const { return EndVelocity(Resolve(point)); }

void World::AddEndForce(const End& e, const Eigen::VectorXd& f, std::vector<Eigen::VectorXd>* Q) const {
  const Slot& b = slots_[e.body];
  Eigen::VectorXd& out = (*Q)[e.body];
  if (b.kind == BodyKind::kLinear) {
    const int d = int(f.size()), n = int(e.p.size());
    AsMatrix(out, d, n) += f * e.p.transpose();  // Q = f pᵀ (§2.2)
  } else if (b.dim == 3) {
    FfdAddEndForce<3>(e, f, &out);
  } else {
    FfdAddEndForce<2>(e, f, &out);
  }
}

void World::ApplyPointForce(const MaterialPoint& point, const Eigen::VectorXd& f) {
  const End e = Resolve(point);
  if (f.size() != dim(point.body) || !f.allFinite())
    throw std::invalid_argument("a force on body '" + body_name(point.body) + "' needs " +
                                std::to_string(dim(point.body)) + " finite components");
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) {
    data_.linear[size_t(b.index)].applied += f * e.p.transpose();
    return;
  }
  // FFD bodies of either dimension: Jᵀ f (Eq. 4.20), as a constraint's force enters
  Eigen::VectorXd& applied =
      b.dim == 3 ? data_.ffd_of<3>()[size_t(b.index)].applied : data_.ffd_of<2>()[size_t(b.index)].applied;
  std::vector<Eigen::VectorXd> Q(num_bodies());
  Q[e.body] = Eigen::VectorXd::Zero(applied.size());
  AddEndForce(e, f, &Q);
  applied += Q[e.body];
}

World::PointVec World::EndJdotQdot(const End& e) const {
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) return PointVec::Zero(linear_[b.index].model->dim());  // J constant
  return b.dim == 3 ? FfdEndJdotQdot<3>(e) : FfdEndJdotQdot<2>(e);
}

Eigen::MatrixXd World::EndJacobian(const End& e) const {
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) {
    const int d = linear_[b.index].model->dim(), n = int(e.p.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(d, d * n);  // ∂x_i/∂R_rs = δ_ir p_s (§3.3)
    for (int i = 0; i < d; ++i) J.block(i, i * n, 1, n) = e.p.transpose();
    return J;
  }
  return b.dim == 3 ? FfdEndJacobian<3>(e) : FfdEndJacobian<2>(e);
}

Eigen::MatrixXd World::EndWJt(const End& e) const {
  const Slot& b = slots_[e.body];
  if (b.kind == BodyKind::kLinear) {
    const int d = linear_[b.index].model->dim(), n = int(e.p.size());
    Eigen::MatrixXd WJt = Eigen::MatrixXd::Zero(d * n, d);
    for (int i = 0; i < d; ++i) WJt.block(i * n, i, n, 1) = e.Wp;
    return WJt;
  }
  const Eigen::MatrixXd Jt = EndJacobian(e).transpose();
  Eigen::MatrixXd WJt(Jt.rows(), Jt.cols());
  for (int i = 0; i < Jt.cols(); ++i) {
    Eigen::VectorXd col;
    ApplyGeneralized(e.body, Jt.col(i), &(col = Eigen::VectorXd::Zero(Jt.rows())));
    WJt.col(i) = col;
  }
  return WJt;
}

void World::ApplyGeneralized(int body, const Eigen::VectorXd& Q, Eigen::VectorXd* acc) const {
  const Slot& b = slots_[body];
  if (b.kind == BodyKind::kLinear) {
    const LinearBodyModel& m = *linear_[b.index].model;
    AsMatrix(*acc, m.dim(), m.basis_size()) += AsMatrix(Q, m.dim(), m.basis_size()) * m.inverse_mass_matrix();  // Eq. 5
    return;
  }
  if (b.dim == 3) FfdApplyGeneralized<3>(body, Q, acc);
  else FfdApplyGeneralized<2>(body, Q, acc);
}

// ---------------------------------------------------------------- constraints

int World::AddConstraint(Constraint c) {
  data_.multipliers.push_back(Eigen::VectorXd::Zero(dim(c.a.body)));
  constraints_.push_back(std::move(c));
  structure_dirty_ = true;
  ++enabled_count_;
  return int(constraints_.size()) - 1;
}

int World::AddNail(const MaterialPoint& point, Eigen::VectorXd where, Feedback fb) {
  Constraint c;
  c.kind = ConstraintKind::kNail;
  c.a = Resolve(point);
  c.where = where.size() == 0 ? Eigen::VectorXd(EndPosition(c.a)) : where;
  if (c.where.size() != dim(point.body) || !c.where.allFinite())
    throw std::invalid_argument("nail on body '" + body_name(point.body) + "': the place needs " +
                                std::to_string(dim(point.body)) + " finite coordinates");
  c.fb = fb;
  return AddConstraint(std::move(c));
}

int World::AddAttachment(const MaterialPoint& a, const MaterialPoint& b, Feedback fb) {
  Constraint c;
  c.kind = ConstraintKind::kAttachment;
  c.a = Resolve(a);
  c.b = Resolve(b);
  if (dim(a.body) != dim(b.body))
    throw std::invalid_argument("attachment between '" + body_name(a.body) + "' (" + std::to_string(dim(a.body)) +
                                "D) and '" + body_name(b.body) + "' (" + std::to_string(dim(b.body)) + "D)");
  c.fb = fb;
  return AddConstraint(std::move(c));
}

int World::AddTrajectory(const MaterialPoint& point, std::shared_ptr<const PointPath> path, Feedback fb) {
  Constraint c;
  c.kind = ConstraintKind::kTrajectory;
  c.a = Resolve(point);
  if (!path || path->dim() != dim(point.body))
    throw std::invalid_argument("trajectory on body '" + body_name(point.body) + "' needs a " +
                                std::to_string(dim(point.body)) + "D path");
  c.path = std::move(path);
  c.fb = fb;
  return AddConstraint(std::move(c));
}

const World::Constraint& World::Get(int id) const {
  if (id < 0 || id >= num_constraints() || constraints_[id].removed)
    throw std::invalid_argument("unknown constraint " + std::to_string(id));
  return constraints_[id];
}
World::Constraint& World::Get(int id) {
  return const_cast<Constraint&>(static_cast<const World*>(this)->Get(id));
}

void World::SetNailPosition(int id, const Eigen::VectorXd& where) {
  Constraint& c = Get(id);
  if (c.kind != ConstraintKind::kNail) throw std::invalid_argument("constraint " + std::to_string(id) + " is not a nail");
  if (where.size() != c.where.size() || !where.allFinite())
    throw std::invalid_argument("nail " + std::to_string(id) + ": the place needs " + std::to_string(c.where.size()) +
                                " finite coordinates");
  c.where = where;
}

void World::SetPath(int id, std::shared_ptr<const PointPath> path) {
  Constraint& c = Get(id);
  if (c.kind != ConstraintKind::kTrajectory)
    throw std::invalid_argument("constraint " + std::to_string(id) + " is not a trajectory");
  if (!path || path->dim() != dim(c.a.body))
    throw std::invalid_argument("trajectory " + std::to_string(id) + " needs a " + std::to_string(dim(c.a.body)) + "D path");
  c.path = std::move(path);
}

void World::SetFeedback(int id, Feedback fb) { Get(id).fb = fb; }

void World::SetEnabled(int id, bool on) {
  Constraint& c = Get(id);
  if (c.enabled == on) return;
  c.enabled = on;
  enabled_count_ += on ? 1 : -1;
  structure_dirty_ = true;
}

void World::Remove(int id) {
  Constraint& c = Get(id);
  if (c.enabled) {
    structure_dirty_ = true;
    --enabled_count_;
  }
  c.enabled = false;
  c.removed = true;
}

bool World::enabled(int id) const { return Get(id).enabled; }
bool World::exists(int id) const { return id >= 0 && id < num_constraints() && !constraints_[id].removed; }
ConstraintKind World::constraint_kind(int id) const { return Get(id).kind; }
Eigen::VectorXd World::Multiplier(int id) const {
  Get(id);
  return data_.multipliers[size_t(id)];
}

void World::Targets(const Constraint& c, double t, PointVec* n, PointVec* n_dot, PointVec* n_ddot) const {
  const int d = dim(c.a.body);
  if (c.kind == ConstraintKind::kTrajectory) {
    const PathSample s = c.path->Evaluate(t);
    if (s.n.size() != d || s.n_dot.size() != d || s.n_ddot.size() != d)
      throw std::invalid_argument("the path of a trajectory on body '" + body_name(c.a.body) +
                                  "' returned a sample of the wrong size at t = " + std::to_string(t));
    if (!s.n.allFinite() || !s.n_dot.allFinite() || !s.n_ddot.allFinite())
      throw std::invalid_argument("the path of a trajectory on body '" + body_name(c.a.body) +
                                  "' returned a non-finite sample at t = " + std::to_string(t));
    *n = s.n;
    *n_dot = s.n_dot;
    *n_ddot = s.n_ddot;
    return;
  }
  if (c.kind == ConstraintKind::kNail)
    *n = c.where;
  else
    n->setZero(d);
  n_dot->setZero(d);
  n_ddot->setZero(d);
}

Eigen::VectorXd World::ConstraintError(int id) const {
  const Constraint& c = Get(id);
  PointVec n, nd, ndd;
  Targets(c, data_.time, &n, &nd, &ndd);
  PointVec e = EndPosition(c.a) - n;
  if (c.b.body >= 0) e -= EndPosition(c.b);
  return e;
}

Eigen::VectorXd World::ConstraintVelocityError(int id) const {
  const Constraint& c = Get(id);
  PointVec n, nd, ndd;
  Targets(c, data_.time, &n, &nd, &ndd);
  PointVec e = EndVelocity(c.a) - nd;
  if (c.b.body >= 0) e -= EndVelocity(c.b);
  return e;
}

double World::MaxViolation() const {
  double worst = 0.0;
  for (int id = 0; id < num_constraints(); ++id)
    if (!constraints_[id].removed && constraints_[id].enabled) worst = std::max(worst, ConstraintError(id).norm());
  return worst;
}

double World::FeedbackAlpha(const Constraint& c) const {
  if (c.fb.alpha >= 0.0) return c.fb.alpha;
  const double w = options_.feedback_rate / options_.dt;
  return w * w;
}
double World::FeedbackBeta(const Constraint& c) const {
  if (c.fb.beta >= 0.0) return c.fb.beta;
  return 2.0 * options_.feedback_rate / options_.dt;
}

bool World::AnyFfdConstrained() const {
  for (const Constraint& c : constraints_) {
    if (!c.enabled) continue;
    if (slots_[c.a.body].kind != BodyKind::kLinear) return true;  // M(q) changes every step
    if (c.b.body >= 0 && slots_[c.b.body].kind != BodyKind::kLinear) return true;
  }
  return false;
}

int World::constraint_rows() const {
  int rows = 0;
  for (const Constraint& c : constraints_)
    if (c.enabled) rows += dim(c.a.body);
  return rows;
}

int World::AssignRows() {
  int row = 0;
  for (Constraint& c : constraints_) {
    c.row = c.enabled ? row : -1;
    if (c.enabled) row += dim(c.a.body);
  }
  return row;
}

// A = J W Jᵀ: W is block diagonal, so only ends on one body meet. Ends are grouped by body and
// every pair (e1, e2) of a body adds s1 s2 J_e1 W J_e2ᵀ to block (row(e1), row(e2)); for a
// linear body that block is (p1ᵀ W p2) I_d.
Eigen::SparseMatrix<double> World::AssembleA(const std::vector<const Constraint*>& rows) const {
  struct EndRef {
    const End* e;
    double sign;
    int row, d;
  };
  std::vector<std::vector<EndRef>> by_body(num_bodies());
  int m = 0;
  for (const Constraint* c : rows) {
    const int d = dim(c->a.body);
    by_body[c->a.body].push_back({&c->a, 1.0, m, d});
    if (c->b.body >= 0) by_body[c->b.body].push_back({&c->b, -1.0, m, d});
    m += d;
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (int body = 0; body < num_bodies(); ++body) {
    const std::vector<EndRef>& ends = by_body[body];
    if (ends.empty()) continue;
    if (slots_[body].kind == BodyKind::kLinear) {
      for (const EndRef& e1 : ends)
        for (const EndRef& e2 : ends) {
          const double k = e1.sign * e2.sign * e1.e->p.dot(e2.e->Wp);
          for (int i = 0; i < e1.d; ++i) triplets.emplace_back(e1.row + i, e2.row + i, k);
        }
    } else {
      std::vector<Eigen::MatrixXd> J, WJt;
      for (const EndRef& e : ends) {
        J.push_back(EndJacobian(*e.e));
        WJt.push_back(EndWJt(*e.e));
      }
      for (size_t a = 0; a < ends.size(); ++a)
        for (size_t b = 0; b < ends.size(); ++b) {
          const Eigen::MatrixXd block = ends[a].sign * ends[b].sign * J[a] * WJt[b];
          for (int i = 0; i < block.rows(); ++i)
            for (int j = 0; j < block.cols(); ++j) triplets.emplace_back(ends[a].row + i, ends[b].row + j, block(i, j));
        }
    }
  }
  Eigen::SparseMatrix<double> A(m, m);
  A.setFromTriplets(triplets.begin(), triplets.end());
  return A;
}

bool World::EnsureFactored(std::string* why, const MultiplierSolver** factored) {
  const bool dynamic = AnyFfdConstrained();
  if (factored) *factored = dynamic ? &dynamic_solver_ : &constant_solver_;
  if (!dynamic && !structure_dirty_ && constant_solver_.factored()) return true;
  const int m = AssignRows();
  std::vector<const Constraint*> rows;
  for (const Constraint& c : constraints_)
    if (c.enabled) rows.push_back(&c);
  MultiplierMethod method = options_.method;
  if (method == MultiplierMethod::kAuto) method = m <= options_.dense_max_rows ? MultiplierMethod::kDense : MultiplierMethod::kSparse;
  last_method_ = method;
  const Eigen::SparseMatrix<double> A = AssembleA(rows);
  MultiplierSolver& solver = dynamic ? dynamic_solver_ : constant_solver_;
  if (!dynamic) {
    constant_solver_.Invalidate();
    structure_dirty_ = false;
  }
  if (!solver.Factor(A, method, why)) {
    structure_dirty_ = true;  // refactor (and fail again) until the set changes
    return false;
  }
  return true;
}

// ---------------------------------------------------------------- stepping

bool World::FreeAccelerations(std::vector<Eigen::VectorXd>* acc, int* failed_body, StepStatus* st, ContactSet contacts) {
  acc->resize(num_bodies());
  for (int body = 0; body < num_bodies(); ++body) {
    const Slot& b = slots_[body];
    Eigen::VectorXd& a = (*acc)[body];
    if (b.kind == BodyKind::kLinear) {
      LinearFreeAcceleration(body, &a);
    } else if (!(b.dim == 3 ? FfdFreeAcceleration<3>(body, &a, st, contacts)
                            : FfdFreeAcceleration<2>(body, &a, st, contacts))) {
      *failed_body = body;
      return false;
    }
  }
  return true;
}

// The constrained accelerations of every body (world.h), at whatever stage an integrator asks.
bool World::ConstrainedAccelerations(double t, double lag, ContactSet contacts, std::vector<Eigen::VectorXd>* acc_out) {
  // unconstrained accelerations W Q of every body
  std::vector<Eigen::VectorXd>& acc = *acc_out;
  int failed = -1;
  StepStatus st;
  if (!FreeAccelerations(&acc, &failed, &st, contacts)) return Fail(st.code, failed, "", st.value);
  // the multipliers: J W Jᵀ λ = −(J W Q + J̇ q̇ − n̈ + α c + β ċ)  (Eq. 8/10 with feedback)
  std::string why;
  try {
    const MultiplierSolver* factored = nullptr;
    if (!EnsureFactored(&why, &factored)) return Fail(StatusCode::kSingularConstraints, -1, why);
    const MultiplierSolver& solver = *factored;
    if (solver.rows() > 0) {
      Eigen::VectorXd& rhs = rhs_;  // per-step work, its storage kept
      rhs.resize(solver.rows());
      PointVec n, nd, ndd;
      for (const Constraint& c : constraints_) {
        if (!c.enabled) continue;
        Targets(c, t, &n, &nd, &ndd);
        const int d = int(n.size());
        // The Euler forms stagger velocities: in velocity-first Euler q̇ₙ = (qₙ − qₙ₋₁)/Δt is the
        // velocity of t − Δt/2, so ċ compares it with ṅ(t − lag) ≈ ṅ − lag n̈. Against ṅ(t) the β
        // term would see a false ċ = −½Δt n̈ and hold the point β Δt n̈ / (2α) behind its path.
        // c, ċ and c̈ summed end by end in plain arrays: scalar stores read back by vector loads
        // (Eigen on d ≤ 3 temporaries) stall store forwarding, a tenth of Fig. 2's step
        double pos_c[3], vel_c[3], accel_c[3];
        for (int i = 0; i < d; ++i) {
          pos_c[i] = -n[i];
          vel_c[i] = -nd[i] + lag * ndd[i];
          accel_c[i] = -ndd[i];
        }
        auto add_end = [&](const End& e, double sign) {
          const Slot& b = slots_[e.body];
          if (b.kind == BodyKind::kLinear) {  // x = R p, ẋ = Ṙ p, J a = R̈ p (J̇ = 0)
            const WorldData::Linear& l = data_.linear[size_t(b.index)];
            const int n_basis = int(e.p.size());
            const double* a = acc[e.body].data();  // R̈ row by row
            for (int i = 0; i < d; ++i) {
              double x = 0.0, v = 0.0, ja = 0.0;
              for (int j = 0; j < n_basis; ++j) {
                x += l.R(i, j) * e.p[j];
                v += l.R_dot(i, j) * e.p[j];
                ja += a[i * n_basis + j] * e.p[j];
              }
              pos_c[i] += sign * x;
              vel_c[i] += sign * v;
              accel_c[i] += sign * ja;
            }
          } else {
            const PointVec x = EndPosition(e), v = EndVelocity(e);
            const PointVec ja = EndJacobian(e) * acc[e.body] + EndJdotQdot(e);
            for (int i = 0; i < d; ++i) {
              pos_c[i] += sign * x[i];
              vel_c[i] += sign * v[i];
              accel_c[i] += sign * ja[i];
            }
          }
        };
        add_end(c.a, 1.0);
        if (c.b.body >= 0) add_end(c.b, -1.0);
        const double alpha = FeedbackAlpha(c), beta = FeedbackBeta(c);
        for (int i = 0; i < d; ++i) rhs[c.row + i] = -(accel_c[i] + alpha * pos_c[i] + beta * vel_c[i]);
      }
      Eigen::VectorXd& lambda = lambda_;
      solver.Solve(rhs, &lambda);
      // constrained accelerations q̈ = W(Q + Jᵀ λ)
      std::vector<Eigen::VectorXd>& force = force_;
      force.resize(num_bodies());
      for (Eigen::VectorXd& f : force) f.resize(0);
      for (size_t id = 0; id < constraints_.size(); ++id) {
        const Constraint& c = constraints_[id];
        if (!c.enabled) continue;
        const int d = dim(c.a.body);
        Eigen::VectorXd& c_lambda = data_.multipliers[id];
        c_lambda = lambda.segment(c.row, d);
        for (int end = 0; end < (c.b.body >= 0 ? 2 : 1); ++end) {
          const End& e = end == 0 ? c.a : c.b;
          const double sign = end == 0 ? 1.0 : -1.0;
          const Slot& b = slots_[e.body];
          if (b.kind == BodyKind::kLinear) {
            const int n_basis = int(e.p.size());
            // (λ pᵀ) W, by plain loops as TimesBasis
            double* a = acc[e.body].data();
            for (int i = 0; i < d; ++i)
              for (int j = 0; j < n_basis; ++j) a[i * n_basis + j] += sign * c_lambda[i] * e.Wp[j];
          } else {
            if (force[e.body].size() == 0) force[e.body] = Eigen::VectorXd::Zero(acc[e.body].size());
            AddEndForce(e, sign * c_lambda, &force);
          }
        }
      }
      for (int body = 0; body < num_bodies(); ++body)
        if (force[body].size() > 0) ApplyGeneralized(body, force[body], &acc[body]);
    }
  } catch (const std::invalid_argument& e) {  // only paths throw here
    return Fail(StatusCode::kBadPath, -1, e.what());
  }
  for (int body = 0; body < num_bodies(); ++body)
    if (!(*acc_out)[body].allFinite()) return Fail(StatusCode::kNonFinite, body, "non-finite acceleration");
  return true;
}

// ---------------------------------------------------------------- impulses (Eq. 9)

bool World::ApplyImpulse(const std::vector<VelocityGoal>& goals, std::string* error) {
  std::string why;
  try {
    std::vector<Constraint> goal_rows;
    std::vector<Eigen::VectorXd> goal_v;
    for (const VelocityGoal& g : goals) {
      Constraint c;
      c.kind = g.b.body >= 0 ? ConstraintKind::kAttachment : ConstraintKind::kNail;
      c.a = Resolve(g.a);
      if (g.b.body >= 0) {
        c.b = Resolve(g.b);
        if (dim(g.b.body) != dim(g.a.body)) throw std::invalid_argument("a velocity goal between a 2D and a 3D body");
      }
      if (g.v.size() != dim(g.a.body) || !g.v.allFinite())
        throw std::invalid_argument("a velocity goal on body '" + body_name(g.a.body) + "' needs " +
                                    std::to_string(dim(g.a.body)) + " finite components");
      goal_rows.push_back(std::move(c));
      goal_v.push_back(g.v);
    }
    // rows: the enabled constraints (wanted ċ = 0), then the goals
    std::vector<const Constraint*> rows;
    std::vector<Eigen::VectorXd> jump;  // wanted minus current velocity, per row block
    PointVec n, nd, ndd;
    for (const Constraint& c : constraints_) {
      if (!c.enabled) continue;
      rows.push_back(&c);
      Targets(c, data_.time, &n, &nd, &ndd);
      Eigen::VectorXd v = EndVelocity(c.a) - nd;
      if (c.b.body >= 0) v -= EndVelocity(c.b);
      jump.push_back(-v);
    }
    for (size_t i = 0; i < goal_rows.size(); ++i) {
      rows.push_back(&goal_rows[i]);
      Eigen::VectorXd v = EndVelocity(goal_rows[i].a);
      if (goal_rows[i].b.body >= 0) v -= EndVelocity(goal_rows[i].b);
      jump.push_back(goal_v[i] - v);
    }
    if (rows.empty()) return true;
    // the factorization: the cached one when only the constraints of linear bodies are involved
    MultiplierSolver local;
    const MultiplierSolver* solver = &local;
    if (goal_rows.empty() && !AnyFfdConstrained()) {
      if (!EnsureFactored(&why)) throw std::invalid_argument(why);
      solver = &constant_solver_;
    } else {
      const Eigen::SparseMatrix<double> A = AssembleA(rows);
      const MultiplierMethod method = A.rows() <= options_.dense_max_rows ? MultiplierMethod::kDense : MultiplierMethod::kSparse;
      if (!local.Factor(A, method, &why))
        throw std::invalid_argument("the velocity goals conflict with each other or with the constraints: " + why);
    }
    Eigen::VectorXd rhs(solver->rows());
    int row = 0;
    for (const Eigen::VectorXd& j : jump) {
      rhs.segment(row, j.size()) = j;
      row += int(j.size());
    }
    // J W Jᵀ λ = Δ(wanted velocity), I = Jᵀ λ, Δq̇ = W I  (Eq. 9)
    Eigen::VectorXd lambda;
    solver->Solve(rhs, &lambda);
    std::vector<Eigen::VectorXd> impulse(num_bodies());
    row = 0;
    for (const Constraint* c : rows) {
      const int d = dim(c->a.body);
      for (int end = 0; end < (c->b.body >= 0 ? 2 : 1); ++end) {
        const End& e = end == 0 ? c->a : c->b;
        if (impulse[e.body].size() == 0) {
          impulse[e.body] = Eigen::VectorXd::Zero(num_q(e.body));
        }
        AddEndForce(e, (end == 0 ? 1.0 : -1.0) * lambda.segment(row, d), &impulse);
      }
      row += d;
    }
    std::vector<Eigen::VectorXd> dv(num_bodies());
    for (int body = 0; body < num_bodies(); ++body) {
      if (impulse[body].size() == 0) continue;
      dv[body] = Eigen::VectorXd::Zero(impulse[body].size());
      ApplyGeneralized(body, impulse[body], &dv[body]);
      if (!dv[body].allFinite()) throw std::invalid_argument("non-finite velocity change on body '" + body_name(body) + "'");
    }
    for (int body = 0; body < num_bodies(); ++body) {
      if (dv[body].size() == 0) continue;
      const Slot& b = slots_[body];
      if (b.kind == BodyKind::kLinear) {
        const LinearBodyModel& m = *linear_[b.index].model;
        data_.linear[size_t(b.index)].R_dot += AsMatrix(dv[body], m.dim(), m.basis_size());
      } else if (b.dim == 3) {
        FfdAddVelocity<3>(body, dv[body]);
      } else {
        FfdAddVelocity<2>(body, dv[body]);
      }
    }
  } catch (const std::invalid_argument& e) {
    if (error) *error = e.what();
    return false;
  }
  return true;
}

}  // namespace wobble
