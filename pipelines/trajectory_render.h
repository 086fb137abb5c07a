// The one render driver: a recorded run (record::Trajectory) turned into PNG frames, a
// filmstrip, a ParaView .vtp/.pvd series, EXR frames (exr_frame.h), displacement images
// (disp.X, disp.Y over an FFD body's rest lattice), charts (energy and cond(M) against
// time, PNG + CSV) and a glTF 2.0 animation (gltf_export.h), for `wobble render`/`export`, a script's `render` (its FFD runs and its
// Witkin & Welch scenes) alike. Every sample is put back into a world (Trajectory::Restore)
// and drawn by SceneView and the sources of world_sources.h; the camera is fixed for the run
// and frames the whole motion.
//
// Layout under out.folder (what is asked for):
//   frames/frame_NNNN.png   one per frame
//   filmstrip.png           the panels side by side, filmstrip_columns per row
//   vtp/NAME.pvd            per frame and body b parts 3b, 3b+1, 3b+2 (lattice or control
//                           box, mass points, shape), files vtp/<body>_<part>_NNNN.vtp
//   exr/frame_NNNN.exr      the frame for compositing (exr_frame.h): the characters' R, G, B,
//                           A, depth.Z, the characters' motion to the next frame (forward.u,
//                           forward.v; 0 on the last), and with view.exr_terrain_layer the
//                           rest as terrain.R/G/B/A
//   exr/disp_NNNN.exr       each FFD body's displacement image (disp_<body>_NNNN.exr when
//                           the world has more than one FFD body)
//   vti/disp_NNNN.vti       a 3D FFD body's displacement volume instead (DisplacementVolume),
//   vti/disp.pvd            with their ParaView time series
//   energy.png/.csv, condition.png/.csv   charts of body chart_body (condition: FFD bodies)
//   NAME.mp4, NAME.webp     the frames as an H.264 video, an animated WebP, at fps (video_writer.h)
//   NAME.glb                glTF 2.0 binary (gltf_export.h): each body's mesh or drawing with
//                           morph targets (an FFD body's modes), its rigid motion and the
//                           weights keyed at the frames; the ground; with frames, the camera
//   web/                    a page that plays NAME.glb in a browser opened from the disk
//                           (web_preview.h): index.html, NAME.glb, model.js, three/*.js
#pragma once

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pipelines/scene_view.h"
#include "pipelines/web_preview.h"
#include "wobble/record/trajectory.h"
#include "wobble/scene/render_options.h"
#include "wobble/world/world.h"

