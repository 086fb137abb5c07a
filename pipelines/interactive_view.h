// The interactive viewer behind `wobble view`: a scene::Scene (the scene runtime a script
// builds, or an object file loaded into one) in a VTK window, simulated in real time by the
// scene's own run (Scene::BeginRun / Step: the step `simul` takes), drawn by the offscreen
// renderer's SceneView on screen. It shows what the scene holds:
//
//   - a Witkin & Welch scene (linear bodies, nails, attachments, behaviours; FFD bodies that
//     joined it): the scene's world, the queued behaviours acting between steps as in `simul`,
//     drawn as `render` draws it (3D bodies in perspective);
//   - otherwise the scene's FFD object, a character session: one slider per deformation mode
//     setting its PD target (chapter 5), a time slider over the recorded frames, live charts
//     of the energy terms and cond₂(M) (RunRecorder, energy_charts.h), restart, poses recorded
//     by key, and the session saved as a script that replays it.
//
// What drives the world are its controllers (wobble/control): the scene's pose graph
// (control::PoseGraphController, started by the scene's run) until a slider moves, the sliders
// (control::ModeTargetController, which logs every target change for the session script) and
// the mouse: on a character a damped spring to the cursor (control::SpringPull), in a scene a
// trajectory constraint that leads the picked point to the cursor (control::ConstraintPull,
// Witkin & Welch §4), in the plane through the point facing the camera. The viewer never sets
// targets or springs between steps itself.
//
// Window layout of a character session (fractions of the window): the scene at the top left,
// the energy chart and the cond₂(M) chart stacked at the top right, the sliders along the
// bottom (mode targets above, the time slider below). A scene takes the whole window.
//
// Keys (also in README, "wobble view"):
//   space play/pause   n one step (pauses)   + / - speed x2 / /2   c recentre   h the keys
//   s shapes   l lattice (control boxes)   m mass points   g ground   p springs and constraints
//   a named points and the drag line      q or Escape quit
//   character sessions: r restart   0 targets to 0   k record the current amplitudes as a pose
//   w write the session script   Left/Right scrub the recorded frames
// Mouse: the left button picks the nearest mass point, drawing sample or named point within
// 30 pixels and pulls it; middle drag pans, wheel or right drag zooms.
//
// VTK 9.1 needs an X display (HasDisplay()); the constructor throws std::runtime_error
// without one. Tests and measurements run it under xvfb-run.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <vtkSmartPointer.h>

#include "pipelines/scene_view.h"
#include "pipelines/viewer_loop.h"
#include "wobble/scene/scene.h"
#include "wobble/world/world.h"

class vtkImageData;
class vtkRenderWindow;
class vtkRenderWindowInteractor;
class vtkSliderWidget;

namespace wobble::pipelines {

struct ViewerOptions {
  int width = 1280, height = 720;  // the window
  double fps = 30.0;               // frames per second the timer asks for
  double speed = 1.0;              // simulated seconds per second of wall time
  // Every frame advances speed / fps of simulated time whatever the wall clock says
  // (deterministic: tests, recorded event playback). Otherwise the frame advances by the wall
  // time since the last frame (at most kMaxFrameTime) times speed.
  bool fixed_frame_time = false;
  double slider_range = 0.5;    // mode sliders go from -range to +range
  double drag_stiffness = 0.0;  // character pulls; 0: total mass x (2 pi x 1 Hz)^2
  double drag_damping = 0.0;    // 0: half of critical for the total mass on that spring
  bool charts = true;
  int chart_every = 10;  // frames between chart redraws
  bool start_playing = true;
  // A character session plays the scene's keys first (a script stopped at `keyframe`), then
  // simulates on from where they end: the hand-over of q and q̇ of §4.10.1, as `keyframe` does.
  bool keys_first = false;
  int shape_samples = 16;
  long max_history = 36000;  // recorded frames kept for the time slider (20 min at 30 fps)
  std::string session_path = "wobble_session.wob";  // where `w` writes
};

class InteractiveView : public ViewerControls {
 public:
  static constexpr double kMaxFrameTime = FramePacer::kMaxFrameTime;
  // Time constant (s) of the path that takes a point pulled in a scene to the cursor.
  static constexpr double kDragTime = 0.08;

