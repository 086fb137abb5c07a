// The task terms of spacetime fits (spacetime.h), each with its exact gradient in the state's
// tangent coordinates (adjoint.h): 2D z = (q, q̇), 3D z = (δt, ε, δγ, δv).
#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include "wobble/fit/spacetime.h"

namespace wobble::fit {

namespace {

void CheckTerm(int step, double weight, const char* what) {
  if (step < 0) throw std::invalid_argument(std::string(what) + ": the step must be >= 0");
  if (!(weight >= 0.0) || !std::isfinite(weight)) throw std::invalid_argument(std::string(what) + ": the weight must be >= 0");
}

}  // namespace

StageCostN<2> CentreOfMassAt(const BodyModelN<2>& body, int step, const Eigen::Vector2d& goal, double weight,
                             Axes axes) {
  CheckTerm(step, weight, "CentreOfMassAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassAt: the goal must be finite");
  const MassMoments mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const Eigen::VectorXd q = s.q;
    const int D = int(q.size()) - kRigidDofs;
    const Eigen::Vector2d c = (mm.c0 + mm.C * q.tail(D)) / mm.m;  // body frame
    const Eigen::Rotation2Dd R(q[2]);
    const Eigen::Vector2d Rc = R * c, x = q.head<2>() + Rc;
    Eigen::Vector2d miss = x - goal;
    if (!axes.x) miss.x() = 0.0;
    if (!axes.y) miss.y() = 0.0;
    const Eigen::Vector2d r = weight * miss;
    dz->head<2>() += r;                                 // ∂x/∂t = I
    (*dz)[2] += r.y() * Rc.x() - r.x() * Rc.y();        // ∂x/∂θ = S R c
    dz->segment(kRigidDofs, D) += mm.C.transpose() * (R.inverse() * r) / mm.m;  // ∂x/∂γ = R C / m
    return 0.5 * weight * miss.squaredNorm();
  };
}

StageCostN<2> CentreOfMassVelocityAt(const BodyModelN<2>& body, int step, const Eigen::Vector2d& goal, double weight,
                                     Axes axes) {
  CheckTerm(step, weight, "CentreOfMassVelocityAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassVelocityAt: the goal must be finite");
  const MassMoments mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const Eigen::VectorXd q = s.q, qd = s.qd;
    const int nq = int(q.size()), D = nq - kRigidDofs;
    Eigen::Matrix2d S;
    S << 0.0, -1.0, 1.0, 0.0;
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(q[2]).toRotationMatrix();
    const Eigen::Vector2d c = (mm.c0 + mm.C * q.tail(D)) / mm.m, cd = mm.C * qd.tail(D) / mm.m;
    const double thd = qd[2];
    const Eigen::Vector2d v = qd.head<2>() + thd * (S * R * c) + R * cd;
    Eigen::Vector2d miss = v - goal;
    if (!axes.x) miss.x() = 0.0;
    if (!axes.y) miss.y() = 0.0;
    const Eigen::Vector2d r = weight * miss;
    // ∂v/∂ṫ = I, ∂v/∂θ̇ = S R c, ∂v/∂γ̇ = R C/m; ∂v/∂θ = θ̇ S S R c + S R ċ, ∂v/∂γ = θ̇ S R C/m
    dz->segment<2>(nq) += r;
    (*dz)[nq + 2] += r.dot(S * R * c);
    dz->tail(D) += mm.C.transpose() * (R.transpose() * r) / mm.m;
    (*dz)[2] += r.dot(thd * (S * S * R * c) + S * R * cd);
    dz->segment(kRigidDofs, D) += thd * mm.C.transpose() * ((S * R).transpose() * r) / mm.m;
    return 0.5 * weight * miss.squaredNorm();
  };
}

template <> StageCostN<2> UprightAt<2>(int step, double weight, double time_scale) {
  CheckTerm(step, weight, "UprightAt");
  if (!(time_scale >= 0.0) || !std::isfinite(time_scale)) throw std::invalid_argument("UprightAt: the time scale must be >= 0");
  return [step, weight, time_scale](int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const int nq = int(s.q.size());
    const double q2 = s.q[2], qd2 = s.qd[2];
    const double s2 = time_scale * time_scale;
    (*dz)[2] += weight * q2;
    (*dz)[nq + 2] += weight * s2 * qd2;
    return 0.5 * weight * (q2 * q2 + s2 * qd2 * qd2);
  };
}

// 3D: where each part of z = (δt, ε, δγ, δv) and of v = (ṫ, ω, γ̇) starts (adjoint.h).
namespace {
struct SpaceTangent {
  int D;
  int t() const { return 0; }
  int eps() const { return 3; }
  int gamma() const { return 6; }
  int tdot() const { return 6 + D; }
  int omega() const { return 9 + D; }
  int gammadot() const { return 12 + D; }
};

Eigen::Vector3d Masked(Eigen::Vector3d miss, Axes axes) {
  if (!axes.x) miss.x() = 0.0;
  if (!axes.y) miss.y() = 0.0;
  if (!axes.z) miss.z() = 0.0;
  return miss;
}
}  // namespace

