#include "wobble/fit/pose_fit3.h"

#include "wobble/core/distribute.h"

#include <ceres/ceres.h>
#include <ceres/dynamic_autodiff_cost_function.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "wobble/core/rotation3.h"
#include "wobble/fit/internal/solve_common.h"

namespace wobble::fit {

std::vector<std::string> CoordinateNames3(const BodyModel3& body) {
  std::vector<std::string> names = {"tx", "ty", "tz", "rx", "ry", "rz"};
  for (const DeformationMode3& m : body.modes()) names.push_back(m.name);
  return names;
}

namespace {

// ---- the local chart: x = [t, δ, γ], R = R0 exp(δ̂) -------------------------------------

template <class T> Vec3<T> Place(const PointBasis3& p, const Eigen::Matrix3d& R0, const T* x, int num_modes) {
  Vec3<T> l = p.b0.cast<T>();
  for (int d = 0; d < num_modes; ++d) l += p.B.col(d).cast<T>() * x[Group<3>::kRigidDofs + d];
  const Mat3<T> dR = ExpRotation<T>(Vec3<T>(x[3], x[4], x[5])).toRotationMatrix();
  return Vec3<T>(x[0], x[1], x[2]) + R0.cast<T>() * (dR * l);
}

Eigen::Vector3d PlaceValue(const PointBasis3& p, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                           const double* gamma, int num_modes) {
  Eigen::Vector3d l = p.b0;
  for (int d = 0; d < num_modes; ++d) l += p.B.col(d) * gamma[d];
  return t + R * l;
}

struct Chart {
  Eigen::Matrix3d R0 = Eigen::Matrix3d::Identity();
  Eigen::VectorXd x;  // [t, δ, γ]
  static Chart At(const Eigen::VectorXd& q) {
    Chart c;
    c.R0 = ExpRotation<double>(q.segment<3>(3)).toRotationMatrix();
    c.x = q;
    c.x.segment<3>(3).setZero();
    return c;
  }
  Eigen::Matrix3d R() const { return R0 * ExpRotation<double>(x.segment<3>(3)).toRotationMatrix(); }
  Eigen::VectorXd q() const {
    Eigen::VectorXd q = x;
    q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(R()));
    return q;
  }
};

// ---- residuals (Ceres functors, one parameter block x of 6 + D) ---------------------------

constexpr int kStride = 6;  // Jet width of the dynamic autodiff

// sqrt(w) (x(q) − y).
struct PointResidual3 {
  PointBasis3 point;
  Eigen::Matrix3d R0;
  Eigen::Vector3d y;
  double sqrt_weight = 1.0;
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    const Vec3<T> e = (Place(point, R0, x[0], num_modes) - y.cast<T>()) * T(sqrt_weight);
    for (int i = 0; i < 3; ++i) r[i] = e[i];
    return true;
  }
};

// The closest point of a triangle or a point, chosen on plain values; the residual then lets
// derivatives flow along the face's normal (inside), across the edge (on an edge), or not at
// all (at a vertex), as ClosestOnSegment does in 2D.
struct TriangleGeometry {
  Eigen::Vector3d a, b, c, normal;  // unit normal, zero for a degenerate triangle
};

