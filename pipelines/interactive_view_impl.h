// The insides of InteractiveView, shared by its two source files: interactive_view.cc (the
// window, the loop, keys, pulls, what every view does) and interactive_view_session.cc (what a
// character session adds: sliders, charts, the recorded frames, restart, the session script).
// Not part of the public API: only those two files include it.
#pragma once

#include <memory>
#include <string>
#include <vector>
#include <vtkSmartPointer.h>

#include "pipelines/energy_charts.h"
#include "pipelines/interactive_view.h"
#include "wobble/control/controllers.h"
#include "wobble/control/pulls.h"

class vtkActor;
class vtkCallbackCommand;
class vtkChartXY;
class vtkPolyData;
class vtkRenderer;
class vtkTextActor;

namespace wobble::pipelines {

// A character session's window layout, fractions of the window (interactive_view.h).
constexpr double kSessionPanelTop = 0.22;   // the sliders live below this
constexpr double kSessionSceneRight = 0.62;  // the charts live right of this

struct InteractiveView::Impl {
  InteractiveView* self = nullptr;
  scene::Scene* scene = nullptr;
  ViewerOptions options;
  bool character = false;  // a 2D FFD object: a character session
  bool object3 = false;    // a 3D FFD object: drawn as a scene, run as the object's runs
  World* world = nullptr;  // the scene's run world (the live one)
  SceneSpec spec;          // a scene's drawings and named points
  std::unique_ptr<SceneView> view;
  vtkSmartPointer<vtkRenderWindowInteractor> interactor;
  vtkSmartPointer<vtkTextActor> status;
  vtkSmartPointer<vtkPolyData> drag_line;  // from the pulled point to the cursor
  vtkSmartPointer<vtkActor> drag_actor;
  // the mouse's pull while dragging (one of them): a character's spring, a scene's constraint
  std::shared_ptr<control::SpringPull> spring_pull;
  std::shared_ptr<control::ConstraintPull> constraint_pull;
  bool playing = true, stopped = false;
  double speed = 1.0;
  std::string message;  // one line shown under the status (saved files, trouble)
  FramePacer pacer;     // frame clock, the simulated time asked for, measurements
  bool initialized = false;
  bool in_keys = false;  // the object's keyframed part is playing (ViewerOptions::keys_first)
  double keys_end = 0.0;

  // ---- a character session (interactive_view_session.cc) ----
  scene::SimulationSetup setup;  // the start: body, world options, state, time, files
  std::unique_ptr<World> scrub_world;
  vtkSmartPointer<vtkRenderer> panel_renderer, energy_renderer, cond_renderer;
  vtkSmartPointer<vtkChartXY> energy_chart, cond_chart;
  std::unique_ptr<RunRecorder> recorder;
  std::vector<vtkSmartPointer<vtkSliderWidget>> mode_sliders;
  vtkSmartPointer<vtkSliderWidget> time_slider;
  std::vector<vtkSmartPointer<vtkCallbackCommand>> callbacks;
  std::vector<Eigen::Vector2d> pickable;  // mass points and drawing samples, by lattice coordinates
  bool scrubbing = false, graph_drives = false;
  std::shared_ptr<control::ModeTargetController> sliders;
  Eigen::VectorXd slider_targets;  // kept over a restart
  long session_steps = 0;
  long key_steps = 0;  // of session_steps, the keys' (set at the hand-over)
  int drags = 0;
  long first_drag_step = -1;
  std::vector<Eigen::VectorXd> recorded_poses;
  std::vector<double> recorded_durations;
  double last_pose_time = 0.0;
  struct Recorded {
    double t;
    Eigen::VectorXd q, qd;
  };
  std::vector<Recorded> history;
  long scrub_frame = -1;

  // interactive_view.cc
  bool StepWorld();
  void Advance(double duration);
  void FrameScene();  // recentre: the bodies with room to move
  Eigen::VectorXd DisplayToWorldAt(double x, double y, double z_display, int dim) const;
  void UpdateDragLine();
  void UpdateStatus();
  void RequireCharacter(const char* what) const;
  void HandOverFromKeys();  // the keys are done: simulate on from their last state

  // interactive_view_session.cc
  void BuildSessionPanels();  // sliders, charts, the time slider; what can be pulled
  void StartSession();        // a new run of the object from the setup, with the sliders
  void BeginSessionRun(scene::RunKind kind);  // the scene's run of that kind, the sliders on it
  void RecordFrame();
  void UpdateTimeSlider();
  void ShowGraphTargets();
  void UpdateCharts();
  void FrameBody();
  std::string SessionStatus() const;
  bool BeginSpringPull(int x, int y);
};

}  // namespace wobble::pipelines
