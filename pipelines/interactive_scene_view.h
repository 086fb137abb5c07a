// `wobble view` of a Witkin & Welch scene (a script with `linear` bodies, nails, attachments
// and behaviours): the script's World in a window, stepped in real time by the
// caller's step function (scene::Scene::Step: the queued behaviours act between steps
// as in `simul`), drawn by SceneView's World constructor (the drawing path of
// `render`). The FFD viewer (interactive_view.h) keeps its mode sliders and charts; a scene has
// no mode targets, so this window shows the scene alone.
//
// Keys (README, "Interactive viewer"): space play/pause   n one step (pauses)   + / - speed
//   a anchors and the drag constraint   l control boxes   m mass points   s shapes
//   c recentre   h print the keys   q or Escape quit
// Mouse: the left button picks the nearest mass point or named point of a body (within 30
// pixels) and a trajectory constraint (Witkin & Welch §4) drives it toward the cursor, in the
// plane through the point facing the camera (control::ConstraintPull, a World controller);
// releasing the button removes the constraint.
// Middle drag pans, the wheel or right drag zooms.
//
// Needs an X display (HasDisplay()); the constructor throws std::runtime_error without one.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vtkSmartPointer.h>

#include "pipelines/interactive_view.h"
#include "pipelines/scene_view.h"
#include "wobble/world/world.h"

class vtkImageData;
class vtkRenderWindow;
class vtkRenderWindowInteractor;

namespace wobble::pipelines {

struct InteractiveSceneInput {
  World* world = nullptr;  // stepped by `step`; the viewer adds and removes its drag constraint
  SceneSpec spec;                     // drawings and named points
  double azimuth = 30.0, elevation = 20.0;  // 3D camera (degrees), as `render`
  // One step of world->options().dt. Throws (std::exception) when the world or a behaviour
  // stops the run: the viewer pauses and shows the message.
  std::function<void()> step;
};

class InteractiveSceneView : public ViewerControls {
 public:
  static constexpr double kMaxFrameTime = FramePacer::kMaxFrameTime;
  // Time constant (s) of the path that takes a dragged point to the cursor.
  static constexpr double kDragTime = 0.08;

  // Uses width, height, fps, speed, fixed_frame_time, start_playing and point sizes of options.
  InteractiveSceneView(InteractiveSceneInput input, ViewerOptions options = {});
  ~InteractiveSceneView() override;
  InteractiveSceneView(const InteractiveSceneView&) = delete;
  InteractiveSceneView& operator=(const InteractiveSceneView&) = delete;

  // As InteractiveView's: the loop until q/Escape or max_frames frames; events played first.
  void Run(long max_frames = 0, const std::string& events_file = "", bool keep_open = false);
  void Initialize();
  // Advances the scene by the frame's share of time when playing, draws.
  void Frame() override;

  bool HandleKey(const std::string& keysym) override;
  void SetPlaying(bool playing);
  bool playing() const;
  void StepOnce();
  void SetSpeed(double speed);
  double speed() const;
  void ToggleLayer(SceneLayer layer);  // kAnchors also hides the drag line
  bool LayerVisible(SceneLayer layer) const;

  // Dragging, in display pixels (origin bottom left). BeginDrag picks the nearest mass point
  // or named point of a body within 30 pixels and adds the trajectory constraint; false when
  // none is near.
  bool BeginDrag(int x, int y) override;
  void DragTo(int x, int y) override;
  void EndDrag() override;
  std::optional<MaterialPoint> dragged_point() const;
  int drag_constraint() const;  // the constraint id while dragging, else -1
  // Where the cursor is in the world (the point's dimension) while dragging.
  Eigen::VectorXd drag_target() const;

  const World& world() const;
  double time() const;
  const ViewerStats& stats() const;
  const std::string& message() const;  // the last trouble (a stopped run), or empty
  std::string StatusLine() const;
  // Display pixels of a world point (2 or 3 coordinates), and back on the plane at depth z_display.
  Eigen::Vector3d WorldToDisplay(const Eigen::VectorXd& p) const;
  vtkRenderWindow* window();
  vtkRenderWindowInteractor* interactor();
  SceneView& scene();
  vtkSmartPointer<vtkImageData> Capture();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wobble::pipelines