enum class Region { kFace, kEdgeAB, kEdgeBC, kEdgeCA, kA, kB, kC };

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d ClosestOnTriangle(const TriangleGeometry& g, const Eigen::Vector3d& p, Region* region) {
  const Eigen::Vector3d& a = g.a;
  const Eigen::Vector3d& b = g.b;
  const Eigen::Vector3d& c = g.c;
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return *region = Region::kA, a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return *region = Region::kB, b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    *region = Region::kEdgeAB;
    return a + (d1 / (d1 - d3)) * ab;
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return *region = Region::kC, c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    *region = Region::kEdgeCA;
    return a + (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    *region = Region::kEdgeBC;
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  *region = g.normal.squaredNorm() > 0 ? Region::kFace : Region::kA;
  if (*region == Region::kA) return a;
  return a + ab * (vb * denom) + ac * (vc * denom);
}

template <class T> Vec3<T> OnEdge(const Vec3<T>& x, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const T u = (x - a.cast<T>()).dot(ab.cast<T>()) / T(ab.squaredNorm());
  return a.cast<T>() + u * ab.cast<T>();
}

// The nearest target element of x: its closest point in T (see TriangleGeometry).
struct SurfaceIndex {
  std::vector<TriangleGeometry> triangles;
  std::vector<Eigen::Vector3d> cloud;

  explicit SurfaceIndex(const SurfaceTarget3& target) {
    for (const std::array<int, 3>& t : target.triangles) {
      TriangleGeometry g{target.points[t[0]], target.points[t[1]], target.points[t[2]], Eigen::Vector3d::Zero()};
      const Eigen::Vector3d n = (g.b - g.a).cross(g.c - g.a);
      if (n.norm() > 1e-14 * std::max(1.0, (g.b - g.a).squaredNorm() + (g.c - g.a).squaredNorm())) g.normal = n.normalized();
      triangles.push_back(g);
    }
    for (int i : target.cloud) cloud.push_back(target.points[i]);
  }

  template <class T> Vec3<T> Closest(const Vec3<T>& x) const {
    const Eigen::Vector3d xv(ScalarValue(x[0]), ScalarValue(x[1]), ScalarValue(x[2]));
    double best = std::numeric_limits<double>::infinity();
    int best_triangle = -1, best_point = -1;
    Region best_region = Region::kA;
    for (size_t i = 0; i < triangles.size(); ++i) {
      Region region;
      const double d2 = (ClosestOnTriangle(triangles[i], xv, &region) - xv).squaredNorm();
      if (d2 < best) best = d2, best_triangle = int(i), best_region = region;
    }
    for (size_t i = 0; i < cloud.size(); ++i) {
      const double d2 = (cloud[i] - xv).squaredNorm();
      if (d2 < best) best = d2, best_point = int(i), best_triangle = -1;
    }
    if (best_point >= 0) return cloud[best_point].cast<T>();
    const TriangleGeometry& g = triangles[best_triangle];
    switch (best_region) {
      case Region::kFace: {
        const Vec3<T> n = g.normal.cast<T>();
        return x - n * n.dot(x - g.a.cast<T>());
      }
      case Region::kEdgeAB: return OnEdge(x, g.a, g.b);
      case Region::kEdgeBC: return OnEdge(x, g.b, g.c);
      case Region::kEdgeCA: return OnEdge(x, g.c, g.a);
      case Region::kA: return g.a.cast<T>();
      case Region::kB: return g.b.cast<T>();
      case Region::kC: return g.c.cast<T>();
    }
    return g.a.cast<T>();
  }
};

// sqrt(w) (x(q) − nearest target point).
struct NearestSurfaceResidual3 {
  PointBasis3 point;
  Eigen::Matrix3d R0;
  const SurfaceIndex* surface = nullptr;
  double sqrt_weight = 1.0;
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    const Vec3<T> p = Place(point, R0, x[0], num_modes);
    const Vec3<T> e = (p - surface->Closest(p)) * T(sqrt_weight);
    for (int i = 0; i < 3; ++i) r[i] = e[i];
    return true;
  }
};

// The reverse direction: sqrt(w) (y − the body sample nearest to y), chosen on plain values.
struct NearestSampleResidual3 {
  const std::vector<PointBasis3>* samples = nullptr;
  Eigen::Matrix3d R0;
  Eigen::Vector3d y;
  double sqrt_weight = 1.0;
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    double xv[kMaxQ];
    for (int i = 0; i < Group<3>::kRigidDofs + num_modes; ++i) xv[i] = ScalarValue(x[0][i]);
    const Eigen::Matrix3d R = R0 * ExpRotation<double>(Eigen::Vector3d(xv[3], xv[4], xv[5])).toRotationMatrix();
    const Eigen::Vector3d t(xv[0], xv[1], xv[2]);
    int best = 0;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < samples->size(); ++k) {
      const double d2 = (PlaceValue((*samples)[k], R, t, xv + Group<3>::kRigidDofs, num_modes) - y).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best = int(k);
    }
    const Vec3<T> e = (y.cast<T>() - Place((*samples)[best], R0, x[0], num_modes)) * T(sqrt_weight);
    for (int i = 0; i < 3; ++i) r[i] = e[i];
    return true;
  }
};

