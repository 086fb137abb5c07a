// Goal-directed behaviours (Witkin & Welch 1990, §4.2) and the sequencer that chains them.
//
// A behaviour computes where controlled points should go from the state and the time, and
// switches constraints on and off or issues impulses between world steps:
//   Chase     a cubic segment from the point's position and velocity to the target's linearly
//             predicted position at the contact time, rebuilt before every step as the target
//             moves (the path's own position and velocity at that time start the new segment,
//             so n and ṅ stay continuous); the final velocity is given or the default of
//             DefaultFinalVelocity; done at the contact time, when its trajectory constraint
//             is removed
//   Connect   a velocity-matching impulse (the point's velocity becomes the target's), then an
//             attachment (a nail for a fixed target)
//   Grab      Chase then Connect
//   Release   removes a named constraint (an attachment made by Connect, a nail, ...)
//   WaitFor   blocks the sequence until a predicate holds ("Wait_For_Humanoid")
//   Follow    keyframed control (§4.1): a trajectory constraint along a path from its onset,
//             with constraint preroll before it when asked
//   Impulse   a velocity jump of one point (§3.2, §4.1: "stop dead", "bounce", start velocities)
//   Switch    a named constraint on or off
//   Wait      blocks for a duration
// The Sequencer runs them one after another: before every step it updates the current
// behaviour; one that finishes hands over to the next in the same call, so instant behaviours
// (Connect, Release, Impulse, Switch) chained after a Chase act at its contact time.
#pragma once

#include <Eigen/Core>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "wobble/control/paths.h"
#include "wobble/world/controller.h"
#include "wobble/world/world.h"

namespace wobble::control {

// Where a behaviour looks: a material point of a body, or a fixed place in the world (a
// "sky point"). Fixed places have zero velocity.
struct Anchor {
  std::string name;
  std::optional<MaterialPoint> point;  // empty: a fixed place
  Eigen::VectorXd place;               // the fixed place
  Eigen::VectorXd Position(const World& w) const;
  Eigen::VectorXd Velocity(const World& w) const;
  bool fixed() const { return !point.has_value(); }
};
inline Anchor PointAnchor(std::string name, MaterialPoint p) { return {std::move(name), std::move(p), {}}; }
inline Anchor PlaceAnchor(std::string name, Eigen::VectorXd place) { return {std::move(name), std::nullopt, std::move(place)}; }

// Constraints made by behaviours, by name, so that later ones (Release, Switch) can find them.
using ConstraintNames = std::map<std::string, int>;

// What a behaviour may touch while it runs.
struct BehaviourContext {
  World* world = nullptr;
  ConstraintNames* names = nullptr;
};

class Behaviour {
 public:
  virtual ~Behaviour() = default;
  // One line for logs and errors, e.g. "chase hook_tip -> pyr_tip".
  virtual std::string Describe() const = 0;
  // Called once, before the step that starts at world.time(), when the behaviour becomes current.
  virtual void Start(BehaviourContext& ctx) = 0;
  // Called before every step while current, also right after Start. True when done.
  virtual bool Update(BehaviourContext& ctx) = 0;
};

// Thrown by a behaviour that cannot act (an unknown constraint name, conflicting impulse goals).
class BehaviourError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Chase (§4.2). `final_velocity` empty: DefaultFinalVelocity of the first plan. The trajectory
// constraint is named `constraint_name` while it runs (default "chase:<point>").
class Chase : public Behaviour {
 public:
  Chase(Anchor chaser, Anchor target, double duration, std::optional<Eigen::VectorXd> final_velocity = std::nullopt);
  std::string Describe() const override;
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext& ctx) override;
  double contact_time() const { return contact_time_; }
  // The segment currently followed (for tests).
  const HermiteSegment* segment() const { return segment_.get(); }
  // Re-plans stop when less than this much time is left (the cubic's coefficients grow as
  // 1/τ² near contact); the last plan is followed to the end.
  static constexpr double kMinReplanTime = 1e-6;

 private:
  void Plan(World& w, const Eigen::VectorXd& x, const Eigen::VectorXd& v);
  Anchor chaser_, target_;
  double duration_;
  std::optional<Eigen::VectorXd> final_velocity_;
  Eigen::VectorXd v1_;
  double contact_time_ = 0.0;
  int constraint_ = -1;
  std::shared_ptr<const HermiteSegment> segment_;
};

// Connect (§4.2): a velocity-matching impulse, then an attachment to the target (or a nail at
// the fixed place), named `name` (default "connect:<point>").
class Connect : public Behaviour {
 public:
  Connect(Anchor point, Anchor target, std::string name = "");
  std::string Describe() const override;
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext&) override { return true; }
  const std::string& constraint_name() const { return name_; }

 private:
  Anchor point_, target_;
  std::string name_;
};

