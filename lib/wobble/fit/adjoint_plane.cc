// The 2D body's step piece of the adjoint (adjoint.h): internal::AdjointStep<2>, whose product
// is derived by hand, or taken by forward-mode Jets with springs (and a terrain under the
// symplectic step).
#include "wobble/fit/adjoint.h"

#include <ceres/jet.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

#include "wobble/fit/internal/adjoint_sweep.h"
#include "wobble/fit/internal/mode_force.h"

namespace wobble::fit {

namespace internal {

namespace {

// Inputs differentiated per Jet pass: the table's step has 2·7 + 3·4 = 26 inputs in the air
// (two passes) and 22 more with all 11 points on the ground.
constexpr int kChunk = kAdjointChunk;
using Jet = AdjointJet;

using Adjoint = StateAdjoint<2>;  // z = (q, q̇)

// q and q̇ as Jets: inputs 0 … nq − 1 and nq … 2 nq − 1 of the chunk at `offset`.
void SeedState(const VecQ<double>& q, const VecQ<double>& qd, int offset, VecQ<Jet>* qj, VecQ<Jet>* qdj) {
  const int nq = int(q.size());
  qj->resize(nq);
  qdj->resize(nq);
  for (int i = 0; i < nq; ++i) {
    (*qj)[i] = Seed(q[i], i, offset);
    (*qdj)[i] = Seed(qd[i], nq + i, offset);
  }
}

// g += (∂(state)/∂(chunk inputs))ᵀ λ: every output of a step, weighted by its adjoint.
void PullState(const BodyState<2, Jet>& s, const Adjoint& lambda, int offset, Eigen::VectorXd* g) {
  for (int i = 0; i < s.q.size(); ++i) {
    Pull(s.q[i], lambda.z[i], offset, g);
    Pull(s.qd[i], lambda.z[s.q.size() + i], offset, g);
  }
  for (const Contact<2, Jet>& c : s.contacts) {
    const auto it = lambda.anchor.find({c.point, c.face});
    if (it == lambda.anchor.end()) continue;
    Pull(c.anchor[0], it->second[0], offset, g);
    Pull(c.anchor[1], it->second[1], offset, g);
  }
}

}  // namespace

// The rollout's step, plain and differentiated, on the body with its own mode forces off
// (adjoint_sweep.h says what a piece holds). The state's tangent coordinates are (q, q̇).
template <> class AdjointStep<2> {
 public:
  static constexpr const char* kWhat = "rollout";
  static constexpr bool kTaped = false;  // the product reads the step's a back from the next state
  struct Tape {};

  template <class Fail> static void CheckStartSizes(const BodyModel& body, const BodyState<2, double>& s, Fail fail) {
    const int nq = body.num_q();
    if (s.q.size() != nq || s.qd.size() != nq)
      fail("q0 and qdot0 need " + std::to_string(nq) + " values (tx ty theta and one per mode)");
  }
  static bool StartFinite(const BodyState<2, double>& s) { return s.q.allFinite() && s.qd.allFinite(); }
  template <class Fail> static void CheckStartValid(const BodyState<2, double>&, Fail) {}
  // a kept state: the struct and its contacts (the start's count: an estimate)
  static size_t StepBytes(const BodyState<2, double>& start) {
    return sizeof(start) + start.contacts.size() * sizeof(start.contacts[0]);
  }

  AdjointStep(const BodyModel& body, const ControlledRollout& r) : passive_(body.WithoutModeGains()), r_(r) {
    params_.K = r.stiffness;
    params_.c = r.damping;
  }
  int nq() const { return passive_.num_q(); }
  int modes() const { return passive_.num_modes(); }

  BodyState<2, double> Start() const {
    BodyState<2, double> s;
    s.q = r_.start.q;
    s.qd = r_.start.qd;
    UpdateContacts(passive_, r_.world.ground, &s);
    return s;
  }

  bool Advance(int n, BodyState<2, double>* s, std::string* why) const {
    const VecD<double> target = r_.targets.col(n);
    const StepStatus st = StepBody(passive_, r_.world, 0, r_.integrator, r_.dt, s, ModeForce<double>{&params_, &target});
    if (!st.ok()) return StepFailed(n, StatusCodeName(st.code), why);
    if (!s->q.allFinite() || !s->qd.allFinite()) return StepFailed(n, "non-finite state", why);
    return true;
  }

  // λ_n from λ_{n+1} = `out` through step n from state s to `next`: by hand (HandVjp) when
  // ByHand, else by Jets (JetVjp).
  bool Vjp(int n, const BodyState<2, double>& s, const BodyState<2, double>& next, const Tape*, const Adjoint& out,
           Adjoint* in, RolloutGradient* g, std::string* why) const {
    if (!ByHand()) return JetVjp(n, s, out, in, g, why);
    HandVjp(n, s, next, out, in, g);
    return true;
  }

  // λ_n from λ_{n+1} = `out` through step n taken from state s by Jets; adds the step's part of
  // the gains' gradient to *g and sets its targets' column.
  bool JetVjp(int n, const BodyState<2, double>& s, const Adjoint& out, Adjoint* in, RolloutGradient* g,
               std::string* why) const {
    const int nq = this->nq(), D = modes(), nc = int(s.contacts.size());
    const int anchors = 2 * nq, controls = anchors + 2 * nc, width = controls + 3 * D;
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(width);
    for (int offset = 0; offset < width; offset += kChunk) {
      BodyState<2, Jet> sj;
      SeedState(s.q, s.qd, offset, &sj.q, &sj.qd);
      sj.contacts.resize(nc);
      for (int c = 0; c < nc; ++c) {
        sj.contacts[c].point = s.contacts[c].point;
        sj.contacts[c].face = s.contacts[c].face;
        for (int k = 0; k < 2; ++k) sj.contacts[c].anchor[k] = Seed(s.contacts[c].anchor[k], anchors + 2 * c + k, offset);
      }
      sj.penetration = s.penetration;
      ModeParams<Jet> mp;
      mp.K.resize(D);
      mp.c.resize(D);
      VecD<Jet> target(D);
      for (int d = 0; d < D; ++d) {
        target[d] = Seed(r_.targets(d, n), controls + d, offset);
        mp.K[d] = Seed(params_.K[d], controls + D + d, offset);
        mp.c[d] = Seed(params_.c[d], controls + 2 * D + d, offset);
      }
      const StepStatus st = StepBody(passive_, r_.world, 0, r_.integrator, r_.dt, &sj, ModeForce<Jet>{&mp, &target});
      if (!st.ok()) return StepFailed(n, StatusCodeName(st.code) + " (differentiated step)", why);
      PullState(sj, out, offset, &grad);
    }
    in->z = grad.head(2 * nq);
    in->anchor.clear();
    for (int c = 0; c < nc; ++c)
      in->anchor[{s.contacts[c].point, s.contacts[c].face}] = grad.segment(anchors + 2 * c, 2);
    g->targets.col(n) = grad.segment(controls, D);
    g->stiffness += grad.segment(controls + D, D);
    g->damping += grad.segment(controls + 2 * D, D);
    return true;
  }

  // Whether step n can take HandVjp: no spring (rare: Jets), and no terrain under the
  // symplectic step (there a new contact's face depends on the velocity, which differs
  // between the force evaluation at (q', q̇) and the contact update at (q', q̇')).
  bool ByHand() const { return r_.world.springs.empty() && (!r_.world.ground.terrain || r_.integrator == Integrator::kThesis); }

  // The same product as JetVjp, by hand: the step is
  //   thesis     q' = q + h q̇ + h² a(q, q̇),  q̇' = q̇ + h a(q, q̇)
  //   symplectic q' = q + h q̇,  q̇' = q̇ + h a(q', q̇)
  // then the contact update (UpdateContacts) at (q', q̇') gives the new anchors. With
  // a = M⁻¹ r, r = gravity + mode forces + ground − w (Eq. 4.21) and y = M⁻¹ μ (M symmetric),
  //   μᵀ da = yᵀ dr − yᵀ dM a,
  // where yᵀ (∂M/∂q_j) a = (K_j(y + a) − K_j(y − a)) / 2 with K_j(v) = ½ vᵀ (∂M/∂q_j) v the
  // kinetic gradient (KineticGradient), and yᵀ dr is written out from the moment formulas of
  // GravityForce and VelocityTerms (kinematics.h). The ground's part of r and the anchors'
  // update are sums over contact points, each a function of (x, v, its anchor) only: each is
  // differentiated by hand (GroundForcePartials, AnchorUpdatePartials) and pulled back
  // through x = t + R l and v = J q̇ (PullPoint).
  // The step's a is read back from the next state, a = (q̇' − q̇)/h (both integrators), exact
  // up to rounding (~1e-13 relative).
  void HandVjp(int n, const BodyState<2, double>& s, const BodyState<2, double>& next, const Adjoint& out, Adjoint* in,
               RolloutGradient* g) const {
    const int nq = this->nq();
    const double h = r_.dt;
    const bool thesis = r_.integrator == Integrator::kThesis;
    // λ of (q', q̇') once the anchors' update is pulled back
    Eigen::VectorXd bar_q = out.z.head(nq), bar_qd = out.z.tail(nq);
    std::map<ContactKey, Eigen::Vector2d> anchor_grad;  // of s's anchors
    auto anchor_slot = [&](const Contact<2, double>* c) -> Eigen::Vector2d* {  // (Eigen leaves a new one unset)
      return c ? &anchor_grad.try_emplace({c->point, c->face}, Eigen::Vector2d::Zero()).first->second : nullptr;
    };
    for (const Contact<2, double>& c : next.contacts) {
      const auto it = out.anchor.find({c.point, c.face});
      if (it == out.anchor.end() || it->second.isZero(0.0)) continue;
      const Contact<2, double>* before = Find(s, c);
      const ContactPoint p = PointAt(c, before, next.q, next.qd);
      PullPoint(p, AnchorUpdatePartials(p, it->second), next.qd, &bar_q, &bar_qd, anchor_slot(before));
    }
    // where a is evaluated, and μ, the adjoint of a
    const VecQ<double> Q = thesis ? s.q : VecQ<double>(s.q + h * s.qd), V = s.qd;
    const VecQ<double> mu = thesis ? VecQ<double>(h * h * bar_q + h * bar_qd) : VecQ<double>(h * bar_qd);
    const VecQ<double> a = (next.qd - s.qd) / h;
    VecQ<double> y, gQ = VecQ<double>::Zero(nq), gV = VecQ<double>::Zero(nq);
    ForceVjp(n, Q, V, a, mu, &y, &gQ, &gV, g);
    // the ground force's part: y · Σ J_kᵀ f_k = Σ (J_k y) · f_k; at (q', q̇) the symplectic step
    // feels the contacts of the next state, with the anchors they had before it
    for (const Contact<2, double>& c : thesis ? s.contacts : next.contacts) {
      const Contact<2, double>* before = thesis ? &c : Find(s, c);
      const ContactPoint p = PointAt(c, before, Q, V);
      const Eigen::Vector2d P = PointVelocity(p.frame, y, p.l, passive_.mode_matrix(c.point));  // J_k y
      bool slipping;
      const Eigen::Vector2d f = GroundForce(p.face, p.x, p.v, p.anchor, &slipping);
      PullPoint(p, GroundForcePartials(p, P), V, &gQ, &gV, anchor_slot(before));
      AddVelocityPartial(p, y, f, &gQ);  // J_k y depends on Q too
    }
    // through the integrator
    in->z.resize(2 * nq);
    in->z.head(nq) = bar_q + gQ;
    in->z.tail(nq) = thesis ? VecQ<double>(h * bar_q + bar_qd + gV) : VecQ<double>(h * (bar_q + gQ) + bar_qd + gV);
    in->anchor.clear();
    for (const Contact<2, double>& c : s.contacts) {
      const auto it = anchor_grad.find({c.point, c.face});
      in->anchor[{c.point, c.face}] = it == anchor_grad.end() ? Eigen::Vector2d::Zero() : it->second;
    }
  }

  // The anchors of the first state come from its contact update (a point below the ground at
  // the start is anchored where it is): their adjoint passes on to q0 and q̇0.
  void StartVjp(const Adjoint& start, Eigen::VectorXd* dz0) const {
    const int nq = this->nq();
    if (start.anchor.empty()) return;
    Adjoint anchors_only{Eigen::VectorXd::Zero(2 * nq), start.anchor};
    Eigen::VectorXd grad = Eigen::VectorXd::Zero(2 * nq);
    for (int offset = 0; offset < 2 * nq; offset += kChunk) {
      BodyState<2, Jet> sj;
      SeedState(r_.start.q, r_.start.qd, offset, &sj.q, &sj.qd);
      UpdateContacts(passive_, r_.world.ground, &sj);
      PullState(sj, anchors_only, offset, &grad);
    }
    dz0->head(nq) += grad.head(nq);
    dz0->tail(nq) += grad.tail(nq);
  }

 private:
  static const Contact<2, double>* Find(const BodyState<2, double>& s, const Contact<2, double>& c) {
    for (const Contact<2, double>& x : s.contacts)
      if (x.point == c.point && x.face == c.face) return &x;
    return nullptr;
  }

  // μᵀ ∂a/∂(q, q̇, gains, targets) at (Q, V) without the ground: sets y = M⁻¹ μ, adds to gQ,
  // gV and the gains' and targets' gradient.
  void ForceVjp(int n, const VecQ<double>& Q, const VecQ<double>& V, const VecQ<double>& a, const VecQ<double>& mu,
                VecQ<double>* y_out, VecQ<double>* gq_out, VecQ<double>* gqd_out, RolloutGradient* g) const {
    const int D = modes();
    const MassMoments& mm = passive_.moments();
    const Mat2<double> R = Rotation(Q[2]);
    VecQ<double>& y = *y_out;
    VecQ<double>& gq = *gq_out;
    VecQ<double>& gqd = *gqd_out;
    double cond = 0.0;
    SolveMassSystem(mm, Q, R, mu, &y, &cond);
    const double thd = V[2], y_theta = y[2];
    const Eigen::Vector2d y_t = y.head<2>();
    Eigen::Matrix2d S;
    S << 0.0, -1.0, 1.0, 0.0;
    // gravity: r_θ = (R S c)·g, r_γ = Cᵀ Rᵀ g, c = c0 + C γ
    const Eigen::Vector2d c = mm.c0 + mm.C * Q.tail(D);
    if (r_.world.gravity_on) {
      const Eigen::Vector2d gv = GravityFor<2>(r_.world);
      gq[2] += -y_theta * gv.dot(R * c);
      if (D > 0) {
        gq[2] += gv.dot(R * S * (mm.C * y.tail(D)));
        gq.tail(D) += y_theta * (mm.C.transpose() * (S.transpose() * (R.transpose() * gv)));
      }
    }
    // −w: w_t = R(−θ̇² c + 2θ̇ S C γ̇), w_θ = 2θ̇ e·γ̇, w_γ = −θ̇² e + 2θ̇ P γ̇, e = e0 + G γ
    if (D > 0) {
      const VecD<double> y_g = y.tail(D), gd = V.tail(D);
      const Eigen::Vector2d Cgd = mm.C * gd;
      const VecD<double> e = mm.e0 + mm.G * Q.tail(D);
      gq[2] -= y_t.dot(R * S * (-thd * thd * c + 2.0 * thd * S * Cgd));
      gq.tail(D) -= -thd * thd * (mm.C.transpose() * (R.transpose() * y_t)) + 2.0 * thd * y_theta * (mm.G * gd) -
                    thd * thd * (mm.G * y_g);
      gqd[2] -= y_t.dot(R * (-2.0 * thd * c + 2.0 * S * Cgd)) + 2.0 * y_theta * e.dot(gd) +
                y_g.dot(-2.0 * thd * e + 2.0 * (mm.P * gd));
      gqd.tail(D) -= 2.0 * thd * (mm.C.transpose() * (S.transpose() * (R.transpose() * y_t))) + 2.0 * thd * y_theta * e +
                     2.0 * thd * (mm.P.transpose() * y_g);
      // the mode forces −2K (γ − γ0) − c γ̇
      for (int d = 0; d < D; ++d) {
        const double yd = y[kRigidDofs + d];
        gq[kRigidDofs + d] += -2.0 * params_.K[d] * yd;
        gqd[kRigidDofs + d] += -params_.c[d] * yd;
        g->targets(d, n) = 2.0 * params_.K[d] * yd;
        g->stiffness[d] += -2.0 * (Q[kRigidDofs + d] - r_.targets(d, n)) * yd;
        g->damping[d] += -V[kRigidDofs + d] * yd;
      }
    }
    // −yᵀ (∂M/∂q) a
    VecQ<double> k_plus, k_minus;
    KineticGradient(mm, Q, VecQ<double>(y + a), &k_plus);
    KineticGradient(mm, Q, VecQ<double>(y - a), &k_minus);
    gq -= 0.5 * (k_plus - k_minus);
  }

  // A contact point at (Q, V) in plain numbers: its frame, local and world position, velocity
  // and the anchor its force is tied to (a new contact's is its projection on the face, as
  // ForEachPointInContact makes it).
  struct ContactPoint {
    int point;
    GroundFace face;
    Frame<2, double> frame;
    Eigen::Vector2d l, x, v, anchor;
    bool fresh;
  };
  ContactPoint PointAt(const Contact<2, double>& c, const Contact<2, double>* before, const VecQ<double>& Q,
                       const VecQ<double>& V) const {
    const GroundFace face = r_.world.ground.Face(c.face);
    const Frame<2, double> frame(Q);
    const Eigen::Vector2d l = LocalPosition<double>(passive_.rest_local(c.point), passive_.mode_matrix(c.point), Q);
    const Eigen::Vector2d x = WorldFromLocal(frame, l);
    const Eigen::Vector2d v = PointVelocity(frame, V, l, passive_.mode_matrix(c.point));
    const Eigen::Vector2d anchor = before ? before->anchor : Eigen::Vector2d(x - face.Height(x) * face.n);
    return {c.point, face, frame, l, x, v, anchor, before == nullptr};
  }

  // ∂φ/∂(x, v, anchor) of one contact point's scalar φ.
  struct PointPartials {
    Eigen::Vector2d x = Eigen::Vector2d::Zero(), v = Eigen::Vector2d::Zero(), anchor = Eigen::Vector2d::Zero();
  };

  // φ = w · f of GroundForce (Eq. 4.24/4.25) with its branches taken as at the plain values:
  // f_n = −K n·(x − a) − C n·v while it pushes (≥ 0), f_t = −K τ·(x − a) − F τ·v while it
  // sticks, ±μ f_n while it slips.
  static PointPartials GroundForcePartials(const ContactPoint& p, const Eigen::Vector2d& w) {
    const GroundFace& g = p.face;
    double w_fn = w.dot(g.n), w_ft = w.dot(g.tau);
    const int slip = SlipSign(p);
    if (slip != 0) {  // f_t = slip μ f_n
      w_fn += slip * g.friction_cap * w_ft;
      w_ft = 0.0;
    }
    PointPartials d;
    if (Pushing(p)) {
      d.x -= g.stiffness * w_fn * g.n;
      d.v -= g.normal_damping * w_fn * g.n;
      d.anchor += g.stiffness * w_fn * g.n;
    }
    d.x -= g.stiffness * w_ft * g.tau;
    d.v -= g.friction_damping * w_ft * g.tau;
    d.anchor += g.stiffness * w_ft * g.tau;
    return d;
  }

  // φ = w · (the anchor after the contact update): the anchor itself while the point sticks;
  // when it slips, SlipAnchor's a' = x − h(x) n − δ τ with δ = −(f·τ + F τ·v)/K and
  // f·τ = ±μ f_n (δ = 0 without stiffness).
  static PointPartials AnchorUpdatePartials(const ContactPoint& p, const Eigen::Vector2d& w) {
    const GroundFace& g = p.face;
    PointPartials d;
    const int slip = SlipSign(p);
    if (slip == 0) {
      d.anchor = w;
      return d;
    }
    d.x = w - g.n * g.n.dot(w);  // x − h(x) n, h(x) = n·(x − point)
    if (!(g.stiffness > 0.0)) return d;
    const double alpha = w.dot(g.tau) / g.stiffness;  // −(w·τ) δ = α (±μ f_n + F τ·v)
    d.v += alpha * g.friction_damping * g.tau;
    if (Pushing(p)) {
      const double k = alpha * slip * g.friction_cap;
      d.x -= k * g.stiffness * g.n;
      d.v -= k * g.normal_damping * g.n;
      d.anchor += k * g.stiffness * g.n;
    }
    return d;
  }

  // GroundForce's branches at the plain values: the normal force pushes (it is not clamped to
  // 0), and the friction slips up (+1), down (−1) or sticks (0).
  static bool Pushing(const ContactPoint& p) { return NormalForce(p) >= 0.0; }
  static double NormalForce(const ContactPoint& p) {
    return -p.face.stiffness * p.face.n.dot(p.x - p.anchor) - p.face.normal_damping * p.face.n.dot(p.v);
  }
  static int SlipSign(const ContactPoint& p) {
    const double ft = -p.face.stiffness * p.face.tau.dot(p.x - p.anchor) - p.face.friction_damping * p.face.tau.dot(p.v);
    const double cap = p.face.friction_cap * std::max(NormalForce(p), 0.0);
    return ft > cap ? 1 : ft < -cap ? -1 : 0;
  }

  // Pulls a point's ∂φ/∂(x, v, anchor) back to Q, V (x = t + R l, v = J V) and its previous
  // anchor; a new contact's anchor is x − h(x) n, which passes its part on to x.
  template <class Vec>
  void PullPoint(const ContactPoint& p, PointPartials d, const VecQ<double>& V, Vec* gQ, Vec* gV,
                 Eigen::Vector2d* g_anchor) const {
    if (p.fresh) {
      d.x += d.anchor - p.face.n * p.face.n.dot(d.anchor);
    } else if (g_anchor) {
      *g_anchor += d.anchor;
    }
    AddJacobianTranspose(p, d.x, gQ);  // ∂x/∂Q = J
    AddJacobianTranspose(p, d.v, gV);  // ∂v/∂V = J
    AddVelocityPartial(p, V, d.v, gQ);
  }

  // out += Jᵀ w at the point: (w, w·R S l, Bᵀ Rᵀ w), Eq. 4.20.
  template <class Vec> void AddJacobianTranspose(const ContactPoint& p, const Eigen::Vector2d& w, Vec* out) const {
    const auto& B = passive_.mode_matrix(p.point);
    const Eigen::Vector2d w_local = p.frame.R.transpose() * w;
    (*out)[0] += w[0];
    (*out)[1] += w[1];
    (*out)[2] += Perp(p.l).dot(w_local);
    for (int d = 0; d < B.cols(); ++d) (*out)[kRigidDofs + d] += B.col(d).dot(w_local);
  }

  // out += (∂(J u)/∂Q)ᵀ w for J u = u_t + R (S l u_θ + B u_γ): by θ, R S (S l u_θ + B u_γ); by
  // γ_d (through l), u_θ R S b_d.
  template <class Vec>
  void AddVelocityPartial(const ContactPoint& p, const VecQ<double>& u, const Eigen::Vector2d& w, Vec* out) const {
    const auto& B = passive_.mode_matrix(p.point);
    const Eigen::Vector2d w_local = p.frame.R.transpose() * w;
    Eigen::Vector2d u_local = Perp(p.l) * u[2];
    for (int d = 0; d < B.cols(); ++d) u_local += B.col(d) * u[kRigidDofs + d];
    (*out)[2] += Perp(u_local).dot(w_local);
    for (int d = 0; d < B.cols(); ++d) (*out)[kRigidDofs + d] += u[2] * Perp(Eigen::Vector2d(B.col(d))).dot(w_local);
  }


  const BodyModel passive_;
  const ControlledRollout& r_;
  ModeParams<double> params_;
};

}  // namespace internal

template <>
double RolloutCost<2>(const BodyModelN<2>& body, const ControlledRolloutN<2>& rollout, const StageCostN<2>& cost) {
  return internal::RolloutCostOf<internal::AdjointStep<2>>(body, rollout, cost);
}

template <>
RolloutGradient RolloutCostGradient<2>(const BodyModelN<2>& body, const ControlledRolloutN<2>& rollout,
                                       const StageCostN<2>& cost, int checkpoint_interval) {
  return internal::RolloutGradientOf<internal::AdjointStep<2>>(body, rollout, cost, checkpoint_interval);
}

}  // namespace wobble::fit

