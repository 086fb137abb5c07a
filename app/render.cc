#include "render.h"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>

#include <vtkDataArray.h>
#include <vtkImageData.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "pipelines/energy_charts.h"
#include "pipelines/exports.h"
#include "pipelines/scene_view.h"
#include "progress.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::app {
namespace {

namespace pl = wobble::pipelines;

const std::set<std::string> kOutputs = {"frames", "filmstrip", "charts", "vtp", "exr", "disp"};

struct Size {
  int w = 0, h = 0;
};

Size ParseSize(const std::string& text, const std::string& flag) {
  Size s;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.w, &x, &s.h, &extra) != 3 || (x != 'x' && x != 'X'))
    throw UsageError(flag + ": expected WIDTHxHEIGHT such as 640x480, got '" + text + "'");
  if (s.w < 16 || s.h < 16 || s.w > 8192 || s.h > 8192)
    throw UsageError(flag + ": each side must be between 16 and 8192 pixels, got '" + text + "'");
  return s;
}

std::vector<double> ParseNumbers(const std::string& text, const std::string& flag) {
  std::vector<double> out;
  std::string t = text;
  for (char& c : t)
    if (c == ',') c = ' ';
  std::istringstream in(t);
  std::string word;
  while (in >> word) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(v))
      throw UsageError(flag + ": '" + word + "' is not a finite number");
    out.push_back(v);
  }
  return out;
}

std::set<std::string> ParseWhat(const std::string& text) {
  std::set<std::string> what;
  std::string t = text;
  for (char& c : t)
    if (c == ',') c = ' ';
  std::istringstream in(t);
  std::string word;
  while (in >> word) {
    if (!kOutputs.count(word))
      throw UsageError("--what: '" + word + "' is not one of frames, filmstrip, charts, vtp, exr, disp");
    what.insert(word);
  }
  if (what.empty()) throw UsageError("--what: nothing to write");
  return what;
}

std::string FrameName(const std::string& folder, const char* stem, int frame, const char* ext) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%s_%04d.%s", stem, frame, ext);
  return folder + "/" + buf;
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

}  // namespace

CLI::App* AddRenderCommand(CLI::App* app, const std::string& name, const std::string& description,
                           const std::string& default_what, RenderArgs* a) {
  CLI::App* cmd = app->add_subcommand(name, description);
  AddBodyFlags(cmd, &a->files);
  cmd->add_option("--q", a->q, "Initial q = \"tx ty theta g1 ..\" (default: at rest at the origin)")->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, "Initial q-dot, same layout (default: zeros)")->type_name("\"NUMS\"");
  cmd->add_option("--integrator", a->integrator, "thesis | symplectic | rk4 | implicit | variational")
      ->capture_default_str()
      ->type_name("NAME");
  cmd->add_option("--dt", a->dt, "Time step")->capture_default_str();
  cmd->add_option("--duration", a->duration, "Simulated time")->capture_default_str();
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--out", a->out, "Output folder")->required()->type_name("DIR");
  cmd->add_option("--what", a->what,
                  "What to write, comma separated: frames, filmstrip, charts, vtp, exr, disp (default: " +
                      default_what + ")")
      ->type_name("LIST");
  cmd->add_option("--size", a->size, "Frame size (PNG and EXR frames)")->capture_default_str()->type_name("WxH");
  cmd->add_option("--fps", a->fps, "Frames per simulated second")->capture_default_str();
  cmd->add_option("--color-by", a->color_by,
                  "Colour mass points by mass | velocity | applied_force | in_contact, or lattice points by "
                  "displacement")
      ->type_name("ARRAY");
  cmd->add_option("--shape-samples", a->shape_samples, "Samples per drawing segment (the shape is drawn finer "
                                                       "than the mass points)")
      ->capture_default_str();
  cmd->add_option("--filmstrip", a->filmstrip_times, "Times of the filmstrip's panels (default: 6 evenly spaced)")
      ->type_name("\"T T ..\"");
  cmd->add_option("--filmstrip-size", a->filmstrip_size, "Size of one filmstrip panel")
      ->capture_default_str()
      ->type_name("WxH");
  cmd->add_option("--filmstrip-columns", a->filmstrip_columns, "Panels per filmstrip row (0: one row)")
      ->capture_default_str();
  cmd->add_option("--disp-size", a->disp_size, "Size of the displacement image (default: 256 wide, lattice aspect)")
      ->type_name("WxH");
  cmd->add_option("--chart-size", a->chart_size, "Size of the charts")->capture_default_str()->type_name("WxH");
  cmd->add_option("--trail", a->trail, "Trace points given by lattice coordinates \"s t s t ..\" in the frames")
      ->type_name("\"S T ..\"");
  return cmd;
}

