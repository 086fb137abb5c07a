// The offscreen renderer: every body of a World (FFD and linear, 2D and 3D) drawn with the
// sources of world_sources.h (per body its lattice or control box, mass points and shape; the
// ground, springs, trails and named points of the world), with an overlay of the time and the
// energy, into PNG or EXR frames. A world of 2D bodies is seen by a parallel camera (FrameBox),
// one with a 3D body in perspective (FrameBox3d).
//
// VTK 9.1 as Debian ships it renders only through X: call HasDisplay() first and run under
// `xvfb-run -a -s "-screen 0 1280x1024x24"` when there is no screen; without a display VTK
// aborts the process.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>
#include <vtkSmartPointer.h>

#include "pipelines/background_writer.h"
#include "pipelines/exr_frame.h"
#include "pipelines/exr_io.h"
#include "pipelines/world_sources.h"
#include "wobble/control/behaviours.h"

class vtkImageData;
class vtkRenderWindow;
class vtkRenderer;

namespace wobble::pipelines {

// True when DISPLAY names an X server that accepts a connection (VTK 9.1 needs one to
// render, even offscreen, and aborts the process without it). Checked once per process.
bool HasDisplay();

// kDiagnostic draws what the simulation works with (lattice, mass points, shape); kClean only
// the character, as a picture: closed outlines filled, thicker anti-aliased lines (FXAA).
enum class RenderStyle { kDiagnostic, kClean };

struct SceneOptions {
  int width = 640, height = 480;
  RenderStyle style = RenderStyle::kDiagnostic;  // kClean hides the lattice and the mass points
  bool show_ground = true, show_lattice = true, show_points = true, show_shape = true, show_springs = true,
       show_trails = false;
  // Colour the mass points by one of their arrays: "mass", "velocity", "applied_force" (vectors
  // by magnitude), "in_contact"; or "displacement" colours the lattice points. Empty: plain.
  std::string color_by;
  // Fixed colour range; when lo >= hi the range of the current frame is used.
  double color_range[2] = {0.0, 0.0};
  bool show_color_bar = true;
  bool overlay = true;     // time and energies, top left
  bool overlay_energy = true;  // the energy line of the overlay (filmstrip panels leave it out)
  std::string title;       // optional line above the overlay
  int shape_samples = 16;  // ShapeSource::SamplesPerSegment
  double point_size = 8.0, line_width = 3.0;
  ExrCompression exr_compression = ExrCompression::kZip;  // of WriteExr's frames
  bool exr_terrain_layer = false;  // EXR frames: the rest of the picture as terrain.R/G/B/A too
  bool exr_nuke_motion = true;      // EXR frames: motion as forward.u/v (Nuke)
  bool exr_blender_motion = false;  // and as ViewLayer.Vector.X/Y/Z/W (Blender)
  int png_compression = 1;                                // zlib level 0-9 of WritePng
  // The interactive viewer (interactive_view.h) draws on screen, in a part of its window:
  // offscreen false opens a visible window; viewport = {xmin, ymin, xmax, ymax} of the window
  // (fractions) that the scene's renderer covers. width and height stay the window's size.
  bool offscreen = true;
  double viewport[4] = {0.0, 0.0, 1.0, 1.0};
  // 3D views (FrameBox3d): the camera looks at the box from this azimuth (degrees about +y,
  // from +z towards +x) and elevation (degrees above the x-z plane), in perspective.
  double azimuth = 30.0, elevation = 20.0;
  double view_angle = 30.0;  // perspective opening, degrees
};

// What a view of a World draws besides what its bodies carry (FFD bodies their drawing):
// the drawings of linear bodies and named points.
struct SceneSpec {
  std::vector<LinearDrawing> drawings;        // per body index (linear bodies); empty or missing: no shape
  std::vector<AnchorSource::Anchor> anchors;  // named points, drawn as larger dots
};
// What a script's scene draws besides its bodies (`render` and `wobble view`): its drawings
// and its named points (`point`, `place`) as anchors.
SceneSpec SceneSpecOf(const std::vector<LinearDrawing>& drawings, const std::vector<control::Anchor>& anchors);

// The layers a SceneView draws; each can be shown or hidden after construction. kLattice (FFD
// lattices, control boxes), kPoints and kShape are drawn per body; kGround, kSprings and kTrails
// when the world has an FFD body; kAnchors when the spec names points.
enum class SceneLayer { kGround, kLattice, kPoints, kShape, kSprings, kTrails, kAnchors };

// A box holding every body of a World now (linear bodies with their drawings, FFD bodies by
// their control points, BodyBounds in world_sources.h; z = 0 for 2D bodies).
Eigen::AlignedBox3d SceneBounds(const World& world, const SceneSpec& spec = {});
// True when every body of the world is 2D (the parallel 2D view suits it).
bool IsFlat(const World& world);

class SceneView {
 public:
  // Every body of the world: FFD bodies as lattice, mass points and their resampled drawing;
  // linear bodies as control box, mass points and the spec's drawing (a lit surface in 3D);
  // with an FFD body also the ground, the springs and trails (of the first FFD body: see
  // trails()); the spec's anchors as dots. The camera starts on the world's bodies
  // (FrameBounds(SceneBounds(world, spec))). Needs a display (HasDisplay()); throws
  // std::runtime_error without one.
  SceneView(const World* world, SceneOptions options = {}, SceneSpec spec = {});
  ~SceneView();
  SceneView(const SceneView&) = delete;
  SceneView& operator=(const SceneView&) = delete;