// sqrt(w) γ_d for every mode.
struct RestPrior3 {
  double sqrt_weight = 0;
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    for (int d = 0; d < num_modes; ++d) r[d] = x[0][Group<3>::kRigidDofs + d] * T(sqrt_weight);
    return true;
  }
};

template <class Functor> ceres::CostFunction* MakeCost(const Functor& f, int num_residuals, int num_blocks, int block_size) {
  auto* cost = new ceres::DynamicAutoDiffCostFunction<Functor, kStride>(new Functor(f));
  for (int i = 0; i < num_blocks; ++i) cost->AddParameterBlock(block_size);
  cost->SetNumResiduals(num_residuals);
  return cost;
}

// Adds the prior and the mode bounds of one pose's block.
void AddPriorAndBounds(const PoseFitOptions& o, int num_modes, double* x, ceres::Problem* problem) {
  const int n = Group<3>::kRigidDofs + num_modes;
  if (o.prior_weight > 0 && num_modes > 0)
    problem->AddResidualBlock(MakeCost(RestPrior3{std::sqrt(o.prior_weight), num_modes}, num_modes, 1, n), nullptr, x);
  if (!problem->HasParameterBlock(x)) return;
  for (int d = 0; d < num_modes; ++d) {
    problem->SetParameterLowerBound(x, Group<3>::kRigidDofs + d, ModeLower(o, d));
    problem->SetParameterUpperBound(x, Group<3>::kRigidDofs + d, ModeUpper(o, d));
  }
}

// Appends one solve's report to the running one (costs over all solves, the last summary).
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

// Solves one pose from q (in and out): `add_terms(chart, problem)` adds the data residuals
// at a chart; the chart is re-centred when its turn δ grows past kRecentreAngle.
template <class AddTerms>
void SolvePose3(int num_modes, const PoseFitOptions& o, const AddTerms& add_terms, Eigen::VectorXd* q,
                FitReport* report) {
  Chart chart = Chart::At(*q);
  for (int d = 0; d < num_modes; ++d)
    chart.x[Group<3>::kRigidDofs + d] = std::clamp(chart.x[Group<3>::kRigidDofs + d], ModeLower(o, d), ModeUpper(o, d));
  constexpr int kMaxCharts = 8;
  for (int k = 0; k < kMaxCharts; ++k) {
    ceres::Problem problem;
    add_terms(chart, &problem);
    AddPriorAndBounds(o, num_modes, chart.x.data(), &problem);
    FitReport part;
    SolvePoseProblem(o, &problem, &part);
    AppendReport(part, k == 0, report);
    const bool turned_far = chart.x.segment<3>(3).norm() > kRecentreAngle;
    chart = Chart::At(chart.q());
    if (!turned_far || report->iterations >= o.max_iterations) break;
  }
  *q = chart.q();
}

// Conditioning of the data terms at q, in the chart centred at q (δ = 0).
template <class AddTerms>
Conditioning Conditioning3(const BodyModel3& body, const AddTerms& add_terms, const Eigen::VectorXd& q) {
  Chart chart = Chart::At(q);
  ceres::Problem problem;
  add_terms(chart, &problem);
  ceres::Problem::EvaluateOptions eval;
  problem.GetResidualBlocks(&eval.residual_blocks);
  return ConditioningOfJacobian(DataJacobian(&problem, eval), CoordinateNames3(body), Group<3>::kRigidDofs);
}


// Weighted Kabsch: q (γ = 0) whose rigid motion best carries `rest` onto `target`.
Eigen::VectorXd RigidStart3(int num_modes, const std::vector<Eigen::Vector3d>& rest,
                            const std::vector<Eigen::Vector3d>& target, const std::vector<double>& w) {
  Eigen::Vector3d ps = Eigen::Vector3d::Zero(), ys = Eigen::Vector3d::Zero();
  double wsum = 0;
  for (size_t i = 0; i < rest.size(); ++i) {
    ps += w[i] * rest[i];
    ys += w[i] * target[i];
    wsum += w[i];
  }
  ps /= wsum;
  ys /= wsum;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < rest.size(); ++i) H += w[i] * (rest[i] - ps) * (target[i] - ys).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  S(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;  // no reflection
  const Eigen::Matrix3d R = svd.matrixV() * S * svd.matrixU().transpose();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(Group<3>::kRigidDofs + num_modes);
  q.head<3>() = ys - R * ps;
  q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(R));
  return q;
}

