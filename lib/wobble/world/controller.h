// What the world calls every step (MuJoCo's mjcb_control is the model): a controller sets PD
// targets, moves kinematic bodies, pulls points, switches constraints or keeps accounts.
// Pose graphs, keyframes, held points, behaviours and paths, the viewer's sliders and mouse
// pulls are all controllers (wobble/control); the recorder is called after them.
//
// World::Step calls, in the order the controllers were added,
//   BeforeStep(world)   at the step's start time, before any body moves;
//   AfterStep(world)    after the step was accepted (world.time() is the new time).
// A refused step (status() not ok) calls no AfterStep. A controller may throw to stop a run
// (behaviours do, with what they could not do); the exception leaves World::Step.
#pragma once

namespace wobble {

class World;

class Controller {
 public:
  virtual ~Controller() = default;
  virtual void BeforeStep(World&) {}
  virtual void AfterStep(World&) {}
};

}  // namespace wobble
