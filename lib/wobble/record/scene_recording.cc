#include "wobble/record/scene_recording.h"

#include <cassert>

namespace wobble::record {

SceneFrame CaptureFrame(const World& world) {
  SceneFrame f;
  f.time = world.time();
  for (int b = 0; b < world.num_bodies(); ++b) {
    if (world.kind(b) == BodyKind::kLinear) {
      f.state.push_back(world.linear_R(b));
      f.rate.push_back(world.linear_R_dot(b));
    } else {
      f.state.push_back(world.state(b).q);
      f.rate.push_back(world.state(b).qd);
    }
  }
  return f;
}

void RestoreFrame(World& world, const SceneFrame& f) {
  assert(int(f.state.size()) == world.num_bodies());
  for (int b = 0; b < world.num_bodies(); ++b) {
    if (world.kind(b) == BodyKind::kLinear)
      world.SetLinearState(b, f.state[b], f.rate[b]);
    else
      world.SetState(b, f.state[b].col(0), f.rate[b].col(0));
  }
  world.SetTime(f.time);
}

}  // namespace wobble::record
