#include "fit.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"
#include "wobble/formats/object_file.h"
#include "wobble/record/trajectory_csv.h"
#include "wobble/formats/parse_error.h"
#include "wobble/formats/target_file.h"

#ifdef WOBBLE_HAVE_PIPELINES
#include <filesystem>

#include "pipelines/charts.h"
#include "pipelines/mesh_io.h"
#include "pipelines/scene_view.h"
#endif

namespace wobble::app {
namespace {

using nlohmann::json;

json Number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }  // JSON has no inf

template <class Derived> json Vector(const Eigen::MatrixBase<Derived>& v) {
  json a = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(Number(double(v[i])));
  return a;
}
json Point(const Eigen::Vector2d& p) { return json::array({p.x(), p.y()}); }
json Point(const Eigen::Vector3d& p) { return json::array({p.x(), p.y(), p.z()}); }

void AddFitFlags(CLI::App* cmd, FitFlags* f) {
  cmd->add_option("--q0", f->q0, "Starting q = \"tx ty theta g1 ..\" (default: see the README)")->type_name("\"NUMS\"");
  cmd->add_option("--gamma-min", f->gamma_min, "Lower bound of every amplitude")->capture_default_str();
  cmd->add_option("--gamma-max", f->gamma_max, "Upper bound of every amplitude")->capture_default_str();
  cmd->add_option("--loss", f->loss, "squared | huber | cauchy (robust against outliers)")->capture_default_str();
  cmd->add_option("--loss-scale", f->loss_scale, "Distance beyond which the robust loss gives way")->capture_default_str();
  cmd->add_option("--prior", f->prior, "Weight of the prior pulling every amplitude toward rest")->capture_default_str();
  cmd->add_option("--max-iterations", f->max_iterations, "Ceres iterations")->capture_default_str();
  cmd->add_flag("--full-report", f->full_report, "Include Ceres' full report in the JSON and print it");
  cmd->add_option("--out", f->out, "Result JSON (written atomically)")->type_name("FILE.json");
  cmd->add_option("--costs", f->costs, "Cost per iteration as CSV (written atomically)")->type_name("FILE.csv");
}

template <int Dim> fit::PoseFitOptions PoseOptions(const FitFlags& f, const BodyModelN<Dim>& body) {
  fit::PoseFitOptions o;
  if (!f.q0.empty()) o.initial_q = ParseCoordinates(f.q0, "--q0", body);  // 3D: t, rotation vector, γ
  RequireFinite(f.gamma_min, "--gamma-min");
  RequireFinite(f.gamma_max, "--gamma-max");
  if (!(f.gamma_min < f.gamma_max)) throw UsageError("--gamma-min must be below --gamma-max");
  o.gamma_lower = f.gamma_min;
  o.gamma_upper = f.gamma_max;
  if (!fit::ParseLoss(f.loss, &o.loss)) throw UsageError("--loss: '" + f.loss + "' is not one of squared, huber, cauchy");
  RequirePositive(f.loss_scale, "--loss-scale");
  o.loss_scale = f.loss_scale;
  RequireNonNegative(f.prior, "--prior");
  o.prior_weight = f.prior;
  if (f.max_iterations < 1) throw UsageError("--max-iterations must be at least 1");
  o.max_iterations = f.max_iterations;
  o.full_report = f.full_report;
  return o;
}

void CheckOutputs(const FitFlags& f) {
  CheckOutputFile("--out", f.out);
  CheckOutputFile("--costs", f.costs);
}

json ReportJson(const fit::FitReport& r) {
  json j;
  j["usable"] = r.usable;
  j["termination"] = r.termination;
  j["initial_cost"] = Number(r.initial_cost);
  j["final_cost"] = Number(r.final_cost);
  j["iterations"] = r.iterations;
  j["solve_seconds"] = r.solve_seconds;
  j["ceres_brief_report"] = r.brief_report;
  if (!r.full_report.empty()) j["ceres_full_report"] = r.full_report;
  return j;
}

#ifdef WOBBLE_HAVE_PIPELINES
// Pictures beside the files, when there is a display: the cost per iteration beside --costs
// (FILE.png), and beside --out the fitted points over their targets (FILE_overlay.png, from
// the JSON's "overlay", at one scale on both axes: the fitted body's drawing, target
// polylines as lines, target points and fitted points as dots, each fitted point joined to
// its target).
void WritePictures(const FitFlags& f, const json& result, const fit::FitReport& r) {
  if (!pipelines::HasDisplay()) {
    if (!f.costs.empty() || !f.out.empty()) std::cout << "no X display: fit pictures skipped (run under xvfb-run -a)\n";
    return;
  }
  if (!f.costs.empty()) {
    pipelines::ChartSpec spec;
    spec.title = "fit cost per iteration";
    spec.x_title = "iteration";
    spec.y_title = "cost";
    spec.log_y = true;
    pipelines::ChartSeries s;
    s.name = "cost";
    for (size_t i = 0; i < r.cost_per_iteration.size(); ++i) s.x.push_back(double(i)), s.y.push_back(r.cost_per_iteration[i]);
    spec.series = {s};
    pipelines::WriteChart(spec, std::filesystem::path(f.costs).replace_extension(".png").string(), "");
  }
  if (!f.out.empty() && result.contains("overlay") && result.value("dimension", 2) == 2) {
    const json& overlay = result["overlay"];
    pipelines::ChartSpec spec;
    spec.title = "fit (dots) against target";
    spec.x_title = "x";
    spec.y_title = "y";
    spec.width = spec.height = 700;
    spec.equal_aspect = true;  // world units on both axes: the body's true shape
    // the fitted body's drawing, and a thin grey line from each fitted point to its target
    auto pairs = [&](const char* key, const char* name, int grey, float width) {
      pipelines::ChartSeries s;
      s.name = name;
      s.segments = true;
      s.rgb[0] = s.rgb[1] = s.rgb[2] = grey;
      s.width = width;
      for (const json& seg : overlay.value(key, json::array()))
        for (const json& p : seg) s.x.push_back(p[0]), s.y.push_back(p[1]);
      if (!s.x.empty()) spec.series.push_back(s);
    };
    pairs("body", "fitted body", 60, 5.0f);  // wide: seen around the target curves over it
    pairs("joins", "fitted to target", 150, 1.0f);
    pipelines::ChartSeries target_points, fitted;
    target_points.name = "target points";
    target_points.points = true;
    fitted.name = "fitted";
    fitted.points = true;
    for (const json& p : overlay["fitted"]) fitted.x.push_back(p[0]), fitted.y.push_back(p[1]);
    int line = 0;
    for (const json& t : overlay["targets"]) {
      if (t.contains("point")) {
        target_points.x.push_back(t["point"][0]);
        target_points.y.push_back(t["point"][1]);
        continue;
      }
      pipelines::ChartSeries curve;
      curve.name = "target curve " + std::to_string(++line);
      for (const json& p : t["polyline"]) curve.x.push_back(p[0]), curve.y.push_back(p[1]);
      if (t.value("closed", false) && !curve.x.empty()) curve.x.push_back(curve.x[0]), curve.y.push_back(curve.y[0]);
      spec.series.push_back(curve);
    }
    if (!target_points.x.empty()) spec.series.push_back(target_points);
    if (!fitted.x.empty()) spec.series.push_back(fitted);
    const std::filesystem::path out(f.out);
    if (!spec.series.empty())
      pipelines::WriteChart(spec, (out.parent_path() / (out.stem().string() + "_overlay.png")).string(), "");
  }
}
#endif

void WriteOutputs(const FitFlags& f, const json& result, const fit::FitReport& r) {
  if (!f.costs.empty()) {
    std::vector<std::vector<double>> rows;
    for (size_t i = 0; i < r.cost_per_iteration.size(); ++i) rows.push_back({double(i), r.cost_per_iteration[i]});
    formats::WriteCsvAtomically(f.costs, {"iteration", "cost"}, rows);
  }
  if (!f.out.empty()) formats::WriteTextAtomically(f.out, result.dump(2) + "\n");
#ifdef WOBBLE_HAVE_PIPELINES
  WritePictures(f, result, r);
#endif
}

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}
std::string List(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

// The file records as fit's input types (lib/wobble/fit does not read files).
template <int Dim>
std::vector<fit::CorrespondenceN<Dim>> Correspondences(const std::vector<formats::PointTargetN<Dim>>& points) {
  std::vector<fit::CorrespondenceN<Dim>> out;
  for (const formats::PointTargetN<Dim>& p : points) out.push_back({p.mass_point, p.lattice_coords, p.position, p.weight});
  return out;
}
template <int Dim>
std::vector<fit::ReferenceFrameN<Dim>> ReferenceFrames(const std::vector<formats::TargetFrameN<Dim>>& frames) {
  std::vector<fit::ReferenceFrameN<Dim>> out;
  for (const formats::TargetFrameN<Dim>& f : frames) out.push_back({f.time, Correspondences(f.points)});
  return out;
}
// What reads a 3D target file's 'mesh' line: VTK's readers, when the pipelines are built.
formats::MeshReader AppMeshReader() {
#ifdef WOBBLE_HAVE_PIPELINES
  return pipelines::ReadSurfaceMesh;
#else
  return nullptr;
#endif
}

json ConditioningJson(const fit::Conditioning& conditioning) {
  json c;
  c["condition_number"] = Number(conditioning.condition_number);
  c["scaled_condition_number"] = Number(conditioning.scaled_condition_number);
  c["column_norms"] = conditioning.column_norms;
  c["undetermined"] = conditioning.undetermined;
  c["poorly_determined"] = conditioning.poorly_determined;
  c["weak_directions"] = json::array();
  for (const fit::WeakDirection& w : conditioning.weak)
    c["weak_directions"].push_back({{"relative_singular_value", w.relative_singular_value},
                                    {"coordinates", w.coordinates},
                                    {"vector", Vector(w.vector)}});
  return c;
}

// The JSON of a pose fit's result (without its overlay).
json PoseJson(const std::string& kind, int dimension, const std::string& body, const std::string& targets,
              const std::vector<std::string>& names, const fit::PoseFitResult& r) {
  json j;
  j["kind"] = kind;
  j["dimension"] = dimension;
  j["body"] = body;
  j["targets"] = targets;
  j["coordinates"] = names;
  j["q"] = Vector(r.q);
  j["report"] = ReportJson(r.report);
  j["rms_residual"] = r.rms_residual;
  j["point_residuals"] = r.point_residuals;
  j["at_bound"] = r.at_bound;
  j["conditioning"] = ConditioningJson(r.conditioning);
  return j;
}

// The summary both pose fits print; returns the exit code.
int PrintPoseSummary(const std::string& headline, const std::vector<std::string>& names, const fit::PoseFitResult& r,
                     bool full_report, const std::string& after_iterations = "") {
  std::ostringstream out;
  out << headline << r.report.termination << " after " << r.report.iterations << " iterations" << after_iterations
      << ".\n";
  out << "q = [";
  for (int i = 0; i < r.q.size(); ++i) out << (i ? " " : "") << names[i] << " " << Num(r.q[i]);
  out << "]\n";
  out << "cost " << Num(r.report.initial_cost) << " -> " << Num(r.report.final_cost) << ", rms residual "
      << Num(r.rms_residual) << "; at a bound: " << List(r.at_bound) << ".\n";
  out << "cond(JtJ) " << Num(r.conditioning.condition_number) << " (column-scaled "
      << Num(r.conditioning.scaled_condition_number) << "); undetermined modes: " << List(r.conditioning.undetermined)
      << "; poorly determined: " << List(r.conditioning.poorly_determined) << ".";
  std::cout << out.str() << std::endl;
  if (full_report) std::cout << r.report.full_report << std::endl;
  if (!r.report.usable) {  // the solver gave up on the numbers: a numerical stop
    std::cerr << "wobble: the fit failed: " << r.report.brief_report << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

fit::CurveTarget CurveTargetOf(const formats::TargetFile& file) {
  fit::CurveTarget c;
  for (const formats::TargetCurve& line : file.polylines) c.AddPolyline(line.points, line.closed);
  for (const Eigen::Vector2d& p : file.cloud) c.AddPoint(p);
  return c;
}

}  // namespace

FitCommands AddFitCommand(CLI::App* app, FitPoseArgs* pose, FitTrajectoryArgs* traj) {
  FitCommands c;
  c.fit = app->add_subcommand("fit", "Fit poses and trajectories with Ceres (see the README: Fitting)");
  c.fit->require_subcommand(1);

  c.pose = c.fit->add_subcommand("pose", "Fit q = [tx ty theta g..] to target points or a target curve");
  AddBodyFlags(c.pose, &pose->files);
  c.pose->add_option("--targets", pose->targets, "Target file (point/sample lines, or polyline/cloud lines)")
      ->required()
      ->type_name("FILE.tgt");
  AddFitFlags(c.pose, &pose->fit);
  c.pose->add_option("--samples-per-segment", pose->samples_per_segment, "Curve targets: samples per drawn segment")
      ->capture_default_str();
  c.pose->add_option("--max-rounds", pose->max_rounds, "Curve targets with --alternate: closest-point rounds")->capture_default_str();
  c.pose->add_flag("--one-sided", pose->one_sided, "Curve targets: only body-to-target distances");
  c.pose->add_option("--mesh-samples", pose->mesh_samples, "3D surface targets: body mesh vertices used as samples")
      ->capture_default_str();
  c.pose->add_flag("--alternate", pose->alternate,
                   "Curve targets: alternate closest-point rounds and solves (ICP) instead of one joint solve");
  c.pose->footer(
      "Examples:\n"
      "  wobble fit pose --object data/table.obj --modes data/table_modes.def \\\n"
      "      --targets data/table_pose.tgt --loss cauchy --loss-scale 5 --out out/pose.json\n"
      "  wobble fit pose --object data/pot3.obj --modes data/pot3_modes.def3 \\\n"
      "      --targets data/pot3_squashed.tgt --out out/pot3_fit.json");

  c.trajectory = c.fit->add_subcommand("trajectory", "Fit q(t) per frame (kinematic) or the simulation's parameters (--dynamic)");
  AddBodyFlags(c.trajectory, &traj->files);
  c.trajectory->add_option("--reference", traj->reference, "Trajectory: a target file with frames, or a `wobble simulate` CSV")
      ->required()
      ->type_name("FILE");
  AddFitFlags(c.trajectory, &traj->fit);
  c.trajectory->add_option("--points", traj->points, "CSV reference: mass points observed, e.g. \"0,4,5\" (default all)");
  c.trajectory->add_option("--every", traj->every, "CSV reference: use every Nth row")->capture_default_str();
  c.trajectory->add_option("--smoothness", traj->smoothness, "Kinematic: weight of the second-difference term")
      ->capture_default_str();
  c.trajectory->add_flag("--dynamic", traj->dynamic, "Fit through the simulation: initial state, mode stiffness, damping");
  c.trajectory->add_option("--dt", traj->dt, "Dynamic: time step (thesis integrator)")->capture_default_str();
  c.trajectory->add_option("--fit", traj->fit_what, "Dynamic: what to fit, from q0,qdot0,stiffness,damping")
      ->capture_default_str();
  c.trajectory->add_option("--qdot0", traj->qdot0, "Dynamic: starting q-dot (default: from the first two frames)");
  c.trajectory->add_option("--gradient", traj->gradient,
                           "Dynamic: jets (Levenberg-Marquardt, Jacobians by forward-mode Jets) or adjoint (BFGS on "
                           "the adjoint gradient, a few simulations whatever the parameters; 2D and 3D)")
      ->check(CLI::IsMember({"jets", "adjoint"}))
      ->capture_default_str();
  c.trajectory->add_flag("--anneal", traj->anneal, "Dynamic: also run simulated annealing with the same number of simulations");
  c.trajectory->add_option("--poses", traj->poses,
                           "Dynamic: a pose-graph controller to start from, \"T1 .. Tk DURATION; ...\" (k active modes)")
      ->type_name("\"POSES\"");
  c.trajectory->add_option("--active", traj->active, "Dynamic: modes the pose graph drives, \"bend,shear\" (default: "
                                                     "those declared active in the .def files)");
  c.trajectory->add_flag("--sequence", traj->sequence, "Dynamic: the poses play once (default: they cycle)");
  c.trajectory->add_option("--switch-width", traj->switch_width,
                           "Dynamic: width w of the smoothed pose switch, seconds (README: Fitting)")
      ->capture_default_str();
  AddWorldFlags(c.trajectory, &traj->world);
  c.trajectory->footer(
      "Examples:\n"
      "  wobble fit trajectory --object data/table.obj --modes data/table_modes.def \\\n"
      "      --reference data/table_keys.tgt --smoothness 1 --out out/keys.json\n"
      "  wobble fit trajectory --object data/table.obj --modes data/table_modes.def \\\n"
      "      --reference out/table_drop.csv --dynamic --no-ground --out out/dyn.json\n"
      "  wobble fit trajectory --object data/table.obj --modes data/bend.def,data/shear.def,data/vsquash.def \\\n"
      "      --active bend,shear --reference out/pose_graph.csv --dynamic --fit poses,times \\\n"
      "      --poses \"0.25 -0.05 0.45; -0.05 0.2 0.25; 0.1 0.1 0.55\" --anneal --out out/graph.json");
  return c;
}

namespace {

// What a pose fit does differently in 2D and 3D: the target file it reads and what it fits
// without correspondences (not twins: a 2D body is fitted to curves, a 3D body to a surface).
// The correspondence fit, the JSON and the summary are one code path (RunPose).
struct ShapeFit {
  fit::PoseFitResult r;
  std::string kind, after_iterations;
};

void SetShapeOptions(const FitPoseArgs& a, const BodyModel&, fit::PoseFitOptions* o) {
  if (a.samples_per_segment < 0) throw UsageError("--samples-per-segment must be >= 0");
  if (a.max_rounds < 1) throw UsageError("--max-rounds must be at least 1");
  o->samples_per_segment = a.samples_per_segment;
  o->max_rounds = a.max_rounds;
  o->joint_closest_points = !a.alternate;
}
void SetShapeOptions(const FitPoseArgs& a, const BodyModelN<3>&, fit::PoseFitOptions* o) {
  if (a.alternate) throw UsageError("--alternate: 3D surface fits find the nearest points jointly (2D curves only)");
  if (a.mesh_samples < 0) throw UsageError("--mesh-samples must be >= 0");
  o->max_mesh_samples = a.mesh_samples;
}

template <int Dim> formats::TargetFileN<Dim> ReadTargets(const std::string& path, const BodyModelN<Dim>&) {
  return formats::ReadTargetFile<Dim>(path, AppMeshReader());
}

// The fitted body's drawing (2D: segments between its curve samples); a 3D body has none here.
void AddBodyDrawing(const BodyModel& body, const fit::PoseFitOptions& o, const Eigen::VectorXd& q, json* overlay) {
  (*overlay)["body"] = json::array();
  const fit::CurveSamples drawing = fit::CurveSamples::Of(body, o);
  std::vector<Eigen::Vector2d> drawn;
  for (const fit::PointBasis& p : drawing.points) drawn.push_back(fit::PointPosition(p, q));
  for (const auto& [a, b] : drawing.segments) (*overlay)["body"].push_back({Point(drawn[size_t(a)]), Point(drawn[size_t(b)])});
}
void AddBodyDrawing(const BodyModelN<3>&, const fit::PoseFitOptions&, const Eigen::VectorXd&, json*) {}

// 2D: the body's outline fitted to the file's polylines and cloud; the overlay joins every
// drawn sample to the nearest target point.
ShapeFit FitShape(const FitPoseArgs& a, const BodyModel& body, const formats::TargetFile& targets,
                  const fit::PoseFitOptions& o, json* overlay) {
  ShapeFit s;
  s.kind = "curve";
  s.r = fit::FitPoseToCurve(body, CurveTargetOf(targets), o);
  EndIterationLine();
  if (a.alternate) s.after_iterations = " in " + std::to_string(s.r.rounds) + " closest-point rounds";
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> target_segments;
  for (const formats::TargetCurve& line : targets.polylines) {
    json pl = json::array();
    for (const Eigen::Vector2d& p : line.points) pl.push_back(Point(p));
    (*overlay)["targets"].push_back({{"polyline", pl}, {"closed", line.closed}});
    for (size_t k = 0; k + 1 < line.points.size(); ++k) target_segments.push_back({line.points[k], line.points[k + 1]});
    if (line.closed && line.points.size() > 2) target_segments.push_back({line.points.back(), line.points.front()});
  }
  for (const Eigen::Vector2d& p : targets.cloud) (*overlay)["targets"].push_back({{"point", Point(p)}});
  for (const fit::PointBasis& p : fit::CurveSamples::Of(body, o).points) {
    const Eigen::Vector2d x = fit::PointPosition(p, s.r.q);
    (*overlay)["fitted"].push_back(Point(x));
    double best = INFINITY;
    Eigen::Vector2d nearest = x;
    for (const auto& [a, b] : target_segments) {
      const Eigen::Vector2d d = b - a;
      const double t = d.squaredNorm() > 0 ? std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
      if ((a + t * d - x).norm() < best) best = (a + t * d - x).norm(), nearest = a + t * d;
    }
    for (const Eigen::Vector2d& p : targets.cloud)
      if ((p - x).norm() < best) best = (p - x).norm(), nearest = p;
    (*overlay)["joins"].push_back({Point(x), Point(nearest)});
  }
  return s;
}

// 3D: the body's samples fitted to the file's mesh and cloud (the overlay's targets: the cloud).
ShapeFit FitShape(const FitPoseArgs&, const BodyModelN<3>& body, const formats::TargetFileN<3>& targets,
                  const fit::PoseFitOptions& o, json* overlay) {
  ShapeFit s;
  s.kind = "surface";
  fit::SurfaceTarget target;
  if (!targets.mesh.empty()) target.AddMesh(targets.mesh);
  for (const Eigen::Vector3d& p : targets.cloud) target.AddPoint(p);
  s.r = fit::FitPoseToSurface(body, target, o);
  EndIterationLine();
  for (const fit::PointBasisN<3>& p : fit::SurfaceSamples(body, o)) (*overlay)["fitted"].push_back(Point(fit::PointPosition(p, s.r.q)));
  for (const Eigen::Vector3d& p : targets.cloud) (*overlay)["targets"].push_back({{"point", Point(p)}});
  return s;
}

// `wobble fit pose` on a body of either dimension: correspondences, or a shape without them.
template <int Dim> int RunPose(const FitPoseArgs& a, const std::shared_ptr<const BodyModelN<Dim>>& body) {
  fit::PoseFitOptions o = PoseOptions(a.fit, *body);
  SetShapeOptions(a, *body, &o);
  o.two_sided = !a.one_sided;
  o.on_iteration = IterationLine();
  const auto targets = ReadTargets(a.targets, *body);
  formats::CheckMassPointIndices(targets, body->num_points());
  if (targets.is_trajectory())
    throw formats::ParseError(a.targets, targets.frames[0].line, "this file has frames: use `wobble fit trajectory`");
  // the overlay hook, world frame: fitted body points and their targets, each fitted point
  // joined to its target (a 2D curve fit: to the nearest point of the target's polylines), and
  // in 2D the fitted body's drawing
  json overlay;
  overlay["fitted"] = json::array();
  overlay["targets"] = json::array();
  ShapeFit s;
  s.kind = "correspondences";
  if (targets.has_curve()) {
    s = FitShape(a, *body, targets, o, &overlay);
  } else {
    const std::vector<fit::CorrespondenceN<Dim>> points = Correspondences(targets.points);
    s.r = fit::FitPose(*body, points, o);
    EndIterationLine();
    for (const fit::CorrespondenceN<Dim>& t : points) {
      const Eigen::Matrix<double, Dim, 1> x = fit::PointPosition(fit::BasisOf(*body, t.mass_point, t.lattice_coords), s.r.q);
      overlay["fitted"].push_back(Point(x));
      overlay["targets"].push_back({{"point", Point(t.position)}});
      overlay["joins"].push_back({Point(x), Point(t.position)});
    }
  }
  const fit::PoseFitResult& r = s.r;
  AddBodyDrawing(*body, o, r.q, &overlay);
  const std::vector<std::string> names = fit::CoordinateNames(*body);
  json j = PoseJson(s.kind, Dim, body->name(), a.targets, names, r);
  if (s.kind == "curve") j["rounds"] = r.rounds;
  j["overlay"] = overlay;
  WriteOutputs(a.fit, j, r.report);
  const std::string fit_kind = s.kind == "correspondences" ? "correspondence" : s.kind;
  return PrintPoseSummary(body->name() + ": " + fit_kind + " fit to " + a.targets + ": ", names, r, a.fit.full_report,
                          s.after_iterations);
}

}  // namespace

int RunFitPose(const FitPoseArgs& a) {
  CheckOutputs(a.fit);
  if (formats::ObjectFileDimension(a.files.object) == 3) return RunPose<3>(a, LoadBody<3>(a.files));
  return RunPose<2>(a, LoadBody<2>(a.files));
}

namespace {

std::vector<int> ParsePointList(const std::string& text, int num_points) {
  std::vector<int> points;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (item.empty()) continue;
    char* end = nullptr;
    const long k = std::strtol(item.c_str(), &end, 10);
    if (*end != '\0' || k < 0 || k >= num_points)
      throw UsageError("--points: '" + item + "' is not a mass point (0.." + std::to_string(num_points - 1) + ")");
    points.push_back(int(k));
  }
  return points;
}

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// --active: a copy of the body with those modes active (the pose graph drives them).
template <int Dim>
std::shared_ptr<const BodyModelN<Dim>> WithActiveModes(const std::shared_ptr<const BodyModelN<Dim>>& body,
                                                       const std::string& names) {
  if (names.empty()) return body;
  std::vector<DeformationModeN<Dim>> modes = body->modes();
  for (DeformationModeN<Dim>& m : modes) m.active = false;
  std::stringstream in(names);
  for (std::string name; std::getline(in, name, ',');) {
    auto it = std::find_if(modes.begin(), modes.end(), [&](const DeformationModeN<Dim>& m) { return m.name == name; });
    if (it == modes.end()) throw UsageError("--active: the body has no mode '" + name + "'");
    it->active = true;
  }
  return std::make_shared<const BodyModelN<Dim>>(body->def(), modes);
}

// --poses "T1 .. Tk D; ...": k targets of the active modes and a transition time per pose.
control::PoseGraph ParsePoseGraph(const std::string& text, int num_active, bool sequence) {
  control::PoseGraph g;
  g.cyclic = !sequence;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ';');) {
    std::istringstream words(item);
    std::vector<double> v;
    for (std::string w; words >> w;) {
      double x = 0.0;
      if (!formats::detail::ParseNumber(w, &x)) throw UsageError("--poses: '" + w + "' is not a number");
      v.push_back(x);
    }
    if (v.empty()) continue;
    if (int(v.size()) != num_active + 1)
      throw UsageError("--poses: a pose needs " + std::to_string(num_active) + " targets (one per active mode) and a "
                       "transition time, got " + std::to_string(v.size()) + " numbers in '" + item + "'");
    g.poses.push_back(Eigen::Map<const Eigen::VectorXd>(v.data(), num_active));
    g.durations.push_back(v.back());
  }
  const std::string invalid = g.Validate(num_active);
  if (!invalid.empty()) throw UsageError("--poses: " + invalid);
  return g;
}

