#include "pipelines/energy_charts.h"

#include <algorithm>
#include <stdexcept>

#include "wobble/analysis/conditioning.h"

namespace wobble::pipelines {
namespace {

std::vector<double> Times(const record::Trajectory& run) {
  std::vector<double> t(run.size());
  for (int k = 0; k < run.size(); ++k) t[k] = run.time(k);
  return t;
}

const record::BodyInfo& FfdInfo(const record::Trajectory& run, int body) {
  if (body < 0 || body >= run.num_bodies() || !run.bodies()[body].has_ffd())
    throw std::invalid_argument("cond(M): body " + std::to_string(body) + " is not an FFD body of the run");
  return run.bodies()[body];
}

ChartSpec ConditionChartOf(const record::Trajectory& run, int body, const std::vector<double>& cond, const std::string& title) {
  ChartSpec spec;
  spec.title = title;
  spec.x_title = "time (s)";
  spec.y_title = "cond(M)";  // linear like Fig. 4.9: over a run it varies by percents, not decades
  ChartSeries s;
  s.name = "cond(M)";
  s.x = Times(run);
  s.y = cond;
  spec.series.push_back(std::move(s));
  spec.markers = ContactEvents(run, body);
  spec.markers_name = "contact";
  return spec;
}

}  // namespace

std::vector<double> ContactEvents(const record::Trajectory& run, int body) {
  std::vector<double> events;
  bool touching = false;
  for (int k = 0; k < run.size(); ++k) {
    const bool now = run.contacts(k, body) > 0;
    if (now && !touching && k > 0) events.push_back(run.time(k));
    touching = now;
  }
  return events;
}

std::vector<double> ConditionNumbers(const record::Trajectory& run, int body, int first) {
  const record::BodyInfo& info = FfdInfo(run, body);
  std::vector<double> cond;
  for (int k = std::max(0, first); k < run.size(); ++k) {
    const Eigen::VectorXd q = run.q(k, body);
    if (const BodyModel* ffd = info.ffd<2>()) {
      cond.push_back(analysis::MassMatrixCondition(*ffd, q).cond);  // +∞ when M is singular
    } else {
      // a 3D row: tx ty tz qw qx qy qz γ..
      const BodyModelN<3>& model = *info.ffd<3>();
      BodyState<3, double> s = RestState<3, double>(model);
      s.translation() = q.head<3>();
      Group<3>::SetOrientation(Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized(), &s.q);
      s.gamma() = q.tail(model.num_modes());
      cond.push_back(analysis::MassMatrixCondition(model, s).cond);
    }
  }
  return cond;
}

ChartSpec EnergyChart(const record::Trajectory& run, int body, const std::string& title) {
  if (body < 0 || body >= run.num_bodies()) throw std::invalid_argument("energy chart: no body " + std::to_string(body));
  const record::BodyInfo& info = run.bodies()[body];
  const int num_modes = info.num_modes();
  std::vector<double> kinetic, gravity, deformation, ground, springs, total;
  std::vector<std::vector<double>> modes(num_modes);  // [mode][sample]
  for (int k = 0; k < run.size(); ++k) {
    const Energies e = run.energies(k, body);
    kinetic.push_back(e.kinetic);
    gravity.push_back(e.gravity);
    deformation.push_back(e.modes);
    ground.push_back(e.ground);
    springs.push_back(e.springs);
    total.push_back(e.total());
    for (int d = 0; d < num_modes; ++d) modes[d].push_back(e.per_mode[d]);  // K (γ − γ0)² (§4.7)
  }
  ChartSpec spec;
  spec.title = title;
  spec.x_title = "time (s)";
  spec.y_title = "energy";
  const std::vector<double> t = Times(run);
  auto add = [&](const std::string& name, const std::vector<double>& y, bool always) {
    if (!always && std::all_of(y.begin(), y.end(), [](double v) { return v == 0.0; })) return;
    ChartSeries s;
    s.name = name;
    s.x = t;
    s.y = y;
    spec.series.push_back(std::move(s));
  };
  add("kinetic", kinetic, true);
  add("gravity", gravity, true);
  for (int d = 0; d < num_modes; ++d) {
    const std::string& name = info.mode_name(d);
    add("mode " + (name.empty() ? std::to_string(d + 1) : name), modes[d], false);
  }
  if (info.kind == BodyKind::kLinear) add("deformation", deformation, false);
  add("ground", ground, false);
  add("springs", springs, false);
  add("total", total, true);
  spec.series.back().width = 3.0f;
  spec.markers = ContactEvents(run, body);
  spec.markers_name = "contact";
  return spec;
}

ChartSpec ConditionChart(const record::Trajectory& run, int body, const std::string& title) {
  return ConditionChartOf(run, body, ConditionNumbers(run, body), title);
}

void RunRecorder::Sample(const World& world) {
  if (run_.num_bodies() == 0) run_ = record::Trajectory(world);
  run_.Append(world);
  const std::vector<double> now = ConditionNumbers(run_, body_, run_.size() - 1);
  cond_.insert(cond_.end(), now.begin(), now.end());
}

std::vector<double> RunRecorder::time() const { return Times(run_); }

ChartSpec RunRecorder::ConditionChart(const std::string& title) const { return ConditionChartOf(run_, body_, cond_, title); }

}  // namespace wobble::pipelines
