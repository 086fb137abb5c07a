// The one writer of scripts (the language of README "Scripts") that rebuild an FFD object's
// setup and replay a controller on it. Every script starts with the same setup (WriteSetup:
// object, modes, world parameters, springs, state) and ends with a pose graph and `simul`:
//   ReplayScript    `save`: the scene's pose graph over a span
//   SessionScript   a session run outside the interpreter (the viewer's `wobble view`): its PD
//                   target changes as an acyclic pose graph
//   PoseGraphScript recorded poses as a cyclic pose graph
// Numbers are written in shortest round-trip form (exact doubles), so a replay steps the same
// world through the same targets and ends in the same state.
#pragma once

#include <Eigen/Core>
#include <iosfwd>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/control/control.h"
#include "wobble/control/controllers.h"
#include "wobble/scene/scene.h"
#include "wobble/world/world.h"

namespace wobble::scene {

// What WriteSetup writes: `load_obj`, `load_def`, `set codamA`, `assign` and `mode` of every
// mode, the world's parameters, the springs (`set spring`, `clear springs`, `spring`), the
// state (`trans 0 0 0`, `set_vec`), and `clear poses`.
// What `assign` and `mode` set of one mode (2D or 3D).
struct ModeSetting {
  double stiffness = 0.0, damping = 0.0;
  bool active = false;
};
template <int Dim> std::vector<ModeSetting> ModeSettings(const std::vector<DeformationModeN<Dim>>& modes) {
  std::vector<ModeSetting> out;
  for (const DeformationModeN<Dim>& m : modes) out.push_back({m.stiffness, m.damping, m.active});
  return out;
}

struct ScriptSetup {
  std::string object_path;              // as load_obj takes it (absolute is safest)
  std::vector<std::string> mode_paths;  // as load_def takes them, in order
  std::vector<ModeSetting> modes;       // K, c and active flag of each, in load order
  double codam_active = 0.0;
  WorldOptions world;                   // ground, gravity, integrator, dt
  bool springs_on = true;
  std::vector<Spring> springs;
  std::vector<SpringN<3>> springs3;  // a 3D object's
  Eigen::VectorXd q, qd;                // world coordinates (3D: t, rotation vector, γ | ṫ, ω, γ̇)
  std::string heightfield_path;         // where world's heightfield was written (empty: none)
};
void WriteSetup(std::ostream& s, const ScriptSetup& setup);
// `set cyclic`, `set switch_width` and one `pose` line per pose.
void WritePoseGraph(std::ostream& s, const control::PoseGraph& graph, double switch_width);

// `save`: the setup, the pose graph, `schedule SCHEDULE` when one plays in its place (a
// spacetime fit's targets, written by the caller to that file), `set time T0`, `set end T1`,
// `simul`, `print`.
std::string ReplayScript(const ScriptSetup& setup, const control::PoseGraph& graph, double switch_width, double t0,
                         double t1, const std::string& schedule = "");

// A session stepped outside the interpreter. How the targets are replayed: every mode is made
// active with `codamA 0` and `assign` gives each its stiffness and damping as the session's body
// had them (codamA already included), so the body is the same; the target changes become an
// acyclic pose graph, one pose per change, whose boundaries fall half a step before the step
// where the change was made, so that PoseAt(n dt) picks the same pose for every step n
// without rounding doubts.
struct SessionRecord {
  std::string object_path;              // as load_obj takes it (absolute is safest)
  std::vector<std::string> mode_paths;  // as load_def takes them, in order
  const BodyModel* body = nullptr;      // the body the session stepped (for K, c, D)
  WorldOptions world;                   // ground, gravity, integrator, dt, the scene's springs
  Eigen::VectorXd q0, qd0;              // state at the session's start
  double t0 = 0.0;                      // time at the session's start
  using Segment = control::TargetSegment;  // control::ModeTargetController logs them
  std::vector<Segment> segments;  // by step, the first at step 0 (none: targets stay zero)
  long steps = 0;                 // steps taken in the session
  // Pulls by the mouse (moving springs) cannot be written in the language: the script says how
  // many there were and from which step on the replay differs.
  int drags = 0;
  long first_drag_step = -1;
  // A session that began with the scene's keys (the viewer's keys_first): the script plays
  // them (`hold`, `set interp`, `key` lines, `keyframe`) before it simulates; the first
  // key_steps of `steps` were theirs, and `segments` count from the hand-over. key_steps < the
  // keys' own steps: saved while they played (the replay plays them to their end).
  control::Keyframes keys;  // none: the session simulated from its start
  control::HeldPoint hold;
  long key_steps = 0;
};

// The replay script (ends with `simul DURATION` and `print`). std::invalid_argument for a
// record without body or object file, or with segments out of order or of the wrong size.
std::string SessionScript(const SessionRecord& record);

// A cyclic pose graph of recorded poses (one target per mode, each held for its duration) on
// the same setup from the same start, simulated for `cycles` periods.
std::string PoseGraphScript(const SessionRecord& record, const std::vector<Eigen::VectorXd>& poses,
                            const std::vector<double>& durations, int cycles = 3);

}  // namespace wobble::scene
