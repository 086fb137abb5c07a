// A script's `render` (`wobble run`): the interpreter's requests drawn by the one render driver
// (pipelines/trajectory_render.h), as `wobble render` draws its runs. Built with the pipelines
// only (app/run.cc calls these under WOBBLE_HAVE_PIPELINES).
#pragma once

#include <string>
#include <vector>

#include "wobble/record/trajectory.h"
#include "wobble/script/interpreter.h"

namespace wobble::app {

// `render DIR [WHAT]` of the FFD object's runs: `run` (of one body, request.body) drawn like
// `wobble render --what WHAT` (default frames,filmstrip,charts) in a world of request.world's
// options. Without a display only vtp and disp are written, with a message.
void RenderScriptRuns(const script::RenderRequest& request, const record::Trajectory& run);
// `render DIR [WHAT]` with a Witkin & Welch scene: `run` (of the scene world's bodies) drawn
// into request.world with the scene's drawings and named points. Returns what was written.
std::vector<std::string> RenderScriptScene(const script::SceneRenderRequest& request, const record::Trajectory& run);

// The request's recorded states as a Trajectory, until the interpreter records one itself.
record::Trajectory TrajectoryOf(const script::RenderRequest& request);
// The scene's recorded frames as a Trajectory (puts each into request.world on the way).
record::Trajectory TrajectoryOf(const script::SceneRenderRequest& request);

}  // namespace wobble::app
