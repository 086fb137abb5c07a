#include "wobble/fit/targets.h"

namespace wobble::fit {

void CurveTarget::AddPolyline(const std::vector<Eigen::Vector2d>& points, bool closed) {
  const size_t n = points.size();
  for (size_t i = 0; i + 1 < n + (closed ? 1 : 0); ++i) {
    a.push_back(points[i]);
    b.push_back(points[(i + 1) % n]);
  }
  vertices.insert(vertices.end(), points.begin(), points.end());
}

void CurveTarget::AddPoint(const Eigen::Vector2d& p) {
  a.push_back(p);
  b.push_back(p);
  vertices.push_back(p);
}

void SurfaceTarget::AddMesh(const SurfaceMesh& mesh) {
  const int first = int(points.size());
  points.insert(points.end(), mesh.points.begin(), mesh.points.end());
  for (const std::array<int, 3>& t : mesh.triangles) triangles.push_back({first + t[0], first + t[1], first + t[2]});
}

void SurfaceTarget::AddPoint(const Eigen::Vector3d& p) {
  cloud.push_back(int(points.size()));
  points.push_back(p);
}

template <int Dim>
PointBasisN<Dim> BasisOf(const BodyModelN<Dim>& body, int mass_point, const Eigen::Matrix<double, Dim, 1>& lattice_coords) {
  PointBasisN<Dim> p;
  if (mass_point >= 0) {
    p.b0 = body.rest_local(mass_point);
    p.B = body.mode_matrix(mass_point);
  } else {
    body.LocalBasis(lattice_coords, &p.b0, &p.B);
  }
  return p;
}

template PointBasisN<2> BasisOf(const BodyModelN<2>&, int, const Eigen::Vector2d&);
template PointBasisN<3> BasisOf(const BodyModelN<3>&, int, const Eigen::Vector3d&);

}  // namespace wobble::fit
