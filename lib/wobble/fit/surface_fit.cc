// FitPoseToSurface (pose_fit.h): a 3D body fitted to a triangle mesh and/or a point cloud,
// without correspondences, through the pose fits' chart (internal/pose_chart.h).
#include "wobble/fit/pose_fit.h"

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
#include "wobble/fit/internal/pose_chart.h"
#include "wobble/fit/internal/solve_common.h"

namespace wobble::fit {

namespace {

using Chart = PoseChart<3>;
constexpr int kRigid = FitPoseQ<3>::kRigid;

// A body point at R, t and the amplitudes γ, in plain doubles.
Eigen::Vector3d PlaceValue(const PointBasisN<3>& p, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                           const double* gamma, int num_modes) {
  Eigen::Vector3d l = p.b0;
  for (int d = 0; d < num_modes; ++d) l += p.B.col(d) * gamma[d];
  return t + R * l;
}

// ---- residuals (Ceres functors, one parameter block x of 6 + D) ---------------------------

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

  explicit SurfaceIndex(const SurfaceTarget& target) {
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
struct NearestSurfaceResidual {
  static constexpr int kResiduals = 3;
  PointBasisN<3> point;
  Chart::Centre centre;
  const SurfaceIndex* surface = nullptr;
  double sqrt_weight = 1.0;
  int num_q = 0;
  template <class T> bool operator()(const T* x, T* r) const {
    const Vec3<T> p = Chart::Place(centre, point, x, num_q);
    const Vec3<T> e = (p - surface->Closest(p)) * T(sqrt_weight);
    for (int i = 0; i < 3; ++i) r[i] = e[i];
    return true;
  }
};

// The reverse direction: sqrt(w) (y − the body sample nearest to y), chosen on plain values.
struct NearestSampleResidual {
  static constexpr int kResiduals = 3;
  const std::vector<PointBasisN<3>>* samples = nullptr;
  Chart::Centre centre;
  Eigen::Vector3d y;
  double sqrt_weight = 1.0;
  int num_q = 0;
  template <class T> bool operator()(const T* x, T* r) const {
    double xv[kMaxQ];
    for (int i = 0; i < num_q; ++i) xv[i] = ScalarValue(x[i]);
    const Eigen::Matrix3d R = centre * ExpRotation<double>(Eigen::Vector3d(xv[3], xv[4], xv[5])).toRotationMatrix();
    const Eigen::Vector3d t(xv[0], xv[1], xv[2]);
    int best = 0;
    double best_d2 = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < samples->size(); ++k) {
      const double d2 = (PlaceValue((*samples)[k], R, t, xv + kRigid, num_q - kRigid) - y).squaredNorm();
      if (d2 < best_d2) best_d2 = d2, best = int(k);
    }
    const Vec3<T> e = (y.cast<T>() - Chart::Place(centre, (*samples)[best], x, num_q)) * T(sqrt_weight);
    for (int i = 0; i < 3; ++i) r[i] = e[i];
    return true;
  }
};

}  // namespace

std::vector<PointBasisN<3>> SurfaceSamples(const BodyModelN<3>& body, const PoseFitOptions& o) {
  std::vector<PointBasisN<3>> samples;
  const size_t nv = body.def().mesh.points.size(), keep = std::min(nv, size_t(o.max_mesh_samples));
  if (keep == 0)  // no mesh to sample: the mass points (a volume grid's lie inside the skin)
    for (int k = 0; k < body.num_points(); ++k) samples.push_back(BasisOf(body, k, {}));
  for (size_t i = 0; i < keep; ++i) {
    const int v = int(i * nv / keep);
    PointBasisN<3> p;
    p.b0 = body.mesh_rest_local(v);
    p.B = body.mesh_mode_matrix(v);
    samples.push_back(p);
  }
  return samples;
}

namespace {

// Centroid and principal axes (columns, major last) of weighted points.
struct SurfaceShape {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d axes;
};
SurfaceShape PrincipalAxes(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w) {
  SurfaceShape s;
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

PoseFitResult FitPoseToSurface(const BodyModelN<3>& body, const SurfaceTarget& target, const PoseFitOptions& o) {
  CheckOptions(body, o, "surface fit");
  if (target.empty()) throw std::invalid_argument("surface fit: the target has no triangles or points");
  const std::vector<PointBasisN<3>> samples = SurfaceSamples(body, o);
  if (samples.empty()) throw std::invalid_argument("surface fit: the body has no samples (no mass points used, no mesh)");
  const SurfaceIndex surface(target);
  const int D = body.num_modes(), n = kRigid + D, ns = int(samples.size());
  // the target's points for the reverse direction (mesh vertices and cloud), evenly spread
  std::vector<Eigen::Vector3d> reverse_points;
  if (o.two_sided) {
    const size_t nv = target.points.size(), keep = std::min(nv, size_t(o.max_reverse_points));
    for (size_t i = 0; i < keep; ++i) reverse_points.push_back(target.points[i * nv / keep]);
  }
  const double reverse_weight = reverse_points.empty() ? 0.0 : double(ns) / double(reverse_points.size());
  auto add_terms = [&](Chart& chart, ceres::Problem* problem) {
    ceres::LossFunction* loss = MakeLoss(o.loss, o.loss_scale);
    for (const PointBasisN<3>& p : samples)
      problem->AddResidualBlock(Chart::Cost(NearestSurfaceResidual{p, chart.centre, &surface, 1.0, n}, n), loss,
                                chart.x.data());
    for (const Eigen::Vector3d& y : reverse_points)
      problem->AddResidualBlock(
          Chart::Cost(NearestSampleResidual{&samples, chart.centre, y, std::sqrt(reverse_weight), n}, n), loss,
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
      for (const PointBasisN<3>& p : samples) all.push_back(int(rest.size())), rest.push_back(p.b0);
      ShapePoints(rest, {}, all, &bp, &bw);
    }
    ShapePoints(target.points, target.triangles, target.cloud, &tp, &tw);
    const SurfaceShape bs = PrincipalAxes(bp, bw), ts = PrincipalAxes(tp, tw);
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
        for (const PointBasisN<3>& p : samples) {
          const Eigen::Vector3d x = PointPosition(p, q);
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
    SolvePoseInChart<3>(D, o, add_terms, &run.q, &run.report);
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
  for (const PointBasisN<3>& p : samples) {
    const Eigen::Vector3d x = PointPosition(p, best.q);
    const double dist = (x - surface.Closest<double>(x)).norm();
    best.point_residuals.push_back(dist);
    sum += dist * dist;
  }
  best.rms_residual = std::sqrt(sum / double(ns));
  FillAtBound(body, o, &best);
  if (o.analyze_conditioning) best.conditioning = ConditioningAt(body, add_terms, best.q);
  return best;
}

}  // namespace wobble::fit