StageCostN<3> CentreOfMassAt(const BodyModelN<3>& body, int step, const Eigen::Vector3d& goal, double weight,
                             Axes axes) {
  CheckTerm(step, weight, "CentreOfMassAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassAt: the goal must be finite");
  const MassMomentsN<3> mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const SpaceTangent z{int(s.gamma().size())};
    const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
    const Eigen::Vector3d c = (mm.c0 + mm.C * s.gamma()) / mm.m;  // body frame
    const Eigen::Vector3d miss = Masked(s.translation() + R * c - goal, axes);
    const Eigen::Vector3d r = weight * miss, r_body = R.transpose() * r;
    dz->segment<3>(z.t()) += r;                                   // ∂x/∂t = I
    dz->segment<3>(z.eps()) += c.cross(r_body);                   // R exp(ε̂) c ≈ R (c + ε × c)
    dz->segment(z.gamma(), z.D) += mm.C.transpose() * r_body / mm.m;  // ∂x/∂γ = R C / m
    return 0.5 * weight * miss.squaredNorm();
  };
}

StageCostN<3> CentreOfMassVelocityAt(const BodyModelN<3>& body, int step, const Eigen::Vector3d& goal, double weight,
                                   Axes axes) {
  CheckTerm(step, weight, "CentreOfMassVelocityAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassVelocityAt: the goal must be finite");
  const MassMomentsN<3> mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const SpaceTangent z{int(s.gamma().size())};
    const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
    const Eigen::Vector3d c = (mm.c0 + mm.C * s.gamma()) / mm.m;
    const Eigen::Vector3d omega = s.qd.segment<3>(3);
    const Eigen::Vector3d w = omega.cross(c) + mm.C * s.qd.tail(z.D) / mm.m;  // body-frame rate of R c
    const Eigen::Vector3d miss = Masked(s.qd.head<3>() + R * w - goal, axes);
    const Eigen::Vector3d r = weight * miss, r_body = R.transpose() * r;
    // v_c = ṫ + R w: ∂/∂ṫ = I; ∂/∂ω: r·R(ω × c) = ω·(c × Rᵀr); ∂/∂γ̇ = R C/m;
    // ∂/∂ε: R exp(ε̂) w ≈ R (w + ε × w); ∂/∂γ: r·R(ω × C δγ/m) = δγ·Cᵀ(Rᵀr × ω)/m
    dz->segment<3>(z.tdot()) += r;
    dz->segment<3>(z.omega()) += c.cross(r_body);
    dz->segment(z.gammadot(), z.D) += mm.C.transpose() * r_body / mm.m;
    dz->segment<3>(z.eps()) += w.cross(r_body);
    dz->segment(z.gamma(), z.D) += mm.C.transpose() * r_body.cross(omega) / mm.m;
    return 0.5 * weight * miss.squaredNorm();
  };
}

template <> StageCostN<3> UprightAt<3>(int step, double weight, double time_scale) {
  CheckTerm(step, weight, "UprightAt");
  if (!(time_scale >= 0.0) || !std::isfinite(time_scale))
    throw std::invalid_argument("UprightAt: the time scale must be >= 0");
  return [step, weight, time_scale](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    const SpaceTangent z{int(s.gamma().size())};
    const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
    const Eigen::Vector3d up = Eigen::Vector3d::UnitY(), up_body = R.transpose() * up;
    const Eigen::Vector3d omega = s.qd.segment<3>(3);
    const double s2 = time_scale * time_scale;
    // |R e_y − e_y|² = 2 − 2 u_y with u_y = e_yᵀ R e_y; under R exp(ε̂), δu_y = ε·(e_y × Rᵀe_y)
    dz->segment<3>(z.eps()) += -weight * up.cross(up_body);
    dz->segment<3>(z.omega()) += weight * s2 * omega;
    return weight * (1.0 - up.dot(R * up)) + 0.5 * weight * s2 * omega.squaredNorm();
  };
}

// w/2 |q̇|², the same numbers in both dimensions: q̇ is the tangent's second half.
template <int Dim> StageCostN<Dim> StillAt(int step, double weight) {
  CheckTerm(step, weight, "StillAt");
  return [step, weight](int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz) {
    if (n != step) return 0.0;
    dz->tail(s.qd.size()) += weight * s.qd;
    return 0.5 * weight * s.qd.squaredNorm();
  };
}
template StageCostN<2> StillAt<2>(int, double);
template StageCostN<3> StillAt<3>(int, double);

namespace {
template <int Dim> StageCostN<Dim> Sum(std::vector<StageCostN<Dim>> terms) {
  for (const StageCostN<Dim>& t : terms)
    if (!t) throw std::invalid_argument("SumOf: an empty term");
  return [terms = std::move(terms)](int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz) {
    double total = 0.0;
    for (const StageCostN<Dim>& t : terms) total += t(n, s, dz);
    return total;
  };
}
}  // namespace

StageCostN<2> SumOf(std::vector<StageCostN<2>> terms) { return Sum<2>(std::move(terms)); }
StageCostN<3> SumOf(std::vector<StageCostN<3>> terms) { return Sum<3>(std::move(terms)); }

}  // namespace wobble::fit
