#include "script_render.h"

#include <algorithm>
#include <cmath>
#include <iostream>

#include "cli_common.h"
#include "wobble/formats/line_reader.h"
#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "render.h"

namespace wobble::app {

namespace pl = wobble::pipelines;

namespace {

// One `NAME=VALUE` of a script's render line: the option of `wobble render` by the same name
// (lists take commas: filmstrip=0.5,1,1.5).
void ApplyRenderOption(const std::string& name, const std::string& value, RenderArgs* a) {
  auto number = [&] {
    double v;
    if (!formats::detail::ParseNumber(value, &v) || !std::isfinite(v))
      throw std::invalid_argument(name + "=: expected a number, got '" + value + "'");
    return v;
  };
  auto spaced = [&] {
    std::string t = value;
    std::replace(t.begin(), t.end(), ',', ' ');
    return t;
  };
  if (name == "size") a->size = value;
  else if (name == "fps") a->fps = number();
  else if (name == "filmstrip") a->filmstrip_times = spaced();
  else if (name == "filmstrip-size") a->filmstrip_size = value;
  else if (name == "filmstrip-cycle") a->filmstrip_cycle = spaced();
  else if (name == "filmstrip-columns") {
    const double v = number();
    if (!(v >= 0 && v <= 100 && v == std::floor(v)))
      throw std::invalid_argument("filmstrip-columns=: expected a whole number from 0 to 100, got '" + value + "'");
    a->filmstrip_columns = int(v);
  } else if (name == "color-by") a->color_by = value;
  else if (name == "shape-samples") {
    const double v = number();
    if (!(v >= 1 && v <= 10000 && v == std::floor(v)))
      throw std::invalid_argument("shape-samples=: expected a whole number from 1 to 10000, got '" + value + "'");
    a->shape_samples = int(v);
  } else if (name == "chart-size") a->chart_size = value;
  else if (name == "disp-size") a->disp_size = value;
  else if (name == "trail") a->trail = spaced();
  else if (name == "azimuth") a->azimuth = number();
  else if (name == "elevation") a->elevation = number();
  else if (name == "orbit") a->orbit = number();
  else if (name == "camera") a->camera = value;
  else if (name == "style") a->style = value;
  else if (name == "exr-terrain") {
    if (value != "on" && value != "off") throw std::invalid_argument("exr-terrain=: expected on or off, got '" + value + "'");
    a->exr_terrain = value == "on";
  } else
    throw std::invalid_argument("unknown option '" + name + "' (" + script::RenderOptionNames() + ")");
}

}  // namespace

void RenderScriptRuns(const script::RenderRequest& r) {
  const record::Trajectory& run = *r.trajectory;
  const std::string default_what = "frames,filmstrip,charts";
  RenderArgs a;
  a.out = r.dir;
  a.what = r.what.empty() ? default_what : r.what;
  for (const auto& [name, value] : r.options) ApplyRenderOption(name, value, &a);
  if (!pl::HasDisplay()) {
    std::string kept;
    for (const char* w : {"vtp", "disp"})
      if (("," + a.what + ",").find(std::string(",") + w + ",") != std::string::npos) kept += (kept.empty() ? "" : ",") + std::string(w);
    std::cout << "no X display: render draws no pictures (run under xvfb-run -a -s \"-screen 0 1280x1024x24\")"
              << (kept.empty() ? "" : "; writing " + kept + " only") << "\n";
    if (kept.empty()) return;
    a.what = kept;
  }
  if (run.empty()) throw std::runtime_error("nothing was recorded: no frames to render");
  World world = pl::WorldFor(run, r.world);
  RenderRun(a, default_what, world, run, run.time(run.size() - 1));  // a bad option: the script's line
}

std::vector<std::string> RenderScriptScene(const script::SceneRenderRequest& r) {
  const record::Trajectory& run = *r.recorded;
  pl::RenderOutputs out = pl::SceneRenderOutputs(r.folder, r.name, r.drawing.azimuth, r.drawing.elevation);
  out.frames = r.frames;
  out.filmstrip = r.filmstrip;
  out.vtp = r.vtp;
  if ((out.frames || out.filmstrip) && !pl::HasDisplay()) {
    // as for the cost charts: the exports that need no display are still written
    std::cout << "no X display: frames and filmstrip skipped (run under xvfb-run -a -s \"-screen 0 1280x1024x24\")\n";
    out.frames = out.filmstrip = false;
  }
  if (!out.frames && !out.filmstrip && !out.vtp) return {};
  World world = pl::WorldFor(run, r.world);
  const pl::RenderReport report = pl::RenderTrajectory(world, run, pl::SceneSpecOf(r.drawing.drawings, r.drawing.anchors), out);
  std::vector<std::string> lines;
  for (const pl::RenderReport::File& f : report.files) lines.push_back(f.Line());
  return lines;
}

}  // namespace wobble::app
