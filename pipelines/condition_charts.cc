#include "pipelines/condition_charts.h"

#include <cmath>

namespace wobble::pipelines {
namespace {

double Deg(double rad) { return rad * 180.0 / 3.14159265358979323846; }

}  // namespace

ChartSpec SweepChart(const std::vector<analysis::SweepSample>& samples) {
  ChartSpec spec;
  spec.title = "cond(M) vs angle between vertical squash and rotated squash (Fig. 4.7)";
  spec.x_title = "phi (degrees)";
  spec.y_title = "cond(M)";
  spec.log_y = true;
  ChartSeries raw, scaled;
  raw.name = "cond(M)";
  // The raw M mixes units (mass, mass·length²), which bounds cond away from the modes'
  // closeness until φ is within a fraction of a degree of π/2; the unit-free scaled cond shows
  // the closeness itself.
  scaled.name = "cond(S M S), S = diag(M)^-1/2";
  for (const analysis::SweepSample& s : samples) {
    // a singular M has no finite cond to plot: a dashed line marks where, named in the legend
    if (s.cond.singular) {
      spec.markers.push_back(Deg(s.phi));
      continue;
    }
    raw.x.push_back(Deg(s.phi));
    raw.y.push_back(s.cond.cond);
    scaled.x.push_back(Deg(s.phi));
    scaled.y.push_back(s.cond.cond_scaled);
  }
  spec.markers_name = "M singular: the two modes coincide";
  spec.series = {raw, scaled};
  return spec;
}

ChartSpec SmallAngleChart(const std::vector<analysis::SweepSample>& samples, int drop_last) {
  ChartSpec spec;
  spec.title = "the same without the last samples, points only (Fig. 4.8)";
  spec.x_title = "phi (degrees)";
  spec.y_title = "cond(M)";
  ChartSeries raw;
  raw.name = "cond(M)";
  raw.points = true;
  const size_t keep = samples.size() > size_t(std::max(0, drop_last)) ? samples.size() - size_t(drop_last) : 0;
  for (size_t i = 0; i < keep; ++i) {
    if (samples[i].cond.singular) continue;
    raw.x.push_back(Deg(samples[i].phi));
    raw.y.push_back(samples[i].cond.cond);
  }
  spec.series = {raw};
  return spec;
}

ScalarFieldSpec ConditionMapField(const ConditionGrid& g, const std::string& x_title, const std::string& y_title) {
  ScalarFieldSpec spec;
  spec.title = "cond(M) over " + x_title + " and " + y_title;
  spec.x_title = x_title;
  spec.y_title = y_title;
  spec.value_title = "cond(M)";
  spec.nx = g.nx;
  spec.ny = g.ny;
  for (double c : g.cond) spec.values.push_back(std::isfinite(c) ? c : std::nan(""));
  spec.x_min = g.x0;
  spec.x_max = g.x0 + g.dx * (g.nx - 1);
  spec.y_min = g.y0;
  spec.y_max = g.y0 + g.dy * (g.ny - 1);
  spec.log_values = true;
  return spec;
}

}  // namespace wobble::pipelines
