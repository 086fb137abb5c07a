#include "script_render.h"

#include <iostream>

#include "cli_common.h"
#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "render.h"

namespace wobble::app {

namespace pl = wobble::pipelines;

void RenderScriptRuns(const script::RenderRequest& r) {
  const record::Trajectory& run = *r.trajectory;
  const std::string default_what = "frames,filmstrip,charts";
  RenderArgs a;
  a.out = r.dir;
  a.what = r.what.empty() ? default_what : r.what;
  for (const auto& [name, value] : r.options) a.picture[name] = value;  // a later one wins
  try {
    scene::ParseRenderOptions(a.picture);  // checked here to name the options as the script spells them
  } catch (const scene::RenderOptionError& e) {
    throw std::invalid_argument(e.option + "=: " + e.what());
  }
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
