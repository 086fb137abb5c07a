#include "wobble/fit/trajectory_fit.h"

#include <ceres/dynamic_autodiff_cost_function.h>

#include <cmath>
#include <stdexcept>

#include "wobble/core/rotation3.h"
#include "wobble/fit/internal/pose_chart.h"
#include "wobble/fit/internal/solve_common.h"

namespace wobble::fit {

// 1 for the translation, the rms radius of the mass points about their centroid for every
// rotation coordinate, each mode's rms displacement of the mass points (1 where there is
// nothing to measure).
template <int Dim> VecQ<double> SmoothnessScales(const BodyModelN<Dim>& body) {
  const int n = body.num_q(), N = body.num_points(), rigid = n - body.num_modes();
  VecQ<double> L = VecQ<double>::Ones(n);
  Eigen::Matrix<double, Dim, 1> c = Eigen::Matrix<double, Dim, 1>::Zero();
  for (int k = 0; k < N; ++k) c += body.rest_local(k);
  c /= N;
  double r2 = 0;
  for (int k = 0; k < N; ++k) r2 += (body.rest_local(k) - c).squaredNorm();
  const double radius = std::sqrt(r2 / N);
  for (int i = Dim; i < rigid; ++i) L[i] = radius > 0 ? radius : 1.0;
  for (int d = 0; d < body.num_modes(); ++d) {
    double m2 = 0;
    for (int k = 0; k < N; ++k) m2 += body.mode_matrix(k).col(d).squaredNorm();
    L[rigid + d] = m2 > 0 ? std::sqrt(m2 / N) : 1.0;
  }
  return L;
}

template VecQ<double> SmoothnessScales(const BodyModelN<2>&);
template VecQ<double> SmoothnessScales(const BodyModelN<3>&);

template <int Dim>
std::vector<ReferenceFrameN<Dim>> FramesFromStates(const BodyModelN<Dim>& body, const std::vector<double>& times,
                                                   const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                                   int every) {
  std::vector<int> which = points;
  if (which.empty())
    for (int k = 0; k < body.num_points(); ++k) which.push_back(k);
  std::vector<ReferenceFrameN<Dim>> frames;
  for (size_t f = 0; f < q.size(); f += size_t(std::max(1, every))) {
    ReferenceFrameN<Dim> frame;
    frame.time = times[f];
    for (int k : which) {
      if (k < 0 || k >= body.num_points()) throw std::invalid_argument("mass point " + std::to_string(k) + " does not exist");
      CorrespondenceN<Dim> p;
      p.mass_point = k;
      p.position = PointPosition(BasisOf(body, k, {}), q[f]);
      frame.points.push_back(p);
    }
    frames.push_back(frame);
  }
  return frames;
}

namespace {

// Smoothness between frames f−1, f, f+1 of a 3D body (blocks x0, x1, x2 in their charts): the
// divided second difference of t and γ, and c2 log(R1ᵀR2) − c0 log(R0ᵀR1) for the orientation,
// each coordinate times its length scale.
struct GroupSecondDifference {
  double c0 = 1, c1 = -2, c2 = 1;
  Eigen::Quaterniond R0[3];
  Eigen::VectorXd scale;  // per coordinate, times sqrt(w)
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    constexpr int kRigid = FitPoseQ<3>::kRigid;
    for (int i = 0; i < 3; ++i) r[i] = (T(c0) * x[0][i] + T(c1) * x[1][i] + T(c2) * x[2][i]) * T(scale[i]);
    for (int d = 0; d < num_modes; ++d) {
      const int i = kRigid + d;
      r[i] = (T(c0) * x[0][i] + T(c1) * x[1][i] + T(c2) * x[2][i]) * T(scale[i]);
    }
    Eigen::Quaternion<T> R[3];
    for (int k = 0; k < 3; ++k) R[k] = R0[k].cast<T>() * ExpRotation<T>(Vec3<T>(x[k][3], x[k][4], x[k][5]));
    const Vec3<T> turn = T(c2) * LogRotation<T>(R[1].conjugate() * R[2]) - T(c0) * LogRotation<T>(R[0].conjugate() * R[1]);
    for (int i = 0; i < 3; ++i) r[3 + i] = turn[i] * T(scale[3 + i]);
    return true;
  }
};

}  // namespace

ceres::CostFunction* PoseChart<3>::Smoothness(const double c[3], const PoseChart* charts[3], const VecQ<double>& scale) {
  const int n = int(scale.size());
  GroupSecondDifference s;
  s.c0 = c[0];
  s.c1 = c[1];
  s.c2 = c[2];
  for (int j = 0; j < 3; ++j) s.R0[j] = Eigen::Quaterniond(charts[j]->centre);
  s.scale = scale;
  s.num_modes = n - FitPoseQ<3>::kRigid;
  auto* cost = new ceres::DynamicAutoDiffCostFunction<GroupSecondDifference, kStride>(new GroupSecondDifference(s));
  for (int b = 0; b < 3; ++b) cost->AddParameterBlock(n);
  cost->SetNumResiduals(n);
  return cost;
}

