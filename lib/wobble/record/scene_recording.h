// Snapshots of a World's bodies, so that a run can be drawn after it was simulated
// (the pictures frame the whole motion, which is known only at the end). Cheap: a few small
// matrices per frame.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "wobble/world/world.h"

namespace wobble::record {

struct SceneFrame {
  double time = 0.0;
  // Per body: linear R and Ṙ (d×n); FFD q and q̇ as one column each.
  std::vector<Eigen::MatrixXd> state, rate;
};

SceneFrame CaptureFrame(const World& world);
// Puts every body back into the frame's state and the world's clock at its time. The frame
// must come from this world (same bodies); constraints are not touched.
void RestoreFrame(World& world, const SceneFrame& frame);

}  // namespace wobble::record
