#include "script_render.h"

#include <iostream>
#include <set>

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
  RenderRequest request = ParseRenderRequest(a, default_what, OptionSpelling::kScript);
  if (!pl::HasDisplay()) {
    std::set<std::string> kept = request.what;
    for (const std::string& w : pl::NeedingDisplay({request.what.begin(), request.what.end()})) kept.erase(w);
    std::string listed;
    for (const std::string& w : kept) listed += (listed.empty() ? "" : ",") + w;
    std::cout << "no X display: render draws no pictures (run under xvfb-run -a -s \"-screen 0 1280x1024x24\")"
              << (kept.empty() ? "" : "; writing " + listed + " only") << "\n";
    if (kept.empty()) return;
    request.what = kept;
  }
  if (run.empty()) throw std::runtime_error("nothing was recorded: no frames to render");
  CheckRenderRequest(request, a.out);
  World world = pl::WorldFor(run, r.world);
  RenderRun(a, request, world, run, run.time(run.size() - 1));
}

std::vector<std::string> RenderScriptScene(const script::SceneRenderRequest& r) {
  const record::Trajectory& run = *r.recorded;
  pl::RenderOutputs out = pl::SceneRenderOutputs(r.folder, r.name, r.drawing.azimuth, r.drawing.elevation);
  pl::SetOutputs(r.what, &out);  // the words were checked by the script's reader
  if (out.mp4 || out.webp) out.fps = r.fps;  // a video at the recorded rate; else every sample is a frame
  if (!pl::HasDisplay()) {
    // as for the cost charts: the exports that need no display are still written
    const std::vector<std::string> skipped = pl::KeepWithoutDisplay(&out);
    std::string listed;
    for (const std::string& w : skipped) listed += (listed.empty() ? "" : ", ") + w;
    if (!skipped.empty()) std::cout << "no X display: " << listed << " skipped (run under xvfb-run -a -s \"-screen 0 1280x1024x24\")\n";
  }
  if (!pl::WritesAnything(out)) return {};
  World world = pl::WorldFor(run, r.world);
  const pl::RenderReport report = pl::RenderTrajectory(world, run, pl::SceneSpecOf(r.drawing.drawings, r.drawing.anchors), out);
  std::vector<std::string> lines;
  for (const pl::RenderReport::File& f : report.files) lines.push_back(f.Line());
  return lines;
}

}  // namespace wobble::app
