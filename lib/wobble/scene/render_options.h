// The picture options of every way wobble draws a run — `wobble render` / `export` flags
// (--NAME VALUE), a script's `render DIR [WHAT] NAME=VALUE ...` in `wobble run` and in Python's
// Interpreter — as one table: each option's name, the kind of value, its default and its help,
// and one parser from the text values to the settings the renderer takes (pipelines/
// trajectory_render.h's RenderOutputs, filled by pipelines::ApplyRenderSettings). VTK-free, so
// the script layer checks names when it reads a line.
#pragma once

#include <Eigen/Core>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace wobble::scene {

struct RenderOptionInfo {
  std::string name;           // the flag without "--", the script's NAME
  std::string value_name;     // what the value looks like: "WxH", "NUMBER", "\"T T ..\"", ...
  std::string default_value;  // as text; empty: none
  std::string help;
  bool flag = false;          // on the command line a flag without a value; in scripts on / off
};

// Every option, in the order `wobble render --help` lists them.
const std::vector<RenderOptionInfo>& RenderOptionTable();
// "azimuth, camera, chart-size, ...": every name, sorted.
std::string RenderOptionNames();
bool IsRenderOption(const std::string& name);

// A bad value: which option, and what was expected. Front ends spell the option their way
// (--size on the command line, size= in scripts).
struct RenderOptionError : std::invalid_argument {
  RenderOptionError(std::string option_name, const std::string& message)
      : std::invalid_argument(message), option(std::move(option_name)) {}
  std::string option;
};

// The options parsed and checked. Lists take commas or spaces (filmstrip=0.5,1,1.5).
struct RenderSettings {
  int width = 640, height = 480;   // frames (PNG and EXR)
  double fps = 30.0;
  std::string color_by;            // a mass-point array, or "displacement"
  int shape_samples = 16;
  std::vector<double> filmstrip_times;  // empty: evenly spaced
  int filmstrip_width = 320, filmstrip_height = 240, filmstrip_columns = 3;
  int filmstrip_cycle = -1, filmstrip_panels = 6;  // gaits: the panels on cycle K (-1: off)
  int disp_width = 0, disp_height = 0;             // 0: the renderer's default
  int chart_width = 800, chart_height = 500;
  std::vector<Eigen::Vector2d> trail;              // lattice coordinates of traced points
  double azimuth = 30.0, elevation = 20.0, orbit = 0.0;  // 3D camera, degrees (per second)
  bool follow = false;       // camera=follow; else whole
  bool clean = false;        // style=clean; else diagnostic
  bool exr_terrain = false;  // EXR frames: the terrain as its own layer too
  // EXR frames' motion vectors: Nuke's forward.u/v, Blender's Vector pass, or both (exr-motion)
  bool exr_nuke_motion = true, exr_blender_motion = false;
  std::string exr_compression = "zip";  // EXR frames: OpenEXR's compression, by name (exr-compression)
};

// Values by name as typed (a flag's value "on"); the rest keep their defaults. Throws
// RenderOptionError for an unknown name or a bad value.
RenderSettings ParseRenderOptions(const std::map<std::string, std::string>& values);

}  // namespace wobble::scene
