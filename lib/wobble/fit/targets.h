// What the fits match, in fit's own types (not file records: `wobble fit` converts the parsed
// target files and simulation CSVs into these), and where a body point is at a given q.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/body/surface_mesh.h"

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

// ---- 3D bodies (pose_fit3.h): q = [t, r, γ], r a rotation vector ----

struct Correspondence3 {
  int mass_point = -1;                                       // >= 0: this mass point
  Eigen::Vector3d lattice_coords = Eigen::Vector3d::Zero();  // (s, t, u), used when mass_point < 0
  Eigen::Vector3d position = Eigen::Vector3d::Zero();        // world
  double weight = 1.0;                                       // > 0
};

struct ReferenceFrame3 {
  double time = 0.0;
  std::vector<Correspondence3> points;
};

// A target without correspondences: triangles (a surface) and unordered points.
struct SurfaceTarget3 {
  std::vector<Eigen::Vector3d> points;             // the mesh's vertices, then cloud points
  std::vector<std::array<int, 3>> triangles;       // indices into points
  std::vector<int> cloud;                          // points that belong to no triangle
  void AddMesh(const SurfaceMesh& mesh);
  void AddPoint(const Eigen::Vector3d& p);
  bool empty() const { return triangles.empty() && cloud.empty(); }
};

struct PointBasis3 {
  Eigen::Vector3d b0 = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 3, Eigen::Dynamic> B;
};
// Mass point k, or the body point at lattice coordinates (s, t, u) when k < 0.
PointBasis3 BasisOf3(const BodyModel3& body, int mass_point, const Eigen::Vector3d& lattice_coords);
// World position of a body point at q = [t, r, γ] (r a rotation vector), in plain doubles.
Eigen::Vector3d PointPosition3(const PointBasis3& p, const Eigen::VectorXd& q);

}  // namespace wobble::fit
