// Ceres cost functors of the 2D curve fits and the linear terms of every pose and trajectory
// fit (internal/pose_chart.h has the ones written once over the dimension), and the helper that turns a
// run-time number of coordinates into Ceres' compile-time block sizes.
//
// Every functor follows Ceres' pattern (examples/snavely_reprojection_error.h): it stores its
// observation and has a templated operator(); positions come from PointPosition (Eq. 4.2,
// fit/targets.h), the simulation's kinematics read in place.
#pragma once

#include <ceres/autodiff_cost_function.h>

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/fit/targets.h"

namespace wobble::fit {

// The closest point of segment [a, b] to x (a == b: the point a). Where the projection is
// clamped to an end the end is a constant, otherwise derivatives flow through the projection.
template <class T> Vec2<T> ClosestOnSegment(const Vec2<T>& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a.cast<T>();
  const T u = (x - a.cast<T>()).dot(ab.cast<T>()) / T(len2);
  if (!(ScalarValue(u) > 0.0)) return a.cast<T>();
  if (!(ScalarValue(u) < 1.0)) return b.cast<T>();
  return a.cast<T>() + u * ab.cast<T>();
}

// Residual sqrt(w) (x(q) − closest point of [a, b]): a target point when a == b, a
// point-to-segment distance for curve targets. Its norm is sqrt(w) times the distance.
struct SegmentResidual {
  PointBasis point;
  Eigen::Vector2d a, b;
  double sqrt_weight = 1.0;
  int num_q = kRigidDofs;
  template <class T> bool operator()(const T* q, T* r) const {
    const Vec2<T> x = PointPosition(point, q, num_q);
    const Vec2<T> e = (x - ClosestOnSegment(x, a, b)) * T(sqrt_weight);
    r[0] = e[0];
    r[1] = e[1];
    return true;
  }
};

// The reverse direction of a curve fit: sqrt(w) (y − closest point of the deformed body
// segment [x_a(q), x_b(q)]) for a fixed target point y. Keeps the body from covering only
// part of the target (a one-sided fit lets legs shrink and slide along longer target legs).
struct ReverseSegmentResidual {
  PointBasis pa, pb;
  Eigen::Vector2d y;
  double sqrt_weight = 1.0;
  int num_q = kRigidDofs;
  template <class T> bool operator()(const T* q, T* r) const {
    const Vec2<T> xa = PointPosition(pa, q, num_q), xb = PointPosition(pb, q, num_q);
    const Vec2<T> ab = xb - xa;
    const T len2 = ab.squaredNorm();
    Vec2<T> closest = xa;
    if (ScalarValue(len2) > 0.0) {
      const T u = (y.cast<T>() - xa).dot(ab) / len2;
      if (!(ScalarValue(u) > 0.0)) {
        closest = xa;
      } else if (!(ScalarValue(u) < 1.0)) {
        closest = xb;
      } else {
        closest = xa + u * ab;
      }
    }
    const Vec2<T> e = (y.cast<T>() - closest) * T(sqrt_weight);
    r[0] = e[0];
    r[1] = e[1];
    return true;
  }
};

// Index of the segment [a_i, b_i] nearest to x (brute force).
int NearestSegment(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                   const Eigen::Vector2d& x);

// Joint closest points: like SegmentResidual, but the target segment is the one nearest to
// the body point at every evaluation (chosen on plain values), so the solver moves across
// segments freely. The distance to a polyline is continuous in q; its gradient jumps only
// where two segments are equally near.
struct NearestSegmentResidual {
  PointBasis point;
  const std::vector<Eigen::Vector2d>* a = nullptr;
  const std::vector<Eigen::Vector2d>* b = nullptr;
  double sqrt_weight = 1.0;
  int num_q = kRigidDofs;
  template <class T> bool operator()(const T* q, T* r) const {
    const Vec2<T> x = PointPosition(point, q, num_q);
    const Eigen::Vector2d xv(ScalarValue(x[0]), ScalarValue(x[1]));
    const int seg = NearestSegment(*a, *b, xv);
    const Vec2<T> e = (x - ClosestOnSegment(x, (*a)[seg], (*b)[seg])) * T(sqrt_weight);
    r[0] = e[0];
    r[1] = e[1];
    return true;
  }
};

// Joint closest points in the reverse direction: the body segment nearest to target point y
// at every evaluation.
struct NearestBodySegmentResidual {
  const std::vector<PointBasis>* points = nullptr;
  const std::vector<std::pair<int, int>>* segments = nullptr;
  Eigen::Vector2d y;
  double sqrt_weight = 1.0;
  int num_q = kRigidDofs;
  template <class T> bool operator()(const T* q, T* r) const {
    // every drawn sample's position at the plain values of q (one sin/cos for all)
    const double c = std::cos(ScalarValue(q[2])), s = std::sin(ScalarValue(q[2]));
    const Eigen::Vector2d t(ScalarValue(q[0]), ScalarValue(q[1]));
    auto place = [&](const PointBasis& p) {
      Eigen::Vector2d l = p.b0;
      for (int d = 0; d + kRigidDofs < num_q; ++d) l += p.B.col(d) * ScalarValue(q[kRigidDofs + d]);
      return Eigen::Vector2d(t.x() + c * l.x() - s * l.y(), t.y() + s * l.x() + c * l.y());
    };
    int best = 0;
    double best_d2 = std::numeric_limits<double>::infinity();
    int cached = -1;
    Eigen::Vector2d xb_cached = Eigen::Vector2d::Zero();
    for (size_t k = 0; k < segments->size(); ++k) {
      const auto [i, j] = (*segments)[k];
      // consecutive segments share their joint point
      const Eigen::Vector2d xa = i == cached ? xb_cached : place((*points)[i]);
      const Eigen::Vector2d xb = place((*points)[j]);
      cached = j;
      xb_cached = xb;
      const double d2 = (y - ClosestOnSegment<double>(y, xa, xb)).squaredNorm();
      if (d2 < best_d2) {
        best_d2 = d2;
        best = int(k);
      }
    }
    ReverseSegmentResidual fixed;
    fixed.pa = (*points)[(*segments)[best].first];
    fixed.pb = (*points)[(*segments)[best].second];
    fixed.y = y;
    fixed.sqrt_weight = sqrt_weight;
    fixed.num_q = num_q;
    return fixed(q, r);
  }
};

// Prior toward rest: sqrt(w) γ_d for every mode d (one residual per mode), γ_d = q[num_rigid + d]
// (2D and 3D). Linear, so its Jacobian is written out (an autodiff instance per size would only
// cost compile time).
struct RestPrior {
  double sqrt_weight = 0.0;
  int num_rigid = kRigidDofs;
  int num_q = kRigidDofs;
};

// Temporal smoothness between three consecutive frames: the divided second difference
// c0 q_{f−1} + c1 q_f + c2 q_{f+1} (c0 = h̄/h0, c2 = h̄/h1, c1 = −c0 − c2, h̄ = (h0 + h1)/2;
// q_{f−1} − 2q_f + q_{f+1} for even frames), each coordinate times a length scale so that
// translation, angle and amplitudes are weighed in the same unit. Linear, Jacobian written out.
struct SecondDifference {
  double c0 = 1, c1 = -2, c2 = 1;
  VecQ<double> scale;  // per coordinate, times sqrt(w)
};

// Calls make(std::integral_constant<int, N>) with N = num_q, for a 2D body (3 to 3 + kMaxModes):
// Ceres' AutoDiffCostFunction wants block sizes at compile time.
template <int N = kRigidDofs, class Make> ceres::CostFunction* WithNumQ(int num_q, Make&& make) {
  if constexpr (N > kRigidDofs + kMaxModes) {
    return nullptr;
  } else {
    if (num_q == N) return make(std::integral_constant<int, N>{});
    return WithNumQ<N + 1>(num_q, make);
  }
}

ceres::CostFunction* MakeSegmentCost(const SegmentResidual& r);
ceres::CostFunction* MakeReverseSegmentCost(const ReverseSegmentResidual& r);
ceres::CostFunction* MakeNearestSegmentCost(const NearestSegmentResidual& r);
ceres::CostFunction* MakeNearestBodySegmentCost(const NearestBodySegmentResidual& r);
ceres::CostFunction* MakeRestPriorCost(const RestPrior& r);
ceres::CostFunction* MakeSecondDifferenceCost(const SecondDifference& r);

}  // namespace wobble::fit