namespace wobble::pipelines {

struct RenderOutputs {
  std::string folder;         // created if missing
  std::string name = "run";   // stem of the .pvd, the videos and the .glb
  bool frames = true, filmstrip = true, charts = false, vtp = true, exr = false, disp = false;
  bool mp4 = false, webp = false, gltf = false;
  // The web preview (folder/web/); it records the glTF whether or not gltf is on.
  bool web = false;
  std::string three_js_dir = kThreeJsDir;  // where the web preview copies three.js from (libjs-three)
  // Frames at t0 + k/fps (t0 the first sample's time) up to t_end, those the run reached (up
  // to half a step after its last sample), each at its exact time: the state interpolated
  // between the samples around it (record::Trajectory::RestoreAt); fps 0:
  // every sample is a frame.
  double fps = 0.0;
  // The run's intended end, for the frames and the default filmstrip times; empty: the last
  // sample's time. A run that stopped early is drawn as far as it went.
  std::optional<double> t_end;
  // The frames' view: size, colour by (a fixed colour_range, or the range over the frames),
  // shape samples, point size, title, 3D camera angles.
  SceneOptions view;
  // 2D worlds: kWhole frames the whole run's motion once (the camera stands still); kFollow
  // follows the bodies at one scale, smoothed, the ground under them in view (follow_camera.h).
  enum class Camera { kWhole, kFollow } camera = Camera::kWhole;
  // 3D worlds: the camera orbits the motion's box at this many degrees per simulated second
  // (azimuth view.azimuth + rate (t − t0)), framing the whole motion from every side; 0: fixed.
  double orbit_deg_per_s = 0.0;
  // Filmstrip panels: the samples nearest these times, in this order (empty: 6 evenly spaced
  // from the first sample to t_end; times the run did not reach have no panel).
  std::vector<double> filmstrip_times;
  int filmstrip_width = 320, filmstrip_height = 240, filmstrip_columns = 3;
  // Gaits (thesis Figs. 5.3 and 5.6): >= 0 puts the panels on cycle `filmstrip_cycle` of the
  // recorded pose graph instead (0 the first; a cycle begins where the active pose returns to
  // the run's first pose): filmstrip_panels equal steps across it and its end, so the last
  // panel is the first pose again one stride on, each labelled with its active pose. A run
  // that does not finish that cycle throws std::invalid_argument.
  int filmstrip_cycle = -1, filmstrip_panels = 6;
  double filmstrip_point_size = 0.0;  // 0: the frames' point size
  int disp_width = 256, disp_height = 0;  // height 0: the body's lattice aspect
  int disp_volume = 32;  // 3D bodies: voxels along the lattice's longest axis (the others by aspect)
  int chart_width = 800, chart_height = 500;
  int chart_body = 0;
  // Points of the first FFD body, by lattice coordinates, traced in the pictures.
  std::vector<Eigen::Vector2d> trail;
  // Called after every frame with the fraction done and the frame's time.
  std::function<void(double fraction, double t)> progress;
};

struct RenderReport {
  struct File {
    std::string path;  // a pattern (frame_NNNN.png) for a series
    std::string note;  // what it holds, or empty
    std::string Line() const { return note.empty() ? path : path + "  (" + note + ")"; }
  };
  long frames = 0;  // frames drawn
  std::vector<File> files;
};

// Draws `run` into `world`, whose bodies are the run's (same numbering; its options give the
// ground, springs and gravity drawn). The samples are put back in order from the world as it
// is (a world as at the run's start draws the ground contacts as the run had them): the world
// is left in the state of the last sample drawn.
// `spec` draws the linear bodies' shapes and the named points. Pictures (frames, filmstrip,
// exr, charts) need HasDisplay(); vtp, disp, gltf and web do not. Throws std::invalid_argument for an
// empty run or a world of other bodies, std::runtime_error for a failed write (naming the file).
RenderReport RenderTrajectory(World& world, const record::Trajectory& run, const SceneSpec& spec, const RenderOutputs& out);

// The times of a gait's filmstrip (RenderOutputs::filmstrip_cycle): `panels` equal steps across
// cycle k of the run's recorded pose graph, and its end. A cycle begins where the active pose
// comes back to the first one recorded. std::invalid_argument: no pose recorded, or fewer than
// k + 1 cycles completed.
std::vector<double> FilmstripCycleTimes(const record::Trajectory& run, int k, int panels);

// A world holding the run's bodies (FFD bodies at their models, linear bodies with the default
// material) with these options: somewhere to draw a run whose world is gone.
World WorldFor(const record::Trajectory& run, const WorldOptions& options);

// The picture options (scene/render_options.h: the one table of `wobble render`'s flags and a
// script's NAME=VALUE) put into `out`: sizes, fps, filmstrip, camera, style, trails, ...
void ApplyRenderSettings(const scene::RenderSettings& settings, RenderOutputs* out);

// The outputs the words of `what` name (frames, filmstrip, charts, vtp, exr, disp, mp4, webp, gltf, web) on,
// the others off (web turns gltf on too: the page shows the .glb, written beside it as well):
// "" when every word is one of them and one at least is given, else what is wrong
// (`wobble render --what`, a script's `render` and Python's render read it the same way).
std::string SetOutputs(const std::vector<std::string>& what, RenderOutputs* out);
// Of those, the ones written without an X display (vtp, disp, gltf, web): the rest are switched off and
// returned, for the message that says they were skipped.
std::vector<std::string> KeepWithoutDisplay(RenderOutputs* out);
// The words of `what` (SetOutputs' words, already checked) that need an X display to be written.
std::vector<std::string> NeedingDisplay(const std::vector<std::string>& what);
// Whether any output is on: a render asked for nothing (or left with nothing) is skipped.
bool WritesAnything(const RenderOutputs& out);

// A Witkin & Welch scene drawn as a script's `render` draws it: frames, filmstrip and .vtp
// series with the scene's drawings and named points, smaller dots than a character's, the
// scene's camera angles (out.view.azimuth/elevation are set from `drawing`).
RenderOutputs SceneRenderOutputs(const std::string& folder, const std::string& name, double azimuth, double elevation);

}  // namespace wobble::pipelines
