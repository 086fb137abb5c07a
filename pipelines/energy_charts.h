// What a run looks like over time, read from its record::Trajectory: energies by term and the
// mass matrix' condition number (thesis Fig. 4.9), drawn with charts.h (PNG + CSV).
#pragma once

#include <string>
#include <vector>

#include "pipelines/charts.h"
#include "wobble/record/trajectory.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

// Energies of body `body` against time: kinetic, gravitational, each FFD mode's potential
// K (γ − γ0)² (§4.7; a linear body's deformation energy as one series), ground, springs, total
// (terms that stay zero for the whole run are left out, except kinetic, gravity and total);
// the contact events as markers.
ChartSpec EnergyChart(const record::Trajectory& run, int body, const std::string& title);
// cond₂(M) of FFD body `body` against time, with the contact events as markers (Fig. 4.9).
ChartSpec ConditionChart(const record::Trajectory& run, int body, const std::string& title);
// cond₂(M) (analysis::MassMatrixCondition, +∞ where M is singular) of FFD body `body` at
// samples first, first + 1, ... of the run.
std::vector<double> ConditionNumbers(const record::Trajectory& run, int body, int first = 0);
// Times at which the body touched the ground after being clear of it (collisions); the first
// sample is never an event.
std::vector<double> ContactEvents(const record::Trajectory& run, int body);

// The live viewer's recorder (interactive_view.h): a Trajectory sampled as a run goes, with
// cond₂(M) kept per sample so that redrawing the charts does not recompute it. Offline runs
// record with record::Recorder and chart with the functions above.
class RunRecorder {
 public:
  explicit RunRecorder(int body = 0) : body_(body) {}
  // Appends the world now (the world's bodies must stay the same between samples).
  void Sample(const World& world);

  const record::Trajectory& trajectory() const { return run_; }
  std::vector<double> time() const;
  const std::vector<double>& condition() const { return cond_; }
  std::vector<double> contact_events() const { return ContactEvents(run_, body_); }
  ChartSpec EnergyChart(const std::string& title) const { return pipelines::EnergyChart(run_, body_, title); }
  ChartSpec ConditionChart(const std::string& title) const;

 private:
  int body_;
  record::Trajectory run_;
  std::vector<double> cond_;
};

}  // namespace wobble::pipelines