// Removes the named constraint.
class Release : public Behaviour {
 public:
  explicit Release(std::string name) : name_(std::move(name)) {}
  std::string Describe() const override { return "release " + name_; }
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext&) override { return true; }

 private:
  std::string name_;
};

// Switches the named constraint on or off (§4.1: control points "turned on and off"). Turning
// a constraint on also makes the velocities legal by an impulse (ProjectVelocities), so a
// trajectory starts moving with ṅ.
class Switch : public Behaviour {
 public:
  Switch(std::string name, bool on) : name_(std::move(name)), on_(on) {}
  std::string Describe() const override { return std::string(on_ ? "on " : "off ") + name_; }
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext&) override { return true; }

 private:
  std::string name_;
  bool on_;
};

// Blocks until `predicate(world)` holds (checked before every step).
class WaitFor : public Behaviour {
 public:
  WaitFor(std::string description, std::function<bool(const World&)> predicate)
      : description_(std::move(description)), predicate_(std::move(predicate)) {}
  std::string Describe() const override { return "wait_for " + description_; }
  void Start(BehaviourContext&) override {}
  bool Update(BehaviourContext& ctx) override { return predicate_(*ctx.world); }

 private:
  std::string description_;
  std::function<bool(const World&)> predicate_;
};

// Blocks for a duration from its start.
class Wait : public Behaviour {
 public:
  explicit Wait(double duration) : duration_(duration) {}
  std::string Describe() const override;
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext& ctx) override;

 private:
  double duration_, end_ = 0.0;
};

// Keyframed control (§4.1): from `onset` the point follows `path` under a trajectory
// constraint named `name`. With preroll > 0 the constraint is installed at onset − preroll
// on a PrerolledPath that joins the point's state then to the path's at onset; without it,
// at onset, followed by an impulse that gives the point the path's velocity. Blocks until the
// constraint is installed (later behaviours run while it follows the path).
class Follow : public Behaviour {
 public:
  Follow(Anchor point, std::shared_ptr<const Path> path, double onset, double preroll, std::string name);
  std::string Describe() const override;
  void Start(BehaviourContext&) override {}
  bool Update(BehaviourContext& ctx) override;

 private:
  Anchor point_;
  std::shared_ptr<const Path> path_;
  double onset_, preroll_;
  std::string name_;
};

// An impulse (§3.2): afterwards the point moves with `velocity` (stop dead: zero), every
// enabled constraint still holds in velocity.
class Impulse : public Behaviour {
 public:
  Impulse(Anchor point, Eigen::VectorXd velocity) : point_(std::move(point)), velocity_(std::move(velocity)) {}
  std::string Describe() const override;
  void Start(BehaviourContext& ctx) override;
  bool Update(BehaviourContext&) override { return true; }

 private:
  Anchor point_;
  Eigen::VectorXd velocity_;
};

// Runs behaviours in order.
class Sequencer {
 public:
  void Add(std::unique_ptr<Behaviour> b) { queue_.push_back(std::move(b)); }
  // Grab (§4.2) = Chase then Connect.
  void AddGrab(const Anchor& point, const Anchor& target, double duration,
               std::optional<Eigen::VectorXd> final_velocity = std::nullopt, const std::string& name = "");
  // Starts and updates behaviours before the step at world.time(); finished ones hand over at
  // once. `log` (optional) hears "t: started <describe>" lines. Throws BehaviourError.
  void BeforeStep(BehaviourContext& ctx, const std::function<void(const std::string&)>& log = nullptr);
  bool idle() const { return queue_.empty(); }
  size_t pending() const { return queue_.size(); }
  // The behaviour running now (nullptr when idle).
  const Behaviour* current() const { return queue_.empty() ? nullptr : queue_.front().get(); }
  void Clear() {
    queue_.clear();
    started_ = false;
  }

 private:
  std::deque<std::unique_ptr<Behaviour>> queue_;
  bool started_ = false;
};

// The Sequencer as a World controller of its own, for a world without a Scene (a program or
// Python builds the world): before every step the current behaviour acts; the constraints the
// behaviours made are in names(), the "t: started ..." lines in log().
class BehaviourController : public Controller {
 public:
  Sequencer& sequencer() { return sequencer_; }
  const ConstraintNames& names() const { return names_; }
  const std::vector<std::string>& log() const { return log_; }
  void BeforeStep(World& world) override {
    BehaviourContext ctx{&world, &names_};
    sequencer_.BeforeStep(ctx, [this](const std::string& line) { log_.push_back(line); });
  }

 private:
  Sequencer sequencer_;
  ConstraintNames names_;
  std::vector<std::string> log_;
};

}  // namespace wobble::control
