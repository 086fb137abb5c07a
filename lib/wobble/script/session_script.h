// A script (the language of script.h) that replays a session run outside the interpreter —
// the interactive viewer's (`wobble view`): the setup, the start state and every change of the
// modes' PD targets, so that `wobble run FILE` steps the same world through the same targets
// and ends in the same state.
//
// How the targets are replayed: every mode is made active with `codamA 0` and `assign` gives
// each its stiffness and damping as the session's body had them (codamA already included), so
// the body is the same; the target changes become an acyclic pose graph (`set cyclic F`), one
// pose per change, whose boundaries fall half a step before the step where the change was
// made, so the interpreter's PoseAt(n dt) picks the same pose for every step n without
// rounding doubts. Numbers are written in shortest round-trip form (exact doubles).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/world/world.h"

namespace wobble::script {

struct SessionRecord {
  std::string object_path;              // as load_obj takes it (absolute is safest)
  std::vector<std::string> mode_paths;  // as load_def takes them, in order
  const BodyModel* body = nullptr;      // the body the session stepped (for K, c, D)
  WorldOptions world;                   // ground, gravity, integrator, dt, the scene's springs
  Eigen::VectorXd q0, qd0;              // state at the session's start
  double t0 = 0.0;                      // time at the session's start
  struct Segment {
    long step = 0;            // the targets hold from this step (0-based from the start) on
    Eigen::VectorXd targets;  // one per mode
  };
  std::vector<Segment> segments;  // by step, the first at step 0 (none: targets stay zero)
  long steps = 0;                 // steps taken in the session
  // Pulls by the mouse (moving springs) cannot be written in the language: the script says how
  // many there were and from which step on the replay differs.
  int drags = 0;
  long first_drag_step = -1;
};

// The replay script (ends with `simul DURATION` and `print`).
std::string SessionScript(const SessionRecord& record);

// A cyclic pose graph of recorded poses (one target per mode, each held for its duration) on
// the same setup from the same start, simulated for `cycles` periods.
std::string PoseGraphScript(const SessionRecord& record, const std::vector<Eigen::VectorXd>& poses,
                            const std::vector<double>& durations, int cycles = 3);

}  // namespace wobble::script
