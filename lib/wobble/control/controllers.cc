#include "wobble/control/controllers.h"

#include "wobble/core/errors.h"

#include <algorithm>
#include <stdexcept>

namespace wobble::control {

namespace {
// The pose graph's targets at t of a 2D or 3D FFD body (the graph drives either the same way).
Eigen::VectorXd Targets(const World& world, int body, const PoseGraph& graph, double t, double width, int pose) {
  if (world.dim(body) == 3)
    return width > 0 ? SmoothPoseTargets(world.body<3>(body), graph, t, width)
                     : TargetsFromPose(world.body<3>(body), graph.poses[size_t(pose)]);
  return width > 0 ? SmoothPoseTargets(world.body<2>(body), graph, t, width)
                   : TargetsFromPose(world.body<2>(body), graph.poses[size_t(pose)]);
}
}  // namespace

PoseGraphController::PoseGraphController(const World& world, int body, PoseGraph graph, double switch_width)
    : body_(body), graph_(std::move(graph)), width_(switch_width) {
  const int active = int(world.dim(body) == 3 ? ActiveModes(world.body<3>(body)).size()
                                                             : ActiveModes(world.body<2>(body)).size());
  const std::string invalid = graph_.Validate(active);
  if (!invalid.empty()) throw std::invalid_argument("pose graph: " + invalid);
  if (!(width_ >= 0.0)) throw std::invalid_argument("pose graph: the switch width must be 0 or positive");
}

void PoseGraphController::BeforeStep(World& world) {
  const double t = double(steps_++) * world.options().dt;
  if (width_ > 0) {
    pose_ = graph_.PoseAt(t);
    world.SetModeTargets(body_, Targets(world, body_, graph_, t, width_, pose_));
    return;
  }
  const int now = graph_.PoseAt(t);
  if (now != pose_) {  // hard switches: the targets change only here
    pose_ = now;
    world.SetModeTargets(body_, Targets(world, body_, graph_, t, 0.0, pose_));
  }
}

TargetScheduleController::TargetScheduleController(const World& world, int body, Eigen::MatrixXd targets)
    : body_(body), targets_(std::move(targets)) {
  if (world.kind(body) != BodyKind::kFfd) throw std::invalid_argument("target schedule: an FFD body only");
  const int modes = world.num_modes(body);
  if (targets_.rows() != modes || targets_.cols() < 1)
    throw std::invalid_argument("target schedule: one row per mode and at least one column needed");
}

void TargetScheduleController::BeforeStep(World& world) {
  const long n = std::min<long>(steps_++, long(targets_.cols()) - 1);
  world.SetModeTargets(body_, targets_.col(n));
}

KeyframeController::KeyframeController(World& world, int body, Keyframes keys, HeldPoint hold)
    : body_(body), keys_(std::move(keys)), hold_(hold), dt_(world.options().dt) {
  if (world.IsFfd(body, 3)) Start<3>(world);  // the same on a 3D body: its orientation is kept
  else Start<2>(world);
}

template <int Dim> void KeyframeController::Start(World& world) {
  const BodyModelN<Dim>& model = world.body<Dim>(body_);
  const std::string invalid = keys_.Validate(model.num_modes());
  if (!invalid.empty()) throw std::invalid_argument("keyframe: " + invalid);
  const Eigen::VectorXd q = world.q(body_);
  // the held point stays where it is at the start; the rotation and, without a hold, t stay as they are
  if (hold_.enabled) anchor_.head<Dim>() = PointAt(model, hold_.coords<Dim>(), q);
  placement_ = q.head(Group<Dim>::kRigidParams);
  world.SetKinematic(body_, true);
  Place<Dim>(world, 0.0);
}

void KeyframeController::AfterStep(World& world) {
  ++steps_;
  try {
    if (world.IsFfd(body_, 3)) Place<3>(world, std::min(double(steps_) * dt_, keys_.Duration()));
    else Place<2>(world, std::min(double(steps_) * dt_, keys_.Duration()));
  } catch (const InputError& e) {  // keys that lead to an infinite energy (a key of 1e300): a numerical stop
    world.Stop(StatusCode::kNonFiniteEnergy, body_, std::string("the keyframed state: ") + e.what());
  }
}

template <int Dim> void KeyframeController::Place(World& world, double t) const {
  Eigen::VectorXd gamma, gamma_dot, q, qd;
  keys_.Evaluate(t, &gamma, &gamma_dot);
  KeyframedState<Dim>(world.body<Dim>(body_), hold_, anchor_.head<Dim>(), placement_, gamma, gamma_dot, &q, &qd);
  world.SetState(body_, q, qd);
}

ModeTargetController::ModeTargetController(const World& world, int body) : body_(body) {
  const BodyModel& model = world.body<2>(body);
  Eigen::VectorXd now = world.mode_targets(body);
  if (now.size() == 0) now = Eigen::VectorXd::Zero(model.num_modes());  // empty means all zero
  segments_.push_back({0, now});
}

void ModeTargetController::Set(const Eigen::VectorXd& targets) {
  if (targets.size() != segments_.back().targets.size())
    throw std::invalid_argument("ModeTargetController: one target per mode");
  if (!targets.allFinite()) throw std::invalid_argument("ModeTargetController: targets must be finite");
  next_ = targets;
  pending_ = true;
}

void ModeTargetController::BeforeStep(World& world) {
  if (pending_) {
    world.SetModeTargets(body_, next_);
    pending_ = false;
  }
  // compared in place: this runs every step, and the targets rarely change
  const VecD<double>& now = world.mode_targets(body_);
  TargetSegment& last = segments_.back();
  if (now.size() == 0 ? last.targets.isZero(0.0) : now == last.targets) return;
  const Eigen::VectorXd logged = now.size() == 0 ? Eigen::VectorXd::Zero(last.targets.size()) : now;
  if (last.step == steps_) last.targets = logged;  // changed again before a step
  else segments_.push_back({steps_, logged});
}

}  // namespace wobble::control
