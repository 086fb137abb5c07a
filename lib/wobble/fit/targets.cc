#include "wobble/fit/targets.h"

#include "wobble/core/rotation3.h"

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

PointBasis BasisOf(const BodyModel& body, int mass_point, const Eigen::Vector2d& lattice_coords) {
  PointBasis p;
  if (mass_point >= 0) {
    p.b0 = body.rest_local(mass_point);
    p.B = body.mode_matrix(mass_point);
  } else {
    body.LocalBasis(lattice_coords, &p.b0, &p.B);
  }
  return p;
}

void SurfaceTarget3::AddMesh(const SurfaceMesh& mesh) {
  const int first = int(points.size());
  points.insert(points.end(), mesh.points.begin(), mesh.points.end());
  for (const std::array<int, 3>& t : mesh.triangles) triangles.push_back({first + t[0], first + t[1], first + t[2]});
}

void SurfaceTarget3::AddPoint(const Eigen::Vector3d& p) {
  cloud.push_back(int(points.size()));
  points.push_back(p);
}

PointBasis3 BasisOf3(const BodyModel3& body, int mass_point, const Eigen::Vector3d& lattice_coords) {
  PointBasis3 p;
  if (mass_point >= 0) {
    p.b0 = body.rest_local(mass_point);
    p.B = body.mode_matrix(mass_point);
  } else {
    BodyModel3::ModeMatrix B;
    body.LocalBasis(lattice_coords, &p.b0, &B);
    p.B = B;
  }
  return p;
}

Eigen::Vector3d PointPosition3(const PointBasis3& p, const Eigen::VectorXd& q) {
  const Eigen::Vector3d local = p.b0 + p.B * q.tail(q.size() - Group<3>::kRigidDofs);
  return q.head<3>() + ExpRotation<double>(q.segment<3>(3)) * local;
}

}  // namespace wobble::fit
