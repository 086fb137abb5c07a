#include "wobble/fit/internal/step_vjp_space.h"

#include <cmath>
#include <vector>

#include "wobble/core/rotation3.h"

namespace wobble::fit::internal {

namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using AnchorAdjoints = std::map<ContactKey, Eigen::Vector3d>;

// Where a state's tangent coordinates sit in z: δt, ε, δγ, then v = (ṫ, ω, γ̇).
struct Tangent {
  explicit Tangent(int modes) : D(modes) {}
  int D;
  static constexpr int kT = 0, kEpsilon = 3, kGamma = 6;
  int v() const { return 6 + D; }
  int omega() const { return 9 + D; }
  int gamma_dot() const { return 12 + D; }
};

void AddTo(AnchorAdjoints* anchors, const ContactKey& key, const Vector3d& value) {
  const auto [it, inserted] = anchors->emplace(key, value);
  if (!inserted) it->second += value;
}

// x = t + R l with l = b0 + B γ:  z += (∂x/∂z)ᵀ λ_x. With R → R exp(ε̂), δx = R (ε × l).
template <class ModeMatrix>
void PullPosition(const Matrix3d& R, const Vector3d& l, const ModeMatrix& B, const Vector3d& lambda_x,
                  const Tangent& ix, Eigen::VectorXd* z) {
  const Vector3d local = R.transpose() * lambda_x;
  z->segment<3>(Tangent::kT) += lambda_x;
  z->segment<3>(Tangent::kEpsilon) += l.cross(local);
  z->segment(Tangent::kGamma, ix.D) += B.transpose() * local;
}

// ẋ = ṫ + R y with y = ω × l + B γ̇:  z += (∂ẋ/∂z)ᵀ λ_ẋ.
template <class ModeMatrix>
void PullVelocity(const Matrix3d& R, const VecQ<double>& v, const Vector3d& l, const ModeMatrix& B,
                  const Vector3d& lambda_v, const Tangent& ix, Eigen::VectorXd* z) {
  const Vector3d mu = R.transpose() * lambda_v, omega = v.segment<3>(3);
  const Vector3d y = omega.cross(l) + B * v.tail(ix.D);
  z->segment<3>(ix.v()) += lambda_v;
  z->segment<3>(Tangent::kEpsilon) += y.cross(mu);
  z->segment<3>(ix.omega()) += l.cross(mu);
  z->segment(Tangent::kGamma, ix.D) += B.transpose() * mu.cross(omega);
  z->segment(ix.gamma_dot(), ix.D) += B.transpose() * mu;
}

// ∂(w·y)/∂(x, ẋ, anchor) of a function y of one point's position, velocity and anchor.
struct PointPullback {
  Vector3d dx, dv, danchor;
};

// y = the ground force f = f_n n + f_t of GroundForcePartsOf: f_n = −K n·Δ − C_n n·ẋ (held at 0
// when negative), the uncapped f_t = −K P Δ − C_f P ẋ with P = 1 − n nᵀ and Δ = x − anchor,
// scaled to μ f_n f_t/|f_t| when it slips. Without `normal`, y is the capped f_t alone.
PointPullback PullGroundForce(const GroundPlane& g, const GroundForceParts<double>& p, const Vector3d& w,
                              bool normal = true) {
  const Vector3d n = g.normal;
  double w_fn = normal ? w.dot(n) : 0.0;  // weights of f_n and of the uncapped f_t
  Vector3d w_ft = w;
  if (p.slipping) {  // d(μ f_n f_t/|f_t|) = μ (f_t/|f_t|) df_n + μ f_n (1 − t̂ t̂ᵀ) df_t/|f_t|
    const Vector3d dir = p.ft / p.ft_norm;
    const double along = dir.dot(w);
    w_fn += g.friction_cap * along;
    w_ft = g.friction_cap * p.fn / p.ft_norm * (w - dir * along);
  }
  if (!p.pressing) w_fn = 0.0;
  const Vector3d w_t = w_ft - n * n.dot(w_ft);
  PointPullback r;
  r.dx = -g.stiffness * (w_fn * n + w_t);
  r.dv = -g.normal_damping * w_fn * n - g.friction_damping * w_t;
  r.danchor = -r.dx;
  return r;
}

// y = the anchor after UpdateContacts: kept, or moved by SlipAnchor to P x + n n·p +
// (f_t + C_f P ẋ)/K (f_t capped) when the friction slips.
PointPullback PullAnchorUpdate(const GroundPlane& g, const GroundForceParts<double>& p, const Vector3d& w) {
  if (!p.slipping || !(g.stiffness > 0.0)) return {Vector3d::Zero(), Vector3d::Zero(), w};
  PointPullback r = PullGroundForce(g, p, w / g.stiffness, false);
  const Vector3d w_t = w - g.normal * g.normal.dot(w);
  r.dx += w_t;
  r.dv += g.friction_damping / g.stiffness * w_t;
  return r;
}

// y = SpringForce's f = −s d with s = K (|Δ| − L) + C d·ẋ, d = Δ/|Δ|, Δ = x − anchor
// (∂d/∂x = (1 − d dᵀ)/|Δ|); the anchor is fixed.
PointPullback PullSpringForce(const Spring& sp, const Vector3d& x, const Vector3d& v, const Vector3d& w) {
  const Vector3d delta = x - sp.anchor;
  const double len = std::sqrt(delta.squaredNorm() + 1e-300);
  const Vector3d d = delta / len;
  const double s = sp.stiffness * (len - sp.rest_length) + sp.damping * d.dot(v), wd = w.dot(d);
  PointPullback r;
  r.dx = -wd * (sp.stiffness * d + sp.damping * (v - d * d.dot(v)) / len) - s * (w - d * wd) / len;
  r.dv = -wd * sp.damping * d;
  r.danchor.setZero();
  return r;
}

// Where ForEachFaceFelt (ground_plane.h) took the anchor of (point k, face) from, among the contacts
// of the state it scanned: the contact on the same face, the first contact of k projected onto
// the face (a − n n·(a − p)), or the point's foot on the face (x − n n·(x − p)). The adjoint of
// the anchor goes back the same way.
void PullAnchor(const std::vector<Contact<3, double>>& contacts, int k, int face, const Vector3d& normal,
                const Vector3d& lambda_anchor, AnchorAdjoints* anchors, Vector3d* lambda_x) {
  const Vector3d along_face = lambda_anchor - normal * normal.dot(lambda_anchor);
  const auto [first, last] = ContactsOfPoint(contacts, k);
  if (first == last) {
    *lambda_x += along_face;
    return;
  }
  for (auto it = first; it != last; ++it) {
    if (it->face == face) {
      AddTo(anchors, {k, face}, lambda_anchor);
      return;
    }
  }
  AddTo(anchors, {k, first->face}, along_face);
}

// The configuration after g·exp(h u) (Group<3>::Advance): z's configuration part holds
// λ there and becomes λ before; λ_u += h (λ_t, J_r(h ω)ᵀ λ_ε, λ_γ). The turn R' = R exp(φ̂),
// φ = h ω, moves a body-frame ε to exp(−φ̂) ε and ω by h J_r(φ) δω.
void PullAdvance(const VecQ<double>& u, double h, const Tangent& ix, Eigen::VectorXd* z, VecQ<double>* lambda_u) {
  const Vector3d phi = h * u.segment<3>(3);
  const Vector3d lambda_eps = z->segment<3>(Tangent::kEpsilon);
  lambda_u->head<3>() += h * z->segment<3>(Tangent::kT);
  lambda_u->segment<3>(3) += h * RightJacobianExp<double>(phi).transpose() * lambda_eps;
  lambda_u->tail(ix.D) += h * z->segment(Tangent::kGamma, ix.D);
  z->segment<3>(Tangent::kEpsilon) = ExpRotation<double>(phi).toRotationMatrix() * lambda_eps;
}

// The part of λ_A' (the anchors after a step) that goes back through UpdateContacts at `after`
// (the state after the step, still with the contacts before it): into z (λ at `after`) and into
// the adjoint of the anchors before.
void PullContactUpdate(const BodyModelN<3>& body, const GroundPlane& ground, const BodyState<3, double>& after,
                       const AnchorAdjoints& lambda_new, const Tangent& ix, Eigen::VectorXd* z,
                       AnchorAdjoints* lambda_old) {
  if (lambda_new.empty()) return;
  const Frame<3, double> frame(after.q);
  ForEachPointInContact(
      body, ground, after, frame,
      [&](int k, const Vector3d& l, const Vector3d& x, const Vector3d& v, const Vector3d& anchor,
          const GroundPlane& plane, int face) {
        const auto it = lambda_new.find({k, face});
        if (it == lambda_new.end()) return;
        PointPullback r = PullAnchorUpdate(plane, GroundForcePartsOf(plane, x, v, anchor), it->second);
        PullAnchor(after.contacts, k, face, plane.normal, r.danchor, lambda_old, &r.dx);
        const auto B = body.mode_matrix(k);
        PullPosition(frame.R, l, B, r.dx, ix, z);
        PullVelocity(frame.R, after.qd, l, B, r.dv, ix, z);
      },
      ContactSet::kDetect);
}

// A world force f(x, ẋ, anchor) at a point of mode matrix B enters Q as Jᵀ f, so ψ gets
// u·f with u = J λ_r = p + R (q × l + B s) (λ_r = (p, q, s)). Adds ∂ψ/∂z at fixed f (J moves
// with ε and, through l, with γ) and returns u, which the caller pulls through f.
template <class ModeMatrix>
Vector3d PullGeneralizedForce(const Matrix3d& R, const Vector3d& l, const ModeMatrix& B, const VecQ<double>& lr,
                              const Vector3d& f, const Tangent& ix, Eigen::VectorXd* z) {
  const Vector3d q = lr.segment<3>(3), f_local = R.transpose() * f;
  const Vector3d y = q.cross(l) + B * lr.tail(ix.D);
  z->segment<3>(Tangent::kEpsilon) += y.cross(f_local);
  z->segment(Tangent::kGamma, ix.D) += B.transpose() * f_local.cross(q);
  return lr.head<3>() + R * y;
}

// ∂K/∂γ_j of K(γ) = S0 + Σ_d γ_d (E_d + E_dᵀ) + Σ_de γ_d γ_e F_de: E_j + L_j + Σ_d γ_d F_dj.
Matrix3d SecondMomentRate(const MassMomentsN<3>& mm, const ShapeMoments<double>& sm, const VecD<double>& gamma, int j) {
  const int D = int(gamma.size());
  Matrix3d dK = mm.E[size_t(j)] + sm.L[size_t(j)];
  for (int d = 0; d < D; ++d) dK += gamma[d] * mm.F[size_t(d) * D + j];
  return dK;
}

// z += ∂ψ/∂z of the mass-moment terms of ψ = λ_rᵀ (Q_gravity − w − M a) at `e` (spatial_inertia.h's
// formulas; ∂I/∂γ_j = tr(K_j) 1 − K_j with K_j = ∂K/∂γ_j, ∂N_d/∂γ_g = X_gd, ∂L_d/∂γ_g = F_dg,
// ∂e/∂γ = G, ∂c/∂γ = C; a rotated vector Rᵀy moves by (Rᵀy) × ε).
void PullMomentTerms(const MassMomentsN<3>& mm, const WorldParams& world, const BodyState<3, double>& e,
                     const Matrix3d& R, const ShapeMoments<double>& sm, const VecQ<double>& a,
                     const VecQ<double>& lr, const Tangent& ix, Eigen::VectorXd* z) {
  const int D = ix.D;
  const Vector3d p = lr.head<3>(), q = lr.segment<3>(3), alpha = a.head<3>(), beta = a.segment<3>(3);
  const VecD<double> s = lr.tail(D), eta = a.tail(D), gdot = e.qd.tail(D);
  const Vector3d omega = e.qd.segment<3>(3);
  const Vector3d P = R.transpose() * p, A = R.transpose() * alpha;
  const Vector3d Cs = mm.C * s, C_eta = mm.C * eta, C_gdot = mm.C * gdot;
  const double omega2 = omega.squaredNorm();
  Vector3d d_eps = Vector3d::Zero(), d_omega = Vector3d::Zero();
  VecD<double> d_gamma = VecD<double>::Zero(D), d_gdot = VecD<double>::Zero(D);

  // gravity: λ_rᵀ Q = p·m g + G_l·(q × c + C s), G_l = Rᵀ g
  if (world.gravity_on) {
    const Vector3d G_local = R.transpose() * world.gravity;
    d_eps += (q.cross(sm.c) + Cs).cross(G_local);
    d_gamma += mm.C.transpose() * G_local.cross(q);
  }
  // −λ_rᵀ M a, with λ_rᵀ M a = m p·α + P·(C η − c × β) + A·(q × c + C s) + q·(I β + N η) + β·N s + s·G η
  d_eps -= (C_eta - sm.c.cross(beta)).cross(P) + (q.cross(sm.c) + Cs).cross(A);
  d_gamma -= mm.C.transpose() * (A.cross(q) - beta.cross(P));
  // −λ_rᵀ w: p·w_t = P·(ω × (ω × c) + 2 ω × C γ̇)
  d_eps -= (omega.cross(omega.cross(sm.c)) + 2.0 * omega.cross(C_gdot)).cross(P);
  d_gamma -= mm.C.transpose() * P.cross(omega).cross(omega);
  d_omega -= P * omega.dot(sm.c) + sm.c * P.dot(omega) - 2.0 * P.dot(sm.c) * omega + 2.0 * C_gdot.cross(P);
  d_gdot -= 2.0 * mm.C.transpose() * P.cross(omega);
  // q·w_ω = q·(ω × I ω) + 2 (q·ω)(e·γ̇) − 2 qᵀ (Σ_d γ̇_d L_d) ω
  Matrix3d L_gdot = Matrix3d::Zero();
  for (int d = 0; d < D; ++d) L_gdot += gdot[d] * sm.L[size_t(d)];
  const Vector3d q_x_omega = q.cross(omega);
  d_omega -= (sm.I * omega).cross(q) + sm.I * q_x_omega + 2.0 * sm.e.dot(gdot) * q - 2.0 * L_gdot.transpose() * q;
  // s·w_γ = Σ_d s_d (ωᵀ L_d ω − |ω|² e_d + 2 ω·Σ_e γ̇_e X_ed)
  for (int d = 0; d < D; ++d) {
    const Matrix3d& L = sm.L[size_t(d)];
    d_gdot[d] -= 2.0 * q.dot(omega) * sm.e[d] - 2.0 * q.dot(L * omega);
    Vector3d X_gdot = Vector3d::Zero();
    for (int k = 0; k < D; ++k) {
      const Vector3d& X = mm.X[size_t(k) * D + d];
      X_gdot += gdot[k] * X;
      d_gdot[k] -= 2.0 * s[d] * omega.dot(X);
    }
    d_omega -= s[d] * ((L + L.transpose()) * omega - 2.0 * sm.e[d] * omega + 2.0 * X_gdot);
  }
  const VecD<double> G_gdot = mm.G.transpose() * gdot;
  for (int j = 0; j < D; ++j) {
    const Matrix3d dK = SecondMomentRate(mm, sm, e.gamma(), j);
    double dj = dK.trace() * q.dot(beta) - q.dot(dK * beta);  // q·(∂I/∂γ_j) β
    for (int d = 0; d < D; ++d) {
      const Matrix3d& F = mm.F[size_t(d) * D + j];
      dj += (eta[d] * q + s[d] * beta).dot(mm.X[size_t(j) * D + d]);                   // (η_d q + s_d β)·∂N_d
      dj += -2.0 * gdot[d] * q.dot(F * omega) + s[d] * (omega.dot(F * omega) - omega2 * mm.G(d, j));  // w_ω, w_γ
    }
    dj += -q_x_omega.dot(dK * omega) + 2.0 * q.dot(omega) * G_gdot[j];  // ω × I ω, e·γ̇
    d_gamma[j] -= dj;
  }
  z->segment<3>(Tangent::kEpsilon) += d_eps;
  z->segment(Tangent::kGamma, D) += d_gamma;
  z->segment<3>(ix.omega()) += d_omega;
  z->segment(ix.gamma_dot(), D) += d_gdot;
}

// z, the anchors and the controls += ∇ψ, ψ = λ_rᵀ (Q − w − M a) at `e` with a and λ_r fixed:
// the pull-back of λ_a through a = M⁻¹ (Q − w), with λ_r = M⁻¹ λ_a.
void PullAccelerations(const StepModel& m, const VecD<double>& target, const BodyState<3, double>& e,
                       const Frame<3, double>& frame, const ShapeMoments<double>& sm, const VecQ<double>& a,
                       const VecQ<double>& lr, const Tangent& ix, StateAdjoint<3>* in, ControlAdjoint* controls) {
  const BodyModelN<3>& body = m.passive;
  const int D = ix.D;
  Eigen::VectorXd& z = in->z;
  PullMomentTerms(body.moments(), m.world, e, frame.R, sm, a, lr, ix, &z);
  // the body's own mode potentials (off in a rollout) and the PD mode forces of ModeForce
  const VecD<double> s = lr.tail(D);
  for (int d = 0; d < D; ++d) {
    const DeformationModeN<3>& mode = body.modes()[size_t(d)];
    const double offset = e.gamma()[d] - target[d];
    z[Tangent::kGamma + d] -= 2.0 * (mode.stiffness + m.gains.K[d]) * s[d];
    z[ix.gamma_dot() + d] -= (mode.damping + m.gains.c[d]) * s[d];
    controls->target[d] = 2.0 * m.gains.K[d] * s[d];
    (*controls->stiffness)[d] -= 2.0 * offset * s[d];
    (*controls->damping)[d] -= e.qd[Group<3>::kRigidDofs + d] * s[d];
  }
  // ground and springs, point by point
  ForEachPointInContact(
      body, m.world.ground_plane, e, frame,
      [&](int k, const Vector3d& l, const Vector3d& x, const Vector3d& v, const Vector3d& anchor,
          const GroundPlane& plane, int face) {
        const auto B = body.mode_matrix(k);
        const GroundForceParts<double> parts = GroundForcePartsOf(plane, x, v, anchor);
        const Vector3d u = PullGeneralizedForce(frame.R, l, B, lr, parts.f, ix, &z);
        PointPullback r = PullGroundForce(plane, parts, u);
        PullAnchor(e.contacts, k, face, plane.normal, r.danchor, &in->anchor, &r.dx);
        PullPosition(frame.R, l, B, r.dx, ix, &z);
        PullVelocity(frame.R, e.qd, l, B, r.dv, ix, &z);
      },
      ContactSet::kDetect);
  for (const Spring& sp : m.world.springs) {
    const Vector3d l = LocalPosition<double>(sp.rest_local, sp.mode_matrix, e.q);
    const Vector3d x = frame.t + frame.R * l, v = PointVelocity(frame, e.qd, l, sp.mode_matrix);
    const Vector3d u = PullGeneralizedForce(frame.R, l, sp.mode_matrix, lr, SpringForce(sp, x, v), ix, &z);
    const PointPullback r = PullSpringForce(sp, x, v, u);
    PullPosition(frame.R, l, sp.mode_matrix, r.dx, ix, &z);
    PullVelocity(frame.R, e.qd, l, sp.mode_matrix, r.dv, ix, &z);
  }
}

}  // namespace

