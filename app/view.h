// `wobble view SCENE_OR_SCRIPT`: the interactive viewer (pipelines/interactive_view.h) on an
// object and its modes (like `wobble render`) or on a script (like `wobble run`: the script runs
// in the interpreter up to its first `simul`, and the viewer plays from there). Options make it
// scriptable without a person: play recorded events, draw N frames, write a screenshot and the
// session script, report the frame rate. Without an X display it stops with exit code 2.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "cli_common.h"

namespace wobble::app {

struct ViewArgs {
  std::string scene;               // .wob: a script; otherwise an object file
  std::string object;              // --object (same as the positional object file)
  std::vector<std::string> modes;  // --modes, for an object file
  WorldFlags world;
  std::string q, qdot;
  std::string integrator = "thesis";
  double dt = 0.01;
  std::string size = "1280x720";
  double fps = 30.0, speed = 1.0;
  bool paused = false, fixed_frame_time = false, no_charts = false, report_fps = false;
  bool anneal = false;  // a synthesis script's anneal / cmaes runs again (else its saved result is used)
  long frames = 0;                 // > 0: quit after this many frames
  std::string play_events;         // vtkInteractorEventRecorder file
  std::string screenshot;          // PNG of the window at the end
  std::string session = "wobble_session.wob";  // where `w` writes
  std::string save_session;        // write the session script here at the end
  double slider_range = 0.5;
  double drag_stiffness = 0.0;
};

CLI::App* AddViewCommand(CLI::App* app, ViewArgs* args);
int RunView(const ViewArgs& args);

}  // namespace wobble::app
