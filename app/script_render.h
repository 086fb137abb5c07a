// A script's `render` (`wobble run`): the interpreter's requests drawn by the one render driver
// (pipelines/trajectory_render.h), as `wobble render` draws its runs. Built with the pipelines
// only (app/run.cc calls these under WOBBLE_HAVE_PIPELINES).
#pragma once

#include <string>
#include <vector>

#include "wobble/script/interpreter.h"

namespace wobble::app {

// `render DIR [WHAT]` of the FFD object's runs: request.trajectory (one body) drawn like
// `wobble render --what WHAT` (default frames,filmstrip,charts) in a world of request.world's
// options. Without a display only vtp and disp are written, with a message.
void RenderScriptRuns(const script::RenderRequest& request);
// `render DIR [WHAT]` with a Witkin & Welch scene: the recorded frames (of the scene's bodies)
// drawn with the scene's drawings and named points. Returns what was written.
std::vector<std::string> RenderScriptScene(const script::SceneRenderRequest& request);

}  // namespace wobble::app