void CheckOptions3(const BodyModel3& body, const PoseFitOptions& o, const char* fit) {
  const std::string error = ValidateOptions(o, body.num_modes(), Group<3>::kRigidDofs);
  if (!error.empty()) throw std::invalid_argument(std::string(fit) + ": " + error);
}

PointResidual3 ToPoint3(const BodyModel3& body, const Correspondence3& t, const char* fit) {
  if (t.mass_point >= body.num_points())
    throw std::invalid_argument(std::string(fit) + ": mass point " + std::to_string(t.mass_point) +
                                " does not exist (the body has " + std::to_string(body.num_points()) + ")");
  if (!(t.weight > 0) || !std::isfinite(t.weight)) throw std::invalid_argument(std::string(fit) + ": weights must be > 0");
  PointResidual3 r;
  r.point = BasisOf3(body, t.mass_point, t.lattice_coords);
  r.y = t.position;
  r.sqrt_weight = std::sqrt(t.weight);
  r.num_modes = body.num_modes();
  return r;
}

}  // namespace

PoseFitResult FitPose3(const BodyModel3& body, const std::vector<Correspondence3>& targets, const PoseFitOptions& o) {
  CheckOptions3(body, o, "pose fit");
  if (targets.empty()) throw std::invalid_argument("pose fit: no target points");
  std::vector<PointResidual3> data;
  std::vector<Eigen::Vector3d> rest, goal;
  std::vector<double> weights;
  for (const Correspondence3& t : targets) {
    data.push_back(ToPoint3(body, t, "pose fit"));
    rest.push_back(data.back().point.b0);
    goal.push_back(t.position);
    weights.push_back(t.weight);
  }
  const int D = body.num_modes(), n = Group<3>::kRigidDofs + D;
  auto add_terms = [&](Chart& chart, ceres::Problem* problem) {
    ceres::LossFunction* loss = MakeLoss(o.loss, o.loss_scale);
    for (PointResidual3 r : data) {
      r.R0 = chart.R0;
      problem->AddResidualBlock(MakeCost(r, 3, 1, n), loss, chart.x.data());
    }
  };
  PoseFitResult result;
  result.q = o.initial_q.size() ? o.initial_q : RigidStart3(D, rest, goal, weights);
  SolvePose3(D, o, add_terms, &result.q, &result.report);
  double sum = 0;
  for (size_t i = 0; i < data.size(); ++i) {
    const double dist = (PointPosition3(data[i].point, result.q) - data[i].y).norm();
    result.point_residuals.push_back(dist);
    sum += dist * dist;
  }
  result.rms_residual = std::sqrt(sum / double(data.size()));
  FillAtBound(body, o, &result);
  if (o.analyze_conditioning) result.conditioning = Conditioning3(body, add_terms, result.q);
  return result;
}

std::vector<PointBasis3> SurfaceSamples3(const BodyModel3& body, const PoseFitOptions& o) {
  std::vector<PointBasis3> samples;
  const size_t nv = body.def().mesh.points.size(), keep = std::min(nv, size_t(o.max_mesh_samples));
  if (keep == 0)  // no mesh to sample: the mass points (a volume grid's lie inside the skin)
    for (int k = 0; k < body.num_points(); ++k) samples.push_back(BasisOf3(body, k, {}));
  for (size_t i = 0; i < keep; ++i) {
    const int v = int(i * nv / keep);
    PointBasis3 p;
    p.b0 = body.mesh_rest_local(v);
    p.B = body.mesh_mode_matrix(v);
    samples.push_back(p);
  }
  return samples;
}

namespace {

// Centroid and principal axes (columns, major last) of weighted points.
struct Shape3 {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d axes;
};
Shape3 Principal3(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w) {
  Shape3 s;
  double wsum = 0;
  s.centroid.setZero();
  for (size_t i = 0; i < p.size(); ++i) s.centroid += w[i] * p[i], wsum += w[i];
  s.centroid /= wsum;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < p.size(); ++i) cov += w[i] * (p[i] - s.centroid) * (p[i] - s.centroid).transpose();
  s.axes = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors();
  return s;
}