int RunRender(const RenderArgs& a, const std::string& default_what) {
  // check every value before reading files or simulating
  const Integrator integrator = ParseIntegratorFlag(a.integrator);
  RequirePositive(a.dt, "--dt");
  RequireNonNegative(a.duration, "--duration");
  RequirePositive(a.fps, "--fps");
  if (a.duration * a.fps > 1e6) throw UsageError("--duration * --fps asks for more than a million frames");
  CheckRenderOptions(a, default_what);

  // the body and its world
  const StartingWorld setup = LoadStartingWorld(a.files, a.q, a.qdot, a.world, integrator, a.dt);
  // the motion: a simulation from (q0, q̇0), run the same way in both passes
  const Motion simulate = [&](World& world, const std::function<void(const World&)>& on_state) {
    world.SetState(0, setup.q0, setup.qd0);
    on_state(world);
    return world.RunUntil(a.duration + 0.5 * a.dt, on_state);
  };
  return RenderMotion(a, default_what, setup.body, setup.options, 0.0, a.duration, simulate);
}

void CheckRenderOptions(const RenderArgs& a, const std::string& default_what) {
  RequirePositive(a.fps, "--fps");
  if (a.shape_samples < 1 || a.shape_samples > 10000) throw UsageError("--shape-samples must be between 1 and 10000");
  const std::set<std::string> what = ParseWhat(a.what.empty() ? default_what : a.what);
  ParseSize(a.size, "--size");
  ParseSize(a.filmstrip_size, "--filmstrip-size");
  ParseSize(a.chart_size, "--chart-size");
  ParseNumbers(a.filmstrip_times, "--filmstrip");
  if (ParseNumbers(a.trail, "--trail").size() % 2) throw UsageError("--trail: lattice coordinates come in pairs s t");
  const bool renders = what.count("frames") || what.count("filmstrip") || what.count("charts") || what.count("exr");
  if (renders && !pl::HasDisplay())
    throw UsageError("rendering needs an X display (VTK 9.1) and DISPLAY is unset or unreachable: run under\n"
                     "  xvfb-run -a -s \"-screen 0 1280x1024x24\" wobble ...\n"
                     "or ask only for --what vtp,disp");
  try {
    formats::CheckWritable(a.out + "/.wobble-probe");  // creates the folder, leaves nothing else
  } catch (const std::runtime_error& e) {
    throw UsageError(std::string("--out: ") + e.what());
  }
}

