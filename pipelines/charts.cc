#include "pipelines/charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <vtkAxis.h>
#include <vtkChartHistogram2D.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkColorTransferFunction.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>

#include "pipelines/exports.h"
#include "pipelines/scene_view.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

template <class T> using Ptr = vtkSmartPointer<T>;

// A colour-blind-friendly palette (Okabe–Ito), then greys.
constexpr unsigned char kPalette[][3] = {{0, 114, 178},  {213, 94, 0},   {0, 158, 115}, {204, 121, 167},
                                         {230, 159, 0},  {86, 180, 233}, {0, 0, 0},     {120, 120, 120},
                                         {240, 228, 66}, {160, 160, 160}};

Ptr<vtkContextView> MakeView(int width, int height) {
  if (!HasDisplay())
    throw std::runtime_error("charts need an X display (VTK 9.1): run under xvfb-run -a -s \"-screen 0 1280x1024x24\"");
  if (width < 32 || height < 32 || width > 8192 || height > 8192)
    throw std::invalid_argument("chart size must be between 32 and 8192 pixels a side");
  auto view = Ptr<vtkContextView>::New();
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetMultiSamples(0);
  view->GetRenderWindow()->SetSize(width, height);
  view->GetRenderer()->SetBackground(1.0, 1.0, 1.0);
  return view;
}

Ptr<vtkImageData> Grab(vtkContextView* view) {
  view->GetRenderWindow()->Render();
  return ReadWindowRgb(view->GetRenderWindow());
}

// VTK 9.1's log axes (vtkAxis::SetLogScale) left the lines of our charts undrawn, so a log
// axis plots log10 of the values on a linear axis titled "log10 ...".
double Axis(double v, bool log) { return log ? std::log10(v) : v; }
std::string AxisTitle(const std::string& title, bool log) { return log ? "log10 " + title : title; }

void StyleAxis(vtkAxis* axis, const std::string& title, bool log) {
  axis->SetTitle(AxisTitle(title, log));
  axis->GetTitleProperties()->SetFontSize(14);
  axis->GetLabelProperties()->SetFontSize(12);
}

void Validate(const ChartSpec& spec) {
  if (spec.series.empty()) throw std::invalid_argument("chart '" + spec.title + "': no series");
  for (const ChartSeries& s : spec.series)
    if (s.x.size() != s.y.size())
      throw std::invalid_argument("chart '" + spec.title + "': series '" + s.name + "' has " +
                                  std::to_string(s.x.size()) + " x and " + std::to_string(s.y.size()) + " y values");
}

bool Usable(double v, bool log) { return std::isfinite(v) && (!log || v > 0.0); }


std::string Num(double v) {
  if (std::isnan(v)) return "nan";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

}  // namespace

namespace {

// One scale on both axes: the plot area's size in pixels is known only once the chart has
// been laid out, and the labels of new ranges can move it by a few pixels, so it is laid out,
// the ranges set around the data's centre, and that done once more.
void EqualAspect(vtkContextView* view, vtkChartXY* chart, const ChartSpec& spec) {
  double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
  for (const ChartSeries& s : spec.series)
    for (size_t i = 0; i < s.x.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        lo[0] = std::min(lo[0], s.x[i]), hi[0] = std::max(hi[0], s.x[i]);
        lo[1] = std::min(lo[1], s.y[i]), hi[1] = std::max(hi[1], s.y[i]);
      }
  if (!(lo[0] <= hi[0])) return;
  vtkAxis* axes[2] = {chart->GetAxis(vtkAxis::BOTTOM), chart->GetAxis(vtkAxis::LEFT)};
  for (int pass = 0; pass < 2; ++pass) {
    view->GetRenderWindow()->Render();
    double pixels[2], units = 0;  // the plot area's pixels, and the larger of units per pixel
    for (int a = 0; a < 2; ++a) {
      const float* p1 = axes[a]->GetPoint1();
      const float* p2 = axes[a]->GetPoint2();
      pixels[a] = std::max(1.0, double(std::abs(p2[a] - p1[a])));
      units = std::max(units, 1.05 * std::max(hi[a] - lo[a], 1e-12) / pixels[a]);  // 5 % margin
    }
    for (int a = 0; a < 2; ++a) {
      const double centre = 0.5 * (lo[a] + hi[a]), half = 0.5 * units * pixels[a];
      axes[a]->SetBehavior(vtkAxis::FIXED);
      axes[a]->SetRange(centre - half, centre + half);
    }
  }
}

}  // namespace

