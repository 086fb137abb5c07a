// Charts and colour-mapped fields as PNG (vtkChartXY / vtkChartHistogram2D, rendered
// offscreen) with their numbers beside them as CSV. Generic: energies, condition numbers,
// sweeps all go through these. Rendering needs an X display (see scene_view.h: HasDisplay()).
#pragma once

#include <string>
#include <vector>
#include <vtkSmartPointer.h>

class vtkChartXY;
class vtkImageData;

namespace wobble::pipelines {

struct ChartSeries {
  std::string name;
  std::vector<double> x, y;  // same length
  bool points = false;       // markers without lines (like thesis Fig. 4.8) instead of a line
  bool segments = false;     // a line per pair of points (P1P2, P3P4, ...) instead of one polyline
  // Colour 0..255; a negative red picks the next colour of a fixed palette.
  int rgb[3] = {-1, 0, 0};
  float width = 2.0f;
};

struct ChartSpec {
  std::string title, x_title, y_title;
  // Log axes plot log10 of the values (titled "log10 ..."); values <= 0 are skipped.
  bool log_x = false, log_y = false;
  // x is a whole number (iterations, seeds): ticks on whole numbers only
  bool integer_x = false;
  std::vector<ChartSeries> series;
  // Vertical dashed lines at these x (e.g. the times of contact events), named in the legend.
  std::vector<double> markers;
  std::string markers_name = "events";
  int width = 800, height = 500;  // pixels
  // The legend beside the plot area instead of over it. RenderChart sets it for charts at
  // least kLegendBesideWidth wide (files); FillChart's callers (the viewer's panels) choose.
  bool legend_beside = false;
  // A linear y axis ignores a spike: when some values lie more than the bulk's span (the 2nd
  // to 98th percentile of every value plotted) beyond it, the axis shows the bulk with a
  // quarter span's margin, and the title says what was cut ("peak 1.3e9 at x = 0.41 off
  // the scale"). The CSV keeps every value.
  bool robust_y = true;
  // x and y in the same units (shapes, positions): RenderChart gives both axes one scale, so
  // that a circle is drawn round, and shows every point (robust_y does not apply); linear
  // axes only.
  bool equal_aspect = false;
};
constexpr int kLegendBesideWidth = 600;

// The y range a linear axis shows for these values (robust_y above), and the value farthest
// outside it (NaN when nothing is cut); lo > hi for no finite value.
struct RobustRange {
  double lo, hi;
  double cut_y, cut_x;
};
RobustRange RobustYRange(const std::vector<ChartSeries>& series);

// Renders the chart offscreen (RGB image, bottom row first). Throws std::invalid_argument for
// a malformed spec, std::runtime_error without a display.
vtkSmartPointer<vtkImageData> RenderChart(const ChartSpec& spec);
// Replaces the plots of an existing chart by the spec's (title, axes, series, markers; the
// size fields are not used): what RenderChart draws, for a chart that lives in a window of
// its own, e.g. the interactive viewer's live panel, redrawn as the run goes on.
void FillChart(vtkChartXY* chart, const ChartSpec& spec);

// Writes the chart as PNG and its data as CSV, both atomically. The CSV has a header row;
// when every series shares one x it is wide (x, then one column per series), otherwise long
// (series, x, y). Markers, when there are any, go to <csv stem>_markers.csv (one column x).
// Either path may be empty to skip that file.
void WriteChart(const ChartSpec& spec, const std::string& png_path, const std::string& csv_path);
void WriteChartCsv(const ChartSpec& spec, const std::string& csv_path);

// A 2D scalar field as a colour-mapped image with axes and a colour bar.
struct ScalarFieldSpec {
  std::string title, x_title, y_title, value_title;
  int nx = 0, ny = 0;          // samples along x and y
  std::vector<double> values;  // nx * ny, row-major, row 0 at the BOTTOM (y = y_min)
  double x_min = 0, x_max = 1, y_min = 0, y_max = 1;  // centres of the first/last samples
  bool log_values = false;     // colour by log10 of the value (positive values only)
  int width = 800, height = 600;
};
vtkSmartPointer<vtkImageData> RenderScalarField(const ScalarFieldSpec& spec);
void WriteScalarFieldPng(const ScalarFieldSpec& spec, const std::string& png_path);

}  // namespace wobble::pipelines