// What the trajectory fit reads differently in 2D and 3D: a `wobble simulate` CSV's q rows as
// the fits' q (a 3D run's hold the orientation as a quaternion, tx ty tz qw qx qy qz γ..,
// turned into the fit's rotation vector).
void ReadStates(const std::string& path, const std::shared_ptr<const BodyModel>& body, std::vector<double>* t,
                std::vector<Eigen::VectorXd>* q) {
  const record::Trajectory sim = record::ReadTrajectoryCsv(path, {record::DescribeFfdBody(body)}).trajectory;
  for (int k = 0; k < sim.size(); ++k) t->push_back(sim.time(k)), q->push_back(sim.q(k, 0));
}
void ReadStates(const std::string& path, const std::shared_ptr<const BodyModelN<3>>& body, std::vector<double>* t,
                std::vector<Eigen::VectorXd>* q) {
  const record::Trajectory sim = record::ReadTrajectoryCsv(path, {record::DescribeFfdBody(body)}).trajectory;
  for (int k = 0; k < sim.size(); ++k) {
    const Eigen::VectorXd row = sim.q(k, 0);
    const Eigen::Quaterniond orientation(row[3], row[4], row[5], row[6]);
    Eigen::VectorXd qk(body->num_q());
    qk << row.head<3>(), LogRotation<double>(orientation.normalized()), row.tail(body->num_modes());
    t->push_back(sim.time(k));
    q->push_back(qk);
  }
}

