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

}  // namespace wobble::fit