StepStatus RecordStep(const StepModel& m, const VecD<double>& target, const BodyState<3, double>& s,
                       StepTape* tape, BodyState<3, double>* next) {
  const BodyModelN<3>& body = m.passive;
  const MassMomentsN<3>& mm = body.moments();
  const double h = m.dt;
  const bool thesis = m.integrator == Integrator::kThesis;
  // accelerations at `eval`: the start for the thesis integrator, the advanced configuration
  // for the symplectic one (StepBody and Accelerations, operation for operation)
  tape->eval = s;
  if (!thesis) Group<3>::Advance(s.qd, h, &tape->eval.q);
  const BodyState<3, double>& eval = tape->eval;
  const Frame<3, double>& frame = tape->frame.emplace(eval.q);
  const ShapeMoments<double>& sm = tape->moments.emplace(mm, eval.gamma());
  VecQ<double> w;
  VelocityTerms(mm, sm, frame.R, eval.qd, &w);
  ForceBreakdown<3, double> forces;
  EvaluateForces(body, m.world, 0, eval, frame, &forces);
  ModeForce<double>{&m.gains, &target}(eval, &forces.total);
  // SolveAccelerations' solve, so the recorded step is StepBody's to the last bit (the
  // checkpointed sweep mixes recorded and plain steps)
  double cond_estimate = 0.0;
  if (!SolveMassSystem(mm, sm, frame.R, VecQ<double>(forces.total - w), &tape->a, &cond_estimate, &tape->factor)) {
    if (!forces.total.allFinite()) return {StatusCode::kOverflowingForce, 0.0};
    return {StatusCode::kSingularMass, 0.0};
  }
  if (cond_estimate > m.world.max_condition) return {StatusCode::kIllConditioned, cond_estimate};
  tape->after = eval;  // the state after the step, with the contacts before it
  tape->after.qd += h * tape->a;
  if (thesis) Group<3>::Advance(tape->after.qd, h, &tape->after.q);
  const BodyState<3, double>& after = tape->after;
  if (!after.qd.allFinite() || !after.translation().allFinite() || !after.gamma().allFinite() ||
      !after.orientation().coeffs().allFinite())
    return {StatusCode::kNonFinite, 0.0};
  *next = after;
  UpdateContacts(body, m.world.ground_plane, next);
  return {};
}

