// How the pose fits hold q while Ceres solves (not part of the public API): one code path for
// both dimensions, what differs in PoseChart<Dim>.
//
//   2D: the solver's coordinates are q itself (θ has no singularity).
//   3D: x = [t, δ, γ] with R = R0 exp(δ̂), R0 the chart's centre and δ a body-frame rotation
//       vector that starts at 0: no Euler-angle singularity, no unit-norm constraint. A solve
//       whose δ grew past kRecentreAngle is restarted from its result (R0 ← R0 exp(δ̂)).
//
// Residual functors are written once over a single parameter block x (operator()(const T* x,
// T* r) and kResiduals); PoseChart<Dim>::Cost wraps them for Ceres (2D: fixed-size autodiff, 3D:
// dynamic autodiff).
#pragma once

#include <ceres/autodiff_cost_function.h>
#include <ceres/ceres.h>
#include <ceres/dynamic_autodiff_cost_function.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "wobble/core/rotation3.h"
#include "wobble/fit/internal/residuals.h"
#include "wobble/fit/internal/solve_common.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::fit {

// A local 3D solve turns by at most this much (radians) before it is re-centred.
constexpr double kRecentreAngle = 1.0;

// A one-block functor as Ceres' fixed-size and dynamic autodiff call it.
template <class F> struct FixedBlock {
  F f;
  template <class T> bool operator()(const T* x, T* r) const { return f(x, r); }
};
template <class F> struct DynamicBlock {
  F f;
  template <class T> bool operator()(T const* const* x, T* r) const { return f(x[0], r); }
};

template <int Dim> struct PoseChart;

template <> struct PoseChart<2> {
  using Vec = Eigen::Vector2d;
  struct Centre {};  // nothing: x = q
  Centre centre;
  Eigen::VectorXd x;

  static PoseChart At(const Eigen::VectorXd& q) {
    PoseChart c;
    c.x = q;
    return c;
  }
  Eigen::VectorXd q() const { return x; }
  bool TurnedFar() const { return false; }
  template <class T> static Vec2<T> Place(const Centre&, const PointBasisN<2>& p, const T* x, int num_q) {
    return FitPoseQ<2>::Place(p, x, num_q);
  }
  template <class F> static ceres::CostFunction* Cost(const F& f, int num_q) {
    return WithNumQ(num_q, [&](auto n) -> ceres::CostFunction* {
      return new ceres::AutoDiffCostFunction<FixedBlock<F>, F::kResiduals, decltype(n)::value>(new FixedBlock<F>{f});
    });
  }
  // Weighted Procrustes: q (γ = 0) whose rigid motion best carries `rest` onto `target`.
  static Eigen::VectorXd RigidStart(int num_modes, const std::vector<Vec>& rest, const std::vector<Vec>& target,
                                    const std::vector<double>& w);
  // A trajectory's starts: θ within π of the previous frame's.
  static void Unwrap(const Eigen::VectorXd& previous, Eigen::VectorXd* q) {
    (*q)[2] = previous[2] + std::remainder((*q)[2] - previous[2], 2.0 * M_PI);
  }
  // The divided second difference c0 q0 + c1 q1 + c2 q2 of three frames, times `scale`
  // (SecondDifference: linear, its Jacobian written out).
  static ceres::CostFunction* Smoothness(const double c[3], const PoseChart* /*charts*/[3], const VecQ<double>& scale) {
    SecondDifference s;
    s.c0 = c[0];
    s.c1 = c[1];
    s.c2 = c[2];
    s.scale = scale;
    return MakeSecondDifferenceCost(s);
  }
};

template <> struct PoseChart<3> {
  using Vec = Eigen::Vector3d;
  using Centre = Eigen::Matrix3d;  // R0
  static constexpr int kStride = 6;  // Jet width of the dynamic autodiff
  Centre centre = Centre::Identity();
  Eigen::VectorXd x;  // [t, δ, γ]

  static PoseChart At(const Eigen::VectorXd& q) {
    PoseChart c;
    c.centre = ExpRotation<double>(q.segment<3>(3)).toRotationMatrix();
    c.x = q;
    c.x.segment<3>(3).setZero();
    return c;
  }
  Eigen::Matrix3d R() const { return centre * ExpRotation<double>(x.segment<3>(3)).toRotationMatrix(); }
  Eigen::VectorXd q() const {
    Eigen::VectorXd q = x;
    q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(R()));
    return q;
  }
  bool TurnedFar() const { return x.segment<3>(3).norm() > kRecentreAngle; }
  template <class T> static Vec3<T> Place(const Centre& R0, const PointBasisN<3>& p, const T* x, int num_q) {
    Vec3<T> l = p.b0.cast<T>();
    for (int d = 0; d + FitPoseQ<3>::kRigid < num_q; ++d) l += p.B.col(d).cast<T>() * x[FitPoseQ<3>::kRigid + d];
    const Mat3<T> dR = ExpRotation<T>(Vec3<T>(x[3], x[4], x[5])).toRotationMatrix();
    return Vec3<T>(x[0], x[1], x[2]) + R0.cast<T>() * (dR * l);
  }
  template <class F> static ceres::CostFunction* Cost(const F& f, int num_q) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<DynamicBlock<F>, kStride>(new DynamicBlock<F>{f});
    cost->AddParameterBlock(num_q);
    cost->SetNumResiduals(F::kResiduals);
    return cost;
  }
  // Weighted Kabsch (SVD, no reflection).
  static Eigen::VectorXd RigidStart(int num_modes, const std::vector<Vec>& rest, const std::vector<Vec>& target,
                                    const std::vector<double>& w);
  static void Unwrap(const Eigen::VectorXd&, Eigen::VectorXd*) {}  // the chart holds any turn
  // t and γ: the divided second difference; the orientation: c2 log(R1ᵀR2) − c0 log(R0ᵀR1)
  // (body-frame turns); each coordinate times `scale`.
  static ceres::CostFunction* Smoothness(const double c[3], const PoseChart* charts[3], const VecQ<double>& scale);
};