vtkSmartPointer<vtkImageData> RenderChart(const ChartSpec& spec) {
  Validate(spec);
  auto view = MakeView(spec.width, spec.height);
  auto chart = Ptr<vtkChartXY>::New();
  view->GetScene()->AddItem(chart);
  ChartSpec drawn = spec;
  drawn.legend_beside = spec.width >= kLegendBesideWidth;
  FillChart(chart, drawn);
  if (spec.equal_aspect && !spec.log_x && !spec.log_y) EqualAspect(view, chart, spec);
  return Grab(view);
}

RobustRange RobustYRange(const std::vector<ChartSeries>& series) {
  std::vector<double> v;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const ChartSeries& s : series)
    for (size_t i = 0; i < s.y.size() && i < s.x.size(); ++i)
      if (std::isfinite(s.y[i]) && std::isfinite(s.x[i])) {
        v.push_back(s.y[i]);
        lo = std::min(lo, s.y[i]);
        hi = std::max(hi, s.y[i]);
      }
  RobustRange r{lo, hi, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  if (v.size() < 10) return r;
  auto rank = [&](double fraction) {
    const size_t k = std::min(v.size() - 1, size_t(fraction * double(v.size() - 1) + 0.5));
    std::nth_element(v.begin(), v.begin() + long(k), v.end());
    return v[k];
  };
  const double q_lo = rank(0.02), q_hi = rank(0.98), span = q_hi - q_lo;
  if (!(span > 0)) return r;
  const bool cut_high = hi > q_hi + span, cut_low = lo < q_lo - span;
  if (!cut_high && !cut_low) return r;
  if (cut_high) r.hi = q_hi + 0.25 * span;
  if (cut_low) r.lo = q_lo - 0.25 * span;
  // the value farthest off the scale, to name in the title
  double worst = 0;
  for (const ChartSeries& s : series)
    for (size_t i = 0; i < s.y.size() && i < s.x.size(); ++i) {
      if (!std::isfinite(s.y[i]) || !std::isfinite(s.x[i])) continue;
      const double off = std::max(s.y[i] - r.hi, r.lo - s.y[i]);
      if (off > worst) worst = off, r.cut_y = s.y[i], r.cut_x = s.x[i];
    }
  return r;
}