// The reference's frames: a `wobble simulate` CSV (the listed mass points at its states) or a
// target file with frames.
template <int Dim>
std::vector<fit::ReferenceFrameN<Dim>> LoadFrames(const FitTrajectoryArgs& a,
                                                  const std::shared_ptr<const BodyModelN<Dim>>& body) {
  if (EndsWith(a.reference, ".csv")) {
    std::vector<double> t;
    std::vector<Eigen::VectorXd> q;
    ReadStates(a.reference, body, &t, &q);
    const std::vector<int> points = ParsePointList(a.points, body->num_points());
    return fit::FramesFromStates(*body, t, q, points, a.every);
  }
  const auto file = ReadTargets(a.reference, *body);
  if (!file.is_trajectory())
    throw formats::ParseError(a.reference, 0, "no 'frame' lines: a trajectory needs frames (for one pose use `wobble fit pose`)");
  formats::CheckMassPointIndices(file, body->num_points());
  return ReferenceFrames(file.frames);
}
// The world of the flags; a 3D body stands on the plane of the ground line, as in simulate
// (cli_common.h: StartingWorld).
template <int Dim> void SetWorld(const WorldFlags& flags, fit::DynamicFitOptionsN<Dim>* o) {
  o->world = MakeWorldParams(flags);
  if constexpr (Dim == 3) o->world.ground_plane = GroundPlaneOf(o->world.ground);
}