// Points and weights that stand for a shape in its principal axes: triangle centroids weighted
// by area, and loose points weighted like an average triangle (1 without triangles).
void ShapePoints(const std::vector<Eigen::Vector3d>& points, const std::vector<std::array<int, 3>>& triangles,
                 const std::vector<int>& loose, std::vector<Eigen::Vector3d>* p, std::vector<double>* w) {
  double area_sum = 0;
  for (const std::array<int, 3>& t : triangles) {
    const Eigen::Vector3d &a = points[t[0]], &b = points[t[1]], &c = points[t[2]];
    p->push_back((a + b + c) / 3.0);
    w->push_back(0.5 * (b - a).cross(c - a).norm());
    area_sum += w->back();
  }
  const double point_weight = triangles.empty() || !(area_sum > 0) ? 1.0 : area_sum / double(triangles.size());
  for (double& x : *w)
    if (!(x > 0)) x = point_weight * 1e-6;  // a degenerate triangle still counts a little
  for (int i : loose) p->push_back(points[i]), w->push_back(point_weight);
}

}  // namespace

namespace {

// A solved start as bytes and back (q and the solver's report), for DistributedMap.
Bytes EncodeSolve(const PoseFitResult& r) {
  return ByteWriter()
      .PutDoubles(std::vector<double>(r.q.data(), r.q.data() + r.q.size()))
      .PutString(EncodeFitReport(r.report))
      .Take();
}

PoseFitResult DecodeSolve(const Bytes& bytes) {
  ByteReader in(bytes);
  PoseFitResult r;
  const std::vector<double> q = in.GetDoubles();
  r.q = Eigen::Map<const Eigen::VectorXd>(q.data(), Eigen::Index(q.size()));
  r.report = DecodeFitReport(in.GetString());
  return r;
}

}  // namespace