void FillChart(vtkChartXY* chart, const ChartSpec& spec) {
  Validate(spec);
  chart->ClearPlots();
  chart->GetAxis(vtkAxis::LEFT)->SetBehavior(vtkAxis::AUTO);
  chart->SetTitle(spec.title);
  // (shapes on equal axes keep every point: no spike is cut)
  const RobustRange robust =
      spec.robust_y && !spec.log_y && !spec.equal_aspect ? RobustYRange(spec.series) : RobustRange{1, 0, NAN, NAN};
  if (std::isfinite(robust.cut_y)) {
    char note[96];
    std::snprintf(note, sizeof note, " (%s %.3g at x = %.3g off the scale)", robust.cut_y > robust.hi ? "peak" : "dip",
                  robust.cut_y, robust.cut_x);
    chart->SetTitle(spec.title + note);
  }
  chart->GetTitleProperties()->SetFontSize(16);
  chart->SetShowLegend(true);
  // beside the plot area (not inline), so that it never covers data; inline in small charts
  // (the viewer's panels, thumbnails), where beside it would leave little room for the plot
  chart->GetLegend()->SetInline(!spec.legend_beside);
  chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
  chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  StyleAxis(chart->GetAxis(vtkAxis::BOTTOM), spec.x_title, spec.log_x);
  StyleAxis(chart->GetAxis(vtkAxis::LEFT), spec.y_title, spec.log_y);

  // the data range, for the marker lines
  double ylo = std::numeric_limits<double>::infinity(), yhi = -ylo;
  int palette = 0;
  for (const ChartSeries& s : spec.series) {
    auto table = Ptr<vtkTable>::New();
    auto x = Ptr<vtkDoubleArray>::New();
    x->SetName("x");
    auto y = Ptr<vtkDoubleArray>::New();
    y->SetName(s.name.empty() ? "y" : s.name.c_str());
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!Usable(s.x[i], spec.log_x) || !Usable(s.y[i], spec.log_y)) continue;
      x->InsertNextValue(Axis(s.x[i], spec.log_x));
      y->InsertNextValue(Axis(s.y[i], spec.log_y));
      ylo = std::min(ylo, Axis(s.y[i], spec.log_y));
      yhi = std::max(yhi, Axis(s.y[i], spec.log_y));
    }
    if (x->GetNumberOfValues() == 0) continue;  // nothing drawable (e.g. all zero on a log axis)
    table->AddColumn(x);
    table->AddColumn(y);
    vtkPlot* plot = chart->AddPlot(s.points ? vtkChart::POINTS : vtkChart::LINE);
    plot->SetInputData(table, 0, 1);
    plot->SetLabel(s.name);
    const unsigned char* c = kPalette[palette++ % (sizeof(kPalette) / sizeof(kPalette[0]))];
    if (s.rgb[0] >= 0) {
      plot->SetColor((unsigned char)s.rgb[0], (unsigned char)s.rgb[1], (unsigned char)s.rgb[2], 255);
    } else {
      plot->SetColor(c[0], c[1], c[2], 255);
    }
    plot->SetWidth(s.width);
    if (s.points) vtkPlotPoints::SafeDownCast(plot)->SetMarkerStyle(vtkPlotPoints::CIRCLE);
    if (s.segments && !s.points) vtkPlotLine::SafeDownCast(plot)->PolyLineOff();
  }
  // VTK 9.1 draws no line when a plot's y range is tiny next to its magnitude (e.g. log10
  // cond(M) between 5.38 and 5.42): give such an axis a fixed, wider range: whole decades on
  // a log axis, at least ±5% of the magnitude on a linear one
  if (std::isfinite(robust.cut_y)) {  // a spike: the bulk's range (clipped lines run off the plot)
    ylo = robust.lo;
    yhi = robust.hi;
    chart->GetAxis(vtkAxis::LEFT)->SetBehavior(vtkAxis::FIXED);
    chart->GetAxis(vtkAxis::LEFT)->SetRange(ylo, yhi);
  } else if (ylo <= yhi) {
    double lo = ylo, hi = yhi;
    if (spec.log_y) {
      lo = std::floor(ylo);
      hi = std::max(std::ceil(yhi), lo + 1.0);
    } else if (hi - lo < 0.1 * std::max(std::abs(lo), std::abs(hi))) {
      const double pad = 0.05 * std::max(std::abs(lo), std::abs(hi));
      lo -= pad;
      hi += pad;
    }
    if (lo != ylo || hi != yhi) {
      chart->GetAxis(vtkAxis::LEFT)->SetBehavior(vtkAxis::FIXED);
      chart->GetAxis(vtkAxis::LEFT)->SetRange(lo, hi);
    }
  }
  // whole-number x (iterations, seeds): ticks on whole numbers only, 1, 2 or 5 times a power
  // of ten apart, about eight of them
  vtkAxis* bottom = chart->GetAxis(vtkAxis::BOTTOM);
  bottom->SetCustomTickPositions(nullptr);
  if (spec.integer_x && !spec.log_x) {
    double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo;
    for (const ChartSeries& s : spec.series)
      for (double v : s.x)
        if (std::isfinite(v)) xlo = std::min(xlo, v), xhi = std::max(xhi, v);
    if (xlo <= xhi) {
      double step = 1.0;
      for (double decade = 1.0; (xhi - xlo) / step > 8.0; decade *= 10.0)
        for (double m : {1.0, 2.0, 5.0})
          if ((xhi - xlo) / step > 8.0) step = m * decade;
      auto ticks = Ptr<vtkDoubleArray>::New();
      for (double t = std::ceil(xlo / step) * step; t <= xhi; t += step) ticks->InsertNextValue(t);
      bottom->SetCustomTickPositions(ticks);
    }
  }
  // a marker at the end of the data (a sweep's singular last sample) would lie on the plot's
  // border: the x range then reaches 3 % past it
  bottom->SetBehavior(vtkAxis::AUTO);
  if (!spec.markers.empty() && !spec.log_x) {
    double xlo = std::numeric_limits<double>::infinity(), xhi = -xlo;
    for (const ChartSeries& s : spec.series)
      for (double v : s.x)
        if (std::isfinite(v)) xlo = std::min(xlo, v), xhi = std::max(xhi, v);
    bool at_an_end = false;
    for (double m : spec.markers)
      if (std::isfinite(m) && (m <= xlo || m >= xhi)) {
        at_an_end = true;
        xlo = std::min(xlo, m), xhi = std::max(xhi, m);
      }
    if (at_an_end && xlo < xhi) {
      const double pad = 0.03 * (xhi - xlo);
      bottom->SetBehavior(vtkAxis::FIXED);
      bottom->SetRange(xlo - pad, xhi + pad);
    }
  }
  // vertical markers: one dashed two-point line each, one legend entry for all of them
  if (!spec.markers.empty() && ylo <= yhi) {
    bool first = true;
    for (double mx : spec.markers) {
      if (!Usable(mx, spec.log_x)) continue;
      auto table = Ptr<vtkTable>::New();
      auto x = Ptr<vtkDoubleArray>::New();
      x->SetName("x");
      auto y = Ptr<vtkDoubleArray>::New();
      y->SetName(spec.markers_name.c_str());
      x->InsertNextValue(Axis(mx, spec.log_x));
      x->InsertNextValue(Axis(mx, spec.log_x));
      y->InsertNextValue(ylo);
      y->InsertNextValue(yhi);
      table->AddColumn(x);
      table->AddColumn(y);
      vtkPlot* plot = chart->AddPlot(vtkChart::LINE);
      plot->SetInputData(table, 0, 1);
      plot->SetLabel(spec.markers_name);
      plot->SetColor(150, 150, 150, 255);
      plot->SetWidth(1.0f);
      plot->GetPen()->SetLineType(vtkPen::DASH_LINE);
      plot->SetLegendVisibility(first);
      first = false;
    }
  }
}

