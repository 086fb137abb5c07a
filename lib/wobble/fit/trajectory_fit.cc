#include "wobble/fit/trajectory_fit.h"

#include "wobble/fit/pose_fit3.h"

#include <cmath>
#include <stdexcept>

#include "wobble/fit/internal/solve_common.h"

namespace wobble::fit {

namespace {

// SmoothnessScales of either dimension: 1 for the translation, the rms radius of the mass
// points about their centroid for every rotation coordinate, each mode's rms displacement of
// the mass points (1 where there is nothing to measure).
template <int Dim> Eigen::VectorXd ScalesOf(const BodyModelN<Dim>& body) {
  const int n = body.num_q(), N = body.num_points(), rigid = n - body.num_modes();
  Eigen::VectorXd L = Eigen::VectorXd::Ones(n);
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

// FramesFromStates of either dimension; place(k, q) is mass point k's world position at q.
template <class Frame, int Dim, class Place>
std::vector<Frame> FramesOf(const BodyModelN<Dim>& body, const std::vector<double>& times,
                            const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points, int every,
                            const Place& place) {
  std::vector<int> which = points;
  if (which.empty())
    for (int k = 0; k < body.num_points(); ++k) which.push_back(k);
  std::vector<Frame> frames;
  for (size_t f = 0; f < q.size(); f += size_t(std::max(1, every))) {
    Frame frame;
    frame.time = times[f];
    for (int k : which) {
      if (k < 0 || k >= body.num_points()) throw std::invalid_argument("mass point " + std::to_string(k) + " does not exist");
      typename decltype(frame.points)::value_type p;
      p.mass_point = k;
      p.position = place(k, q[f]);
      frame.points.push_back(p);
    }
    frames.push_back(frame);
  }
  return frames;
}

}  // namespace

VecQ<double> SmoothnessScales(const BodyModel& body) { return ScalesOf(body); }
VecQ<double> SmoothnessScales3(const BodyModel3& body) { return ScalesOf(body); }

std::vector<ReferenceFrame> FramesFromStates(const BodyModel& body, const std::vector<double>& times,
                                             const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                             int every) {
  return FramesOf<ReferenceFrame>(body, times, q, points, every, [&](int k, const Eigen::VectorXd& qf) {
    return Eigen::Vector2d(PointPosition(BasisOf(body, k, {}), qf.data(), int(qf.size())));
  });
}

std::vector<ReferenceFrame3> FramesFromStates3(const BodyModel3& body, const std::vector<double>& times,
                                               const std::vector<Eigen::VectorXd>& q, const std::vector<int>& points,
                                               int every) {
  return FramesOf<ReferenceFrame3>(body, times, q, points, every,
                                   [&](int k, const Eigen::VectorXd& qf) { return PointPosition3(BasisOf3(body, k, {}), qf); });
}

TrajectoryFitResult FitKinematicTrajectory(const BodyModel& body, const std::vector<ReferenceFrame>& frames,
                                           const TrajectoryFitOptions& o) {
  const PoseFitOptions& po = o.pose;
  const std::string error = ValidateOptions(po, body.num_modes());
  if (!error.empty()) throw std::invalid_argument("trajectory fit: " + error);
  if (!(o.smoothness >= 0) || !std::isfinite(o.smoothness))
    throw std::invalid_argument("trajectory fit: smoothness must be >= 0");
  if (frames.empty()) throw std::invalid_argument("trajectory fit: no frames");
  const int F = int(frames.size()), n = body.num_q();
  for (int f = 1; f < F; ++f)
    if (!(frames[f].time > frames[f - 1].time))
      throw std::invalid_argument("trajectory fit: frame times must strictly increase");

  // per-frame data terms and starts
  TrajectoryFitResult result;
  std::vector<std::vector<SegmentResidual>> data(F);
  result.q.resize(F);
  for (int f = 0; f < F; ++f) {
    result.times.push_back(frames[f].time);
    std::vector<Eigen::Vector2d> rest, goal;
    std::vector<double> w;
    for (const Correspondence& t : frames[f].points) {
      if (t.mass_point >= body.num_points())
        throw std::invalid_argument("trajectory fit: mass point " + std::to_string(t.mass_point) + " does not exist");
      SegmentResidual r;
      r.point = BasisOf(body, t.mass_point, t.lattice_coords);
      r.a = r.b = t.position;
      r.sqrt_weight = std::sqrt(t.weight);
      r.num_q = n;
      data[f].push_back(r);
      rest.push_back(r.point.b0);
      goal.push_back(t.position);
      w.push_back(t.weight);
    }
    if (po.initial_q.size()) {
      result.q[f] = po.initial_q;
    } else {
      result.q[f] = RigidStart(body, rest, goal, w);
      // unwrap: keep θ within π of the previous frame's
      if (f > 0) result.q[f][2] = result.q[f - 1][2] + std::remainder(result.q[f][2] - result.q[f - 1][2], 2.0 * M_PI);
    }
    for (int d = 0; d < body.num_modes(); ++d)
      result.q[f][kRigidDofs + d] = std::clamp(result.q[f][kRigidDofs + d], ModeLower(po, d), ModeUpper(po, d));
  }

  // one problem: every frame's pose terms, and the smoothness between neighbours
  ceres::Problem problem;
  for (int f = 0; f < F; ++f) AddPoseTerms(body, data[f], {}, po, result.q[f].data(), &problem);
  if (o.smoothness > 0 && F >= 3) {
    const VecQ<double> L = SmoothnessScales(body) * std::sqrt(o.smoothness);
    for (int f = 1; f + 1 < F; ++f) {
      const double h0 = frames[f].time - frames[f - 1].time, h1 = frames[f + 1].time - frames[f].time;
      const double hm = 0.5 * (h0 + h1);
      SecondDifference s;
      s.c0 = hm / h0;
      s.c2 = hm / h1;
      s.c1 = -s.c0 - s.c2;
      s.scale = L;
      problem.AddResidualBlock(MakeSecondDifferenceCost(s), nullptr, result.q[f - 1].data(), result.q[f].data(),
                               result.q[f + 1].data());
    }
  }
  const ceres::Solver::Options options = TrajectorySolverOptions(po, &result.linear_solver);
  SolveAndReport(options, &problem, po.on_iteration, po.full_report, &result.report);

  // residuals per frame
  double sum = 0;
  size_t count = 0;
  for (int f = 0; f < F; ++f) {
    double fs = 0;
    for (const SegmentResidual& d : data[f]) {
      const Vec2<double> x = PointPosition(d.point, result.q[f].data(), n);
      fs += (x - d.a).squaredNorm();
    }
    result.frame_rms.push_back(std::sqrt(fs / double(data[f].size())));
    sum += fs;
    count += data[f].size();
  }
  result.rms_residual = std::sqrt(sum / double(count));
  return result;
}

}  // namespace wobble::fit
