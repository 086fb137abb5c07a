// Pictures of the conditioning analysis (thesis §4.10.3, wobble/analysis/conditioning.h):
// Fig. 4.7 (cond against the angle between the squashes), Fig. 4.8 (the same without the last
// samples, points only) and the map of cond over the angle and a second parameter. Drawn with
// charts.h; the condition-number-against-time chart (Fig. 4.9) is RunRecorder's.
#pragma once

#include <vector>

#include "pipelines/charts.h"
#include "wobble/analysis/conditioning.h"

namespace wobble::pipelines {

// Fig. 4.7: cond(M) and the unit-free cond(S M S) against φ in degrees, log scale. Singular
// samples have no finite value and are left out.
ChartSpec SweepChart(const std::vector<analysis::SweepSample>& samples);
// Fig. 4.8: raw cond(M) without the last `drop_last` samples, as points, linear scale.
ChartSpec SmallAngleChart(const std::vector<analysis::SweepSample>& samples, int drop_last);

// A regular grid of cond values (nx × ny, row-major, row 0 at y0), +∞ where M is singular.
struct ConditionGrid {
  int nx = 0, ny = 0;
  double x0 = 0, dx = 1, y0 = 0, dy = 1;
  std::vector<double> cond;
};
// Colour-mapped by log10 cond; singular cells are left uncoloured.
ScalarFieldSpec ConditionMapField(const ConditionGrid& grid, const std::string& x_title, const std::string& y_title);

}  // namespace wobble::pipelines
