#include "wobble/scene/render_options.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "wobble/formats/line_reader.h"

namespace wobble::scene {

const std::vector<RenderOptionInfo>& RenderOptionTable() {
  static const std::vector<RenderOptionInfo> table = {
      {"size", "WxH", "640x480", "Frame size (PNG and EXR frames)"},
      {"fps", "NUMBER", "30", "Frames per simulated second"},
      {"color-by", "ARRAY", "",
       "Colour mass points by mass | velocity | applied_force | in_contact, or lattice points by displacement"},
      {"shape-samples", "N", "16", "Samples per drawing segment (the shape is drawn finer than the mass points)"},
      {"filmstrip", "\"T T ..\"", "", "Times of the filmstrip's panels (default: 6 evenly spaced)"},
      {"filmstrip-size", "WxH", "320x240", "Size of one filmstrip panel"},
      {"filmstrip-columns", "N", "3", "Panels per filmstrip row (0: one row)"},
      {"filmstrip-cycle", "\"K [PANELS]\"", "",
       "Gaits: the panels sample cycle K of the pose graph (0 the first) at PANELS equal steps (6) and its end, each "
       "labelled with its active pose (in place of filmstrip times)"},
      {"disp-size", "WxH", "", "Size of the displacement image (default: 256 wide, lattice aspect)"},
      {"chart-size", "WxH", "800x500", "Size of the charts"},
      {"azimuth", "DEGREES", "30", "3D: the camera's angle about +y, degrees from +z towards +x"},
      {"elevation", "DEGREES", "20", "3D: the camera's angle above the ground plane, degrees"},
      {"orbit", "DEGREES/S", "0", "3D: the camera orbits the motion at this many degrees per simulated second"},
      {"camera", "whole|follow", "whole",
       "whole (frame the whole run, standing still) or follow (the body, smoothed, the ground under it in view; 3D: "
       "a cube about it from the azimuth and elevation)"},
      {"style", "diagnostic|clean", "diagnostic",
       "diagnostic (lattice, mass points, shape) or clean (the character: filled, anti-aliased, no lattice or points)"},
      {"exr-terrain", "on|off", "off",
       "EXR frames: write the rest of the picture (terrain or ground, springs, trails) as its own layer terrain.R,G,B,A "
       "too (the characters' R,G,B,A are always written)",
       true},
      {"exr-motion", "nuke|blender|both", "nuke",
       "EXR frames: the motion vectors as Nuke's forward.u,v (to the next frame), as Blender's Vector pass "
       "ViewLayer.Vector.X,Y,Z,W (to the previous frame and from the next; four channels more per frame), or both"},
      {"exr-compression", "zip|zips|piz|dwaa|none", "zip",
       "EXR frames: OpenEXR's compression. zip, zips (zlib, 16 lines or 1 line a block), piz (wavelet) and none are "
       "lossless; dwaa is lossy on the colour channels (alpha, depth and motion stay exact)"},
      {"trail", "\"S T ..\"", "", "Trace points given by lattice coordinates \"s t s t ..\" in the frames"},
  };
  return table;
}

std::string RenderOptionNames() {
  std::vector<std::string> names;
  for (const RenderOptionInfo& o : RenderOptionTable()) names.push_back(o.name);
  std::sort(names.begin(), names.end());
  std::string all;
  for (const std::string& n : names) all += (all.empty() ? "" : ", ") + n;
  return all;
}

bool IsRenderOption(const std::string& name) {
  for (const RenderOptionInfo& o : RenderOptionTable())
    if (o.name == name) return true;
  return false;
}

namespace {

std::vector<double> Numbers(const std::string& option, const std::string& text) {
  std::string t = text;
  std::replace(t.begin(), t.end(), ',', ' ');
  std::istringstream in(t);
  std::vector<double> out;
  for (std::string word; in >> word;) {
    double v = 0.0;
    if (!formats::detail::ParseNumber(word, &v)) throw RenderOptionError(option, "'" + word + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

double Number(const std::string& option, const std::string& text) {
  const std::vector<double> v = Numbers(option, text);
  if (v.size() != 1) throw RenderOptionError(option, "expected a number, got '" + text + "'");
  return v[0];
}

int Whole(const std::string& option, const std::string& text, int lo, int hi) {
  const double v = Number(option, text);
  if (!(v >= lo && v <= hi && v == std::floor(v)))
    throw RenderOptionError(option, "expected a whole number from " + std::to_string(lo) + " to " + std::to_string(hi) +
                                        ", got '" + text + "'");
  return int(v);
}

void Size(const std::string& option, const std::string& text, int* w, int* h) {
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", w, &x, h, &extra) != 3 || (x != 'x' && x != 'X'))
    throw RenderOptionError(option, "expected WIDTHxHEIGHT such as 640x480, got '" + text + "'");
  if (*w < 16 || *h < 16 || *w > 8192 || *h > 8192)
    throw RenderOptionError(option, "each side must be between 16 and 8192 pixels, got '" + text + "'");
}

}  // namespace

RenderSettings ParseRenderOptions(const std::map<std::string, std::string>& values) {
  for (const auto& [name, value] : values)
    if (!IsRenderOption(name)) throw RenderOptionError(name, "unknown option (" + RenderOptionNames() + ")");
  auto has = [&](const char* name) { return values.count(name) > 0; };
  auto text = [&](const char* name) { return values.at(name); };
  RenderSettings s;
  if (has("size")) Size("size", text("size"), &s.width, &s.height);
  if (has("fps")) {
    s.fps = Number("fps", text("fps"));
    if (!(s.fps > 0)) throw RenderOptionError("fps", "must be > 0, got '" + text("fps") + "'");
  }
  if (has("color-by")) s.color_by = text("color-by");
  if (has("shape-samples")) s.shape_samples = Whole("shape-samples", text("shape-samples"), 1, 10000);
  if (has("filmstrip")) s.filmstrip_times = Numbers("filmstrip", text("filmstrip"));
  if (has("filmstrip-size")) Size("filmstrip-size", text("filmstrip-size"), &s.filmstrip_width, &s.filmstrip_height);
  if (has("filmstrip-columns")) s.filmstrip_columns = Whole("filmstrip-columns", text("filmstrip-columns"), 0, 100);
  if (has("filmstrip-cycle")) {
    const std::vector<double> v = Numbers("filmstrip-cycle", text("filmstrip-cycle"));
    const bool whole = std::all_of(v.begin(), v.end(), [](double x) { return x == std::floor(x); });
    if (v.empty() || v.size() > 2 || !whole || v[0] < 0 || v[0] > 1e6 || (v.size() == 2 && (v[1] < 1 || v[1] > 100)))
      throw RenderOptionError("filmstrip-cycle", "expected a cycle K >= 0 and optionally 1 to 100 panels, got '" +
                                                     text("filmstrip-cycle") + "'");
    if (has("filmstrip")) throw RenderOptionError("filmstrip-cycle", "filmstrip-cycle and filmstrip both place the panels: give one");
    s.filmstrip_cycle = int(v[0]);
    if (v.size() == 2) s.filmstrip_panels = int(v[1]);
  }
  if (has("disp-size")) Size("disp-size", text("disp-size"), &s.disp_width, &s.disp_height);
  if (has("chart-size")) Size("chart-size", text("chart-size"), &s.chart_width, &s.chart_height);
  if (has("trail")) {
    const std::vector<double> st = Numbers("trail", text("trail"));
    if (st.size() % 2) throw RenderOptionError("trail", "lattice coordinates come in pairs s t");
    for (size_t i = 0; i + 1 < st.size(); i += 2) s.trail.emplace_back(st[i], st[i + 1]);
  }
  if (has("azimuth")) s.azimuth = Number("azimuth", text("azimuth"));
  if (has("elevation")) {
    s.elevation = Number("elevation", text("elevation"));
    if (!(std::abs(s.elevation) < 90.0)) throw RenderOptionError("elevation", "must be between -90 and 90 degrees");
  }
  if (has("orbit")) s.orbit = Number("orbit", text("orbit"));
  if (has("camera")) {
    if (text("camera") != "whole" && text("camera") != "follow")
      throw RenderOptionError("camera", "expected whole or follow, got '" + text("camera") + "'");
    s.follow = text("camera") == "follow";
  }
  if (has("style")) {
    if (text("style") != "diagnostic" && text("style") != "clean")
      throw RenderOptionError("style", "expected diagnostic or clean, got '" + text("style") + "'");
    s.clean = text("style") == "clean";
  }
  if (has("exr-terrain")) {
    if (text("exr-terrain") != "on" && text("exr-terrain") != "off")
      throw RenderOptionError("exr-terrain", "expected on or off, got '" + text("exr-terrain") + "'");
    s.exr_terrain = text("exr-terrain") == "on";
  }
  if (has("exr-motion")) {
    const std::string m = text("exr-motion");
    if (m != "nuke" && m != "blender" && m != "both")
      throw RenderOptionError("exr-motion", "expected nuke, blender or both, got '" + m + "'");
    s.exr_nuke_motion = m != "blender";
    s.exr_blender_motion = m != "nuke";
  }
  if (has("exr-compression")) {
    const std::string c = text("exr-compression");
    if (c != "zip" && c != "zips" && c != "piz" && c != "dwaa" && c != "none")
      throw RenderOptionError("exr-compression", "expected zip, zips, piz, dwaa or none, got '" + c + "'");
    s.exr_compression = c;
  }
  return s;
}

}  // namespace wobble::scene
