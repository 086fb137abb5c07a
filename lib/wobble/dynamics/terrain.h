// Terrain: a 2D ground made of straight faces (cliffs, steps, slopes, a valley floor), each with
// its own penalty parameters (§4.9, Eq. 4.24/4.25). The solid is below a piecewise-linear
// profile y = h(x) whose vertices run left to right; two vertices at the same x make a vertical
// face (a cliff). Beyond its ends the profile continues level.
//
// Which faces a point inside the solid feels (forces.h applies them, one contact per face):
//   - a face only when the point is behind its line and within its slab (the strip swept by
//     the face along its normal), the slab reaching past an end where the corner is concave;
//   - the faces it already touches (its anchors) while that holds;
//   - a point that touches none enters through the face whose line it crossed last
//     (depth / approach speed smallest; the nearest when it does not move);
//   - then every face that meets a felt face at a concave corner (a valley's floor and wall),
//     never one across a convex corner (a cliff's top and face): a point that lands near the
//     edge of a cliff is pushed up, not sideways, and leaves the top face's contact the moment
//     it passes the edge, so it neither sticks to the wall nor tunnels through it.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace wobble {

// Penalty parameters of one face; NaN means "the ground's" (Ground's own fields, `set`).
struct SurfaceOverrides {
  double stiffness = std::numeric_limits<double>::quiet_NaN();
  double normal_damping = std::numeric_limits<double>::quiet_NaN();
  double friction_damping = std::numeric_limits<double>::quiet_NaN();
  double friction_cap = std::numeric_limits<double>::quiet_NaN();
  bool operator==(const SurfaceOverrides& o) const;
  // Sets the constant `set` names `name` (grconst, grdam, frconst or frsin: appendix C's names
  // of K_d, C_dam, FR_dam, tan θ); false for any other name.
  bool Set(const std::string& name, double value);
  static const std::vector<std::string>& Names();
};

// One straight piece of the ground with its parameters resolved: a point on its line, the
// outward normal n (into the air), the tangent τ (n = τ rotated by +90°), and Eq. 4.24/4.25's
// K_d, C_dam, FR_dam and tan θ.
struct GroundFace {
  Eigen::Vector2d point = Eigen::Vector2d::Zero(), n = Eigen::Vector2d::UnitY(), tau = Eigen::Vector2d::UnitX();
  double stiffness = 0, normal_damping = 0, friction_damping = 0, friction_cap = 0;
  // Signed height of x above the face's line (negative behind it).
  template <class V> auto Height(const V& x) const {
    using T = typename V::Scalar;
    return n.cast<T>().dot(x - point.cast<T>());
  }
};

class Terrain {
 public:
  // Throws InputError (naming the vertex or segment) unless: at least two vertices, all
  // finite; x never decreasing; no two consecutive vertices equal; no three in a vertical
  // line (one cliff face, not two); `segments` empty or one per segment, each override
  // finite and >= 0 (a cap is a ratio, stiffness and damping rates).
  static std::shared_ptr<const Terrain> Make(std::vector<Eigen::Vector2d> vertices,
                                             std::vector<SurfaceOverrides> segments = {});

  const std::vector<Eigen::Vector2d>& vertices() const { return vertices_; }
  const std::vector<SurfaceOverrides>& segments() const { return segments_; }

  // Faces: 0 is the level continuation left of the first vertex, 1 .. n−1 the segments,
  // n the level continuation right of the last vertex.
  int num_faces() const { return int(faces_.size()); }
  // Face i with the ground's parameters where the segment has no override of its own.
  GroundFace Face(int i, double stiffness, double normal_damping, double friction_damping, double friction_cap) const;
  const Eigen::Vector2d& FaceNormal(int i) const { return faces_[i].n; }

  // The surface height at x (at a cliff's x, the top of the cliff).
  double HeightAt(double x) const;
  // The highest surface point over [x0, x1].
  double MaxHeight(double x0, double x1) const;
  bool Inside(const Eigen::Vector2d& x) const { return x.y() < HeightAt(x.x()); }

  // The faces a point at x inside the solid, moving at v, feels, in increasing order (rules
  // above); `touching(i)` says whether it already has a contact on face i. Appends to *out.
  template <class Touching>
  void FacesFelt(const Eigen::Vector2d& x, const Eigen::Vector2d& v, Touching&& touching, std::vector<int>* out) const;

  bool operator==(const Terrain& o) const { return vertices_ == o.vertices_ && segments_ == o.segments_; }

 private:
  struct FaceGeometry {
    Eigen::Vector2d point, n, tau;
    double s0, s1;  // the slab: τ·(x − point) within [s0, s1] (±∞ past a concave corner or an end)
    int segment;    // index into segments_, −1 for the level continuations
  };
  // Behind face i's line and inside its slab; *depth is how far behind.
  bool Behind(int i, const Eigen::Vector2d& x, double* depth) const;
  bool ConcaveAfter(int i) const { return concave_after_[i]; }  // faces i and i+1 meet in a valley

  std::vector<Eigen::Vector2d> vertices_;
  std::vector<SurfaceOverrides> segments_;
  std::vector<FaceGeometry> faces_;
  std::vector<char> concave_after_;
};

template <class Touching>
void Terrain::FacesFelt(const Eigen::Vector2d& x, const Eigen::Vector2d& v, Touching&& touching,
                        std::vector<int>* out) const {
  // Candidates. Terrains are tens of faces, so every face is tried (a heightfield of
  // thousands would want the faces near x by a search on the vertices' x first).
  const int n = num_faces();
  const size_t first = out->size();
  int entry = -1;
  double entry_time = std::numeric_limits<double>::infinity(), entry_depth = entry_time;
  bool any_touching = false;
  thread_local std::vector<char> candidate;
  candidate.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    double depth;
    if (!Behind(i, x, &depth)) continue;
    candidate[i] = 1;
    if (touching(i)) {
      any_touching = true;
      out->push_back(i);
      continue;
    }
    // the face whose line was crossed last: depth over the speed into it
    const double approach = -faces_[i].n.dot(v);
    const double time = approach > 0 ? depth / approach : std::numeric_limits<double>::infinity();
    if (time < entry_time || (time == entry_time && depth < entry_depth)) {
      entry = i;
      entry_time = time;
      entry_depth = depth;
    }
  }
  if (!any_touching) {
    if (entry < 0) return;
    out->push_back(entry);
  }
  // grow across concave corners, both ways from every felt face
  for (size_t k = first; k < out->size(); ++k) {
    const int i = (*out)[k];
    for (int j : {i - 1, i + 1}) {
      if (j < 0 || j >= n || !candidate[j]) continue;
      if (!ConcaveAfter(std::min(i, j))) continue;
      candidate[j] = 0;
      bool felt = false;
      for (size_t m = first; m < out->size(); ++m) felt = felt || (*out)[m] == j;
      if (!felt) out->push_back(j);
    }
  }
  std::sort(out->begin() + long(first), out->end());
}

}  // namespace wobble