  // Starts the scene's run (Scene::BeginRun; the view ends it when it closes). The scene
  // must outlive the view. Throws std::invalid_argument when the scene has neither bodies nor
  // an FFD object, or for bad options.
  InteractiveView(scene::Scene& scene, ViewerOptions options = {});
  ~InteractiveView() override;
  InteractiveView(const InteractiveView&) = delete;
  InteractiveView& operator=(const InteractiveView&) = delete;

  // True for a character session (the scene's FFD object), false for a Witkin & Welch scene.
  bool character() const;

  // The event loop: returns when the window closes, on q/Escape, or after max_frames frames
  // (when > 0). With an events file (vtkInteractorEventRecorder format: "EventName x y ctrl
  // shift keycode repeat keysym" per line, "TimerEvent" lines draw frames), the events are
  // played first and the loop is not entered unless keep_open.
  void Run(long max_frames = 0, const std::string& events_file = "", bool keep_open = false);
  // Opens the window and draws the first frame without entering the loop (Run does it; tests
  // call it and then Frame() or play events themselves). Idempotent.
  void Initialize();
  // One frame: advance the world by the frame's share of time when playing, record the
  // frame, draw. The timer calls it; tests call it directly.
  void Frame() override;

  // What the keys do.
  bool HandleKey(const std::string& keysym) override;
  void SetPlaying(bool playing);
  bool playing() const;
  void StepOnce();  // one simulation step; pauses
  void SetSpeed(double speed);
  double speed() const;
  void ToggleLayer(SceneLayer layer);  // kAnchors also hides the drag line
  bool LayerVisible(SceneLayer layer) const;

  // Character sessions (std::logic_error in a scene).
  void Restart();     // the start state, a new session (the targets the sliders show stay)
  void RecordPose();  // current amplitudes γ as a pose of a pose graph (held since the last)
  // Writes the session script (scene::SessionScript) atomically, and beside it, when poses were
  // recorded, STEM_poses.wob with them as a cyclic pose graph. Returns the paths written.
  std::vector<std::string> SaveSession(const std::string& path);
  std::string SessionScriptText() const;
  void ScrubTo(long frame);  // shows a recorded frame; pauses
  // PD target γ0 of a mode from the next step on; moves its slider too. The pose graph, if
  // any, stops driving the targets.
  void SetModeTarget(int mode, double target);
  const Eigen::VectorXd& mode_targets() const;
  long num_recorded_frames() const;
  long session_steps() const;
  vtkSliderWidget* mode_slider(int mode);
  vtkSliderWidget* time_slider();

  // Pulling with the mouse, in display pixels (origin at the bottom left, as VTK's). Begin
  // picks the nearest point within 30 pixels; false when none is near.
  bool BeginDrag(int x, int y) override;
  void DragTo(int x, int y) override;
  void EndDrag() override;
  // The point being pulled (an FFD point by its lattice coordinates u), if any.
  std::optional<MaterialPoint> dragged_point() const;
  int drag_constraint() const;  // a scene's pull: the constraint id while dragging, else -1
  // Where the cursor is in the world (the point's dimension) while dragging, else empty.
  Eigen::VectorXd drag_target() const;

  const World& world() const;  // the live world
  double time() const;         // its time
  const ViewerStats& stats() const;
  const std::string& message() const;  // the last trouble (a stopped run) or note, or empty
  bool stopped() const;                // the run stopped (the world or a behaviour)
  std::string StatusLine() const;      // what the status text shows
  // Display pixels of a world point (2 or 3 coordinates), and back from pixels onto z = 0.
  Eigen::Vector3d WorldToDisplay(const Eigen::VectorXd& p) const;
  Eigen::Vector2d DisplayToWorld(double x, double y) const;
  vtkRenderWindow* window();
  vtkRenderWindowInteractor* interactor();
  SceneView& view();
  // The whole window as drawn last (RGB, bottom row first).
  vtkSmartPointer<vtkImageData> Capture();

  struct Impl;  // interactive_view_impl.h: shared by the two source files of the viewer

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace wobble::pipelines
