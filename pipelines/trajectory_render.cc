#include "pipelines/trajectory_render.h"

#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vtkCamera.h>
#include <vtkImageData.h>
#include <vtkRenderer.h>
#include <vtkSmartPointer.h>

#include "pipelines/background_writer.h"
#include "pipelines/follow_camera.h"
#include "pipelines/energy_charts.h"
#include "pipelines/exr_frame.h"
#include "pipelines/exports.h"
#include "pipelines/gltf_export.h"
#include "pipelines/video_writer.h"
#include "wobble/formats/atomic_file.h"

namespace wobble::pipelines {
namespace {

std::string Numbered(const std::string& folder, const std::string& stem, long frame, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "_%04ld.%s", frame, ext);
  return folder + "/" + stem + buf;
}

// The first sample at or after time t (run.size() when none is): sample times never decrease.
int FirstAtOrAfter(const record::Trajectory& run, double t) {
  int lo = 0, hi = run.size();
  while (lo < hi) {
    const int mid = (lo + hi) / 2;
    if (run.time(mid) < t) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

// The last sample at or before time t (0 when t is before every sample): a frame between two
// samples is drawn from the state interpolated between them (Trajectory::RestoreAt).
int SampleAtOrBefore(const record::Trajectory& run, double t) {
  const int after = FirstAtOrAfter(run, t);
  if (after < run.size() && run.time(after) == t) return after;
  return std::max(after - 1, 0);
}

// Puts the run's samples back into a world one after the other up to the one asked for, so
// that the ground contacts (whose anchors a trajectory does not hold) evolve from sample to
// sample as they did in the run.
class Replay {
 public:
  Replay(const record::Trajectory& run, World* world) : run_(run), world_(world) {}
  void To(int k) {
    if (k < at_) throw std::logic_error("Replay: samples are visited in order");
    for (int i = at_ + 1; i <= k; ++i) run_.Restore(i, *world_);
    at_ = k;
  }
  // The world at time t, from sample k (the last at or before t) on: between two samples the
  // state is interpolated, so frames are at their exact times, not snapped to the steps.
  void At(int k, double t) {
    To(k);
    if (t != run_.time(k)) run_.RestoreAt(t, *world_);
  }

 private:
  const record::Trajectory& run_;
  World* world_;
  int at_ = -1;
};

// What is drawn at one time t, from the samples at or before it: frames first, then filmstrip
// panels (so a panel's trails hold the frames before it).
struct Visit {
  int sample;  // the last at or before t
  long frame;  // -1: a panel
  int panel;   // -1: a frame
  double t;
  bool operator<(const Visit& o) const {
    if (sample != o.sample) return sample < o.sample;
    if ((frame < 0) != (o.frame < 0)) return frame >= 0;
    return frame < 0 ? panel < o.panel : frame < o.frame;
  }
};

}  // namespace

std::vector<double> FilmstripCycleTimes(const record::Trajectory& run, int k, int panels) {
  int i = 0;  // the first sample with an active pose (the run's first row may precede the controller)
  while (i < run.size() && run.pose(i) < 0) ++i;
  if (i == run.size()) throw std::invalid_argument("filmstrip cycle: the run has no pose graph (no active pose recorded)");
  const int first = run.pose(i);
  std::vector<double> starts = {run.time(i)};
  for (++i; i < run.size(); ++i)
    if (run.pose(i) == first && run.pose(i - 1) != first) starts.push_back(run.time(i));
  if (int(starts.size()) < k + 2)
    throw std::invalid_argument("filmstrip cycle " + std::to_string(k) + ": the run completes only " +
                                std::to_string(starts.size() - 1) + " cycles of its pose graph");
  const double t0 = starts[size_t(k)], period = starts[size_t(k) + 1] - t0;
  std::vector<double> times;
  for (int p = 0; p <= panels; ++p) times.push_back(t0 + period * p / panels);
  return times;
}

namespace {

std::vector<Visit> PlanVisits(const record::Trajectory& run, const RenderOutputs& out, double dt, long* num_frames) {
  std::vector<Visit> visits;
  const double t0 = run.time(0), t_last = run.time(run.size() - 1), t1 = out.t_end.value_or(t_last);
  auto reached = [&](double t) { return t >= t0 - 0.5 * dt && t <= t_last + 0.5 * dt; };
  // the frames are visited whatever is written: the camera frames them, the trails follow them
  if (out.fps > 0) {
    const long wanted = long(std::floor((t1 - t0) * out.fps + 1e-9)) + 1;
    for (long k = 0; k < wanted && reached(t0 + double(k) / out.fps); ++k)
      visits.push_back({SampleAtOrBefore(run, t0 + double(k) / out.fps), k, -1, t0 + double(k) / out.fps});
    *num_frames = long(visits.size());
  } else {
    *num_frames = run.size();
    for (int k = 0; k < run.size(); ++k) visits.push_back({k, k, -1, run.time(k)});
  }
  if (out.filmstrip) {
    std::vector<double> times = out.filmstrip_cycle >= 0 ? FilmstripCycleTimes(run, out.filmstrip_cycle, out.filmstrip_panels)
                                                         : out.filmstrip_times;
    if (times.empty())
      for (int k = 0; k < 6; ++k) times.push_back(t0 + (t1 - t0) * k / 5.0);
    int panel = 0;
    for (double t : times)
      if (reached(t)) visits.push_back({SampleAtOrBefore(run, t), -1, panel++, t});
  }
  std::stable_sort(visits.begin(), visits.end());
  return visits;
}

// The displacement image's (2D) or volume's (3D) name and size for each FFD body.
struct DispTarget {
  int body;
  std::string stem;
  int width, height, depth;  // depth 0: a 2D body's image
};

std::vector<DispTarget> DispTargets(const World& world, const RenderOutputs& out) {
  std::vector<int> ffd;
  for (int b = 0; b < world.num_bodies(); ++b)
    if (world.kind(b) == BodyKind::kFfd) ffd.push_back(b);
  std::vector<DispTarget> targets;
  for (int b : ffd) {
    const std::string stem = ffd.size() == 1 ? "disp" : "disp_" + world.body_name(b);
    if (world.dim(b) == 3) {  // disp_volume voxels along the longest axis
      const LatticeN<3>& lat = world.body<3>(b).lattice();
      double longest = 0;
      for (const auto& axis : lat.axes()) longest = std::max(longest, axis.norm());
      int n[3];
      for (int a = 0; a < 3; ++a) n[a] = std::max(1, int(std::lround(out.disp_volume * lat.axes()[size_t(a)].norm() / longest)));
      targets.push_back({b, stem, n[0], n[1], n[2]});
      continue;
    }
    const Lattice& lat = world.body<2>(b).lattice();
    const int h = out.disp_height > 0 ? out.disp_height
                                      : std::max(1, int(std::lround(out.disp_width * lat.axis_t().norm() / lat.axis_s().norm())));
    targets.push_back({b, stem, out.disp_width, h, 0});
  }
  return targets;
}

// The camera the view rendered its last frame with, for the .glb.
GltfCamera CameraOf(SceneView& view) {
  vtkCamera* c = view.renderer()->GetActiveCamera();
  GltfCamera camera;
  camera.position = Eigen::Vector3d(c->GetPosition());
  camera.focal_point = Eigen::Vector3d(c->GetFocalPoint());
  camera.view_up = Eigen::Vector3d(c->GetViewUp());
  camera.parallel = c->GetParallelProjection() != 0;
  camera.view_angle_deg = c->GetViewAngle();
  camera.parallel_scale = c->GetParallelScale();
  camera.aspect = double(view.options().width) / view.options().height;
  return camera;
}

bool StandsOn2DGround(const World& world) {  // the ground line or terrain is framed with the motion
  for (int b = 0; b < world.num_bodies(); ++b)
    if (GroundDimensionOf(world, b) == 2) return true;
  return false;
}

void WriteCharts(const record::Trajectory& run, const RenderOutputs& out, RenderReport* report) {
  const int b = out.chart_body;
  if (b < 0 || b >= run.num_bodies()) throw std::invalid_argument("charts: the run has no body " + std::to_string(b));
  const std::string& name = run.bodies()[b].name;
  std::vector<std::pair<ChartSpec, std::string>> charts = {{EnergyChart(run, b, name + ": energy"), "energy"}};
  if (run.bodies()[b].IsFfd(2))
    charts.push_back({ConditionChart(run, b, name + ": condition number of M (Fig. 4.9)"), "condition"});
  for (auto& [spec, stem] : charts) {
    spec.width = out.chart_width;
    spec.height = out.chart_height;
    WriteChart(spec, out.folder + "/" + stem + ".png", out.folder + "/" + stem + ".csv");
    report->files.push_back({out.folder + "/" + stem + ".png", "numbers in " + stem + ".csv"});
  }
}

// The ground's surface height under c, if any: 2D the line's or the terrain's under x; 3D the
// heightfield's or the plane's (n·(x − p) = 0 solved for y) under (x, z).
std::optional<double> GroundHeightUnder(const Ground& g, const Eigen::Vector2d& c) {
  if (g.enabled && g.terrain) return g.terrain->HeightAt(c.x());
  if (g.enabled) return g.point.y() + std::tan(g.slope) * (c.x() - g.point.x());
  return std::nullopt;
}
std::optional<double> GroundHeightUnder(const GroundPlane& g, const Eigen::Vector3d& c) {
  if (g.enabled && g.heightfield) return g.heightfield->HeightAt(c.x(), c.z());
  if (g.enabled && std::abs(g.normal.y()) > 1e-9)
    return g.point.y() - (g.normal.x() * (c.x() - g.point.x()) + g.normal.z() * (c.z() - g.point.z())) / g.normal.y();
  return std::nullopt;
}

// The follow camera's boxes (issue 19) of a world of Dim, one per visit, from the time and the
// bodies' box at each visit of the camera's pass, with the ground of Dim under them; as 3D
// boxes (z = 0 in 2D).
template <int Dim>
std::vector<Eigen::AlignedBox3d> FollowBoxesOf(const World& world, const std::vector<std::pair<double, Eigen::AlignedBox3d>>& seen,
                                               const FollowOptions& options) {
  std::vector<FollowMomentN<Dim>> moments;
  for (const auto& [t, bodies] : seen) {
    FollowMomentN<Dim> m;
    m.t = t;
    m.body = Eigen::AlignedBox<double, Dim>(bodies.min().template head<Dim>(), bodies.max().template head<Dim>());
    m.ground_height = GroundHeightUnder(GroundFor<Dim>(world.options().params), m.body.center());
    moments.push_back(m);
  }
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Eigen::AlignedBox<double, Dim>& box : FollowBoxes(moments, options)) boxes.emplace_back(To3(box.min()), To3(box.max()));
  return boxes;
}

}  // namespace

void ApplyRenderSettings(const scene::RenderSettings& s, RenderOutputs* out) {
  out->fps = s.fps;
  out->view.width = s.width;
  out->view.height = s.height;
  out->view.color_by = s.color_by;
  out->view.shape_samples = s.shape_samples;
  out->filmstrip_times = s.filmstrip_times;
  out->filmstrip_width = s.filmstrip_width;
  out->filmstrip_height = s.filmstrip_height;
  out->filmstrip_columns = s.filmstrip_columns;
  out->filmstrip_cycle = s.filmstrip_cycle;
  out->filmstrip_panels = s.filmstrip_panels;
  if (s.disp_width > 0) {
    out->disp_width = s.disp_width;
    out->disp_height = s.disp_height;
  }
  out->chart_width = s.chart_width;
  out->chart_height = s.chart_height;
  out->trail = s.trail;
  out->view.show_trails = !s.trail.empty();
  out->view.azimuth = s.azimuth;
  out->view.elevation = s.elevation;
  out->orbit_deg_per_s = s.orbit;
  out->camera = s.follow ? RenderOutputs::Camera::kFollow : RenderOutputs::Camera::kWhole;
  out->view.style = s.clean ? RenderStyle::kClean : RenderStyle::kDiagnostic;
  out->view.exr_terrain_layer = s.exr_terrain;
  out->view.exr_nuke_motion = s.exr_nuke_motion;
  out->view.exr_blender_motion = s.exr_blender_motion;
  out->view.exr_compression = ExrCompressionFromName(s.exr_compression);
}

std::string SetOutputs(const std::vector<std::string>& what, RenderOutputs* out) {
  out->frames = out->filmstrip = out->charts = out->vtp = out->exr = out->disp = out->mp4 = out->webp = out->gltf = out->web = false;
  for (const std::string& w : what) {
    bool* flag = w == "frames"      ? &out->frames
                 : w == "filmstrip" ? &out->filmstrip
                 : w == "charts"    ? &out->charts
                 : w == "vtp"       ? &out->vtp
                 : w == "exr"       ? &out->exr
                 : w == "disp"      ? &out->disp
                 : w == "mp4"       ? &out->mp4
                 : w == "webp"      ? &out->webp
                 : w == "gltf"      ? &out->gltf
                 : w == "web"       ? &out->web
                                    : nullptr;
    if (!flag) return "'" + w + "' is not one of frames, filmstrip, charts, vtp, exr, disp, mp4, webp, gltf, web";
    *flag = true;
  }
  if (out->web) out->gltf = true;  // the page plays the .glb, which is also written beside the other outputs
  if (what.empty()) return "nothing to write";
  return "";
}

std::vector<std::string> KeepWithoutDisplay(RenderOutputs* out) {
  std::vector<std::string> skipped;
  for (auto [flag, name] : {std::pair{&out->frames, "frames"}, std::pair{&out->filmstrip, "filmstrip"},
                            std::pair{&out->charts, "charts"}, std::pair{&out->exr, "exr"}, std::pair{&out->mp4, "mp4"},
                            std::pair{&out->webp, "webp"}})
    if (*flag) {
      skipped.push_back(name);
      *flag = false;
    }
  return skipped;
}

std::vector<std::string> NeedingDisplay(const std::vector<std::string>& what) {
  RenderOutputs probe;
  SetOutputs(what, &probe);
  return KeepWithoutDisplay(&probe);
}

bool WritesAnything(const RenderOutputs& out) {
  return out.frames || out.filmstrip || out.charts || out.vtp || out.exr || out.disp || out.mp4 || out.webp || out.gltf ||
         out.web;
}

RenderOutputs SceneRenderOutputs(const std::string& folder, const std::string& name, double azimuth, double elevation) {
  RenderOutputs out;
  out.folder = folder;
  out.name = name;
  out.view.point_size = 5.0;  // a scene has many mass points: smaller dots than the FFD view's
  out.filmstrip_point_size = 3.0;
  out.view.azimuth = azimuth;
  out.view.elevation = elevation;
  out.view.title = name;
  return out;
}

World WorldFor(const record::Trajectory& run, const WorldOptions& options) {
  World world(options);
  for (const record::BodyInfo& b : run.bodies()) {
    if (b.IsFfd(2)) world.AddBody(b.shared_ffd<2>());
    else if (b.IsFfd(3)) world.AddBody(b.shared_ffd<3>());
    else world.SetGroundContact(world.AddLinearBody(b.linear), b.ground_contact);
  }
  return world;
}

RenderReport RenderTrajectory(World& caller, const record::Trajectory& run, const SceneSpec& spec, const RenderOutputs& out) {
  if (run.empty()) throw std::invalid_argument("nothing was recorded: no frames to render");
  if (caller.num_bodies() != run.num_bodies()) throw std::invalid_argument("RenderTrajectory: the world's bodies are not the run's");
  if (out.web) CheckThreeJs(out.three_js_dir);  // a missing libjs-three fails before a long render
  // each pass replays the run in the caller's world, whose data (states, contacts, clock:
  // WorldData, not the models) is kept first and put back between the passes and at the end,
  // where the world is left in the state of the last sample drawn (and as it was on a throw)
  World& world = caller;
  const WorldData start = caller.data();
  struct PutBack {
    World& world;
    const WorldData& data;
    bool done = false;
    ~PutBack() {
      if (done) return;
      try {
        world.SetData(data);
      } catch (...) {  // its own data always fits; a destructor must not throw
      }
    }
  } put_back{caller, start};
  const double dt = world.options().dt;
  long num_frames = 0;
  const std::vector<Visit> visits = PlanVisits(run, out, dt, &num_frames);
  RenderReport report;

  std::unique_ptr<SceneView> view, strip_view;
  if ((out.mp4 || out.webp) && !(out.fps > 0.0))
    throw std::invalid_argument("a video needs frames at a rate: fps must be above 0");
  if (out.frames || out.exr || out.mp4 || out.webp) view = std::make_unique<SceneView>(&world, out.view, spec);
  if (out.filmstrip) {
    SceneOptions s = out.view;
    s.width = out.filmstrip_width;
    s.height = out.filmstrip_height;
    s.show_color_bar = false;
    s.overlay_energy = false;  // panels are small: the time only
    s.title.clear();
    if (out.filmstrip_point_size > 0) s.point_size = out.filmstrip_point_size;
    strip_view = std::make_unique<SceneView>(&world, s, spec);
  }

  // the camera's pass: the box of every drawn state (and the ground below it), the colour range
  Eigen::AlignedBox3d motion, cycle;  // cycle: the panels' states of a gait's filmstrip
  const bool follow = out.camera == RenderOutputs::Camera::kFollow, flat = IsFlat(world);
  std::vector<std::pair<double, Eigen::AlignedBox3d>> seen;  // the follow camera's: time, bodies' box
  std::vector<Eigen::AlignedBox3d> follow_boxes;              // per visit (z = 0 in a flat world)
  const bool orbit = out.orbit_deg_per_s != 0.0 && !flat;
  if (view || strip_view) {
    double lo = 1e300, hi = -1e300;
    const bool fixed_range = out.view.color_range[0] < out.view.color_range[1];
    Replay replay(run, &world);
    for (const Visit& v : visits) {
      replay.At(v.sample, v.t);
      const Eigen::AlignedBox3d bodies = SceneBounds(world, spec);
      motion.extend(bodies);
      if (v.frame < 0 && out.filmstrip_cycle >= 0) cycle.extend(bodies);
      if (follow) seen.push_back({world.time(), bodies});
      double r[2];
      if (!fixed_range && (view ? view : strip_view)->ColorRangeNow(r)) {
        lo = std::min(lo, r[0]);
        hi = std::max(hi, r[1]);
      }
    }
    const std::shared_ptr<const Terrain>& terrain = world.options().params.ground.terrain;
    const bool ground_in_view = StandsOn2DGround(world) && out.view.show_ground;
    auto with_ground = [&](Eigen::AlignedBox3d box) {
      if (!ground_in_view || box.isEmpty()) return box;
      if (terrain) {  // the terrain under the motion in view: the cliff the body leaves, the floor it lands on
        const double x0 = box.min().x(), x1 = box.max().x();
        box.extend(Eigen::Vector3d(x0, terrain->HeightAt(x0), 0.0));
        box.extend(Eigen::Vector3d(x1, terrain->HeightAt(x1), 0.0));
        for (const Eigen::Vector2d& v : terrain->vertices())
          if (v.x() >= x0 && v.x() <= x1) box.extend(Eigen::Vector3d(v.x(), v.y(), 0.0));
      }
      Eigen::Vector3d below = box.min();  // the ground seen below the bodies: a band under the lowest point
      below.y() -= 0.1 * box.sizes().head<2>().maxCoeff();
      box.extend(below);
      return box;
    };
    motion = with_ground(motion);
    cycle = with_ground(cycle);
    for (SceneView* v : {view.get(), strip_view.get()}) {
      if (!v) continue;
      // a gait's panels are framed on the cycle they show, not on the whole run's travel
      v->FrameBounds(v == strip_view.get() && !cycle.isEmpty() ? cycle : motion);
      if (lo < hi) v->SetColorRange(lo, hi);  // one colour scale for the whole run
    }
    const FollowOptions follow_options{double(out.view.width) / out.view.height};
    if (follow) follow_boxes = flat ? FollowBoxesOf<2>(world, seen, follow_options) : FollowBoxesOf<3>(world, seen, follow_options);
    world.SetData(start);  // the writing pass replays the run from the start again
  }
  for (SceneView* v : {view.get(), strip_view.get()})
    if (v && !out.trail.empty() && v->trails()) v->trails()->SetTrackedPoints(out.trail);

  std::unique_ptr<VtpSeriesWriter> vtp;
  if (out.vtp) vtp = std::make_unique<VtpSeriesWriter>(&world, out.folder + "/vtp", out.name, spec.drawings, out.view.shape_samples);
  std::unique_ptr<GltfRecorder> gltf;
  if (out.gltf || out.web) gltf = std::make_unique<GltfRecorder>(&world, spec.drawings, out.view.shape_samples);
  double gltf_seconds = 0;  // the glTF part's own time (its frames' keys and the file), for the report
  const std::vector<DispTarget> disp = out.disp ? DispTargets(world, out) : std::vector<DispTarget>();
  PvdCollection volumes;  // 3D bodies' displacement volumes
  std::vector<vtkSmartPointer<vtkImageData>> panels;
  BackgroundWriter writer;  // files are compressed and written while the next frame renders
  std::vector<std::unique_ptr<VideoWriter>> videos;  // each encodes on its own thread, in frame order
  for (auto [asked, format, extension] : {std::tuple{out.mp4, VideoFormat::kMp4, ".mp4"},
                                          std::tuple{out.webp, VideoFormat::kWebp, ".webp"}}) {
    if (!asked) continue;
    VideoOptions video_options;
    video_options.format = format;
    video_options.fps = out.fps;
    videos.push_back(std::make_unique<VideoWriter>(out.folder + "/" + out.name + extension, out.view.width,
                                                   out.view.height, video_options));
  }
  // An EXR frame waits for the next frame's characters: its motion vectors point to them (and,
  // in Blender's Vector pass, to the previous frame's too).
  struct PendingExr {
    std::string path;
    ExrFrame frame;
  };
  std::optional<PendingExr> pending_exr;
  std::optional<ScreenGeometry> before_pending;  // the characters of the frame before it
  const ExrCompression exr_compression = out.view.exr_compression;
  auto submit_exr = [&](const ScreenGeometry* next) {
    if (!pending_exr) return;
    std::optional<ScreenGeometry> previous =  // kept only when Blender's pass needs it
        std::exchange(before_pending, pending_exr->frame.blender_motion ? std::optional<ScreenGeometry>(
                                                                              pending_exr->frame.characters)
                                                                        : std::nullopt);
    writer.Submit([p = std::move(*pending_exr), next_copy = next ? std::optional<ScreenGeometry>(*next) : std::nullopt,
                   previous = std::move(previous), exr_compression] {
      WriteExrFrame(p.path, p.frame, next_copy ? &*next_copy : nullptr, previous ? &*previous : nullptr, exr_compression);
    });
    pending_exr.reset();
  };
  Replay replay(run, &world);
  bool interrupted = false;
  for (const Visit& v : visits) {
    if (InterruptRequested()) {  // Ctrl-C: the frames written so far are kept, and said
      interrupted = true;
      break;
    }
    replay.At(v.sample, v.t);
    if (!follow_boxes.empty()) {  // an orbiting view frames its box below, at the frame's angle
      const Eigen::AlignedBox3d& box = follow_boxes[size_t(&v - visits.data())];
      for (SceneView* sv : {view.get(), strip_view.get()}) {
        if (!sv || (orbit && sv == view.get())) continue;
        if (flat) sv->FrameBounds(box, 0.0);  // 2D: the box is the picture
        else sv->FrameBounds(box);            // 3D: the cube, with the usual margin
      }
    }
    if (v.frame < 0) {
      if (out.filmstrip_cycle >= 0) strip_view->SetCaption("pose " + std::to_string(run.pose(v.sample)));
      strip_view->Render();
      panels.push_back(strip_view->Capture());
      continue;
    }
    for (SceneView* sv : {view.get(), strip_view.get()})
      if (sv && !out.trail.empty() && sv->trails()) sv->trails()->Record();
    if (view && orbit) {  // the frame's angle of the orbit; the box framed is the whole motion's
      view->SetViewAngles(out.view.azimuth + out.orbit_deg_per_s * (world.time() - run.time(0)), out.view.elevation);
      view->FrameBox3d(follow_boxes.empty() ? motion : follow_boxes[size_t(&v - visits.data())]);
    }
    if (view) {
      view->Render();
      if (out.frames) view->WritePng(Numbered(out.folder + "/frames", "frame", v.frame, "png"), &writer);
      for (const std::unique_ptr<VideoWriter>& video : videos) video->AddFrame(PixelsOf(view->Capture()));
      if (out.exr) {
        ExrFrame frame = view->CaptureExrFrame();
        frame.metadata.frames_per_second = out.fps;
        frame.metadata.frame = v.frame;
        submit_exr(&frame.characters);  // the previous frame's motion ends here
        pending_exr = PendingExr{Numbered(out.folder + "/exr", "frame", v.frame, "exr"), std::move(frame)};
      }
    }
    if (vtp) vtp->WriteFrame(int(v.frame), &writer);
    if (gltf) {
      const auto start_key = std::chrono::steady_clock::now();
      gltf->AddFrame();
      if (view) gltf->AddCameraFrame(CameraOf(*view));  // the frame's camera, as rendered
      gltf_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_key).count();
    }
    for (const DispTarget& d : disp) {
      if (d.depth == 0) {
        WriteDisplacementExr(Numbered(out.folder + "/exr", d.stem, v.frame, "exr"), world, d.body, d.width, d.height, &writer);
      } else {
        const std::string file = Numbered(out.folder + "/vti", d.stem, v.frame, "vti");
        writer.Submit([file, image = DisplacementVolume(world, d.body, d.width, d.height, d.depth)] { WriteVti(file, image); });
        volumes.Add(world.time(), int(&d - disp.data()), file, d.stem);
      }
    }
    ++report.frames;
    if (out.progress) out.progress(double(report.frames) / double(num_frames), world.time());
  }
  submit_exr(nullptr);  // the last frame drawn has no next frame: no motion
  writer.Wait();
  std::vector<long> video_frames;  // an interrupted run's videos hold the frames drawn
  for (const std::unique_ptr<VideoWriter>& video : videos) video_frames.push_back(video->Finish());
  if (interrupted) {
    std::string where = std::to_string(report.frames) + " of " + std::to_string(num_frames) + " frames";
    if (vtp) where += ", and " + vtp->WriteCollection() + " for them";
    for (const std::unique_ptr<VideoWriter>& video : videos) where += ", and " + video->path() + " of them";
    throw Interrupted("rendering stopped by Ctrl-C: " + where + " written in " + out.folder);
  }
  world.SetData(start);
  put_back.done = true;
  if (!visits.empty()) run.Restore(visits.back().sample, caller);

