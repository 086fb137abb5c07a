// Pictures and exports of a recorded World run (Witkin & Welch scenes: `render` in
// a script): PNG frames, a filmstrip and a ParaView .pvd series, through SceneView and the
// writers of exports.h. The camera is fixed for the run and frames the whole recorded motion.
#pragma once

#include <string>
#include <vector>

#include "pipelines/scene_view.h"
#include "wobble/control/behaviours.h"
#include "wobble/record/scene_recording.h"

namespace wobble::pipelines {

struct SceneRunOutputs {
  std::string folder;           // created if missing
  std::string name = "scene";   // stem of the .pvd and .vtp files
  bool frames = true, filmstrip = true, vtp = true;
  int width = 640, height = 480;
  // Filmstrip panels: the recorded frames nearest these times (empty: 6 evenly spaced).
  std::vector<double> filmstrip_times;
  int filmstrip_width = 320, filmstrip_height = 240, filmstrip_columns = 3;
  SceneOptions view = DefaultView();  // sizes, 3D camera angles (width/height come from above)
  static SceneOptions DefaultView() {
    SceneOptions o;
    o.point_size = 5.0;  // a scene has many mass points: smaller dots than the FFD view's
    return o;
  }
};

// Writes <folder>/frames/frame_NNNN.png (one per recorded frame), <folder>/filmstrip.png and
// <folder>/vtp/<name>.pvd with, per frame and linear body b, parts 3b, 3b+1, 3b+2 (control
// box, mass points, shape; FFD bodies: lattice, mass points, shape). Rendering needs
// HasDisplay() (frames, filmstrip); vtp does not. The world is left in the state of the last
// frame. Returns the paths written (the frame pattern once). Throws std::runtime_error on a
// failed write and std::invalid_argument on an empty recording.
// What a script's scene draws besides its bodies (`render` and `wobble view`): its drawings
// and its named points (`point`, `place`) as anchors.
ConstrainedSceneSpec SceneSpecOf(const std::vector<LinearDrawing>& drawings, const std::vector<control::Anchor>& anchors);

std::vector<std::string> WriteSceneRun(World& world, const ConstrainedSceneSpec& spec,
                                       const std::vector<record::SceneFrame>& frames, const SceneRunOutputs& out);

}  // namespace wobble::pipelines
