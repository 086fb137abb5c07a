#include "wobble/body/linear_shapes.h"

#include <cmath>

#include "wobble/core/limits.h"

#include <stdexcept>

namespace wobble {

int LinearDrawing::dim() const {
  if (!polylines.empty() && !polylines[0].points.empty()) return int(polylines[0].points[0].size());
  if (!vertices.empty()) return int(vertices[0].size());
  return 0;
}

namespace {

// The segment a → b cut into `pieces`, both ends included.
std::vector<Eigen::VectorXd> Cut(const Eigen::VectorXd& a, const Eigen::VectorXd& b, int pieces) {
  std::vector<Eigen::VectorXd> out;
  for (int i = 0; i <= pieces; ++i) out.push_back(a + (b - a) * (double(i) / pieces));
  return out;
}

// A closed outline through the corners, every side cut into `pieces`.
LinearDrawing::Polyline Outline(const std::vector<Eigen::VectorXd>& corners, int pieces) {
  LinearDrawing::Polyline line;
  line.closed = true;
  for (size_t i = 0; i < corners.size(); ++i) {
    std::vector<Eigen::VectorXd> side = Cut(corners[i], corners[(i + 1) % corners.size()], pieces);
    line.points.insert(line.points.end(), side.begin(), side.end() - 1);  // the next side starts there
  }
  return line;
}

// A grid of pieces × pieces quads on the parallelogram o + s a + t b, s, t in [0, 1], as triangles.
void AddQuadGrid(const Eigen::VectorXd& o, const Eigen::VectorXd& a, const Eigen::VectorXd& b, int pieces,
                 LinearDrawing* d) {
  const int base = int(d->vertices.size());
  for (int j = 0; j <= pieces; ++j)
    for (int i = 0; i <= pieces; ++i) d->vertices.push_back(o + a * (double(i) / pieces) + b * (double(j) / pieces));
  auto id = [&](int i, int j) { return base + j * (pieces + 1) + i; };
  for (int j = 0; j < pieces; ++j)
    for (int i = 0; i < pieces; ++i) {
      d->triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      d->triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
}

// A triangle a, b, c cut into pieces² small triangles.
void AddTriangleGrid(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& c, int pieces,
                     LinearDrawing* d) {
  const int base = int(d->vertices.size());
  // rows j = 0..pieces from edge ab towards c; row j has pieces − j + 1 vertices
  std::vector<int> row_start;
  for (int j = 0; j <= pieces; ++j) {
    row_start.push_back(int(d->vertices.size()) - base);
    for (int i = 0; i <= pieces - j; ++i)
      d->vertices.push_back(a + (b - a) * (double(i) / pieces) + (c - a) * (double(j) / pieces));
  }
  auto id = [&](int i, int j) { return base + row_start[j] + i; };
  for (int j = 0; j < pieces; ++j)
    for (int i = 0; i < pieces - j; ++i) {
      d->triangles.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
      if (i < pieces - j - 1) d->triangles.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
    }
}

Eigen::VectorXd P(double x, double y) { return (Eigen::VectorXd(2) << x, y).finished(); }
Eigen::VectorXd P(double x, double y, double z) { return (Eigen::VectorXd(3) << x, y, z).finished(); }

}  // namespace

LinearDrawing MakeBoxDrawing(const Eigen::VectorXd& h, int pieces) {
  if (pieces < 1) throw std::invalid_argument("box drawing: pieces must be >= 1");
  LinearDrawing d;
  if (h.size() == 2) {
    d.polylines.push_back(Outline({P(-h[0], -h[1]), P(h[0], -h[1]), P(h[0], h[1]), P(-h[0], h[1])}, pieces));
    return d;
  }
  if (h.size() != 3) throw std::invalid_argument("box drawing: 2 or 3 half extents");
  // the 12 edges: 4 along each axis
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (double s1 : {-1.0, 1.0})
      for (double s2 : {-1.0, 1.0}) {
        Eigen::VectorXd from(3), to(3);
        from[axis] = -h[axis];
        to[axis] = h[axis];
        from[a1] = to[a1] = s1 * h[a1];
        from[a2] = to[a2] = s2 * h[a2];
        d.polylines.push_back({Cut(from, to, pieces), false});
      }
  }
  // the six faces
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (double side : {-1.0, 1.0}) {
      Eigen::VectorXd o = Eigen::VectorXd::Zero(3), ea = Eigen::VectorXd::Zero(3), eb = Eigen::VectorXd::Zero(3);
      o[axis] = side * h[axis];
      o[a1] = -h[a1];
      o[a2] = -h[a2];
      ea[a1] = 2 * h[a1];
      eb[a2] = 2 * h[a2];
      AddQuadGrid(o, ea, eb, pieces, &d);
    }
  }
  return d;
}

LinearDrawing MakePyramidDrawing(int dim, double w, double height, int pieces) {
  if (pieces < 1) throw std::invalid_argument("pyramid drawing: pieces must be >= 1");
  LinearDrawing d;
  if (dim == 2) {
    d.polylines.push_back(Outline({P(-w, 0), P(w, 0), P(0, height)}, pieces));
    return d;
  }
  if (dim != 3) throw std::invalid_argument("pyramid drawing: dim must be 2 or 3");
  const std::vector<Eigen::VectorXd> base = {P(-w, 0, -w), P(w, 0, -w), P(w, 0, w), P(-w, 0, w)};
  const Eigen::VectorXd apex = P(0, height, 0);
  d.polylines.push_back(Outline(base, pieces));
  for (const Eigen::VectorXd& c : base) d.polylines.push_back({Cut(c, apex, pieces), false});
  for (int i = 0; i < 4; ++i) AddTriangleGrid(base[i], base[(i + 1) % 4], apex, pieces, &d);
  AddQuadGrid(base[0], base[1] - base[0], base[3] - base[0], pieces, &d);
  return d;
}

LinearBodyDef MakePyramidBody(const std::string& name, int dim, LinearOrder order, double w, double height, int levels,
                              int per_side, double mass) {
  if (dim != 2 && dim != 3) throw std::invalid_argument("pyramid '" + name + "': dim must be 2 or 3");
  if (levels < 2 || per_side < 2) throw std::invalid_argument("pyramid '" + name + "': levels and per_side must be >= 2");
  if (!(w > 0) || !(height > 0)) throw std::invalid_argument("pyramid '" + name + "': sizes must be positive");
  CheckedCount(double(levels) * std::pow(double(per_side), dim - 1), 1, kMaxLinearPoints,
               "pyramid '" + name + "': its mass points (levels x grid^(dim-1))");
  LinearBodyDef def;
  def.name = name;
  def.dim = dim;
  def.order = order;
  for (int k = 0; k < levels; ++k) {
    const double y = height * k / levels;  // the apex (k = levels) is added alone below
    const double half = w * (1.0 - y / height);
    for (int i = 0; i < per_side; ++i) {
      const double x = half * (-1.0 + 2.0 * i / (per_side - 1));
      if (dim == 2) {
        def.points.push_back(P(x, y));
        continue;
      }
      for (int j = 0; j < per_side; ++j) def.points.push_back(P(x, y, half * (-1.0 + 2.0 * j / (per_side - 1))));
    }
  }
  def.points.push_back(dim == 2 ? P(0, height) : P(0, height, 0));
  def.masses.assign(def.points.size(), mass / double(def.points.size()));
  return def;
}

}  // namespace wobble