// sqrt(w) (x(q) − y): a body point pulled to a target position.
template <int Dim> struct PointResidual {
  static constexpr int kResiduals = Dim;
  PointBasisN<Dim> point;
  typename PoseChart<Dim>::Centre centre;
  Eigen::Matrix<double, Dim, 1> y;
  double sqrt_weight = 1.0;
  int num_q = 0;
  template <class T> bool operator()(const T* x, T* r) const {
    const Eigen::Matrix<T, Dim, 1> e = (PoseChart<Dim>::Place(centre, point, x, num_q) - y.template cast<T>()) * T(sqrt_weight);
    for (int i = 0; i < Dim; ++i) r[i] = e[i];
    return true;
  }
};

// The residual of correspondence `t` (its centre set per chart). Throws std::invalid_argument
// naming `fit` for a mass point the body lacks or a weight that is not > 0.
template <int Dim>
PointResidual<Dim> ToPoint(const BodyModelN<Dim>& body, const CorrespondenceN<Dim>& t, const char* fit) {
  if (t.mass_point >= body.num_points())
    throw std::invalid_argument(std::string(fit) + ": mass point " + std::to_string(t.mass_point) +
                                " does not exist (the body has " + std::to_string(body.num_points()) + ")");
  if (!(t.weight > 0) || !std::isfinite(t.weight)) throw std::invalid_argument(std::string(fit) + ": weights must be > 0");
  PointResidual<Dim> r;
  r.point = BasisOf(body, t.mass_point, t.lattice_coords);
  r.y = t.position;
  r.sqrt_weight = std::sqrt(t.weight);
  r.num_q = body.num_q();
  return r;
}

// Validated options of a fit of `body`; throws std::invalid_argument naming `fit`.
template <int Dim> void CheckOptions(const BodyModelN<Dim>& body, const PoseFitOptions& o, const char* fit) {
  const std::string error = ValidateOptions(o, body.num_modes(), FitPoseQ<Dim>::kRigid);
  if (!error.empty()) throw std::invalid_argument(std::string(fit) + ": " + error);
}

// Adds the prior and the mode bounds of one pose's block x (num_rigid + num_modes numbers).
void AddPriorAndBounds(const PoseFitOptions& o, int num_rigid, int num_modes, double* x, ceres::Problem* problem);

// Appends one solve's report to the running one (costs over all solves, the last summary).
void AppendReport(const FitReport& next, bool first, FitReport* report);

// Solves one pose from q (in and out): `add_terms(chart, problem)` adds the data residuals at
// a chart; the chart is re-centred while its turn grows past kRecentreAngle (3D).
template <int Dim, class AddTerms>
void SolvePoseInChart(int num_modes, const PoseFitOptions& o, const AddTerms& add_terms, Eigen::VectorXd* q,
                      FitReport* report) {
  constexpr int kRigid = FitPoseQ<Dim>::kRigid;
  PoseChart<Dim> chart = PoseChart<Dim>::At(*q);
  for (int d = 0; d < num_modes; ++d)
    chart.x[kRigid + d] = std::clamp(chart.x[kRigid + d], ModeLower(o, d), ModeUpper(o, d));
  constexpr int kMaxCharts = 8;
  for (int k = 0; k < kMaxCharts; ++k) {
    ceres::Problem problem;
    add_terms(chart, &problem);
    AddPriorAndBounds(o, kRigid, num_modes, chart.x.data(), &problem);
    FitReport part;
    SolvePoseProblem(o, &problem, &part);
    AppendReport(part, k == 0, report);
    const bool turned_far = chart.TurnedFar();
    chart = PoseChart<Dim>::At(chart.q());
    if (!turned_far || report->iterations >= o.max_iterations) break;
  }
  *q = chart.q();
}

// Conditioning of the data terms at q, in the chart centred at q.
template <int Dim, class AddTerms>
Conditioning ConditioningAt(const BodyModelN<Dim>& body, const AddTerms& add_terms, const Eigen::VectorXd& q) {
  PoseChart<Dim> chart = PoseChart<Dim>::At(q);
  ceres::Problem problem;
  add_terms(chart, &problem);
  ceres::Problem::EvaluateOptions eval;
  problem.GetResidualBlocks(&eval.residual_blocks);
  return ConditioningOfJacobian(DataJacobian(&problem, eval), CoordinateNames(body), FitPoseQ<Dim>::kRigid);
}

}  // namespace wobble::fit