template <int Dim> int RunTrajectory(const FitTrajectoryArgs& a, const std::shared_ptr<const BodyModelN<Dim>>& body) {
  fit::PoseFitOptions po = PoseOptions(a.fit, *body);
  if (a.every < 1) throw UsageError("--every must be at least 1");
  RequireNonNegative(a.smoothness, "--smoothness");
  // the reference: a simulation CSV or a target file with frames
  if (!EndsWith(a.reference, ".csv") && (!a.points.empty() || a.every != 1))
    throw UsageError("--points and --every apply to a CSV reference only");
  const auto frames = LoadFrames(a, body);

  json j;
  j["body"] = body->name();
  j["dimension"] = Dim;
  j["reference"] = a.reference;
  j["coordinates"] = fit::CoordinateNames(*body);
  std::ostringstream out;
  fit::FitReport report;
  if (!a.dynamic) {
    fit::TrajectoryFitOptions o;
    o.pose = po;
    o.pose.on_iteration = IterationLine();
    o.smoothness = a.smoothness;
    const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(*body, frames, o);
    EndIterationLine();
    report = r.report;
    j["kind"] = "kinematic";
    j["smoothness"] = a.smoothness;
    j["linear_solver"] = r.linear_solver;
    j["report"] = ReportJson(r.report);
    j["times"] = r.times;
    j["q"] = json::array();
    for (const Eigen::VectorXd& q : r.q) j["q"].push_back(Vector(q));
    j["frame_rms"] = r.frame_rms;
    j["rms_residual"] = r.rms_residual;
    out << body->name() << ": kinematic fit of " << frames.size() << " frames (" << r.linear_solver << "): "
        << r.report.termination << " after " << r.report.iterations << " iterations in " << Num(r.report.solve_seconds)
        << " s.\ncost " << Num(r.report.initial_cost) << " -> " << Num(r.report.final_cost) << ", rms residual "
        << Num(r.rms_residual) << ".";
  } else {
    fit::DynamicFitOptionsN<Dim> o;
    SetWorld(a.world, &o);
    RequirePositive(a.dt, "--dt");
    o.dt = a.dt;
    o.max_iterations = po.max_iterations;
    o.full_report = po.full_report;
    if (a.gradient == "adjoint") o.gradient = fit::FitGradient::kAdjoint;
    o.fit_q0 = o.fit_qd0 = o.fit_stiffness = o.fit_damping = false;
    std::stringstream what(a.fit_what);
    for (std::string item; std::getline(what, item, ',');) {
      if (item == "q0") o.fit_q0 = true;
      else if (item == "qdot0") o.fit_qd0 = true;
      else if (item == "stiffness") o.fit_stiffness = true;
      else if (item == "damping") o.fit_damping = true;
      else if (item == "poses") o.fit_poses = true;
      else if (item == "times") o.fit_times = true;
      else throw UsageError("--fit: '" + item + "' is not one of q0, qdot0, stiffness, damping, poses, times");
    }
    RequireNonNegative(a.switch_width, "--switch-width");
    o.switch_width = a.switch_width;
    fit::DynamicParameters start;
    const int num_active = int(control::ActiveModes(*body).size());
    if (!a.poses.empty()) {
      if (num_active == 0) throw UsageError("--poses: no mode is active (--active, or 'active' in the .def header)");
      start.graph = ParsePoseGraph(a.poses, num_active, a.sequence);
    }
    if ((o.fit_poses || o.fit_times) && start.graph.empty()) throw UsageError("--fit poses,times needs --poses to start from");
    if (o.fit_times && !(o.switch_width > 0))
      throw UsageError("--fit times needs --switch-width > 0: a hard switch gives the times no gradient");
    if (!a.fit.q0.empty()) start.q0 = po.initial_q;
    if (!a.qdot0.empty()) start.qd0 = ParseVelocities(a.qdot0, "--qdot0", *body);
    try {
      fit::FrameSteps(frames, o.dt);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string(e.what()) + " (--dt " + Num(o.dt) + ")");
    }
    o.on_iteration = IterationLine();
    const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*body, frames, start, o);
    EndIterationLine();
    report = r.report;
    j["kind"] = "dynamic";
    j["gradient"] = a.gradient;
    j["dt"] = o.dt;
    j["report"] = ReportJson(r.report);
    j["q0"] = Vector(r.params.q0);
    j["qdot0"] = Vector(r.params.qd0);
    j["stiffness"] = Vector(r.params.stiffness);
    j["damping"] = Vector(r.params.damping);
    j["rms_residual"] = r.rms_residual;
    j["simulations"] = r.simulations;
    out << body->name() << ": dynamic fit of " << frames.size() << " frames: " << r.report.termination << " after "
        << r.report.iterations << " iterations, " << r.simulations << " simulations, " << Num(r.report.solve_seconds)
        << " s.\ncost " << Num(r.report.initial_cost) << " -> " << Num(r.report.final_cost) << ", rms residual "
        << Num(r.rms_residual) << ".\nq0 = " << r.params.q0.transpose() << "\nqdot0 = " << r.params.qd0.transpose()
        << "\nstiffness = " << r.params.stiffness.transpose() << "\ndamping = " << r.params.damping.transpose();
    if (!r.params.graph.empty()) {
      json g;
      g["poses"] = json::array();
      for (const Eigen::VectorXd& p : r.params.graph.poses) g["poses"].push_back(Vector(p));
      g["durations"] = r.params.graph.durations;
      g["cyclic"] = r.params.graph.cyclic;
      g["switch_width"] = o.switch_width;
      g["active"] = json::array();
      for (int m : control::ActiveModes(*body)) g["active"].push_back(body->modes()[m].name);
      j["pose_graph"] = g;
      out << "\npose graph (active:";
      for (int m : control::ActiveModes(*body)) out << " " << body->modes()[m].name;
      out << "):";
      for (size_t i = 0; i < r.params.graph.poses.size(); ++i)
        out << "\n  pose " << i << ": " << r.params.graph.poses[i].transpose() << "  held " << Num(r.params.graph.durations[i]);
    }
    if (a.anneal) {
      // the controller alone by lib/wobble/synth's annealer when poses or times are fitted
      const fit::AnnealingResult sa = o.fit_poses || o.fit_times
                                          ? fit::AnnealPoseGraph(*body, frames, start, o, r.simulations)
                                          : fit::AnnealDynamicTrajectory(*body, frames, start, o, r.simulations);
      j["annealing"] = {{"simulations", sa.simulations}, {"cost", Number(sa.cost)}};
      out << "\nsimulated annealing with the same " << sa.simulations << " simulations: cost " << Num(sa.cost) << ".";
    }
  }
  WriteOutputs(a.fit, j, report);
  std::cout << out.str() << std::endl;
  if (a.fit.full_report) std::cout << report.full_report << std::endl;
  if (!report.usable) {  // the solver gave up on the numbers: a numerical stop
    std::cerr << "wobble: the fit failed: " << report.brief_report << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace

int RunFitTrajectory(const FitTrajectoryArgs& a) {
  CheckOutputs(a.fit);
  if (formats::ObjectFileDimension(a.files.object) == 3) return RunTrajectory<3>(a, WithActiveModes(LoadBody<3>(a.files), a.active));
  return RunTrajectory<2>(a, WithActiveModes(LoadBody<2>(a.files), a.active));
}

}  // namespace wobble::app