template std::vector<ReferenceFrameN<2>> FramesFromStates(const BodyModelN<2>&, const std::vector<double>&,
                                                          const std::vector<Eigen::VectorXd>&, const std::vector<int>&, int);
template std::vector<ReferenceFrameN<3>> FramesFromStates(const BodyModelN<3>&, const std::vector<double>&,
                                                          const std::vector<Eigen::VectorXd>&, const std::vector<int>&, int);

template <int Dim>
TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                           const TrajectoryFitOptions& o) {
  using Chart = PoseChart<Dim>;
  constexpr int kRigid = FitPoseQ<Dim>::kRigid;
  const PoseFitOptions& po = o.pose;
  CheckOptions(body, po, "trajectory fit");
  if (!(o.smoothness >= 0) || !std::isfinite(o.smoothness))
    throw std::invalid_argument("trajectory fit: smoothness must be >= 0");
  if (frames.empty()) throw std::invalid_argument("trajectory fit: no frames");
  const int F = int(frames.size()), D = body.num_modes(), n = body.num_q();
  for (int f = 1; f < F; ++f)
    if (!(frames[f].time > frames[f - 1].time))
      throw std::invalid_argument("trajectory fit: frame times must strictly increase");

  // per-frame data terms and starts
  TrajectoryFitResult result;
  std::vector<std::vector<PointResidual<Dim>>> data(F);
  std::vector<Chart> charts(F);
  for (int f = 0; f < F; ++f) {
    result.times.push_back(frames[f].time);
    if (frames[f].points.empty()) throw std::invalid_argument("trajectory fit: a frame has no points");
    std::vector<typename Chart::Vec> rest, goal;
    std::vector<double> w;
    for (const CorrespondenceN<Dim>& t : frames[f].points) {
      data[f].push_back(ToPoint(body, t, "trajectory fit"));
      rest.push_back(data[f].back().point.b0);
      goal.push_back(t.position);
      w.push_back(t.weight);
    }
    Eigen::VectorXd q = po.initial_q;
    if (!po.initial_q.size()) {
      q = Chart::RigidStart(D, rest, goal, w);
      if (f > 0) Chart::Unwrap(charts[f - 1].q(), &q);
    }
    charts[f] = Chart::At(q);
    for (int d = 0; d < D; ++d)
      charts[f].x[kRigid + d] = std::clamp(charts[f].x[kRigid + d], ModeLower(po, d), ModeUpper(po, d));
  }
  const VecQ<double> L = SmoothnessScales(body) * std::sqrt(o.smoothness);
  // one problem: every frame's pose terms, and the smoothness between neighbours; re-centred
  // (all charts) while some frame turned far from its chart's centre
  constexpr int kMaxCharts = 8;
  for (int k = 0; k < kMaxCharts; ++k) {
    ceres::Problem problem;
    ceres::LossFunction* loss = MakeLoss(po.loss, po.loss_scale);
    for (int f = 0; f < F; ++f) {
      for (PointResidual<Dim> r : data[f]) {
        r.centre = charts[f].centre;
        problem.AddResidualBlock(Chart::Cost(r, n), loss, charts[f].x.data());
      }
      AddPriorAndBounds(po, kRigid, D, charts[f].x.data(), &problem);
    }
    if (o.smoothness > 0 && F >= 3)
      for (int f = 1; f + 1 < F; ++f) {
        const double h0 = frames[f].time - frames[f - 1].time, h1 = frames[f + 1].time - frames[f].time;
        const double hm = 0.5 * (h0 + h1);
        const double c[3] = {hm / h0, -hm / h0 - hm / h1, hm / h1};
        const Chart* three[3] = {&charts[f - 1], &charts[f], &charts[f + 1]};
        problem.AddResidualBlock(Chart::Smoothness(c, three, L), nullptr, charts[f - 1].x.data(), charts[f].x.data(),
                                 charts[f + 1].x.data());
      }
    const ceres::Solver::Options options = TrajectorySolverOptions(po, &result.linear_solver);
    FitReport part;
    SolveAndReport(options, &problem, po.on_iteration, po.full_report, &part);
    AppendReport(part, k == 0, &result.report);
    bool turned_far = false;
    for (Chart& chart : charts) {
      turned_far = turned_far || chart.TurnedFar();
      chart = Chart::At(chart.q());
    }
    if (!turned_far) break;
  }
  // q per frame, and the residuals
  double sum = 0;
  size_t count = 0;
  for (int f = 0; f < F; ++f) {
    result.q.push_back(charts[f].q());
    double fs = 0;
    for (const PointResidual<Dim>& d : data[f]) fs += (PointPosition(d.point, result.q[f]) - d.y).squaredNorm();
    result.frame_rms.push_back(std::sqrt(fs / double(data[f].size())));
    sum += fs;
    count += data[f].size();
  }
  result.rms_residual = std::sqrt(sum / double(count));
  return result;
}
template TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                                    const TrajectoryFitOptions&);
template TrajectoryFitResult FitKinematicTrajectory(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                                    const TrajectoryFitOptions&);

}  // namespace wobble::fit
