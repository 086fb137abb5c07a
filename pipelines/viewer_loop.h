// What the viewer of `wobble view` (InteractiveView) builds on: the frame
// clock and its statistics, the event loop, the interactor style that sends mouse and keys to
// a ViewerControls, and the capture of the on-screen window.
#pragma once

#include <chrono>
#include <string>
#include <vtkSmartPointer.h>

class vtkImageData;
class vtkRenderWindow;
class vtkRenderWindowInteractor;

namespace wobble::pipelines {

struct ViewerStats {
  long frames = 0;         // frames drawn
  long steps = 0;          // simulation steps taken in all
  double wall = 0.0;       // seconds between the first and the last frame drawn
  double simulated = 0.0;  // simulated seconds advanced while playing
  double playing_wall = 0.0;  // wall seconds spent playing (frames that advanced the world)
  long playing_frames = 0;    // frames drawn while playing
};

// The viewer's real-time bookkeeping: the
// frame clock, how much simulated time a frame asks for, stepping toward it, and the
// statistics that --report-fps prints. Each viewer keeps its own world and step.
class FramePacer {
 public:
  static constexpr double kMaxFrameTime = 0.25;  // a slow frame advances at most this (s)

  // Starts a frame: the time it stands for, 1/fps with fixed_frame_time, otherwise the wall
  // time since the last frame (at most kMaxFrameTime).
  double BeginFrame(double fps, bool fixed_frame_time);
  // Asks for `duration` more simulated time and steps toward it: step() takes one step of dt
  // and returns false on trouble, which ends the request at the world's time, time().
  template <class Time, class Step> void Advance(double duration, double dt, Time&& time, Step&& step) {
    goal_ += duration;
    while (time() + 0.5 * dt < goal_)
      if (!step()) {
        goal_ = time();
        return;
      }
  }
  void SetGoal(double t) { goal_ = t; }  // after a restart or a single step
  // The frame advanced the world by `simulated` seconds while playing.
  void Played(double simulated);
  // Ends the frame; true once max_frames (> 0) frames have been drawn.
  bool EndFrame();

  ViewerStats stats;
  long max_frames = 0;

 private:
  std::chrono::steady_clock::time_point first_, last_;
  bool have_frame_ = false;
  double since_ = 0.0;  // wall time of the current frame
  double goal_ = 0.0;   // the world time the frames have asked for
};

// Both viewers' event loop: plays the events file (vtkInteractorEventRecorder format) first and
// returns unless keep_open; otherwise runs the repeating timer at fps until quit or max_frames.
// Refuses (formats::ParseError, FILE:LINE) an events file VTK 9.1's vtkInteractorEventRecorder
// would play only in part: it skips unknown event names and reads lines with the wrong number of
// values silently wrong (a key line in 1.0's layout under `# StreamVersion 1.1` loses its key).
// 1.0: `EventName X Y ctrl shift keycode repeatCount keysym`; 1.1: `EventName X Y modifiers
// keycode repeatCount keysym` (modifiers: 1 shift, 2 control, 4 alt).
void CheckEventFile(const std::string& path);

void RunViewerLoop(vtkRenderWindowInteractor* interactor, double fps, const FramePacer& pacer,
                   const std::string& events_file, bool keep_open);

// What the mouse and keys of a viewer window reach; both viewers implement it, and
// AttachViewerStyle wires one interactor style to it.
class ViewerControls {
 public:
  virtual ~ViewerControls() = default;
  virtual void Frame() = 0;                                // the repeating timer
  virtual bool HandleKey(const std::string& keysym) = 0;  // printable keys, space, Escape, Left, Right
  virtual bool BeginDrag(int x, int y) = 0;                // left button, display pixels
  virtual void DragTo(int x, int y) = 0;
  virtual void EndDrag() = 0;
};

// Sets the viewers' interactor style on `interactor`: the left button drags, keys go to
// HandleKey, the timer calls Frame; middle/right buttons and the wheel keep
// vtkInteractorStyleImage's pan and zoom.
void AttachViewerStyle(vtkRenderWindowInteractor* interactor, ViewerControls* controls);

// The on-screen window re-rendered and read back (the back buffer is undefined after a swap).
vtkSmartPointer<vtkImageData> CaptureWindow(vtkRenderWindow* window);

}  // namespace wobble::pipelines
