// What the fits match, in fit's own types (not file records: `wobble fit` converts the parsed
// target files and simulation CSVs into these), and where a body point is at a given q.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "wobble/body/body_model.h"

namespace wobble::fit {

// One correspondence: a body point (a mass point, or lattice coordinates) and where it should be.
struct Correspondence {
  int mass_point = -1;                                       // >= 0: this mass point
  Eigen::Vector2d lattice_coords = Eigen::Vector2d::Zero();  // used when mass_point < 0
  Eigen::Vector2d position = Eigen::Vector2d::Zero();        // world
  double weight = 1.0;                                       // > 0
};

// One frame of a reference trajectory: where some body points are at `time`.
struct ReferenceFrame {
  double time = 0.0;
  std::vector<Correspondence> points;
};

// A target without correspondences: segments [a_i, b_i] (a == b for an unordered point) and
// its vertices (polyline points and unordered points, each once, in the order added).
struct CurveTarget {
  std::vector<Eigen::Vector2d> a, b;
  std::vector<Eigen::Vector2d> vertices;
  // Its segments (closed: also last to first) and its points.
  void AddPolyline(const std::vector<Eigen::Vector2d>& points, bool closed);
  void AddPoint(const Eigen::Vector2d& p);
};

// What a body point needs to be placed: x(q) = t + R(θ)(b0 + B γ) (Eq. 4.2).
struct PointBasis {
  Eigen::Vector2d b0 = Eigen::Vector2d::Zero();
  Mat2D<double> B;
};
// Mass point k, or the body point at lattice coordinates (s, t) when k < 0.
PointBasis BasisOf(const BodyModel& body, int mass_point, const Eigen::Vector2d& lattice_coords);

// World position of a body point, templated for autodiff: x = t + R(θ)(b0 + Σ_d γ_d b^d)
// (Eq. 4.2), as LocalPosition/WorldFromLocal of kinematics.h but reading q in place (copying
// q into a VecQ of Jets dominated the cost of a residual).
template <class T> Vec2<T> PointPosition(const PointBasis& p, const T* q, int num_q) {
  using std::cos;
  using std::sin;
  T lx(p.b0.x()), ly(p.b0.y());
  for (int d = 0; d + kRigidDofs < num_q; ++d) {
    lx += p.B(0, d) * q[kRigidDofs + d];
    ly += p.B(1, d) * q[kRigidDofs + d];
  }
  const T c = cos(q[2]), s = sin(q[2]);
  return Vec2<T>(q[0] + c * lx - s * ly, q[1] + s * lx + c * ly);
}

}  // namespace wobble::fit
