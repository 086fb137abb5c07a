#include "wobble/body/surface_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>

#include "wobble/core/errors.h"

namespace wobble {

namespace {

using Vec3 = Eigen::Vector3d;

Eigen::AlignedBox3d Bounds(const SurfaceMesh& mesh) {
  Eigen::AlignedBox3d box;
  for (const std::array<int, 3>& tri : mesh.triangles)
    for (int v : tri) box.extend(mesh.points[size_t(v)]);
  return box;
}

double TriangleArea(const SurfaceMesh& mesh, const std::array<int, 3>& tri) {
  const Vec3& a = mesh.points[size_t(tri[0])];
  return 0.5 * (mesh.points[size_t(tri[1])] - a).cross(mesh.points[size_t(tri[2])] - a).norm();
}

// The fractional part of x (the R2 sequence wraps into [0, 1)).
double Fraction(double x) { return x - std::floor(x); }

}  // namespace

void CheckSurfaceMesh(const SurfaceMesh& mesh) {
  if (mesh.triangles.empty()) throw InputError("the mesh has no triangles");
  if (mesh.points.size() > size_t(kMaxMeshPoints))
    throw InputError("the mesh has " + std::to_string(mesh.points.size()) + " points, more than wobble takes (" +
                     std::to_string(kMaxMeshPoints) + ")");
  if (mesh.triangles.size() > size_t(kMaxMeshTriangles))
    throw InputError("the mesh has " + std::to_string(mesh.triangles.size()) + " triangles, more than wobble takes (" +
                     std::to_string(kMaxMeshTriangles) + ")");
  for (size_t i = 0; i < mesh.points.size(); ++i)
    if (!mesh.points[i].allFinite()) throw InputError("mesh point " + std::to_string(i) + " is not finite");
  const int n = int(mesh.points.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int v : mesh.triangles[t])
      if (v < 0 || v >= n)
        throw InputError("mesh triangle " + std::to_string(t) + " names point " + std::to_string(v) + " of " +
                         std::to_string(n));
}

double SurfaceArea(const SurfaceMesh& mesh) {
  double area = 0.0;
  for (const std::array<int, 3>& tri : mesh.triangles) area += TriangleArea(mesh, tri);
  return area;
}

double EnclosedVolume(const SurfaceMesh& mesh) {
  // about the box centre, not the origin: a mesh far from its origin keeps its digits
  const Vec3 c = Bounds(mesh).center();
  double six_v = 0.0;
  for (const std::array<int, 3>& tri : mesh.triangles) {
    const Vec3 a = mesh.points[size_t(tri[0])] - c, b = mesh.points[size_t(tri[1])] - c,
               d = mesh.points[size_t(tri[2])] - c;
    six_v += a.dot(b.cross(d));
  }
  return std::abs(six_v) / 6.0;
}

double WindingNumber(const SurfaceMesh& mesh, const Vec3& p) {
  double total = 0.0;
  for (const std::array<int, 3>& tri : mesh.triangles) {
    const Vec3 a = mesh.points[size_t(tri[0])] - p, b = mesh.points[size_t(tri[1])] - p,
               c = mesh.points[size_t(tri[2])] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    // tan(Ω/2) = det[a b c] / (|a||b||c| + (a·b)|c| + (b·c)|a| + (c·a)|b|)  (Van Oosterom & Strackee)
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2.0 * std::atan2(num, den);
  }
  return total / (4.0 * M_PI);
}

LatticeN<3> FitLattice(const SurfaceMesh& mesh, const LatticeN<3>::Sizes& sizes, BasisKind basis, double margin) {
  CheckSurfaceMesh(mesh);
  if (!(margin >= 0.0 && margin <= 10.0)) throw InputError("lattice margin must be in [0, 10], got " + std::to_string(margin));
  const Eigen::AlignedBox3d box = Bounds(mesh);
  const Vec3 size = box.sizes();
  const double pad = margin * size.maxCoeff();
  if (!(size.maxCoeff() > 0.0)) throw InputError("the mesh is a single point: no lattice fits around it");
  // a flat mesh (a sheet) still gets a lattice of some thickness: pad its thin axes to the margin
  LatticeN<3>::Axes axes;
  Vec3 origin;
  for (int a = 0; a < 3; ++a) {
    double side = size[a] + 2.0 * pad;
    if (side <= 1e-9 * size.maxCoeff()) side = std::max(0.1, 2.0 * margin) * size.maxCoeff();
    origin[a] = box.center()[a] - 0.5 * side;
    axes[size_t(a)] = Vec3::Unit(a) * side;
  }
  return LatticeN<3>(origin, axes, sizes, basis);
}

std::vector<Vec3> SampleSurface(const SurfaceMesh& mesh, int n) {
  CheckSurfaceMesh(mesh);
  if (n < 1 || n > kMaxSampledPoints)
    throw InputError("surface samples must be 1.." + std::to_string(kMaxSampledPoints) + ", got " + std::to_string(n));
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) cumulative[t] = total += TriangleArea(mesh, mesh.triangles[t]);
  if (!(total > 0.0) || !std::isfinite(total)) throw InputError("the mesh's surface area is zero or not finite");
  // the R2 sequence: the plastic number's inverse powers (Roberts 2018)
  const double g = 1.32471795724474602596, a1 = 1.0 / g, a2 = 1.0 / (g * g);
  std::vector<Vec3> points;
  points.reserve(size_t(n));
  for (int i = 0; i < n; ++i) {
    const double target = (i + 0.5) / n * total;
    const size_t t = size_t(std::lower_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin());
    const std::array<int, 3>& tri = mesh.triangles[std::min(t, cumulative.size() - 1)];
    double u = Fraction(0.5 + a1 * (i + 1)), v = Fraction(0.5 + a2 * (i + 1));
    if (u + v > 1.0) {  // fold the square's far half onto the triangle
      u = 1.0 - u;
      v = 1.0 - v;
    }
    const Vec3& a = mesh.points[size_t(tri[0])];
    points.push_back(a + u * (mesh.points[size_t(tri[1])] - a) + v * (mesh.points[size_t(tri[2])] - a));
  }
  return points;
}

