#include "wobble/dynamics/terrain.h"

#include <cmath>
#include <sstream>

#include "wobble/core/errors.h"

namespace wobble {

namespace {

bool SameOrBothNan(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

[[noreturn]] void Refuse(const std::string& what) { throw InputError("terrain: " + what); }

}  // namespace

bool SurfaceOverrides::Set(const std::string& name, double value) {
  if (name == "grconst") stiffness = value;
  else if (name == "grdam") normal_damping = value;
  else if (name == "frconst") friction_damping = value;
  else if (name == "frsin") friction_cap = value;
  else return false;
  return true;
}

const std::vector<std::string>& SurfaceOverrides::Names() {
  static const std::vector<std::string> names = {"grconst", "grdam", "frconst", "frsin"};
  return names;
}

bool SurfaceOverrides::operator==(const SurfaceOverrides& o) const {
  return SameOrBothNan(stiffness, o.stiffness) && SameOrBothNan(normal_damping, o.normal_damping) &&
         SameOrBothNan(friction_damping, o.friction_damping) && SameOrBothNan(friction_cap, o.friction_cap);
}

std::shared_ptr<const Terrain> Terrain::Make(std::vector<Eigen::Vector2d> vertices,
                                             std::vector<SurfaceOverrides> segments) {
  const int nv = int(vertices.size());
  if (nv < 2) Refuse("needs at least two vertices, got " + std::to_string(nv));
  // |coordinates| up to 1e15: face lengths and slab tests stay exact to far below a unit
  constexpr double kLargest = 1e15;
  for (int i = 0; i < nv; ++i) {
    const Eigen::Vector2d& p = vertices[i];
    if (!(std::abs(p.x()) <= kLargest && std::abs(p.y()) <= kLargest)) {
      std::ostringstream m;
      m << "vertex " << i + 1 << " (" << p.x() << ", " << p.y() << ") is not a finite number of at most 1e15";
      Refuse(m.str());
    }
    if (i == 0) continue;
    const Eigen::Vector2d& q = vertices[i - 1];
    if (p.x() < q.x()) {
      std::ostringstream m;
      m << "vertex " << i + 1 << " (x " << p.x() << ") is left of vertex " << i << " (x " << q.x()
        << "): the profile runs left to right, the solid below it";
      Refuse(m.str());
    }
    if (p == q) Refuse("vertices " + std::to_string(i) + " and " + std::to_string(i + 1) + " are the same point");
    if (i >= 2 && p.x() == q.x() && q.x() == vertices[i - 2].x())
      Refuse("vertices " + std::to_string(i - 1) + " to " + std::to_string(i + 1) +
             " are one vertical line: a cliff is one face, give its two ends only");
  }
  if (!segments.empty() && int(segments.size()) != nv - 1)
    Refuse("has " + std::to_string(nv - 1) + " segments but parameters for " + std::to_string(segments.size()));
  for (size_t i = 0; i < segments.size(); ++i) {
    const SurfaceOverrides& s = segments[i];
    for (double v : {s.stiffness, s.normal_damping, s.friction_damping, s.friction_cap})
      if (!std::isnan(v) && !(v >= 0 && v <= 1e30))
        Refuse("segment " + std::to_string(i + 1) + " has a parameter that is not a number in [0, 1e30]");
  }

  auto terrain = std::shared_ptr<Terrain>(new Terrain);
  Terrain& t = *terrain;
  t.vertices_ = std::move(vertices);
  t.segments_ = std::move(segments);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Eigen::Vector2d level = Eigen::Vector2d::UnitX();
  auto add = [&](const Eigen::Vector2d& point, const Eigen::Vector2d& tau, double s0, double s1, int segment) {
    t.faces_.push_back({point, Eigen::Vector2d(-tau.y(), tau.x()), tau, s0, s1, segment});
  };
  add(t.vertices_.front(), level, -kInf, 0.0, -1);
  for (int i = 0; i + 1 < nv; ++i) {
    const Eigen::Vector2d d = t.vertices_[i + 1] - t.vertices_[i];
    add(t.vertices_[i], d.normalized(), 0.0, d.norm(), i);
  }
  add(t.vertices_.back(), level, 0.0, kInf, -1);
  // a valley where the profile turns left (counter-clockwise): the slabs of both faces reach
  // past the corner, so a point pressed into it feels both
  const int nf = int(t.faces_.size());
  t.concave_after_.assign(nf, 0);
  for (int i = 0; i + 1 < nf; ++i) {
    if (Cross(t.faces_[i].tau, t.faces_[i + 1].tau) <= 0) continue;
    t.concave_after_[i] = 1;
    t.faces_[i].s1 = kInf;
    t.faces_[i + 1].s0 = -kInf;
  }
  return terrain;
}

GroundFace Terrain::Face(int i, double stiffness, double normal_damping, double friction_damping,
                         double friction_cap) const {
  const FaceGeometry& f = faces_[i];
  GroundFace g;
  g.point = f.point;
  g.n = f.n;
  g.tau = f.tau;
  const SurfaceOverrides* o = f.segment >= 0 && !segments_.empty() ? &segments_[f.segment] : nullptr;
  auto pick = [](double own, double ground) { return std::isnan(own) ? ground : own; };
  g.stiffness = o ? pick(o->stiffness, stiffness) : stiffness;
  g.normal_damping = o ? pick(o->normal_damping, normal_damping) : normal_damping;
  g.friction_damping = o ? pick(o->friction_damping, friction_damping) : friction_damping;
  g.friction_cap = o ? pick(o->friction_cap, friction_cap) : friction_cap;
  return g;
}

double Terrain::HeightAt(double x) const {
  const std::vector<Eigen::Vector2d>& v = vertices_;
  if (x < v.front().x()) return v.front().y();
  if (x > v.back().x()) return v.back().y();
  // the last vertex at or left of x
  const auto after = std::upper_bound(v.begin(), v.end(), x, [](double a, const Eigen::Vector2d& p) { return a < p.x(); });
  const long i = long(after - v.begin()) - 1;
  if (v[i].x() == x) {  // on a vertex; at a cliff's x, its top
    double h = v[i].y();
    if (i > 0 && v[i - 1].x() == x) h = std::max(h, v[i - 1].y());
    return h;
  }
  const Eigen::Vector2d& a = v[i];
  const Eigen::Vector2d& b = v[i + 1];
  return a.y() + (b.y() - a.y()) * ((x - a.x()) / (b.x() - a.x()));
}

double Terrain::MaxHeight(double x0, double x1) const {
  double h = std::max(HeightAt(x0), HeightAt(x1));
  const std::vector<Eigen::Vector2d>& v = vertices_;
  auto first = std::lower_bound(v.begin(), v.end(), x0, [](const Eigen::Vector2d& p, double a) { return p.x() < a; });
  for (auto it = first; it != v.end() && it->x() <= x1; ++it) h = std::max(h, it->y());
  return h;
}

bool Terrain::Behind(int i, const Eigen::Vector2d& x, double* depth) const {
  const FaceGeometry& f = faces_[i];
  const Eigen::Vector2d d = x - f.point;
  const double h = f.n.dot(d);
  if (!(h < 0)) return false;
  const double s = f.tau.dot(d);
  if (!(s >= f.s0 && s <= f.s1)) return false;
  *depth = -h;
  return true;
}

}  // namespace wobble
