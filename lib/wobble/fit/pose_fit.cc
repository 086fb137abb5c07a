#include "wobble/fit/pose_fit.h"

#include "wobble/core/distribute.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "wobble/core/rotation3.h"
#include "wobble/fit/internal/pose_chart.h"
#include "wobble/fit/internal/solve_common.h"

namespace wobble::fit {

std::string LossName(Loss loss) {
  switch (loss) {
    case Loss::kSquared: return "squared";
    case Loss::kHuber: return "huber";
    case Loss::kCauchy: return "cauchy";
  }
  return "?";
}

bool ParseLoss(const std::string& text, Loss* loss) {
  for (Loss l : {Loss::kSquared, Loss::kHuber, Loss::kCauchy})
    if (text == LossName(l)) {
      *loss = l;
      return true;
    }
  return false;
}

std::string ValidateOptions(const PoseFitOptions& o, int num_modes, int num_rigid) {
  auto finite = [](double v) { return std::isfinite(v); };
  if (o.initial_q.size() != 0 && o.initial_q.size() != num_rigid + num_modes)
    return "initial q has " + std::to_string(o.initial_q.size()) + " numbers, the body has " +
           std::to_string(num_rigid + num_modes) + " coordinates";
  for (int i = 0; i < o.initial_q.size(); ++i)
    if (!finite(o.initial_q[i])) return "initial q is not finite";
  if (!o.mode_lower.empty() && int(o.mode_lower.size()) != num_modes) return "mode_lower needs one bound per mode";
  if (!o.mode_upper.empty() && int(o.mode_upper.size()) != num_modes) return "mode_upper needs one bound per mode";
  for (int d = 0; d < num_modes; ++d)
    if (!(ModeLower(o, d) < ModeUpper(o, d))) return "mode bounds: lower must be below upper (mode " + std::to_string(d) + ")";
  if (!(o.loss_scale > 0) || !finite(o.loss_scale)) return "loss scale must be positive";
  if (!(o.prior_weight >= 0) || !finite(o.prior_weight)) return "prior weight must be >= 0";
  if (o.max_iterations < 1) return "max iterations must be >= 1";
  if (o.samples_per_segment < 0) return "samples per segment must be >= 0";
  if (o.max_rounds < 1) return "max rounds must be >= 1";
  if (o.max_mesh_samples < 0) return "max mesh samples must be >= 0";
  if (o.max_reverse_points < 1) return "max reverse points must be >= 1";
  return "";
}

template <int Dim> std::vector<std::string> CoordinateNames(const BodyModelN<Dim>& body) {
  std::vector<std::string> names = FitPoseQ<Dim>::RigidNames();
  for (const DeformationModeN<Dim>& m : body.modes()) names.push_back(m.name);
  return names;
}
template std::vector<std::string> CoordinateNames(const BodyModelN<2>&);
template std::vector<std::string> CoordinateNames(const BodyModelN<3>&);

namespace {

// The weighted centroids of the rest positions and of their targets, and the cross-covariance
// H = Σ w (p − p̄)(y − ȳ)ᵀ the best rotation is found from (Procrustes, Kabsch).
template <int Dim> struct CrossCovariance {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  Vec ps = Vec::Zero(), ys = Vec::Zero();
  Eigen::Matrix<double, Dim, Dim> H = Eigen::Matrix<double, Dim, Dim>::Zero();
  CrossCovariance(const std::vector<Vec>& rest, const std::vector<Vec>& target, const std::vector<double>& w) {
    double wsum = 0;
    for (size_t i = 0; i < rest.size(); ++i) {
      ps += w[i] * rest[i];
      ys += w[i] * target[i];
      wsum += w[i];
    }
    ps /= wsum;
    ys /= wsum;
    for (size_t i = 0; i < rest.size(); ++i) H += w[i] * (rest[i] - ps) * (target[i] - ys).transpose();
  }
};

}  // namespace

Eigen::VectorXd PoseChart<2>::RigidStart(int num_modes, const std::vector<Vec>& rest, const std::vector<Vec>& target,
                                         const std::vector<double>& w) {
  const CrossCovariance<2> c(rest, target, w);
  // maximise Σ w yᵀ R p: θ = atan2(H01 − H10, H00 + H11) (0 when the points are all one point)
  const double theta = std::atan2(c.H(0, 1) - c.H(1, 0), c.H(0, 0) + c.H(1, 1));
  Eigen::VectorXd q = Eigen::VectorXd::Zero(FitPoseQ<2>::kRigid + num_modes);
  const Eigen::Vector2d t = c.ys - Rotation(theta) * c.ps;
  q << t.x(), t.y(), theta, Eigen::VectorXd::Zero(num_modes);
  return q;
}

Eigen::VectorXd PoseChart<3>::RigidStart(int num_modes, const std::vector<Vec>& rest, const std::vector<Vec>& target,
                                         const std::vector<double>& w) {
  const CrossCovariance<3> c(rest, target, w);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(c.H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;  // no reflection
  const Eigen::Matrix3d R = svd.matrixV() * S * svd.matrixU().transpose();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(FitPoseQ<3>::kRigid + num_modes);
  q.head<3>() = c.ys - R * c.ps;
  q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(R));
  return q;
}

void AddPriorAndBounds(const PoseFitOptions& o, int num_rigid, int num_modes, double* x, ceres::Problem* problem) {
  const int n = num_rigid + num_modes;
  if (o.prior_weight > 0 && num_modes > 0) {
    RestPrior prior;
    prior.sqrt_weight = std::sqrt(o.prior_weight);
    prior.num_rigid = num_rigid;
    prior.num_q = n;
    problem->AddResidualBlock(MakeRestPriorCost(prior), nullptr, x);
  }
  if (!problem->HasParameterBlock(x)) problem->AddParameterBlock(x, n);
  for (int d = 0; d < num_modes; ++d) {
    problem->SetParameterLowerBound(x, num_rigid + d, ModeLower(o, d));
    problem->SetParameterUpperBound(x, num_rigid + d, ModeUpper(o, d));
  }
}

void AppendReport(const FitReport& next, bool first, FitReport* report) {
  const std::vector<double> before = report->cost_per_iteration;
  const int iterations = report->iterations;
  const double initial = first ? next.initial_cost : report->initial_cost;
  const double seconds = report->solve_seconds;
  *report = next;
  report->initial_cost = initial;
  report->cost_per_iteration.insert(report->cost_per_iteration.begin(), before.begin(), before.end());
  report->iterations += iterations;
  report->solve_seconds += seconds;
}

namespace {

void FillResiduals(const std::vector<SegmentResidual>& data, const Eigen::VectorXd& q, PoseFitResult* r) {
  r->point_residuals.clear();
  double sum = 0;
  for (const SegmentResidual& d : data) {
    const Vec2<double> x = PointPosition(d.point, q.data(), int(q.size()));
    const double dist = (x - ClosestOnSegment(x, d.a, d.b)).norm();
    r->point_residuals.push_back(dist);
    sum += dist * dist;
  }
  r->rms_residual = data.empty() ? 0.0 : std::sqrt(sum / double(data.size()));
}

}  // namespace

template <int Dim>
PoseFitResult FitPose(const BodyModelN<Dim>& body, const std::vector<CorrespondenceN<Dim>>& targets,
                      const PoseFitOptions& o) {
  CheckOptions(body, o, "pose fit");
  if (targets.empty()) throw std::invalid_argument("pose fit: no target points");
  std::vector<PointResidual<Dim>> data;
  std::vector<typename PoseChart<Dim>::Vec> rest, goal;
  std::vector<double> weights;
  for (const CorrespondenceN<Dim>& t : targets) {
    data.push_back(ToPoint(body, t, "pose fit"));
    rest.push_back(data.back().point.b0);
    goal.push_back(t.position);
    weights.push_back(t.weight);
  }
  const int D = body.num_modes(), n = body.num_q();
  auto add_terms = [&](PoseChart<Dim>& chart, ceres::Problem* problem) {
    // one loss object shared by every data term (Ceres deletes it once)
    ceres::LossFunction* loss = MakeLoss(o.loss, o.loss_scale);
    for (PointResidual<Dim> r : data) {
      r.centre = chart.centre;
      problem->AddResidualBlock(PoseChart<Dim>::Cost(r, n), loss, chart.x.data());
    }
  };
  PoseFitResult result;
  result.q = o.initial_q.size() ? o.initial_q : PoseChart<Dim>::RigidStart(D, rest, goal, weights);
  SolvePoseInChart<Dim>(D, o, add_terms, &result.q, &result.report);
  double sum = 0;
  for (const PointResidual<Dim>& d : data) {
    const double dist = (PointPosition(d.point, result.q) - d.y).norm();
    result.point_residuals.push_back(dist);
    sum += dist * dist;
  }
  result.rms_residual = std::sqrt(sum / double(data.size()));
  FillAtBound(body, o, &result);
  if (o.analyze_conditioning) result.conditioning = ConditioningAt(body, add_terms, result.q);
  return result;
}
template PoseFitResult FitPose(const BodyModelN<2>&, const std::vector<CorrespondenceN<2>>&, const PoseFitOptions&);
template PoseFitResult FitPose(const BodyModelN<3>&, const std::vector<CorrespondenceN<3>>&, const PoseFitOptions&);

CurveSamples CurveSamples::Of(const BodyModel& body, const PoseFitOptions& o) {
  CurveSamples s;
  if (o.use_mass_points)
    for (int k = 0; k < body.num_points(); ++k) s.points.push_back(BasisOf(body, k, {}));
  for (const Polyline& line : body.def().shapes) {
    const size_t n = line.points.size();
    const int m = std::max(1, o.samples_per_segment);
    const int first = int(s.points.size());
    for (size_t i = 0; i + 1 < n + (line.closed ? 1 : 0); ++i) {
      const Eigen::Vector2d a = line.points[i], b = line.points[(i + 1) % n];
      for (int j = (i == 0 ? 0 : 1); j <= m; ++j) {
        if (j == m && line.closed && i + 1 == n) break;  // back at the first point
        const Eigen::Vector2d p = a + (b - a) * (double(j) / m);
        if (int(s.points.size()) > first) s.segments.push_back({int(s.points.size()) - 1, int(s.points.size())});
        s.points.push_back(BasisOf(body, -1, body.lattice().LocalCoords(p)));
      }
    }
    if (line.closed && int(s.points.size()) - first > 2) s.segments.push_back({int(s.points.size()) - 1, first});
  }
  return s;
}

namespace {

// Centroid and principal-axis angle of weighted points; `isotropy` = λ_min / λ_max.
struct Shape2 {
  Eigen::Vector2d centroid;
  double axis_angle = 0, isotropy = 1;
};
Shape2 Principal(const std::vector<Eigen::Vector2d>& p, const std::vector<double>& w) {
  Shape2 s;
  double wsum = 0;
  s.centroid.setZero();
  for (size_t i = 0; i < p.size(); ++i) {
    s.centroid += w[i] * p[i];
    wsum += w[i];
  }
  s.centroid /= wsum;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (size_t i = 0; i < p.size(); ++i) cov += w[i] * (p[i] - s.centroid) * (p[i] - s.centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  const Eigen::Vector2d major = eig.eigenvectors().col(1);
  s.axis_angle = std::atan2(major.y(), major.x());
  const double hi = eig.eigenvalues()[1];
  s.isotropy = hi > 0 ? eig.eigenvalues()[0] / hi : 1.0;
  return s;
}

}  // namespace

PoseFitResult FitPoseToCurve(const BodyModel& body, const CurveTarget& target, const PoseFitOptions& o) {
  const std::string error = ValidateOptions(o, body.num_modes());
  if (!error.empty()) throw std::invalid_argument("curve fit: " + error);
  if (target.a.empty()) throw std::invalid_argument("curve fit: the target has no points");
  const CurveSamples samples = CurveSamples::Of(body, o);
  if (samples.points.empty())
    throw std::invalid_argument("curve fit: the body has no samples (no mass points used, no drawing)");
  const int ns = int(samples.points.size());
  const bool two_sided = o.two_sided && !samples.segments.empty();
  std::vector<Eigen::Vector2d> reverse_points;
  if (two_sided) {
    const size_t nv = target.vertices.size(), keep = std::min(nv, size_t(std::max(1, o.max_reverse_points)));
    for (size_t i = 0; i < keep; ++i) reverse_points.push_back(target.vertices[i * nv / keep]);
  }
  // both directions weigh the same in total
  const double reverse_weight = two_sided ? double(ns) / double(reverse_points.size()) : 0.0;

  // the starts: centroid onto centroid, principal axis onto principal axis
  std::vector<Eigen::VectorXd> starts;
  if (o.initial_q.size()) {
    starts.push_back(o.initial_q);
  } else {
    std::vector<Eigen::Vector2d> rest, tp;
    std::vector<double> ones(ns, 1.0), tw;
    for (const PointBasis& s : samples.points) rest.push_back(s.b0);
    for (size_t i = 0; i < target.a.size(); ++i) {
      tp.push_back(0.5 * (target.a[i] + target.b[i]));
      const double len = (target.b[i] - target.a[i]).norm();
      tw.push_back(len > 0 ? len : 1.0);  // cloud points weigh like a unit of length
    }
    const Shape2 bs = Principal(rest, ones), ts = Principal(tp, tw);
    const int turns = (bs.isotropy > 0.8 || ts.isotropy > 0.8) ? 4 : 2;
    for (int k = 0; k < turns; ++k) {
      const double theta = std::remainder(ts.axis_angle - bs.axis_angle + k * 2.0 * M_PI / turns, 2.0 * M_PI);
      Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
      const Eigen::Vector2d t = ts.centroid - Rotation(theta) * bs.centroid;
      q << t.x(), t.y(), theta, Eigen::VectorXd::Zero(body.num_modes());
      starts.push_back(q);
    }
  }

  // one start's state across rounds
  struct Run {
    Eigen::VectorXd q;
    PoseFitResult r;
    std::vector<int> assigned, reverse_assigned;
    std::vector<SegmentResidual> data;
    std::vector<ReverseSegmentResidual> reverse;
    double seconds = 0, previous_cost = std::numeric_limits<double>::infinity();
    int round = 0;
    bool done = false;
  };
  // the residuals of the assignments run->assigned and run->reverse_assigned
  auto residuals = [&](Run* run) {
    for (int i = 0; i < ns; ++i) {
      const int seg = run->assigned[i];
      SegmentResidual& d = run->data[i];
      d.point = samples.points[i];
      d.a = target.a[seg];
      d.b = target.b[seg];
      d.num_q = body.num_q();
    }
    if (!two_sided) return;
    for (size_t v = 0; v < reverse_points.size(); ++v) {
      const int seg = run->reverse_assigned[v];
      ReverseSegmentResidual& d = run->reverse[v];
      d.pa = samples.points[samples.segments[seg].first];
      d.pb = samples.points[samples.segments[seg].second];
      d.y = reverse_points[v];
      d.sqrt_weight = std::sqrt(reverse_weight);
      d.num_q = body.num_q();
    }
  };
  // closest points at run->q; returns whether any assignment changed
  auto assign = [&](Run* run) {
    const Eigen::VectorXd& q = run->q;
    // closest points at the current q: body samples to target segments ...
    bool changed = false;
    std::vector<Eigen::Vector2d> x(ns);
    for (int i = 0; i < ns; ++i) {
      x[i] = PointPosition(samples.points[i], q.data(), int(q.size()));
      const int seg = NearestSegment(target.a, target.b, x[i]);
      changed = changed || seg != run->assigned[i];
      run->assigned[i] = seg;
    }
    // ... and target vertices to the body's drawn segments
    if (two_sided) {
      std::vector<Eigen::Vector2d> ba, bb;
      for (const auto& [i, j] : samples.segments) {
        ba.push_back(x[i]);
        bb.push_back(x[j]);
      }
      for (size_t v = 0; v < reverse_points.size(); ++v) {
        const int seg = NearestSegment(ba, bb, reverse_points[v]);
        changed = changed || seg != run->reverse_assigned[v];
        run->reverse_assigned[v] = seg;
      }
    }
    residuals(run);
    return changed;
  };
  // runs rounds until `last_round` (exclusive) or convergence
  auto advance = [&](Run* run, int last_round) {
    for (; run->round < last_round && !run->done; ++run->round) {
      Eigen::VectorXd& q = run->q;
      if (!assign(run)) {
        run->done = true;
        break;
      }
      FitReport round_report;
      SolvePose(body, run->data, run->reverse, o, &q, &round_report);
      // the cost history runs over all rounds; the summary is that of the last round
      PoseFitResult& r = run->r;
      const std::vector<double> before = r.report.cost_per_iteration;
      const int iterations = r.report.iterations;
      const double initial = run->round == 0 ? round_report.initial_cost : r.report.initial_cost;
      r.report = round_report;
      r.report.initial_cost = initial;
      r.report.cost_per_iteration.insert(r.report.cost_per_iteration.begin(), before.begin(), before.end());
      r.report.iterations += iterations;
      run->seconds += round_report.solve_seconds;
      r.rounds = run->round + 1;
      // assignments may keep flipping between neighbouring segments at equal distance: stop
      // as well when a round no longer lowers the cost
      if (run->round > 0 && run->previous_cost - round_report.final_cost <= 1e-6 * run->previous_cost) run->done = true;
      run->previous_cost = round_report.final_cost;
    }
  };

  // The starts are solved at once, on threads and, under mpirun, on ranks (core/distribute.h);
  // a start's state crosses as bytes and the winner goes on from it exactly as it would have.
  auto encode = [&](const Run& run) {
    ByteWriter w;
    w.PutDoubles(std::vector<double>(run.q.data(), run.q.data() + run.q.size()));
    w.PutString(EncodeFitReport(run.r.report)).Put<std::int32_t>(run.r.rounds);
    w.Put<std::uint64_t>(run.assigned.size());
    for (int a : run.assigned) w.Put<std::int32_t>(a);
    w.Put<std::uint64_t>(run.reverse_assigned.size());
    for (int a : run.reverse_assigned) w.Put<std::int32_t>(a);
    w.Put(run.seconds).Put(run.previous_cost).Put<std::int32_t>(run.round).Put<std::uint8_t>(run.done);
    return w.Take();
  };
  auto decode = [&](const Bytes& bytes) {
    ByteReader in(bytes);
    Run run;
    const std::vector<double> q = in.GetDoubles();
    run.q = Eigen::Map<const Eigen::VectorXd>(q.data(), Eigen::Index(q.size()));
    run.r.report = DecodeFitReport(in.GetString());
    run.r.rounds = in.Get<std::int32_t>();
    run.assigned.resize(in.Get<std::uint64_t>());
    for (int& a : run.assigned) a = in.Get<std::int32_t>();
    run.reverse_assigned.resize(in.Get<std::uint64_t>());
    for (int& a : run.reverse_assigned) a = in.Get<std::int32_t>();
    run.seconds = in.Get<double>();
    run.previous_cost = in.Get<double>();
    run.round = in.Get<std::int32_t>();
    run.done = in.Get<std::uint8_t>() != 0;
    run.data.resize(ns);
    run.reverse.resize(reverse_points.size());
    if (!run.assigned.empty() && run.assigned[0] >= 0) residuals(&run);  // assigned: the winner goes on from them
    return run;
  };
  const std::vector<Bytes> solved = DistributedMap(starts.size(), MapOptions(), [&](size_t k) {
    const Eigen::VectorXd& start = starts[k];
    Run run;
    run.q = start;
    for (int d = 0; d < body.num_modes(); ++d)
      run.q[kRigidDofs + d] = std::clamp(run.q[kRigidDofs + d], ModeLower(o, d), ModeUpper(o, d));
    run.assigned.assign(ns, -1);
    run.reverse_assigned.assign(reverse_points.size(), -1);
    run.data.resize(ns);
    run.reverse.resize(reverse_points.size());
    if (o.joint_closest_points) {
      // one solve, nearest segments found inside the residuals
      ceres::Problem problem;
      ceres::LossFunction* loss = MakeLoss(o.loss, o.loss_scale);
      for (const PointBasis& p : samples.points) {
        NearestSegmentResidual r;
        r.point = p;
        r.a = &target.a;
        r.b = &target.b;
        r.num_q = body.num_q();
        problem.AddResidualBlock(MakeNearestSegmentCost(r), loss, run.q.data());
      }
      for (const Eigen::Vector2d& y : reverse_points) {
        NearestBodySegmentResidual r;
        r.points = &samples.points;
        r.segments = &samples.segments;
        r.y = y;
        r.sqrt_weight = std::sqrt(reverse_weight);
        r.num_q = body.num_q();
        problem.AddResidualBlock(MakeNearestBodySegmentCost(r), loss, run.q.data());
      }
      AddPoseTerms(body, {}, {}, o, run.q.data(), &problem);  // prior and bounds
      SolvePoseProblem(o, &problem, &run.r.report);
      run.seconds = run.r.report.solve_seconds;
      run.r.rounds = 1;
      assign(&run);  // the final nearest segments, for the residuals and the conditioning
    } else {
      advance(&run, std::min(o.start_rounds, o.max_rounds));
    }
    return encode(run);
  });
  std::vector<Run> runs;
  for (const Bytes& bytes : solved) runs.push_back(decode(bytes));
  size_t best_index = 0;
  for (size_t i = 1; i < runs.size(); ++i)
    if (runs[i].r.report.final_cost < runs[best_index].r.report.final_cost) best_index = i;
  Run& winner = runs[best_index];
  if (!o.joint_closest_points) advance(&winner, o.max_rounds);
  PoseFitResult best = winner.r;
  best.report.solve_seconds = winner.seconds;
  best.q = winner.q;
  const std::vector<SegmentResidual>& best_data = winner.data;
  const std::vector<ReverseSegmentResidual>& best_reverse = winner.reverse;
  FillResiduals(best_data, best.q, &best);
  FillAtBound(body, o, &best);
  if (o.analyze_conditioning) best.conditioning = ComputeConditioning(body, best_data, best_reverse, o, best.q);
  return best;
}

}  // namespace wobble::fit
