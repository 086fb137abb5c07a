// A recorded run as one glTF 2.0 binary file (.glb, written with tinygltf), for Blender,
// three.js and other viewers: every body as a mesh whose morph targets and node animation
// reproduce wobble's deformation exactly, not as a vertex cache.
//   FFD bodies (2D and 3D): a point is x = t + R (b0 + B γ) (Eq. 4.2, dynamics/kinematics.h),
//     linear in the mode amplitudes γ: the mesh holds b0 of every vertex and one morph target
//     per mode (B's column: the displacement at γ_j = 1), the weights are γ, and the node's
//     translation and rotation are t and R; glTF's base + Σ w_j target_j moved by the node is
//     the same map.
//   Witkin & Welch linear bodies: x = R p(u) (body/linear_body.h) is linear in R's entries: the
//     mesh's base is 0 and target (i, j), named R_i_j, is p_j(u) along axis i; the weights are
//     R's entries and the node does not move.
// States are sampled at the frames of the render (RenderTrajectory) and interpolated LINEARly
// between them.
//
// File layout (one scene, one animation "run", one buffer in the GLB's BIN chunk, one
// material "wobble", double-sided: a drawing's fill and a user's mesh may face either way):
//   per body drawn (the world's order; the k-th written is node k and mesh k, both named as the body):
//     node k       translation, rotation and weights of the first frame (what a viewer shows
//                  without playing the animation); a 2D body at z = 0, turning about z
//     mesh k       POSITION (base, float VEC3) and the targets' POSITIONs shared by up to two
//                  primitives: TRIANGLES (a body's mesh, BodyDefN::mesh or a linear drawing's
//                  surface; a 2D FFD body's closed outlines filled, triangulated at rest) and
//                  LINES (the drawing's polylines, resampled shape_samples times per segment
//                  as ShapeSource draws them). Vertex order: the mesh's vertices, then the
//                  drawing's samples (ShapeSource's order); indices UNSIGNED_INT.
//                  extras.targetNames: the modes' names (mode_<j+1> for an unnamed mode)
//   node "ground" (last, when a body stands on the ground): the ground or terrain as wobble
//                  draws it at the first frame (GroundSource), a static mesh
//   node "camera" (last, when the frames were rendered: RenderTrajectory with frames or exr):
//                  the render's camera (perspective yfov = the view angle, or orthographic
//                  with the parallel scale, as at the first frame), its translation and
//                  rotation keyed per frame (glTF's camera looks down its −z, +y up)
//   animation "run": per moving body samplers sharing one input accessor (the frame times in
//                  seconds, float): FFD bodies translation (VEC3), rotation (x y z w, signs kept
//                  continuous so a slerp takes the short way) and weights (frames × targets
//                  floats); linear bodies weights only.
// Bodies left out (a linear body without a drawing, a body with nothing to draw) are named by
// SkippedBodies().
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "wobble/body/linear_shapes.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

// A camera at one frame, as VTK's (vtkCamera): where it is, what it looks at, which way is up.
struct GltfCamera {
  Eigen::Vector3d position = Eigen::Vector3d::UnitZ(), focal_point = Eigen::Vector3d::Zero(),
                  view_up = Eigen::Vector3d::UnitY();
  bool parallel = false;
  double view_angle_deg = 30.0;  // vertical, perspective
  double parallel_scale = 1.0;   // half the view's height in world units, parallel
  double aspect = 4.0 / 3.0;     // width / height
};

class GltfRecorder {
 public:
  // The bodies' rest vertices and targets are taken from the world now; it must outlive the
  // recorder (AddFrame reads its state). drawings[b]: linear body b's drawing (SceneSpec's);
  // shape_samples: pieces per drawing segment of an FFD body (ShapeSource's).
  explicit GltfRecorder(const World* world, const std::vector<LinearDrawing>& drawings = {}, int shape_samples = 16);
  // Appends the world's current state at its time as the next frame (times must increase);
  // the first also takes the ground.
  void AddFrame();
  // The camera of the frame AddFrame added last (every frame has one, or the file has no camera).
  void AddCameraFrame(const GltfCamera& camera);
  // Writes the .glb atomically (path + ".tmp", then renamed). std::runtime_error naming the
  // file when it cannot be written; std::logic_error when no frame was added.
  void Write(const std::string& path) const;
  // The file's bytes (what Write writes).
  std::string Bytes() const;

  int num_frames() const { return int(times_.size()); }
  int num_bodies() const;  // bodies written (not the ground)
  const std::vector<std::string>& SkippedBodies() const { return skipped_; }

 private:
  struct Part {  // one node and mesh of the file
    enum class Motion { kStatic, kFfd, kLinear } motion = Motion::kStatic;
    int body = -1;  // in the world
    std::string name;
    std::vector<float> rest;                  // 3 per vertex
    std::vector<std::vector<float>> targets;  // per target, 3 per vertex
    std::vector<std::string> target_names;
    std::vector<unsigned> triangles, lines;   // 3 and 2 indices per element
    std::vector<float> translation, rotation, weights;  // per frame: 3, 4 (x y z w), targets
  };
  template <int Dim> Part FfdPart(int body) const;
  Part LinearPart(int body, const LinearDrawing& drawing) const;
  void AddGround();
  template <int Dim> void KeyFfd(Part* part) const;

  const World* world_;
  int shape_samples_;
  std::vector<Part> parts_;
  std::vector<std::string> skipped_;
  std::vector<double> times_;
  std::vector<GltfCamera> cameras_;  // per frame, or none
};

}  // namespace wobble::pipelines