std::vector<Vec3> SampleVolume(const SurfaceMesh& mesh, int n) {
  CheckSurfaceMesh(mesh);
  if (n < 1 || n > kMaxSampledPoints)
    throw InputError("volume samples must be 1.." + std::to_string(kMaxSampledPoints) + ", got " + std::to_string(n));
  const double volume = EnclosedVolume(mesh);
  const Eigen::AlignedBox3d box = Bounds(mesh);
  if (!(volume > 1e-12 * box.sizes().prod()) || !std::isfinite(volume))
    throw InputError("the mesh encloses no volume (an open or flat surface): sample its surface instead");
  const double h = std::cbrt(volume / n);
  std::array<long, 3> cells{};
  double candidates = 1.0;
  for (int a = 0; a < 3; ++a) {
    cells[size_t(a)] = std::max(1L, long(std::ceil(box.sizes()[a] / h)));
    candidates *= double(cells[size_t(a)]);
  }
  // the box holds the solid, so candidates / n is the box's volume over the solid's: bounded
  // unless the mesh is a thin shell around a big hole (then sample the surface)
  if (candidates > 50.0 * kMaxSampledPoints || candidates * double(mesh.triangles.size()) > 2e9)
    throw InputError("volume sampling would test " + std::to_string(long(candidates)) +
                     " grid points against " + std::to_string(mesh.triangles.size()) +
                     " triangles (too much work): sample its surface, or ask for fewer points");
  std::vector<Vec3> points;
  for (long i = 0; i < cells[0]; ++i)
    for (long j = 0; j < cells[1]; ++j)
      for (long k = 0; k < cells[2]; ++k) {
        const Vec3 p = box.min() + h * Vec3(i + 0.5, j + 0.5, k + 0.5);
        if (std::abs(WindingNumber(mesh, p)) >= 0.5) points.push_back(p);  // either orientation
      }
  if (points.empty())
    throw InputError("no grid point of spacing " + std::to_string(h) + " falls inside the mesh: ask for more points");
  return points;
}

}  // namespace wobble
