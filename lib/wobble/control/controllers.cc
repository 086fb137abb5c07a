#include "wobble/control/controllers.h"

#include "wobble/core/errors.h"

#include <algorithm>
#include <stdexcept>

namespace wobble::control {

namespace {
// The pose graph's targets at t of a 2D or 3D FFD body (the graph drives either the same way).
Eigen::VectorXd Targets(const World& world, int body, const PoseGraph& graph, double t, double width, int pose) {
  if (world.kind(body) == BodyKind::kFfd3)
    return width > 0 ? SmoothPoseTargets(world.body3(body), graph, t, width)
                     : TargetsFromPose(world.body3(body), graph.poses[size_t(pose)]);
  return width > 0 ? SmoothPoseTargets(world.body(body), graph, t, width)
                   : TargetsFromPose(world.body(body), graph.poses[size_t(pose)]);
}
}  // namespace

PoseGraphController::PoseGraphController(const World& world, int body, PoseGraph graph, double switch_width)
    : body_(body), graph_(std::move(graph)), width_(switch_width) {
  const int active = int(world.kind(body) == BodyKind::kFfd3 ? ActiveModes(world.body3(body)).size()
                                                             : ActiveModes(world.body(body)).size());
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
  const BodyKind kind = world.kind(body);
  if (kind != BodyKind::kFfd && kind != BodyKind::kFfd3) throw std::invalid_argument("target schedule: an FFD body only");
  const int modes = kind == BodyKind::kFfd3 ? world.body3(body).num_modes() : world.body(body).num_modes();
  if (targets_.rows() != modes || targets_.cols() < 1)
    throw std::invalid_argument("target schedule: one row per mode and at least one column needed");
}

void TargetScheduleController::BeforeStep(World& world) {
  const long n = std::min<long>(steps_++, long(targets_.cols()) - 1);
  world.SetModeTargets(body_, targets_.col(n));
}

KeyframeController::KeyframeController(World& world, int body, Keyframes keys, HeldPoint hold)
    : body_(body), keys_(std::move(keys)), hold_(hold), dt_(world.options().dt) {
  if (world.kind(body) == BodyKind::kFfd3) {  // the same on a 3D body: its orientation is kept
    const BodyModel3& model = world.body3(body);
    const std::string invalid = keys_.Validate(model.num_modes());
    if (!invalid.empty()) throw std::invalid_argument("keyframe: " + invalid);
    const BodyState<3, double>& s = world.state3(body);
    translation3_ = s.translation();
    orientation_ = s.orientation();
    if (hold_.enabled) {
      Eigen::Vector3d b0;
      Mat3D<double> B;
      model.LocalBasis(hold_.lattice_coords3, &b0, &B);
      anchor3_ = s.translation() + s.orientation() * (b0 + B * s.gamma());
    }
    world.SetKinematic(body, true);
    Place(world, 0.0);
    return;
  }
  const BodyModel& model = world.body(body);
  const std::string invalid = keys_.Validate(model.num_modes());
  if (!invalid.empty()) throw std::invalid_argument("keyframe: " + invalid);
  const Eigen::VectorXd q = world.state(body).q;
  // the held point stays where it is at the start; θ and, without a hold, t stay as they are
  anchor_ = hold_.enabled ? PointAt(model, hold_.lattice_coords, q) : Eigen::Vector2d::Zero();
  translation_ = q.head<2>();
  theta_ = q[2];
  world.SetKinematic(body, true);
  Place(world, 0.0);
}

void KeyframeController::AfterStep(World& world) {
  ++steps_;
  try {
    Place(world, std::min(double(steps_) * dt_, keys_.Duration()));
  } catch (const InputError& e) {  // keys that lead to an infinite energy (a key of 1e300): a numerical stop
    world.Stop(StatusCode::kNonFiniteEnergy, body_, std::string("the keyframed state: ") + e.what());
  }
}

void KeyframeController::Place(World& world, double t) const {
  Eigen::VectorXd gamma, gamma_dot, q, qd;
  keys_.Evaluate(t, &gamma, &gamma_dot);
  if (world.kind(body_) == BodyKind::kFfd3) {
    Eigen::Vector3d translation;
    KeyframedState3(world.body3(body_), hold_, anchor3_, translation3_, orientation_, gamma, gamma_dot, &translation, &qd);
    world.SetState3(body_, translation, orientation_, gamma, qd);
    return;
  }
  KeyframedState(world.body(body_), hold_, anchor_, translation_, theta_, gamma, gamma_dot, &q, &qd);
  world.SetState(body_, q, qd);
}

ModeTargetController::ModeTargetController(const World& world, int body) : body_(body) {
  const BodyModel& model = world.body(body);
  Eigen::VectorXd now = world.state(body).mode_target;
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
  const Eigen::VectorXd& now = world.state(body_).mode_target;
  TargetSegment& last = segments_.back();
  if (now.size() == 0 ? last.targets.isZero(0.0) : now == last.targets) return;
  const Eigen::VectorXd logged = now.size() == 0 ? Eigen::VectorXd::Zero(last.targets.size()) : now;
  if (last.step == steps_) last.targets = logged;  // changed again before a step
  else segments_.push_back({steps_, logged});
}

}  // namespace wobble::control
