// What the fits match, in fit's own types (not file records: `wobble fit` converts the parsed
// target files and simulation CSVs into these), and where a body point is at a given q. One
// type per concept over the dimension (CorrespondenceN<Dim>, ...; the 2D names are aliases as
// BodyModel is of BodyModelN<2>); what differs, the rotation's parameters in q, is FitPoseQ<Dim>.
//   2D: q = [tx, ty, θ, γ1..γD]                       (Eq. 4.4)
//   3D: q = [tx, ty, tz, rx, ry, rz, γ1..γD], r the rotation vector of the orientation R
// and every body point is x(q) = t + R (b0 + B γ) (Eq. 4.2).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/body/surface_mesh.h"
#include "wobble/core/rotation3.h"

namespace wobble::fit {

// One correspondence: a body point (a mass point, or lattice coordinates (s, t[, u])) and
// where it should be.
template <int Dim> struct CorrespondenceN {
  using Vec = Eigen::Matrix<double, Dim, 1>;
  int mass_point = -1;                 // >= 0: this mass point
  Vec lattice_coords = Vec::Zero();    // used when mass_point < 0
  Vec position = Vec::Zero();          // world
  double weight = 1.0;                 // > 0
};
using Correspondence = CorrespondenceN<2>;

// One frame of a reference trajectory: where some body points are at `time`.
template <int Dim> struct ReferenceFrameN {
  double time = 0.0;
  std::vector<CorrespondenceN<Dim>> points;
};
using ReferenceFrame = ReferenceFrameN<2>;

// A 2D target without correspondences: segments [a_i, b_i] (a == b for an unordered point)
// and its vertices (polyline points and unordered points, each once, in the order added).
struct CurveTarget {
  std::vector<Eigen::Vector2d> a, b;
  std::vector<Eigen::Vector2d> vertices;
  // Its segments (closed: also last to first) and its points.
  void AddPolyline(const std::vector<Eigen::Vector2d>& points, bool closed);
  void AddPoint(const Eigen::Vector2d& p);
};

// A 3D target without correspondences: triangles (a surface) and unordered points.
struct SurfaceTarget {
  std::vector<Eigen::Vector3d> points;             // the mesh's vertices, then cloud points
  std::vector<std::array<int, 3>> triangles;       // indices into points
  std::vector<int> cloud;                          // points that belong to no triangle
  void AddMesh(const SurfaceMesh& mesh);
  void AddPoint(const Eigen::Vector3d& p);
  bool empty() const { return triangles.empty() && cloud.empty(); }
};

// What a body point needs to be placed: x(q) = t + R (b0 + B γ) (Eq. 4.2).
template <int Dim> struct PointBasisN {
  Eigen::Matrix<double, Dim, 1> b0 = Eigen::Matrix<double, Dim, 1>::Zero();
  MatND<double, Dim> B;
};
using PointBasis = PointBasisN<2>;

// Mass point k, or the body point at lattice coordinates u when k < 0.
template <int Dim>
PointBasisN<Dim> BasisOf(const BodyModelN<Dim>& body, int mass_point, const Eigen::Matrix<double, Dim, 1>& lattice_coords);
extern template PointBasisN<2> BasisOf(const BodyModelN<2>&, int, const Eigen::Vector2d&);
extern template PointBasisN<3> BasisOf(const BodyModelN<3>&, int, const Eigen::Vector3d&);

// What differs between the dimensions in a fit's q: the rigid coordinates, their names, and
// where a body point is (templated for autodiff, reading q in place: copying q into a VecQ of
// Jets dominated the cost of a residual).
template <int Dim> struct FitPoseQ;

template <> struct FitPoseQ<2> {
  static constexpr int kRigid = 3;  // tx, ty, θ
  static std::vector<std::string> RigidNames() { return {"tx", "ty", "theta"}; }
  // x = t + R(θ)(b0 + Σ_d γ_d b^d), as LocalPosition/WorldFromLocal of kinematics.h.
  template <class T> static Vec2<T> Place(const PointBasisN<2>& p, const T* q, int num_q) {
    using std::cos;
    using std::sin;
    T lx(p.b0.x()), ly(p.b0.y());
    for (int d = 0; d + kRigid < num_q; ++d) {
      lx += p.B(0, d) * q[kRigid + d];
      ly += p.B(1, d) * q[kRigid + d];
    }
    const T c = cos(q[2]), s = sin(q[2]);
    return Vec2<T>(q[0] + c * lx - s * ly, q[1] + s * lx + c * ly);
  }
};

template <> struct FitPoseQ<3> {
  static constexpr int kRigid = 6;  // t, the rotation vector r
  static std::vector<std::string> RigidNames() { return {"tx", "ty", "tz", "rx", "ry", "rz"}; }
  // x = t + exp(r̂)(b0 + B γ).
  template <class T> static Vec3<T> Place(const PointBasisN<3>& p, const T* q, int num_q) {
    const Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, 1>> gamma(q + kRigid, num_q - kRigid);
    const Vec3<T> local = p.b0.template cast<T>() + p.B.template cast<T>() * gamma;
    return Vec3<T>(q[0], q[1], q[2]) + ExpRotation<T>(Vec3<T>(q[3], q[4], q[5])) * local;
  }
};

// World position of a body point at q (num_q numbers).
template <class T, int Dim> Eigen::Matrix<T, Dim, 1> PointPosition(const PointBasisN<Dim>& p, const T* q, int num_q) {
  return FitPoseQ<Dim>::Place(p, q, num_q);
}
template <int Dim> Eigen::Matrix<double, Dim, 1> PointPosition(const PointBasisN<Dim>& p, const Eigen::VectorXd& q) {
  return FitPoseQ<Dim>::Place(p, q.data(), int(q.size()));
}

}  // namespace wobble::fit
