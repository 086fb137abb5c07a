// A deformation mode: one displacement d_c per lattice control point (Eq. 4.2), scaled by
// the amplitude γ, with the mode's own potential V = K γ² (§4.7) and damping −c γ̇. The same
// type serves 2D lattices and 3D (trivariate) ones.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace wobble {

template <int Dim> struct DeformationModeN {
  std::string name;
  // lattice size the displacements belong to: control points per axis (s, t[, u])
  std::array<int, Dim> lattice_size = DefaultSize();
  // d_c at the lattice's flat index (LatticeN: row-major in (i, j[, k])), body-frame units.
  std::vector<Eigen::Matrix<double, Dim, 1>> displacement;
  double stiffness = 0.0;  // K in V = K γ²
  double damping = 0.0;    // c in Q = −c γ̇
  bool active = false;     // driven by a controller (chapter 5) rather than left passive
  std::string source;      // "FILE:LINE" it was read from, for errors (empty: made in code)

  static std::array<int, Dim> DefaultSize() {
    std::array<int, Dim> s;
    s.fill(4);
    return s;
  }
};

using DeformationMode = DeformationModeN<2>;

}  // namespace wobble
