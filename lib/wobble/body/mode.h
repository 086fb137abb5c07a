// A deformation mode: one displacement d_ij per lattice control point (Eq. 4.2), scaled by
// the amplitude γ, with the mode's own potential V = K γ² (§4.7) and damping −c γ̇.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace wobble {

struct DeformationMode {
  std::string name;
  int num_s = 4, num_t = 4;  // lattice size the displacements belong to
  // d_ij at flat index i*num_t + j (i along s, j along t), body-frame units.
  std::vector<Eigen::Vector2d> displacement;
  double stiffness = 0.0;  // K in V = K γ²
  double damping = 0.0;    // c in Q = −c γ̇
  bool active = false;     // driven by a controller (chapter 5) rather than left passive
  std::string source;      // "FILE:LINE" it was read from, for errors (empty: made in code)
};

}  // namespace wobble