PoseFitResult FitPoseToSurface3(const BodyModel3& body, const SurfaceTarget3& target, const PoseFitOptions& o) {
  CheckOptions3(body, o, "surface fit");
  if (target.empty()) throw std::invalid_argument("surface fit: the target has no triangles or points");
  const std::vector<PointBasis3> samples = SurfaceSamples3(body, o);
  if (samples.empty()) throw std::invalid_argument("surface fit: the body has no samples (no mass points used, no mesh)");
  const SurfaceIndex surface(target);
  const int D = body.num_modes(), n = Group<3>::kRigidDofs + D, ns = int(samples.size());
  // the target's points for the reverse direction (mesh vertices and cloud), evenly spread
  std::vector<Eigen::Vector3d> reverse_points;
  if (o.two_sided) {
    const size_t nv = target.points.size(), keep = std::min(nv, size_t(o.max_reverse_points));
    for (size_t i = 0; i < keep; ++i) reverse_points.push_back(target.points[i * nv / keep]);
  }
  const double reverse_weight = reverse_points.empty() ? 0.0 : double(ns) / double(reverse_points.size());
  auto add_terms = [&](Chart& chart, ceres::Problem* problem) {
    ceres::LossFunction* loss = MakeLoss(o.loss, o.loss_scale);
    for (const PointBasis3& p : samples)
      problem->AddResidualBlock(MakeCost(NearestSurfaceResidual3{p, chart.R0, &surface, 1.0, D}, 3, 1, n), loss,
                                chart.x.data());
    for (const Eigen::Vector3d& y : reverse_points)
      problem->AddResidualBlock(
          MakeCost(NearestSampleResidual3{&samples, chart.R0, y, std::sqrt(reverse_weight), D}, 3, 1, n), loss,
          chart.x.data());
  };

  std::vector<Eigen::VectorXd> starts;
  if (o.initial_q.size()) {
    starts.push_back(o.initial_q);
  } else {
    // the same measure on both sides: area on a mesh, count on points
    std::vector<Eigen::Vector3d> bp, tp;
    std::vector<double> bw, tw;
    const SurfaceMesh& mesh = body.def().mesh;
    if (!mesh.empty() && o.max_mesh_samples > 0) {
      ShapePoints(mesh.points, mesh.triangles, {}, &bp, &bw);
    } else {
      std::vector<Eigen::Vector3d> rest;
      std::vector<int> all;
      for (const PointBasis3& p : samples) all.push_back(int(rest.size())), rest.push_back(p.b0);
      ShapePoints(rest, {}, all, &bp, &bw);
    }
    ShapePoints(target.points, target.triangles, target.cloud, &tp, &tw);
    const Shape3 bs = Principal3(bp, bw), ts = Principal3(tp, tw);
    // every proper rotation that carries the body's principal axes onto the target's, in any
    // order (a deformation may change which axis is longest) and with any signs: 24; the
    // kStartsSolved that fit best as they are (γ = 0) are solved
    struct Candidate {
      double cost;
      Eigen::VectorXd q;
    };
    std::vector<Candidate> candidates;
    const int permutations[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (const auto& perm : permutations)
      for (int k = 0; k < 4; ++k) {
        Eigen::Matrix3d target_axes;
        for (int i = 0; i < 3; ++i) target_axes.col(i) = ts.axes.col(perm[i]);
        Eigen::Vector3d sign(k & 1 ? -1.0 : 1.0, k & 2 ? -1.0 : 1.0, 1.0);
        Eigen::Matrix3d R = target_axes * sign.asDiagonal() * bs.axes.transpose();
        if (R.determinant() < 0) {
          sign.z() = -1.0;
          R = target_axes * sign.asDiagonal() * bs.axes.transpose();
        }
        Eigen::VectorXd q = Eigen::VectorXd::Zero(n);
        q.head<3>() = ts.centroid - R * bs.centroid;
        q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(R));
        double cost = 0;
        for (const PointBasis3& p : samples) {
          const Eigen::Vector3d x = PointPosition3(p, q);
          cost += (x - surface.Closest<double>(x)).squaredNorm();
        }
        candidates.push_back({cost, q});
      }
    constexpr size_t kStartsSolved = 4;
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
    for (size_t i = 0; i < std::min(kStartsSolved, candidates.size()); ++i) starts.push_back(candidates[i].q);
  }
  // The starts are solved at once, on threads and, under mpirun, on ranks (core/distribute.h),
  // then taken in order as one after the other would take them: so the answer is the same.
  const std::vector<Bytes> solved = DistributedMap(starts.size(), MapOptions(), [&](size_t i) {
    PoseFitResult run;
    run.q = starts[i];
    SolvePose3(D, o, add_terms, &run.q, &run.report);
    return EncodeSolve(run);
  });
  PoseFitResult best;
  best.report.final_cost = std::numeric_limits<double>::infinity();
  double seconds = 0;
  for (const Bytes& bytes : solved) {
    const PoseFitResult run = DecodeSolve(bytes);
    seconds += run.report.solve_seconds;
    if (!(run.report.final_cost >= best.report.final_cost)) best = run;
    // a start that met the target exactly (cost down by 1e12) leaves nothing for the others
    if (run.report.final_cost <= 1e-12 * run.report.initial_cost) break;
  }
  best.report.solve_seconds = seconds;
  best.rounds = 1;
  double sum = 0;
  for (const PointBasis3& p : samples) {
    const Eigen::Vector3d x = PointPosition3(p, best.q);
    const double dist = (x - surface.Closest<double>(x)).norm();
    best.point_residuals.push_back(dist);
    sum += dist * dist;
  }
  best.rms_residual = std::sqrt(sum / double(ns));
  FillAtBound(body, o, &best);
  if (o.analyze_conditioning) best.conditioning = Conditioning3(body, add_terms, best.q);
  return best;
}

