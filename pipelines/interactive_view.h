// The interactive viewer behind `wobble view`: one body of a World in a VTK window, simulated
// in real time (a repeating timer), with the mouse pulling points, one slider per deformation
// mode setting its PD target (chapter 5), a time slider over the recorded frames, and live
// charts of the energy terms and cond₂(M) beside the scene.
//
// It draws with the offscreen renderer's own pieces: a SceneView (scene_view.h) set to draw
// on screen in the left part of the window, fed by the sources of world_sources.h; the charts
// are RunRecorder's (energy_charts.h) filled into vtkChartXY by FillChart (charts.h). There is
// no second drawing path.
//
// Window layout (fractions of the window): the scene at the top left, the energy chart and
// the cond₂(M) chart stacked at the top right, the sliders along the bottom (mode targets
// above, the time slider below).
//
// Keys (also in README, "wobble view"):
//   space play/pause   n one step (pauses)   r restart   + / - speed x2 / /2   0 targets to 0
//   s shape   l lattice   m mass points   g ground   p springs (and constraints)   c recentre
//   k record the current amplitudes as a pose   w write the session script   Left/Right scrub
//   h print the keys   q or Escape quit
// Mouse: left button on the body pulls the nearest point (mass point or drawing sample) with
// a spring to the cursor; middle drag pans, wheel or right drag zooms.
//
// What drives the world are its controllers (wobble/control): the script's pose graph
// (control::PoseGraphController) until a slider moves, the sliders
// (control::ModeTargetController, which logs every target change for the session script) and
// the mouse (control::SpringPull). The viewer never sets targets or springs between steps.
//
// VTK 9.1 needs an X display (HasDisplay()); the constructor throws std::runtime_error
// without one. Tests and measurements run it under xvfb-run.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>
#include <vtkSmartPointer.h>

#include "pipelines/scene_view.h"
#include "pipelines/viewer_loop.h"
#include "wobble/control/control.h"
#include "wobble/world/world.h"
#include "wobble/scene/scene.h"

class vtkImageData;
class vtkRenderWindow;
class vtkRenderWindowInteractor;
class vtkSliderWidget;

namespace wobble::pipelines {

// What the viewer simulates: body 0 of a world built from these.
struct ViewerScene {
  std::shared_ptr<const BodyModel> body;
  WorldOptions world;      // ground, gravity, integrator, dt and the scene's springs
  Eigen::VectorXd q0, qd0;  // the start state (restart returns to it)
  double t0 = 0.0;          // the time shown at the start (a script's `time`)
  // Drives the targets of the active modes (a script's `pose` lines) until a slider moves.
  control::PoseGraph graph;
  // Files the body came from: the saved session script loads them again.
  std::string object_path;
  std::vector<std::string> mode_paths;

  // What a script's next `simul` would run (scene::Scene::CurrentSetup).
  static ViewerScene FromScript(const scene::SimulationSetup& setup);
};

struct ViewerOptions {
  int width = 1280, height = 720;  // the window
  double fps = 30.0;               // frames per second the timer asks for
  double speed = 1.0;              // simulated seconds per second of wall time
  // Every frame advances speed / fps of simulated time whatever the wall clock says
  // (deterministic: tests, recorded event playback). Otherwise the frame advances by the wall
  // time since the last frame (at most kMaxFrameTime) times speed.
  bool fixed_frame_time = false;
  double slider_range = 0.5;    // mode sliders go from -range to +range
  double drag_stiffness = 0.0;  // 0: total mass x (2 pi x 1 Hz)^2
  double drag_damping = 0.0;    // 0: half of critical for the total mass on that spring
  bool charts = true;
  int chart_every = 10;  // frames between chart redraws
  bool start_playing = true;
  int shape_samples = 16;
  long max_history = 36000;  // recorded frames kept for the time slider (20 min at 30 fps)
  std::string session_path = "wobble_session.wob";  // where `w` writes
};

class InteractiveView : public ViewerControls {
 public:
  static constexpr double kMaxFrameTime = FramePacer::kMaxFrameTime;

  InteractiveView(ViewerScene scene, ViewerOptions options = {});
  ~InteractiveView() override;
  InteractiveView(const InteractiveView&) = delete;
  InteractiveView& operator=(const InteractiveView&) = delete;

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
  void Restart();   // the start state, a new session (the targets the sliders show stay)
  void SetSpeed(double speed);
  double speed() const;
  void ToggleLayer(SceneLayer layer);
  bool LayerVisible(SceneLayer layer) const;
  void RecordPose();  // current amplitudes γ as a pose of a pose graph (held since the last)
  // Writes the session script (scene::SessionScript) atomically, and beside it, when poses were
  // recorded, STEM_poses.wob with them as a cyclic pose graph. Returns the paths written.
  std::vector<std::string> SaveSession(const std::string& path);
  std::string SessionScriptText() const;
  void ScrubTo(long frame);  // shows a recorded frame; pauses

  // PD target γ0 of a mode (World::SetModeTargets); moves its slider too. The pose graph, if
  // any, stops driving the targets.
  void SetModeTarget(int mode, double target);
  const Eigen::VectorXd& mode_targets() const;

  // Pulling with the mouse, in display pixels (origin at the bottom left, as VTK's). Begin
  // picks the nearest mass point or drawing sample within 30 pixels; false when none.
  bool BeginDrag(int x, int y) override;
  void DragTo(int x, int y) override;
  void EndDrag() override;
  // Lattice coordinates of the point being pulled.
  std::optional<Eigen::Vector2d> dragged_point() const;

  // For tests and the CLI.
  const World& world() const;  // the live world
  double time() const;         // t0 + the live world's time
  long num_recorded_frames() const;
  long session_steps() const;
  const ViewerStats& stats() const;
  std::string StatusLine() const;  // what the status text shows
  Eigen::Vector2d DisplayToWorld(double x, double y) const;
  Eigen::Vector2d WorldToDisplay(const Eigen::Vector2d& p) const;
  vtkRenderWindow* window();
  vtkRenderWindowInteractor* interactor();
  vtkSliderWidget* mode_slider(int mode);
  vtkSliderWidget* time_slider();
  SceneView& scene();
  // The whole window as drawn last (RGB, bottom row first).
  vtkSmartPointer<vtkImageData> Capture();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace wobble::pipelines
