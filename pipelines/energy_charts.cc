#include "pipelines/energy_charts.h"

#include <algorithm>
#include <limits>

#include "wobble/analysis/conditioning.h"

namespace wobble::pipelines {

void RunRecorder::Sample(const World& world) {
  const BodyModel& body = world.body(body_);
  if (mode_names_.empty() && body.num_modes() > 0) {
    for (const DeformationMode& m : body.modes()) mode_names_.push_back(m.name);
    modes_.resize(body.num_modes());
  }
  const Energies e = world.ComputeEnergies(body_);
  t_.push_back(world.time());
  kinetic_.push_back(e.kinetic);
  gravity_.push_back(e.gravity);
  ground_.push_back(e.ground);
  springs_.push_back(e.springs);
  total_.push_back(e.total());
  for (int d = 0; d < body.num_modes(); ++d) modes_[d].push_back(e.per_mode[d]);  // K (γ − γ0)² (§4.7)
  // +∞ when M is singular (analysis::Condition's numerical-rank test)
  cond_.push_back(analysis::MassMatrixCondition(body, world.state(body_).q).cond);
  const bool touching = !world.state(body_).contacts.empty();
  if (touching && !touching_ && t_.size() > 1) events_.push_back(world.time());
  touching_ = touching;
}

ChartSpec RunRecorder::EnergyChart(const std::string& title) const {
  ChartSpec spec;
  spec.title = title;
  spec.x_title = "time (s)";
  spec.y_title = "energy";
  auto add = [&](const std::string& name, const std::vector<double>& y, bool always) {
    if (!always && std::all_of(y.begin(), y.end(), [](double v) { return v == 0.0; })) return;
    ChartSeries s;
    s.name = name;
    s.x = t_;
    s.y = y;
    spec.series.push_back(std::move(s));
  };
  add("kinetic", kinetic_, true);
  add("gravity", gravity_, true);
  for (size_t d = 0; d < modes_.size(); ++d)
    add("mode " + (mode_names_[d].empty() ? std::to_string(d + 1) : mode_names_[d]), modes_[d], false);
  add("ground", ground_, false);
  add("springs", springs_, false);
  add("total", total_, true);
  spec.series.back().width = 3.0f;
  spec.markers = events_;
  spec.markers_name = "contact";
  return spec;
}

ChartSpec RunRecorder::ConditionChart(const std::string& title) const {
  ChartSpec spec;
  spec.title = title;
  spec.x_title = "time (s)";
  spec.y_title = "cond(M)";  // linear like Fig. 4.9: over a run it varies by percents, not decades
  ChartSeries s;
  s.name = "cond(M)";
  s.x = t_;
  s.y = cond_;
  spec.series.push_back(std::move(s));
  spec.markers = events_;
  spec.markers_name = "contact";
  return spec;
}

}  // namespace wobble::pipelines