void WriteChartCsv(const ChartSpec& spec, const std::string& csv_path) {
  Validate(spec);
  bool same_x = true;
  for (const ChartSeries& s : spec.series) same_x = same_x && s.x == spec.series[0].x;
  const std::string x_name = spec.x_title.empty() ? "x" : spec.x_title;
  std::string text;
  if (same_x) {
    text = CsvField(x_name);
    for (const ChartSeries& s : spec.series) text += "," + CsvField(s.name);
    text += "\n";
    for (size_t i = 0; i < spec.series[0].x.size(); ++i) {
      text += Num(spec.series[0].x[i]);
      for (const ChartSeries& s : spec.series) text += "," + Num(s.y[i]);
      text += "\n";
    }
  } else {
    text = "series," + CsvField(x_name) + "," + CsvField(spec.y_title.empty() ? "y" : spec.y_title) + "\n";
    for (const ChartSeries& s : spec.series)
      for (size_t i = 0; i < s.x.size(); ++i) text += CsvField(s.name) + "," + Num(s.x[i]) + "," + Num(s.y[i]) + "\n";
  }
  formats::WriteTextAtomically(csv_path, text);
  if (!spec.markers.empty()) {
    namespace fs = std::filesystem;
    const fs::path p(csv_path);
    std::string markers = CsvField(x_name) + "\n";
    for (double m : spec.markers) markers += Num(m) + "\n";
    formats::WriteTextAtomically((p.parent_path() / (p.stem().string() + "_markers.csv")).string(), markers);
  }
}