  // A parallel camera looking down −z that shows `box` (world units) with a margin
  // (fraction of the box) around it, keeping the aspect ratio of the image.
  void FrameBox(const Eigen::AlignedBox2d& box, double margin = 0.08);
  // A perspective camera from options().azimuth/elevation, looking at the centre of `box`
  // from the nearest distance that keeps all its corners in view (plus the margin): the 3D view.
  void FrameBox3d(const Eigen::AlignedBox3d& box, double margin = 0.08);
  // FrameBox of the box's x-y extent for a world of 2D bodies, FrameBox3d otherwise.
  void FrameBounds(const Eigen::AlignedBox3d& box, double margin = 0.08);
  // The 3D camera's angles (degrees) for the next FrameBox3d: an orbiting camera sets them
  // per frame and frames the same box again.
  void SetViewAngles(double azimuth, double elevation) {
    options_.azimuth = azimuth;
    options_.elevation = elevation;
  }
  const Eigen::AlignedBox2d& framed_box() const { return framed_; }

  // Rebuilds every source from the world's current state and renders.
  void Render();
  // A line after the overlay's time, for what the world does not know (the active pose of a
  // recorded run); empty: none.
  void SetCaption(std::string caption) { caption_ = std::move(caption); }
  // The last rendered image (RGB, bottom row first as VTK images are). Read back from the
  // window once per Render() and shared by the PNG and EXR outputs.
  vtkSmartPointer<vtkImageData> Capture();
  // With a BackgroundWriter the pixels are read now and the file is written by its thread.
  void WritePng(const std::string& path, BackgroundWriter* writer = nullptr);
  // The bodies as the last Render() drew them, in pixels (exr_frame.h): the visible actors of
  // the shape, lattice and point layers, one vertex group per actor.
  ScreenGeometry CharacterGeometry() const;
  // The last render for compositing (exr_frame.h): the colour in linear light (the frame
  // buffer's 8-bit sRGB decoded; the 2D text overlay, which has no depth, is left out), the
  // distance from the camera along the view direction of what was drawn (+inf where nothing
  // was), the characters' geometry and the camera (ExrCameraMetadata).
  ExrFrame CaptureExrFrame();
  // The last render as one EXR frame (ExrFrameChannels, without a next frame: no motion), with
  // the camera in the header, and the frame's place in a series at `fps` when frame >= 0.
  // The render driver writes its frames itself, each with the next frame's motion.
  void WriteExr(const std::string& path, BackgroundWriter* writer = nullptr, double fps = 0, long frame = -1);
  // OpenEXR's worldToCamera and worldToNDC of the current camera (exr_io.h's conventions).
  ExrMetadata ExrCameraMetadata() const;

  // The range of options().color_by over every body in the world's state now (magnitudes
  // for vectors); false (and 0..1) when nothing is coloured or no body has the array.
  bool ColorRangeNow(double range[2]);
  // A fixed colour range from now on (lo >= hi: each frame's own range).
  void SetColorRange(double lo, double hi);

  // Shows or hides one layer (the interactive viewer's keys). The show_* options set the start.
  void SetLayerVisible(SceneLayer layer, bool visible);
  bool LayerVisible(SceneLayer layer) const;
  // Draws another world from now on (the same bodies; e.g. a recorded state while scrubbing).
  void SetWorld(const World* world);

  // The trails of the first FFD body (SetBody picks another); nullptr without an FFD body.
  TrailSource* trails();
  vtkRenderWindow* window();
  vtkRenderer* renderer();
  const SceneOptions& options() const { return options_; }

 private:
  struct Impl;
  void SetUpWindow();
  void SetUpOverlay();
  std::unique_ptr<Impl> impl_;
  SceneOptions options_;
  std::string caption_;
  Eigen::AlignedBox2d framed_;
};

// The pixels of a window's back buffer as an RGB image (bottom row first), read after its last
// render (rerender: renders once more first).
vtkSmartPointer<vtkImageData> ReadWindowRgb(vtkRenderWindow* window, bool rerender = false);

// Puts images of one size side by side, `columns` per row (0: all in one row), with a thin
// gap of background colour: the papers' strips of snapshots (thesis Fig. 4.10–4.12).
vtkSmartPointer<vtkImageData> TileImages(const std::vector<vtkSmartPointer<vtkImageData>>& images, int columns,
                                         int gap = 4);

}  // namespace wobble::pipelines
