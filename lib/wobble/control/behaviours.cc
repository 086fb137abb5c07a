#include "wobble/control/behaviours.h"

#include <cmath>
#include <sstream>

namespace wobble::control {

namespace {

std::string Num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Half a step: "now" for comparisons of times on the step grid.
double HalfStep(const World& w) { return 0.5 * w.options().dt; }

int FindConstraint(const BehaviourContext& ctx, const std::string& name, const std::string& who) {
  const auto it = ctx.names->find(name);
  if (it == ctx.names->end() || !ctx.world->exists(it->second)) {
    std::string known;
    for (const auto& [n, id] : *ctx.names)
      if (ctx.world->exists(id)) known += (known.empty() ? "" : ", ") + n;
    throw BehaviourError(who + ": no constraint named '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
  }
  return it->second;
}

void Name(BehaviourContext& ctx, const std::string& name, int id) { (*ctx.names)[name] = id; }

}  // namespace

Eigen::VectorXd Anchor::Position(const World& w) const { return point ? w.PointPosition(*point) : place; }

Eigen::VectorXd Anchor::Velocity(const World& w) const {
  return point ? w.PointVelocity(*point) : Eigen::VectorXd::Zero(place.size());
}

// ---------------------------------------------------------------------------------------------
// Chase

Chase::Chase(Anchor chaser, Anchor target, double duration, std::optional<Eigen::VectorXd> final_velocity)
    : chaser_(std::move(chaser)), target_(std::move(target)), duration_(duration), final_velocity_(std::move(final_velocity)) {}

std::string Chase::Describe() const { return "chase " + chaser_.name + " -> " + target_.name + " in " + Num(duration_); }

void Chase::Start(BehaviourContext& ctx) {
  World& w = *ctx.world;
  if (chaser_.fixed()) throw BehaviourError(Describe() + ": the chaser must be a point of a body");
  if (!(duration_ > 0)) throw BehaviourError(Describe() + ": the duration must be positive");
  const double t = w.time();
  contact_time_ = t + duration_;
  const Eigen::VectorXd x = chaser_.Position(w), v = chaser_.Velocity(w);
  // linear prediction of the target at the contact time
  const Eigen::VectorXd y = target_.Position(w) + target_.Velocity(w) * duration_;
  if (y.size() != x.size()) throw BehaviourError(Describe() + ": the chaser and the target live in different dimensions");
  if (final_velocity_ && final_velocity_->size() != x.size())
    throw BehaviourError(Describe() + ": the final velocity needs " + std::to_string(x.size()) + " components");
  v1_ = final_velocity_ ? *final_velocity_ : DefaultFinalVelocity(x, v, y, duration_);
  segment_ = std::make_shared<HermiteSegment>(t, x, v, contact_time_, y, v1_);
  // the segment starts at the point's own position and velocity: c = ċ = 0, no impulse needed
  constraint_ = w.AddTrajectory(*chaser_.point, segment_);
  Name(ctx, "chase:" + chaser_.name, constraint_);
}

void Chase::Plan(World& w, const Eigen::VectorXd& x, const Eigen::VectorXd& v) {
  const double t = w.time(), tau = contact_time_ - t;
  const Eigen::VectorXd y = target_.Position(w) + target_.Velocity(w) * tau;
  segment_ = std::make_shared<HermiteSegment>(t, x, v, contact_time_, y, v1_);
  w.SetPath(constraint_, segment_);  // same constraint rows: the factorization is kept
}

bool Chase::Update(BehaviourContext& ctx) {
  World& w = *ctx.world;
  const double t = w.time();
  if (t + HalfStep(w) >= contact_time_) {
    // contact: the chase is over and the point is free for what comes next (Connect)
    if (w.exists(constraint_)) w.Remove(constraint_);
    ctx.names->erase("chase:" + chaser_.name);
    return true;
  }
  // re-plan from where the path is now (n and ṅ stay continuous) to the new prediction
  if (contact_time_ - t > kMinReplanTime && t > segment_->t0()) {
    const PathPoint now = segment_->Evaluate(t);
    Plan(w, now.n, now.n_dot);
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Connect, Release, Switch, Impulse, Wait, Follow

Connect::Connect(Anchor point, Anchor target, std::string name)
    : point_(std::move(point)), target_(std::move(target)), name_(std::move(name)) {
  if (name_.empty()) name_ = "connect:" + point_.name;
}

std::string Connect::Describe() const { return "connect " + point_.name + " -> " + target_.name; }

void Connect::Start(BehaviourContext& ctx) {
  World& w = *ctx.world;
  if (point_.fixed()) throw BehaviourError(Describe() + ": the connecting point must be a point of a body");
  // velocity matching: afterwards v(point) − v(target) = 0 (v(point) = 0 for a fixed place)
  VelocityGoal goal;
  goal.a = *point_.point;
  if (target_.point) goal.b = *target_.point;
  goal.v = Eigen::VectorXd::Zero(w.dim(point_.point->body));
  std::string error;
  if (!w.ApplyImpulse({goal}, &error)) throw BehaviourError(Describe() + ": " + error);
  const int id = target_.point ? w.AddAttachment(*point_.point, *target_.point) : w.AddNail(*point_.point, target_.place);
  Name(ctx, name_, id);
}

void Release::Start(BehaviourContext& ctx) {
  const int id = FindConstraint(ctx, name_, "release");
  ctx.world->Remove(id);
  ctx.names->erase(name_);
}

void Switch::Start(BehaviourContext& ctx) {
  const int id = FindConstraint(ctx, name_, on_ ? "on" : "off");
  ctx.world->SetEnabled(id, on_);
  std::string error;
  if (on_ && !ctx.world->ProjectVelocities(&error)) throw BehaviourError(Describe() + ": " + error);
}

std::string Impulse::Describe() const {
  std::ostringstream s;
  s << "impulse " << point_.name << " to (" << velocity_.transpose() << ")";
  return s.str();
}

void Impulse::Start(BehaviourContext& ctx) {
  if (point_.fixed()) throw BehaviourError(Describe() + ": needs a point of a body");
  VelocityGoal goal;
  goal.a = *point_.point;
  goal.v = velocity_;
  std::string error;
  if (!ctx.world->ApplyImpulse({goal}, &error)) throw BehaviourError(Describe() + ": " + error);
}

std::string Wait::Describe() const { return "wait " + Num(duration_); }
void Wait::Start(BehaviourContext& ctx) { end_ = ctx.world->time() + duration_; }
bool Wait::Update(BehaviourContext& ctx) { return ctx.world->time() + HalfStep(*ctx.world) >= end_; }

Follow::Follow(Anchor point, std::shared_ptr<const Path> path, double onset, double preroll, std::string name)
    : point_(std::move(point)), path_(std::move(path)), onset_(onset), preroll_(preroll), name_(std::move(name)) {}

std::string Follow::Describe() const {
  return "follow " + point_.name + " from " + Num(onset_) + (preroll_ > 0 ? " with preroll " + Num(preroll_) : "");
}

bool Follow::Update(BehaviourContext& ctx) {
  World& w = *ctx.world;
  const double t = w.time();
  if (t + HalfStep(w) < onset_ - preroll_) return false;  // not yet
  if (point_.fixed()) throw BehaviourError(Describe() + ": needs a point of a body");
  if (ctx.names->count(name_) && w.exists(ctx.names->at(name_)))
    throw BehaviourError(Describe() + ": a constraint named '" + name_ + "' exists already");
  if (onset_ - t > HalfStep(w)) {
    // preroll (§4.1): from the point's state now to the path's at onset
    auto prerolled = std::make_shared<PrerolledPath>(path_, t, point_.Position(w), point_.Velocity(w), onset_);
    Name(ctx, name_, w.AddTrajectory(*point_.point, prerolled));
  } else {
    // no preroll: control starts with an impulse that gives the point the path's velocity
    Name(ctx, name_, w.AddTrajectory(*point_.point, path_));
    std::string error;
    if (!w.ProjectVelocities(&error)) throw BehaviourError(Describe() + ": " + error);
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Sequencer

void Sequencer::AddGrab(const Anchor& point, const Anchor& target, double duration,
                        std::optional<Eigen::VectorXd> final_velocity, const std::string& name) {
  Add(std::make_unique<Chase>(point, target, duration, std::move(final_velocity)));
  Add(std::make_unique<Connect>(point, target, name));
}

void Sequencer::BeforeStep(BehaviourContext& ctx, const std::function<void(const std::string&)>& log) {
  while (!queue_.empty()) {
    Behaviour& b = *queue_.front();
    if (!started_) {
      if (log) log("t = " + Num(ctx.world->time()) + ": " + b.Describe());
      b.Start(ctx);
      started_ = true;
    }
    if (!b.Update(ctx)) return;
    queue_.pop_front();
    started_ = false;
  }
}

}  // namespace wobble::control
