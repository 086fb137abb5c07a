// What a run looks like over time: energies by term and the mass matrix' condition number
// (thesis Fig. 4.9), sampled from a World, then drawn with charts.h (PNG + CSV).
#pragma once

#include <string>
#include <vector>

#include "pipelines/charts.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

class RunRecorder {
 public:
  explicit RunRecorder(int body = 0) : body_(body) {}
  // Samples the world now: energies (World::ComputeEnergies), each mode's potential K γ²
  // (§4.7), cond₂(M) from the singular values of M (Eq. 4.10), and whether a point touches.
  void Sample(const World& world);

  const std::vector<double>& time() const { return t_; }
  const std::vector<double>& condition() const { return cond_; }
  // Times at which the body touched the ground after being clear of it (collisions).
  const std::vector<double>& contact_events() const { return events_; }

  // kinetic, gravitational, each mode's potential, ground, springs, total (terms that stay
  // zero for the whole run are left out, except kinetic, gravity and total).
  ChartSpec EnergyChart(const std::string& title) const;
  // cond₂(M) against time, with the contact events as markers (Fig. 4.9).
  ChartSpec ConditionChart(const std::string& title) const;

 private:
  int body_;
  std::vector<std::string> mode_names_;
  std::vector<double> t_, kinetic_, gravity_, ground_, springs_, total_, cond_;
  std::vector<std::vector<double>> modes_;  // [mode][sample]
  std::vector<double> events_;
  bool touching_ = false;
};


}  // namespace wobble::pipelines
