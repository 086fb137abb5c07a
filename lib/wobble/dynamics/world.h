// A world of FFD bodies over one ground: what `wobble simulate` runs.
//
// Bodies do not interact with each other yet; each is advanced by StepBody. The world checks
// every accepted state and stops at the first trouble with a status that names the step,
// the time, the body and the cause.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "wobble/dynamics/step.h"

namespace wobble {

struct Energies {
  double kinetic = 0, gravity = 0, modes = 0, ground = 0, springs = 0;
  std::vector<double> per_mode;  // each mode's K (γ − γ0)²; `modes` is their sum
  double total() const { return kinetic + gravity + modes + ground + springs; }
};

struct SimStatus {
  StepStatus::Code code = StepStatus::Code::kOk;
  long step = 0;      // the step that failed (1-based), or steps taken
  double time = 0.0;  // simulated time at the start of that step
  int body = -1;
  std::string message;  // one line for people
  bool ok() const { return code == StepStatus::Code::kOk; }
};

struct WorldOptions {
  WorldParams params;
  Integrator integrator = Integrator::kThesis;
  double dt = 0.01;
};

class World {
 public:
  explicit World(WorldOptions options = {}) : options_(std::move(options)) {}

  // Returns the body's index. q and q̇ start at rest in the body frame unless set.
  int AddBody(std::shared_ptr<const BodyModel> body);
  void SetState(int body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd);
  // PD targets γ0 of the body's modes (one per mode; empty: all zero). See wobble/control.
  void SetModeTargets(int body, const Eigen::VectorXd& targets);
  // Sets the clock, for replaying recorded states (a script's runs drawn by `render`); later
  // steps continue from t.
  void SetTime(double t) {
    time_origin_ = t - steps_ * options_.dt;
    time_ = t;
  }
  // Springs hold a point given by lattice coordinates (Fig. 4.4).
  void AddSpring(Spring spring);

  // One step of every body. Returns false (and keeps status()) at the first trouble.
  bool Step();
  // Steps until time >= t_end or trouble; calls on_step(world) after every accepted step.
  template <class F> bool RunUntil(double t_end, F&& on_step) {
    while (time_ + 0.5 * options_.dt < t_end) {
      if (!Step()) return false;
      on_step(*this);
    }
    return true;
  }

  int num_bodies() const { return int(bodies_.size()); }
  const BodyModel& body(int i) const { return *bodies_[i]; }
  const BodyState<double>& state(int i) const { return states_[i]; }
  const WorldOptions& options() const { return options_; }
  WorldParams& params() { return options_.params; }
  double time() const { return time_; }
  long steps() const { return steps_; }
  const SimStatus& status() const { return status_; }

  Energies ComputeEnergies(int body) const;
  ForceBreakdown<double> Forces(int body) const;
  Eigen::VectorXd Accelerations(int body) const;
  // World positions of the body's mass points.
  std::vector<Eigen::Vector2d> PointPositions(int body) const;

 private:
  bool Fail(int body, StepStatus st, const std::string& detail = "");
  double PenetrationLimit(int body) const;

  WorldOptions options_;
  std::vector<std::shared_ptr<const BodyModel>> bodies_;
  std::vector<BodyState<double>> states_;
  double time_ = 0.0;
  double time_origin_ = 0.0;  // SetTime
  long steps_ = 0;
  SimStatus status_;
};

}  // namespace wobble