int RenderMotion(const RenderArgs& a, const std::string& default_what, const std::shared_ptr<const BodyModel>& body,
                 const WorldOptions& options, double t_begin, double t_end, const Motion& motion) {
  CheckRenderOptions(a, default_what);
  const std::set<std::string> what = ParseWhat(a.what.empty() ? default_what : a.what);
  const Size frame_size = ParseSize(a.size, "--size");
  const Size strip_size = ParseSize(a.filmstrip_size, "--filmstrip-size");
  const Size chart_size = ParseSize(a.chart_size, "--chart-size");
  std::vector<double> strip_times = ParseNumbers(a.filmstrip_times, "--filmstrip");
  const std::vector<double> trail_coords = ParseNumbers(a.trail, "--trail");
  const double duration = t_end - t_begin;
  const double dt = options.dt;
  const long num_frames = long(std::floor(duration * a.fps + 1e-9)) + 1;
  auto frame_time = [&](long k) { return t_begin + double(k) / a.fps; };
  // a frame shows the first state at or after its time (within half a step)
  auto due = [&](long k, double t) { return k < num_frames && frame_time(k) <= t + 0.5 * dt; };
  if (strip_times.empty())
    for (int k = 0; k < 6; ++k) strip_times.push_back(t_begin + duration * k / 5.0);

  // pass 1: where the body goes (the camera keeps all of it in view) and the colour range
  Eigen::AlignedBox2d swept;
  double color_lo = 1e300, color_hi = -1e300;
  {
    World world(options);
    world.AddBody(body);
    auto probe = vtkSmartPointer<pl::MassPointSource>::New();
    auto lattice_probe = vtkSmartPointer<pl::LatticeSource>::New();
    probe->SetWorld(&world);
    lattice_probe->SetWorld(&world);
    long k = 0;
    auto look = [&](const World& w) {
      while (due(k, w.time())) {
        swept.extend(pl::BodyBounds(w, 0));
        if (!a.color_by.empty()) {
          vtkPolyDataAlgorithm* src = a.color_by == "displacement" ? (vtkPolyDataAlgorithm*)lattice_probe : probe.Get();
          src->Modified();
          src->Update();
          if (vtkDataArray* arr = src->GetOutput()->GetPointData()->GetArray(a.color_by.c_str())) {
            double r[2];
            arr->GetRange(r, arr->GetNumberOfComponents() > 1 ? -1 : 0);
            color_lo = std::min(color_lo, r[0]);
            color_hi = std::max(color_hi, r[1]);
          }
        }
        ++k;
      }
    };
    motion(world, look);
  }

  // pass 2: the same run, writing as it goes
  World world(options);
  world.AddBody(body);
  pl::SceneOptions scene;
  scene.width = frame_size.w;
  scene.height = frame_size.h;
  scene.color_by = a.color_by;
  if (color_lo < color_hi) {
    scene.color_range[0] = color_lo;
    scene.color_range[1] = color_hi;
  }
  scene.shape_samples = a.shape_samples;
  scene.show_trails = !trail_coords.empty();
  scene.title = body->name();
  // the ground seen below the body: frame the motion plus a band under its lowest point
  Eigen::AlignedBox2d view_box = swept;
  view_box.extend(swept.min() - Eigen::Vector2d(0, 0.1 * swept.sizes().maxCoeff()));
  std::unique_ptr<pl::SceneView> view, strip_view;
  if (what.count("frames") || what.count("exr")) {
    view = std::make_unique<pl::SceneView>(&world, 0, scene);
    view->FrameBox(view_box);
  }
  if (what.count("filmstrip")) {
    pl::SceneOptions s = scene;
    s.width = strip_size.w;
    s.height = strip_size.h;
    s.show_color_bar = false;
    s.overlay_energy = false;  // panels are small: the time only
    s.title.clear();
    strip_view = std::make_unique<pl::SceneView>(&world, 0, s);
    strip_view->FrameBox(view_box);
  }
  std::vector<Eigen::Vector2d> tracked;
  for (size_t i = 0; i + 1 < trail_coords.size(); i += 2) tracked.emplace_back(trail_coords[i], trail_coords[i + 1]);
  for (pl::SceneView* v : {view.get(), strip_view.get()})
    if (v && !tracked.empty()) v->trails()->SetTrackedPoints(tracked);
  std::unique_ptr<pl::VtpSeriesWriter> vtp;
  if (what.count("vtp")) vtp = std::make_unique<pl::VtpSeriesWriter>(&world, 0, a.out + "/vtp", body->name(), a.shape_samples);
  Size disp_size{256, 0};
  if (!a.disp_size.empty()) {
    disp_size = ParseSize(a.disp_size, "--disp-size");
  } else {
    const Lattice& lat = body->lattice();
    disp_size.h = std::max(1, int(std::lround(256.0 * lat.axis_t().norm() / lat.axis_s().norm())));
  }
  pl::RunRecorder recorder(0);

  long next_frame = 0;
  size_t next_strip = 0;
  std::vector<vtkSmartPointer<vtkImageData>> strip_images;
  long written = 0;
  pl::BackgroundWriter writer;  // files are compressed and written while the next frame renders
  Progress progress(isatty(STDERR_FILENO) == 1);
  const auto start = std::chrono::steady_clock::now();
  auto on_state = [&](const World& w) {
    if (what.count("charts")) recorder.Sample(w);
    while (due(next_frame, w.time())) {
      const int k = int(next_frame++);
      for (pl::SceneView* v : {view.get(), strip_view.get()})
        if (v && !tracked.empty()) v->trails()->Record();
      if (view) {
        view->Render();
        if (what.count("frames")) view->WritePng(FrameName(a.out + "/frames", "frame", k, "png"), &writer);
        if (what.count("exr")) view->WriteExr(FrameName(a.out + "/exr", "frame", k, "exr"), &writer);
      }
      if (vtp) vtp->WriteFrame(k, &writer);
      if (what.count("disp"))
        pl::WriteDisplacementExr(FrameName(a.out + "/exr", "disp", k, "exr"), w, 0, disp_size.w, disp_size.h, &writer);
      ++written;
      progress.Update(double(next_frame) / double(num_frames), w.time());
    }
    while (strip_view && next_strip < strip_times.size() && strip_times[next_strip] <= w.time() + 0.5 * dt) {
      strip_view->Render();
      strip_images.push_back(strip_view->Capture());
      ++next_strip;
    }
  };
  const bool ok = motion(world, on_state);
  writer.Wait();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.Finish();

  // what is collected over the run, also when it stopped early
  std::vector<std::string> files;
  if (what.count("frames")) files.push_back(a.out + "/frames/frame_NNNN.png");
  if (what.count("exr")) files.push_back(a.out + "/exr/frame_NNNN.exr  (R, G, B, A, depth.Z)");
  if (what.count("disp")) files.push_back(a.out + "/exr/disp_NNNN.exr  (disp.X, disp.Y over the rest lattice)");
  if (vtp) files.push_back(vtp->WriteCollection() + "  (ParaView time series of lattice, points, shape)");
  if (strip_view && !strip_images.empty()) {
    const std::string path = a.out + "/filmstrip.png";
    pl::WritePng(path, pl::TileImages(strip_images, a.filmstrip_columns));
    files.push_back(path);
  }
  if (what.count("charts")) {
    pl::ChartSpec energy = recorder.EnergyChart(body->name() + ": energy");
    pl::ChartSpec cond = recorder.ConditionChart(body->name() + ": condition number of M (Fig. 4.9)");
    for (pl::ChartSpec* c : {&energy, &cond}) {
      c->width = chart_size.w;
      c->height = chart_size.h;
    }
    pl::WriteChart(energy, a.out + "/energy.png", a.out + "/energy.csv");
    pl::WriteChart(cond, a.out + "/condition.png", a.out + "/condition.csv");
    files.push_back(a.out + "/energy.png, energy.csv");
    files.push_back(a.out + "/condition.png, condition.csv");
  }

  std::cout << body->name() << ": " << written << " frames at " << Num(a.fps) << " fps over " << Num(world.time())
            << " s, " << Num(wall) << " s wall (" << (wall > 0 ? Num(written / wall) : std::string("-"))
            << " frames/s).\n";
  for (const std::string& f : files) std::cout << "  " << f << "\n";
  std::cout << std::flush;
  if (!ok) {
    std::cerr << "wobble: simulation stopped: " << world.status().message << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace wobble::app
