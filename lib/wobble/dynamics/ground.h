// The ground a body stands on: the 2D line or terrain of straight faces (Ground, §4.9), the 3D
// plane or heightfield (GroundPlane). Geometry and ground constants only; the penalty forces
// are in ground_line.h (2D) and ground_plane.h (3D).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <memory>

#include "wobble/core/types.h"
#include "wobble/dynamics/heightfield.h"
#include "wobble/dynamics/terrain.h"

namespace wobble {

// The ground line through `point` at angle `slope` (radians, counter-clockwise from +x).
// World y points up, gravity is −y.
struct Ground {
  bool enabled = true;
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  double slope = 0.0;
  double stiffness = 4500.0;       // K_d of Eq. 4.24/4.25 (appendix C: grconst)
  double normal_damping = 550.0;   // C_dam, damping along the normal (grdam)
  double friction_damping = 50.0;  // FR_dam, damping along the tangent (frconst)
  double friction_cap = 0.1;       // tan θ: |friction / normal force| never exceeds it
  // A point deeper than this stops the run (runaway penetration). 0 means automatic: half
  // the shorter lattice side of the body.
  double max_penetration = 0.0;
  // A terrain of straight faces (terrain.h) in place of the line through `point`; the
  // parameters above are those of every face that has none of its own.
  std::shared_ptr<const Terrain> terrain;
  // The 3D bodies' ground in place of the plane of this line (GroundPlaneOf in world.h); 2D
  // bodies never feel it.
  std::shared_ptr<const Heightfield> heightfield;

  Eigen::Vector2d tangent() const { return {std::cos(slope), std::sin(slope)}; }
  Eigen::Vector2d normal() const { return {-std::sin(slope), std::cos(slope)}; }
  bool operator==(const Ground& o) const {
    return enabled == o.enabled && point == o.point && slope == o.slope && stiffness == o.stiffness &&
           normal_damping == o.normal_damping && friction_damping == o.friction_damping &&
           friction_cap == o.friction_cap && max_penetration == o.max_penetration &&
           (terrain == o.terrain || (terrain && o.terrain && *terrain == *o.terrain)) &&
           (heightfield == o.heightfield || (heightfield && o.heightfield && *heightfield == *o.heightfield));
  }
  // Face i of the ground (0 for the line) with its parameters resolved.
  GroundFace Face(int i) const {
    if (terrain) return terrain->Face(i, stiffness, normal_damping, friction_damping, friction_cap);
    GroundFace f;
    f.point = point;
    f.n = normal();
    f.tau = tangent();
    f.stiffness = stiffness;
    f.normal_damping = normal_damping;
    f.friction_damping = friction_damping;
    f.friction_cap = friction_cap;
    return f;
  }
};

// The 3D ground: a plane of any normal, or a heightfield in its place (heightfield.h), with the
// ground constants of the 2D Ground (forces.h).
struct GroundPlane {
  bool enabled = false;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit, pointing out of the ground
  double stiffness = 4500.0, normal_damping = 550.0, friction_damping = 50.0, friction_cap = 0.1;
  std::shared_ptr<const Heightfield> heightfield;  // when set, the ground (point and normal unused)
  bool operator==(const GroundPlane& o) const {
    return enabled == o.enabled && point == o.point && normal == o.normal && stiffness == o.stiffness &&
           normal_damping == o.normal_damping && friction_damping == o.friction_damping &&
           friction_cap == o.friction_cap && heightfield == o.heightfield;
  }
  template <class T> T Height(const Vec3<T>& x) const { return normal.cast<T>().dot(x - point.cast<T>()); }
  // Face f's plane near x with its constants: the plane itself (face 0) or a heightfield face
  // (with its cell's own constants, where set).
  // Built field by field, not copied: a copy would touch the shared_ptr's atomic count once
  // per (point, face) per force evaluation.
  GroundPlane Face(int f, const Eigen::Vector3d& x) const {
    GroundPlane p;
    p.enabled = enabled;
    p.stiffness = stiffness;
    p.normal_damping = normal_damping;
    p.friction_damping = friction_damping;
    p.friction_cap = friction_cap;
    if (heightfield) {
      heightfield->FacePlane(f, x, &p.point, &p.normal);
      if (const SurfaceOverrides* own = heightfield->FaceOverrides(f)) {  // the cell's own constants
        if (!std::isnan(own->stiffness)) p.stiffness = own->stiffness;
        if (!std::isnan(own->normal_damping)) p.normal_damping = own->normal_damping;
        if (!std::isnan(own->friction_damping)) p.friction_damping = own->friction_damping;
        if (!std::isnan(own->friction_cap)) p.friction_cap = own->friction_cap;
      }
    } else {
      p.point = point;
      p.normal = normal;
    }
    return p;
  }
};

// The ground of a body of dimension Dim: the 2D line or terrain (Ground), the 3D plane or
// heightfield (GroundPlane).
template <int Dim> struct GroundOfDim;
template <> struct GroundOfDim<2> { using type = Ground; };
template <> struct GroundOfDim<3> { using type = GroundPlane; };
template <int Dim> using GroundOf = typename GroundOfDim<Dim>::type;

}  // namespace wobble
