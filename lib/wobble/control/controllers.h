// The controllers of control.h as World controllers (wobble/world/controller.h): the one place
// where a pose graph is run and where keyframes move a body. The interpreter, synthesis
// trials and the viewer add these to a World instead of stepping targets themselves.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "wobble/control/control.h"
#include "wobble/world/controller.h"
#include "wobble/world/world.h"

namespace wobble::control {

// Something that knows which pose of a pose graph is active (for the recorder's `pose`).
class PoseSource {
 public:
  virtual ~PoseSource() = default;
  virtual int pose() const = 0;  // −1: none
};

// Runs a pose graph on one FFD body's PD targets (chapter 5). The graph starts from its first
// pose at the first step the controller sees: before step n (n = 0, 1, ...) the active pose is
// PoseAt(n Δt). Hard switches (switch_width 0) set the targets when the pose changes; smoothed
// ones (switch_width w > 0, SmoothPoseTargets, as the dynamic fit models the controller) set
// them every step.
class PoseGraphController : public Controller, public PoseSource {
 public:
  // Throws std::invalid_argument when the graph does not fit the body's active modes.
  PoseGraphController(const World& world, int body, PoseGraph graph, double switch_width = 0.0);
  void BeforeStep(World& world) override;
  int pose() const override { return pose_; }
  long steps() const { return steps_; }

 private:
  int body_;
  PoseGraph graph_;
  double width_;
  long steps_ = 0;
  int pose_ = -1;
};

// Per-step PD targets of every mode of one FFD body (2D or 3D), as a spacetime fit finds them
// (fit/spacetime.h): column n before the run's step n; the last column holds after the end.
class TargetScheduleController : public Controller {
 public:
  // Throws std::invalid_argument when the rows are not the body's modes or there is no column.
  TargetScheduleController(const World& world, int body, Eigen::MatrixXd targets);
  void BeforeStep(World& world) override;

 private:
  int body_;
  Eigen::MatrixXd targets_;
  long steps_ = 0;
};

// Keyframed mode amplitudes (§4.10.1) on one FFD body, which the controller makes kinematic:
// after step n its state is the keyframed state at min(n Δt, Duration()) with θ kept and, with
// a held point, the translation solved so that the point stays where it was at the start
// (KeyframedState). Finished() once the keys are done; the body's velocity is then the one of
// the last segment (the hand-over to the simulation keeps q and q̇).
class KeyframeController : public Controller {
 public:
  // Starts from the body's state in `world` now and puts it at the first key.
  KeyframeController(World& world, int body, Keyframes keys, HeldPoint hold);
  ~KeyframeController() override = default;
  void AfterStep(World& world) override;
  bool Finished() const { return steps_ * dt_ >= keys_.Duration() - 0.5 * dt_; }
  // Ends the keyframing: the body is simulated again from its keyframed state.
  void Release(World& world) const { world.SetKinematic(body_, false); }

 private:
  template <int Dim> void Start(World& world);
  template <int Dim> void Place(World& world, double t) const;
  int body_;
  Keyframes keys_;
  HeldPoint hold_;
  double dt_;
  Eigen::Vector3d anchor_ = Eigen::Vector3d::Zero();  // the held point's place (2D: x, y)
  Eigen::VectorXd placement_;                         // the start's translation and rotation, kept
  long steps_ = 0;
};

// A body's PD targets γ0 as the viewer's sliders set them, and the record of every change of
// them, whoever made it (a pose graph added before this controller, or Set): what a session
// script replays. Set takes effect at the start of the next step.
struct TargetSegment {
  long step = 0;            // the targets hold from this step (0-based from the start) on
  Eigen::VectorXd targets;  // one per mode
};

class ModeTargetController : public Controller {
 public:
  // Starts logging from the body's targets now (step 0).
  ModeTargetController(const World& world, int body);
  void Set(const Eigen::VectorXd& targets);  // one per mode; from the next step on
  // The targets the next step will use as far as this controller knows (the pending Set, or
  // the last logged).
  const Eigen::VectorXd& targets() const { return pending_ ? next_ : segments_.back().targets; }
  void BeforeStep(World& world) override;
  void AfterStep(World&) override { ++steps_; }
  const std::vector<TargetSegment>& segments() const { return segments_; }
  long steps() const { return steps_; }  // steps taken since the start

 private:
  int body_;
  bool pending_ = false;
  Eigen::VectorXd next_;
  std::vector<TargetSegment> segments_;
  long steps_ = 0;
};

}  // namespace wobble::control
