#include "wobble/dynamics/heightfield.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "wobble/core/errors.h"

namespace wobble {

namespace {

[[noreturn]] void Refuse(const std::string& what) { throw InputError("heightfield: " + what); }

}  // namespace

std::shared_ptr<const Heightfield> Heightfield::Make(const Eigen::Vector2d& origin, const Eigen::Vector2d& spacing,
                                                     int nx, int nz, std::vector<double> heights) {
  constexpr double kLargest = 1e15;  // as the 2D Terrain: plane tests stay exact far below a unit
  if (nx < 2 || nz < 2) Refuse("needs at least 2 x 2 nodes, got " + std::to_string(nx) + " x " + std::to_string(nz));
  if (!(std::abs(origin.x()) <= kLargest && std::abs(origin.y()) <= kLargest))
    Refuse("the origin must be finite numbers of at most 1e15");
  if (!(spacing.x() > 0 && spacing.y() > 0 && spacing.x() <= kLargest && spacing.y() <= kLargest))
    Refuse("the spacing must be numbers > 0");
  if (heights.size() != size_t(nx) * size_t(nz))
    Refuse("needs " + std::to_string(nx) + " x " + std::to_string(nz) + " heights, got " + std::to_string(heights.size()));
  for (size_t k = 0; k < heights.size(); ++k)
    if (!(std::abs(heights[k]) <= kLargest)) {
      std::ostringstream m;
      m << "the height of node (" << k % size_t(nx) + 1 << ", " << k / size_t(nx) + 1 << ") is " << heights[k]
        << ", not a finite number of at most 1e15";
      Refuse(m.str());
    }
  auto h = std::shared_ptr<Heightfield>(new Heightfield);
  h->origin_ = origin;
  h->spacing_ = spacing;
  h->nx_ = nx;
  h->nz_ = nz;
  h->heights_ = std::move(heights);
  h->max_height_ = *std::max_element(h->heights_.begin(), h->heights_.end());
  const int triangles = h->num_faces() - 1;
  h->normals_.resize(size_t(triangles));
  h->points_.resize(size_t(triangles));
  const double dx = spacing.x(), dz = spacing.y();
  for (int j = 0; j + 1 < nz; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const double h00 = h->Node(i, j), h10 = h->Node(i + 1, j), h01 = h->Node(i, j + 1), h11 = h->Node(i + 1, j + 1);
      const Eigen::Vector3d p00(origin.x() + i * dx, h00, origin.y() + j * dz);
      // triangle 0: (0,0) (1,0) (1,1), slopes along x then z; triangle 1: (0,0) (1,1) (0,1)
      const double slopes[2][2] = {{(h10 - h00) / dx, (h11 - h10) / dz}, {(h11 - h01) / dx, (h01 - h00) / dz}};
      for (int t = 0; t < 2; ++t) {
        const int f = 2 * (i + (nx - 1) * j) + t;
        h->points_[size_t(f)] = p00;
        h->normals_[size_t(f)] = Eigen::Vector3d(-slopes[t][0], 1.0, -slopes[t][1]).normalized();
      }
    }
  // which edges are valleys depends on the heights only: decided once here, not per query
  h->valleys_.resize(size_t(triangles));
  for (int a = 0; a < triangles; ++a) {
    std::array<int, 3> across = h->Across(a);
    for (int& b : across)
      if (b >= 0 && !h->Concave(a, b)) b = -1;
    h->valleys_[size_t(a)] = across;
  }
  return h;
}

int Heightfield::TriangleUnder(double x, double z) const {
  const double u = (x - origin_.x()) / spacing_.x(), w = (z - origin_.y()) / spacing_.y();
  const int i = std::clamp(int(std::floor(u)), 0, nx_ - 2), j = std::clamp(int(std::floor(w)), 0, nz_ - 2);
  const int t = (u - i) >= (w - j) ? 0 : 1;
  return 2 * (i + (nx_ - 1) * j) + t;
}

double Heightfield::Behind(int f, const Eigen::Vector3d& x) const { return normals_[size_t(f)].dot(x - points_[size_t(f)]); }

double Heightfield::HeightAt(double x, double z) const {
  const double xc = std::clamp(x, origin_.x(), origin_.x() + (nx_ - 1) * spacing_.x());
  const double zc = std::clamp(z, origin_.y(), origin_.y() + (nz_ - 1) * spacing_.y());
  const int f = TriangleUnder(xc, zc);
  const Eigen::Vector3d& n = normals_[size_t(f)];
  const Eigen::Vector3d& p = points_[size_t(f)];
  // n·((xc, y, zc) − p) = 0 solved for y
  return p.y() - (n.x() * (xc - p.x()) + n.z() * (zc - p.z())) / n.y();
}

void Heightfield::FacePlane(int f, const Eigen::Vector3d& x, Eigen::Vector3d* point, Eigen::Vector3d* normal) const {
  if (f == outside_face()) {
    *point = Eigen::Vector3d(x.x(), HeightAt(x.x(), x.z()), x.z());
    *normal = Eigen::Vector3d::UnitY();
    return;
  }
  *point = points_[size_t(f)];
  *normal = normals_[size_t(f)];
}

bool Heightfield::Concave(int a, int b) const {
  // b rises out of a's plane on the air side: a valley between them. b's far corner is its
  // third vertex; the centroid tells the same and needs no bookkeeping of which one it is.
  const int cell = b / 2, i = cell % (nx_ - 1), j = cell / (nx_ - 1);
  const double x0 = origin_.x() + i * spacing_.x(), z0 = origin_.y() + j * spacing_.y();
  const double dx = spacing_.x(), dz = spacing_.y();
  const Eigen::Vector3d c00(x0, Node(i, j), z0), c11(x0 + dx, Node(i + 1, j + 1), z0 + dz);
  const Eigen::Vector3d third = b % 2 == 0 ? Eigen::Vector3d(x0 + dx, Node(i + 1, j), z0)
                                           : Eigen::Vector3d(x0, Node(i, j + 1), z0 + dz);
  const Eigen::Vector3d centroid = (c00 + c11 + third) / 3.0;
  const double scale = 1e-12 * std::max({1.0, std::abs(centroid.y()), dx, dz});
  return Behind(a, centroid) > scale;
}

void Heightfield::FacesFelt(const Eigen::Vector3d& x, std::vector<int>* out) const {
  const double x1 = origin_.x() + (nx_ - 1) * spacing_.x(), z1 = origin_.y() + (nz_ - 1) * spacing_.y();
  if (x.x() < origin_.x() || x.x() > x1 || x.z() < origin_.y() || x.z() > z1) {
    if (x.y() < HeightAt(x.x(), x.z())) out->push_back(outside_face());
    return;
  }
  const int a = TriangleUnder(x.x(), x.z());
  if (!(Behind(a, x) < 0.0)) return;
  const size_t first = out->size();
  out->push_back(a);
  for (int b : valleys_[size_t(a)])
    if (b >= 0 && Behind(b, x) < 0.0) out->push_back(b);
  std::sort(out->begin() + long(first), out->end());
}

std::array<int, 3> Heightfield::Across(int a) const {
  const int cell = a / 2, i = cell % (nx_ - 1), j = cell / (nx_ - 1);
  std::array<int, 3> across = {a % 2 == 0 ? a + 1 : a - 1, -1, -1};  // the diagonal first
  if (a % 2 == 0) {
    if (j > 0) across[1] = 2 * (i + (nx_ - 1) * (j - 1)) + 1;       // the edge at z_j
    if (i + 2 < nx_) across[2] = 2 * (i + 1 + (nx_ - 1) * j) + 1;  // the edge at x_{i+1}
  } else {
    if (i > 0) across[1] = 2 * (i - 1 + (nx_ - 1) * j);            // the edge at x_i
    if (j + 2 < nz_) across[2] = 2 * (i + (nx_ - 1) * (j + 1));    // the edge at z_{j+1}
  }
  return across;
}

std::shared_ptr<const Heightfield> Heightfield::WithRegion(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                                                           const SurfaceOverrides& overrides) const {
  const double values[] = {overrides.stiffness, overrides.normal_damping, overrides.friction_damping,
                           overrides.friction_cap};
  for (size_t k = 0; k < 4; ++k)
    if (!std::isnan(values[k]) && !(values[k] >= 0 && values[k] <= 1e15))
      Refuse(SurfaceOverrides::Names()[k] + " must be a finite number >= 0, got " + std::to_string(values[k]));
  auto copy = std::make_shared<Heightfield>(*this);
  if (copy->cells_.empty()) copy->cells_.resize(size_t(num_cells()));
  int covered = 0;
  for (int j = 0; j + 1 < nz_; ++j)
    for (int i = 0; i + 1 < nx_; ++i) {
      const Eigen::Vector2d centre = origin_ + spacing_.cwiseProduct(Eigen::Vector2d(i + 0.5, j + 0.5));
      if ((centre.array() < lo.array()).any() || (centre.array() > hi.array()).any()) continue;
      SurfaceOverrides& cell = copy->cells_[size_t(i + (nx_ - 1) * j)];
      for (size_t k = 0; k < 4; ++k)
        if (!std::isnan(values[k])) cell.Set(SurfaceOverrides::Names()[k], values[k]);
      ++covered;
    }
  if (covered == 0) {
    std::ostringstream m;
    m << "no cell's centre is in the region x " << lo.x() << " .. " << hi.x() << ", z " << lo.y() << " .. " << hi.y();
    Refuse(m.str());
  }
  return copy;
}

const SurfaceOverrides& Heightfield::CellOverrides(int cell) const {
  static const SurfaceOverrides kNone;
  return cells_.empty() ? kNone : cells_.at(size_t(cell));
}

bool Heightfield::CellsEqual(const Heightfield& o) const {
  for (int c = 0; c < num_cells(); ++c)
    if (!(CellOverrides(c) == o.CellOverrides(c))) return false;
  return true;
}

}  // namespace wobble
