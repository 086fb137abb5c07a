// A recorded run as one glTF 2.0 binary file (.glb, written with tinygltf), for Blender,
// three.js and other viewers: every 3D FFD body as its rest mesh with one morph target per
// mode, animated exactly. An FFD body's point is x = t + R (b0 + B γ) (Eq. 4.2,
// dynamics/kinematics.h): linear in the mode amplitudes γ, so glTF's morphing
// (base + Σ w_j target_j) with w = γ, followed by the node's translation t and rotation R,
// is the same map, not a vertex cache. The states are sampled at the frames of the render
// (RenderTrajectory) and interpolated LINEARly between them.
//
// File layout (one scene, one animation "run", one buffer in the GLB's BIN chunk):
//   per 3D FFD body b (in the world's order, the k-th exported body):
//     node k       name = the body's name; mesh k; translation, rotation and weights of
//                  the first frame (what a viewer shows without the animation)
//     mesh k       one TRIANGLES primitive over the body's mesh (BodyDefN::mesh):
//                    POSITION   b0 of every vertex (the rest mesh in the body frame), float VEC3
//                    indices    the triangles, UNSIGNED_INT
//                    targets[j] POSITION = column j of B at every vertex (the displacement for
//                               γ_j = 1, body frame), j over the modes
//                  extras.targetNames: the modes' names (mode_<j+1> for an unnamed mode)
//   animation "run": samplers 3k, 3k+1, 3k+2 (all LINEAR, one shared input accessor: the
//                  frame times in seconds as float) driving node k's translation (t, VEC3),
//                  rotation (the unit quaternion of R, x y z w, signs kept continuous so a
//                  slerp takes the short way) and weights (γ, frames × modes floats).
// Bodies of other kinds (2D FFD, Witkin & Welch linear bodies) and the ground are not written
// (SkippedBodies() names them).
#pragma once

#include <string>
#include <vector>

#include "wobble/world/world.h"

namespace wobble::pipelines {

class GltfRecorder {
 public:
  // The bodies' rest meshes and mode columns are taken from the world now; it must outlive
  // the recorder (AddFrame reads its state).
  explicit GltfRecorder(const World* world);
  // Appends the world's current state at its time as the next frame (times must increase).
  void AddFrame();
  // Writes the .glb atomically (path + ".tmp", then renamed). std::runtime_error naming the
  // file when it cannot be written; std::logic_error when no frame was added.
  void Write(const std::string& path) const;
  // The file's bytes (what Write writes).
  std::string Bytes() const;

  int num_frames() const { return int(times_.size()); }
  int num_bodies() const { return int(bodies_.size()); }
  // Bodies of the world not written (not 3D FFD bodies), by name.
  const std::vector<std::string>& SkippedBodies() const { return skipped_; }

 private:
  struct Body {
    int index;  // in the world
    std::string name;
    int num_modes;
    std::vector<float> rest;                  // b0: 3 per vertex
    std::vector<std::vector<float>> targets;  // per mode: B's column, 3 per vertex
    std::vector<unsigned> triangles;          // 3 per triangle
    std::vector<std::string> mode_names;
    std::vector<float> translation, rotation, weights;  // per frame: 3, 4 (x y z w), num_modes
  };
  const World* world_;
  std::vector<Body> bodies_;
  std::vector<std::string> skipped_;
  std::vector<double> times_;
};

}  // namespace wobble::pipelines