void StepVjp(const StepModel& m, const VecD<double>& target, const BodyState<3, double>& s, const StepTape& tape,
              const StateAdjoint<3>& out, StateAdjoint<3>* in, ControlAdjoint* controls) {
  const int D = m.passive.num_modes(), nv = Group<3>::kRigidDofs + D;
  const Tangent ix(D);
  const double h = m.dt;
  const bool thesis = m.integrator == Integrator::kThesis;
  // backwards: the contact update at `after`, the thesis integrator's advance by v', then
  // v' = v + h a(eval), then the symplectic integrator's advance by v
  in->anchor.clear();
  in->z = out.z;
  PullContactUpdate(m.passive, m.world.ground_plane, tape.after, out.anchor, ix, &in->z, &in->anchor);
  VecQ<double> lambda_v = in->z.tail(nv);
  if (thesis) PullAdvance(tape.after.qd, h, ix, &in->z, &lambda_v);
  VecQ<double> lr;  // M⁻¹ h λ_v (M symmetric: the step's own factor, applied again)
  SolveFactored(m.passive.moments(), *tape.moments, tape.factor, tape.frame->R, VecQ<double>(h * lambda_v), &lr);
  in->z.tail(nv) = lambda_v;
  controls->target = VecD<double>::Zero(D);
  PullAccelerations(m, target, tape.eval, *tape.frame, *tape.moments, tape.a, lr, ix, in, controls);
  if (!thesis) {
    VecQ<double> lambda_u = VecQ<double>::Zero(nv);
    PullAdvance(s.qd, h, ix, &in->z, &lambda_u);
    in->z.tail(nv) += lambda_u;
  }
}

void StartContactsVjp(const BodyModelN<3>& passive, const GroundPlane& ground, BodyState<3, double> s,
                       const AnchorAdjoints& anchor, Eigen::VectorXd* dz) {
  s.contacts.clear();
  AnchorAdjoints none;  // without contacts before, every anchor comes from its point's foot
  PullContactUpdate(passive, ground, s, anchor, Tangent(passive.num_modes()), dz, &none);
}

}  // namespace wobble::fit::internal