namespace {

// Smoothness between frames f−1, f, f+1 (blocks x0, x1, x2 in their charts): the divided
// second difference of t and γ, and c2 log(R1ᵀR2) − c0 log(R0ᵀR1) for the orientation, each
// coordinate times its length scale (trajectory_fit.h's SecondDifference on SO(3)).
struct SecondDifference3 {
  double c0 = 1, c1 = -2, c2 = 1;
  Eigen::Quaterniond R0[3];
  Eigen::VectorXd scale;  // per coordinate, times sqrt(w)
  int num_modes = 0;
  template <class T> bool operator()(T const* const* x, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = (T(c0) * x[0][i] + T(c1) * x[1][i] + T(c2) * x[2][i]) * T(scale[i]);
    for (int d = 0; d < num_modes; ++d) {
      const int i = Group<3>::kRigidDofs + d;
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

TrajectoryFitResult FitKinematicTrajectory3(const BodyModel3& body, const std::vector<ReferenceFrame3>& frames,
                                            const TrajectoryFitOptions& o) {
  const PoseFitOptions& po = o.pose;
  CheckOptions3(body, po, "trajectory fit");
  if (!(o.smoothness >= 0) || !std::isfinite(o.smoothness))
    throw std::invalid_argument("trajectory fit: smoothness must be >= 0");
  if (frames.empty()) throw std::invalid_argument("trajectory fit: no frames");
  const int F = int(frames.size()), D = body.num_modes(), n = Group<3>::kRigidDofs + D;
  for (int f = 1; f < F; ++f)
    if (!(frames[f].time > frames[f - 1].time))
      throw std::invalid_argument("trajectory fit: frame times must strictly increase");

  TrajectoryFitResult result;
  std::vector<std::vector<PointResidual3>> data(F);
  std::vector<Chart> charts(F);
  for (int f = 0; f < F; ++f) {
    result.times.push_back(frames[f].time);
    if (frames[f].points.empty()) throw std::invalid_argument("trajectory fit: a frame has no points");
    std::vector<Eigen::Vector3d> rest, goal;
    std::vector<double> w;
    for (const Correspondence3& t : frames[f].points) {
      data[f].push_back(ToPoint3(body, t, "trajectory fit"));
      rest.push_back(data[f].back().point.b0);
      goal.push_back(t.position);
      w.push_back(t.weight);
    }
    charts[f] = Chart::At(po.initial_q.size() ? po.initial_q : RigidStart3(D, rest, goal, w));
    for (int d = 0; d < D; ++d)
      charts[f].x[Group<3>::kRigidDofs + d] = std::clamp(charts[f].x[Group<3>::kRigidDofs + d], ModeLower(po, d), ModeUpper(po, d));
  }
  const VecQ<double> L = SmoothnessScales3(body) * std::sqrt(o.smoothness);
  // one problem; re-centred (all charts) while some frame turned far from its chart's centre
  constexpr int kMaxCharts = 8;
  for (int k = 0; k < kMaxCharts; ++k) {
    ceres::Problem problem;
    ceres::LossFunction* loss = MakeLoss(po.loss, po.loss_scale);
    for (int f = 0; f < F; ++f) {
      for (PointResidual3 r : data[f]) {
        r.R0 = charts[f].R0;
        problem.AddResidualBlock(MakeCost(r, 3, 1, n), loss, charts[f].x.data());
      }
      AddPriorAndBounds(po, D, charts[f].x.data(), &problem);
    }
    if (o.smoothness > 0 && F >= 3)
      for (int f = 1; f + 1 < F; ++f) {
        const double h0 = frames[f].time - frames[f - 1].time, h1 = frames[f + 1].time - frames[f].time;
        const double hm = 0.5 * (h0 + h1);
        SecondDifference3 s;
        s.c0 = hm / h0;
        s.c2 = hm / h1;
        s.c1 = -s.c0 - s.c2;
        for (int j = 0; j < 3; ++j) s.R0[j] = Eigen::Quaterniond(charts[f - 1 + j].R0);
        s.scale = L;
        s.num_modes = D;
        problem.AddResidualBlock(MakeCost(s, n, 3, n), nullptr, charts[f - 1].x.data(), charts[f].x.data(),
                                 charts[f + 1].x.data());
      }
    const ceres::Solver::Options options = TrajectorySolverOptions(po, &result.linear_solver);
    FitReport part;
    SolveAndReport(options, &problem, po.on_iteration, po.full_report, &part);
    AppendReport(part, k == 0, &result.report);
    bool turned_far = false;
    for (Chart& chart : charts) {
      turned_far = turned_far || chart.x.segment<3>(3).norm() > kRecentreAngle;
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
    for (const PointResidual3& d : data[f]) fs += (PointPosition3(d.point, result.q[f]) - d.y).squaredNorm();
    result.frame_rms.push_back(std::sqrt(fs / double(data[f].size())));
    sum += fs;
    count += data[f].size();
  }
  result.rms_residual = std::sqrt(sum / double(count));
  return result;
}

}  // namespace wobble::fit