  if (out.frames) report.files.push_back({out.folder + "/frames/frame_NNNN.png", ""});
  for (size_t i = 0; i < videos.size(); ++i) {
    char note[96];
    std::snprintf(note, sizeof(note), "%s, %ld frames at %g fps, %.4g s",
                  videos[i]->format() == VideoFormat::kMp4 ? "H.264 video" : "animated WebP", video_frames[i], out.fps,
                  double(video_frames[i]) / out.fps);
    report.files.push_back({videos[i]->path(), note});
  }
  if (out.exr)
    report.files.push_back({out.folder + "/exr/frame_NNNN.exr",
                            std::string("characters R, G, B, A; ") + (out.view.exr_terrain_layer ? "terrain.R, G, B, A; " : "") +
                                "depth.Z; motion vectors" + (out.view.exr_nuke_motion ? " forward.u, forward.v" : "") +
                                (out.view.exr_blender_motion ? " ViewLayer.Vector.X, Y, Z, W" : "")});
  bool any_volume = false;
  for (const DispTarget& d : disp) {
    if (d.depth == 0) {
      report.files.push_back({out.folder + "/exr/" + d.stem + "_NNNN.exr", "disp.X, disp.Y over the rest lattice"});
    } else {
      report.files.push_back({out.folder + "/vti/" + d.stem + "_NNNN.vti", "disp (x, y, z) over the rest lattice box"});
      any_volume = true;
    }
  }
  if (any_volume) {
    volumes.Write(out.folder + "/vti/disp.pvd");
    report.files.push_back({out.folder + "/vti/disp.pvd", "ParaView time series of the displacement volumes"});
  }
  if (vtp) report.files.push_back({vtp->WriteCollection(), "ParaView time series of lattice, points, shape"});
  if (strip_view && !panels.empty()) {
    const std::string path = out.folder + "/filmstrip.png";
    WritePng(path, TileImages(panels, out.filmstrip_columns));
    report.files.push_back({path, ""});
  }
  if (gltf && gltf->num_frames() > 0) {
    const auto start_write = std::chrono::steady_clock::now();
    const std::string path = out.folder + "/" + out.name + ".glb";
    std::string bytes;
    try {
      bytes = gltf->Bytes();
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(path + ": " + e.what());
    }
    if (out.gltf) formats::WriteTextAtomically(path, bytes);
    gltf_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_write).count();
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%.3g", gltf_seconds);
    std::string note = "glTF 2.0: " + std::to_string(gltf->num_bodies()) + " bod" + (gltf->num_bodies() == 1 ? "y" : "ies") +
                       " with morph targets (FFD: one per mode), " + std::to_string(gltf->num_frames()) + " keys; " +
                       seconds + " s";
    if (view) note += "; the render's camera";
    for (const std::string& skipped : gltf->SkippedBodies()) note += "; " + skipped + " not in it (nothing to draw)";
    if (out.gltf) report.files.push_back({path, note});
    if (out.web) {
      const std::string folder = out.folder + "/web";
      WriteWebPreview(folder, out.name, bytes, out.view.title.empty() ? out.name : out.view.title, out.three_js_dir);
      report.files.push_back({folder + "/", "web preview: open " + folder + "/index.html in a browser (three.js r111 "
                                            "from libjs-three and the .glb inside, nothing fetched from the network)"});
    }
  }
  if (out.charts) WriteCharts(run, out, &report);
  return report;
}

}  // namespace wobble::pipelines