void WriteChart(const ChartSpec& spec, const std::string& png_path, const std::string& csv_path) {
  if (!csv_path.empty()) WriteChartCsv(spec, csv_path);
  if (!png_path.empty()) WritePng(png_path, RenderChart(spec));
}

vtkSmartPointer<vtkImageData> RenderScalarField(const ScalarFieldSpec& spec) {
  if (spec.nx < 1 || spec.ny < 1 || spec.values.size() != size_t(spec.nx) * spec.ny)
    throw std::invalid_argument("scalar field '" + spec.title + "': values must be nx * ny");
  // the field as an image in data coordinates, coloured through a transfer function
  auto image = Ptr<vtkImageData>::New();
  image->SetDimensions(spec.nx, spec.ny, 1);
  // the chart draws sample i as the cell [origin + i h, origin + (i + 1) h]: centre it on its x
  const double hx = spec.nx > 1 ? (spec.x_max - spec.x_min) / (spec.nx - 1) : 1.0;
  const double hy = spec.ny > 1 ? (spec.y_max - spec.y_min) / (spec.ny - 1) : 1.0;
  image->SetOrigin(spec.x_min - 0.5 * hx, spec.y_min - 0.5 * hy, 0.0);
  image->SetSpacing(hx, hy, 1.0);
  image->AllocateScalars(VTK_DOUBLE, 1);
  auto* v = static_cast<double*>(image->GetScalarPointer());
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t i = 0; i < spec.values.size(); ++i) {
    double value = spec.values[i];
    if (spec.log_values) value = value > 0 ? std::log10(value) : std::numeric_limits<double>::quiet_NaN();
    v[i] = value;
    if (std::isfinite(value)) {
      lo = std::min(lo, value);
      hi = std::max(hi, value);
    }
  }
  if (!(lo <= hi)) lo = 0, hi = 1;
  if (hi == lo) hi = lo + 1;
  auto tf = Ptr<vtkColorTransferFunction>::New();
  tf->SetColorSpaceToDiverging();
  tf->AddRGBPoint(lo, 0.23, 0.30, 0.75);
  tf->AddRGBPoint(0.5 * (lo + hi), 0.87, 0.87, 0.87);
  tf->AddRGBPoint(hi, 0.71, 0.02, 0.15);
  tf->SetNanColor(0.5, 0.5, 0.5);

  auto view = MakeView(spec.width, spec.height);
  auto chart = Ptr<vtkChartHistogram2D>::New();
  view->GetScene()->AddItem(chart);
  chart->SetInputData(image);
  chart->SetTransferFunction(tf);
  std::string colour = spec.log_values ? "log10 " + spec.value_title : spec.value_title;
  chart->SetTitle(spec.title + (colour.empty() || colour == "log10 " ? "" : "  (colour: " + colour + ")"));
  StyleAxis(chart->GetAxis(vtkAxis::BOTTOM), spec.x_title, false);
  StyleAxis(chart->GetAxis(vtkAxis::LEFT), spec.y_title, false);
  return Grab(view);
}

void WriteScalarFieldPng(const ScalarFieldSpec& spec, const std::string& png_path) {
  WritePng(png_path, RenderScalarField(spec));
}

}  // namespace wobble::pipelines
