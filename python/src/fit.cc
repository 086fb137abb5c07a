// Fits from Python (fit/pose_fit.h, Ceres): mode amplitudes and placement from target points
// (mass points or lattice points matched to world positions) or from target curves, with the
// report and the conditioning of the fit (which modes the data cannot see). Every fit takes a
// 2D or a 3D body (one C++ template per fit; points (K, 3) and q = [t, r, γ] in 3D); 2D curves
// without correspondences go to fit_pose_to_curves, 3D surfaces to fit_pose_to_surface.
#include "support.h"

#include <cmath>

#include "wobble/body/surface_mesh.h"
#include "wobble/core/errors.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble::python {
namespace {

template <int Dim>
fit::PoseFitOptions Options(const BodyModelN<Dim>& body, const py::object& initial_q, const std::string& loss, double loss_scale,
                            double prior_weight, std::pair<double, double> bounds, int max_iterations) {
  fit::PoseFitOptions o;
  if (!initial_q.is_none()) {
    auto q = AsMatrix(initial_q, body.num_q(), -1, "initial_q");
    o.initial_q = Eigen::Map<const Eigen::VectorXd>(q.data(), body.num_q());
    if (!o.initial_q.allFinite()) throw InputError("initial_q must be finite");
  }
  if (!fit::ParseLoss(loss, &o.loss)) throw InputError("loss: '" + loss + "' is not squared, huber or cauchy");
  o.loss_scale = loss_scale;
  o.prior_weight = prior_weight;
  o.gamma_lower = bounds.first;
  o.gamma_upper = bounds.second;
  o.max_iterations = max_iterations;
  const std::string error = fit::ValidateOptions(o, body.num_modes(), body.num_q() - body.num_modes());
  if (!error.empty()) throw InputError("pose fit: " + error);
  return o;
}

// Target points: positions (K, Dim), each on a mass point (mass_points, K ints) or at lattice
// coordinates (lattice_coords, K x Dim); weights > 0.
template <int Dim>
std::vector<fit::CorrespondenceN<Dim>> Targets(const BodyModelN<Dim>& body, const py::object& positions_in,
                                           const py::object& mass_points, const py::object& lattice_coords,
                                           const py::object& weights_in) {
  auto probe = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(positions_in);
  const std::string dim = std::to_string(Dim);
  if (!probe || probe.ndim() != 2) throw InputError("points: expected an array (K, " + dim + ") of world positions");
  const long K = probe.shape(0);
  auto positions = AsMatrix(probe, K, Dim, "points");
  if (mass_points.is_none() == lattice_coords.is_none())
    throw InputError("give the body's points as exactly one of mass_points (K,) or lattice_coords (K, " + dim + ")");
  std::vector<fit::CorrespondenceN<Dim>> out(K);
  std::vector<long> which;
  if (!mass_points.is_none()) which = mass_points.cast<std::vector<long>>();
  py::array_t<double, py::array::c_style> st;
  if (!lattice_coords.is_none()) st = AsMatrix(lattice_coords, K, Dim, "lattice_coords");
  if (!mass_points.is_none() && long(which.size()) != K)
    throw InputError("mass_points: expected " + std::to_string(K) + " indices, one per point, got " + std::to_string(which.size()));
  std::vector<double> weights(K, 1.0);
  if (!weights_in.is_none()) {
    auto w = AsMatrix(weights_in, K, -1, "weights");
    weights.assign(w.data(), w.data() + K);
  }
  for (long k = 0; k < K; ++k) {
    fit::CorrespondenceN<Dim>& c = out[k];
    for (int i = 0; i < Dim; ++i) c.position[i] = positions.at(k, i);
    if (!c.position.allFinite()) throw InputError("points[" + std::to_string(k) + "] is not finite");
    if (!(weights[k] > 0) || !std::isfinite(weights[k]))
      throw InputError("weights[" + std::to_string(k) + "] must be a finite number > 0");
    c.weight = weights[k];
    if (!which.empty()) {
      if (which[k] < 0 || which[k] >= body.num_points())
        throw InputError("mass_points[" + std::to_string(k) + "] = " + std::to_string(which[k]) + ": the body has " +
                         std::to_string(body.num_points()) + " mass points");
      c.mass_point = int(which[k]);
    } else {
      for (int i = 0; i < Dim; ++i) c.lattice_coords[i] = st.at(k, i);
      if (!c.lattice_coords.allFinite()) throw InputError("lattice_coords[" + std::to_string(k) + "] is not finite");
    }
  }
  return out;
}

// Reference frames: times (F,), world positions (F, K, Dim) of the mass points mass_points (K,).
template <int Dim>
std::vector<fit::ReferenceFrameN<Dim>> Frames(const BodyModelN<Dim>& body, const py::object& times_in, const py::object& points_in,
                                 const std::vector<long>& mass_points) {
  auto probe = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(times_in);
  if (!probe || probe.ndim() != 1 || probe.shape(0) < 1) throw InputError("times: expected (F,) frame times, F >= 1");
  const long F = probe.shape(0), K = long(mass_points.size());
  auto points = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(points_in);
  if (!points || points.ndim() != 3 || points.shape(0) != F || points.shape(1) != K || points.shape(2) != Dim)
    throw InputError("points: expected shape (" + std::to_string(F) + ", " + std::to_string(K) + ", " + std::to_string(Dim) +
                     "): frames x mass_points x coordinates");
  std::vector<fit::ReferenceFrameN<Dim>> frames(F);
  for (long f = 0; f < F; ++f) {
    frames[f].time = probe.at(f);
    if (!std::isfinite(frames[f].time)) throw InputError("times[" + std::to_string(f) + "] is not finite");
    for (long k = 0; k < K; ++k) {
      fit::CorrespondenceN<Dim> c;
      if (mass_points[k] < 0 || mass_points[k] >= body.num_points())
        throw InputError("mass_points[" + std::to_string(k) + "]: the body has " + std::to_string(body.num_points()) + " mass points");
      c.mass_point = int(mass_points[k]);
      for (int i = 0; i < Dim; ++i) c.position[i] = points.at(f, k, i);
      if (!c.position.allFinite()) throw InputError("points[" + std::to_string(f) + ", " + std::to_string(k) + "] is not finite");
      frames[f].points.push_back(c);
    }
  }
  return frames;
}

// The fits of both dimensions under one name each (pybind11 overloads on the body's type).
template <int Dim> void BindPoseFit(py::module_& m) {
  m.def(
      "fit_pose",
      [](std::shared_ptr<BodyModelN<Dim>> body, const py::object& points, const py::object& mass_points,
         const py::object& lattice_coords, const py::object& weights, const py::object& initial_q, const std::string& loss,
         double loss_scale, double prior_weight, std::pair<double, double> bounds, int max_iterations) {
        const auto targets = Targets(*body, points, mass_points, lattice_coords, weights);
        const auto o = Options(*body, initial_q, loss, loss_scale, prior_weight, bounds, max_iterations);
        return WithCtrlC([&] { return fit::FitPose(*body, targets, o); });
      },
      py::arg("body"), py::arg("points"), py::kw_only(), py::arg("mass_points") = py::none(),
      py::arg("lattice_coords") = py::none(), py::arg("weights") = py::none(), py::arg("initial_q") = py::none(),
      py::arg("loss") = "squared", py::arg("loss_scale") = 1.0, py::arg("prior_weight") = 0.0,
      py::arg("mode_bounds") = std::make_pair(-1.0, 1.0), py::arg("max_iterations") = 200,
      Dim == 2 ? "Fits q = [tx, ty, θ, γ...] so that the body's points land on `points` (K, 2): point k is mass\n"
                 "point mass_points[k], or the lattice point lattice_coords[k] = (s, t). Like `wobble fit pose`.\n"
                 "loss: squared, huber or cauchy (robust, scale loss_scale); prior_weight pulls γ to 0."
               : "A 3D body: points (K, 3), lattice_coords (s, t, u), q = [tx, ty, tz, rx, ry, rz, γ...] with r\n"
                 "the rotation vector (fit/pose_fit.h: Kabsch start, the turn solved on SO(3)).");
}

template <int Dim> void BindTrajectoryFit(py::module_& m) {
  m.def(
      "fit_trajectory",
      [](std::shared_ptr<BodyModelN<Dim>> body, const py::object& times, const py::object& points,
         const std::vector<long>& mass_points, double smoothness, const std::string& loss, double loss_scale,
         double prior_weight, std::pair<double, double> bounds, int max_iterations) {
        const auto frames = Frames(*body, times, points, mass_points);
        if (!(smoothness >= 0) || !std::isfinite(smoothness)) throw InputError("smoothness must be a finite number >= 0");
        fit::TrajectoryFitOptions o;
        o.pose = Options(*body, py::none(), loss, loss_scale, prior_weight, bounds, max_iterations);
        o.smoothness = smoothness;
        return WithCtrlC([&] { return fit::FitKinematicTrajectory(*body, frames, o); });
      },
      py::arg("body"), py::arg("times"), py::arg("points"), py::arg("mass_points"), py::kw_only(),
      py::arg("smoothness") = 1.0, py::arg("loss") = "squared", py::arg("loss_scale") = 1.0,
      py::arg("prior_weight") = 0.0, py::arg("mode_bounds") = std::make_pair(-1.0, 1.0), py::arg("max_iterations") = 200,
      Dim == 2 ? "Fits a pose per frame to mass points mass_points (K,) seen at `points` (F, K, 2), all frames\n"
                 "in one problem with ½ w Σ |L Δ²q|² (w = smoothness) tying neighbours. Like `wobble fit trajectory`."
               : "A 3D body: points (F, K, 3); q rows [t, r, γ], the orientation's smoothness on SO(3).");
}


template <int Dim> void BindDynamicFit(py::module_& m) {
  m.def(
      "fit_dynamic",
      [](std::shared_ptr<BodyModelN<Dim>> body, const py::object& times, const py::object& points,
         const std::vector<long>& mass_points, const py::object& q0, const py::object& qd0, const py::object& stiffness,
         const py::object& damping, const py::object& graph, const WorldOptions& world, bool fit_q0, bool fit_qd0,
         bool fit_stiffness, bool fit_damping, bool fit_poses, bool fit_times, double switch_width, int max_iterations,
         const std::string& gradient) {
        const auto frames = Frames(*body, times, points, mass_points);
        fit::DynamicParameters start;
        start.q0 = VectorOr(q0, body->num_q(), Eigen::VectorXd(), "q0");
        start.qd0 = VectorOr(qd0, body->num_q(), Eigen::VectorXd(), "qd0");
        start.stiffness = VectorOr(stiffness, body->num_modes(), Eigen::VectorXd(), "stiffness");
        start.damping = VectorOr(damping, body->num_modes(), Eigen::VectorXd(), "damping");
        if (!graph.is_none()) start.graph = graph.cast<control::PoseGraph>();
        if (world.integrator != Integrator::kThesis)
          throw InputError("fit_dynamic simulates with the thesis integrator (options.integrator = 'thesis')");
        fit::DynamicFitOptionsN<Dim> o;
        o.world = world.params;  // as World steps it
        o.dt = world.dt;
        o.fit_q0 = fit_q0;
        o.fit_qd0 = fit_qd0;
        o.fit_stiffness = fit_stiffness;
        o.fit_damping = fit_damping;
        o.fit_poses = fit_poses;
        o.fit_times = fit_times;
        o.switch_width = switch_width;
        o.max_iterations = max_iterations;
        if (gradient != "jets" && gradient != "adjoint") throw InputError("gradient: expected 'jets' or 'adjoint', got '" + gradient + "'");
        o.gradient = gradient == "adjoint" ? fit::FitGradient::kAdjoint : fit::FitGradient::kJets;
        return WithCtrlC([&] { return fit::FitDynamicTrajectory(*body, frames, start, o); });
      },
      py::arg("body"), py::arg("times"), py::arg("points"), py::arg("mass_points"), py::kw_only(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), py::arg("graph") = py::none(), py::arg("options") = WorldOptions(),
      py::arg("fit_q0") = true, py::arg("fit_qd0") = true, py::arg("fit_stiffness") = true, py::arg("fit_damping") = true,
      py::arg("fit_poses") = false, py::arg("fit_times") = false, py::arg("switch_width") = 0.05,
      py::arg("max_iterations") = 50, py::arg("gradient") = "jets",
      Dim == 2 ? "Fits the start state, mode stiffness and damping (and a pose graph's poses and times) so that\n"
                 "a simulation puts mass points mass_points (K,) where `points` (F, K, 2) has them at `times`\n"
                 "(F,, on the step grid). Starts: q0/qd0 None: from pose fits of the first frames; stiffness\n"
                 "and damping None: the body's. Like `wobble fit trajectory --dynamic`; differentiates with Ceres Jets\n"
                 "(Levenberg-Marquardt), or with gradient='adjoint' by one adjoint sweep per gradient (BFGS)."
               : "A 3D body: points (F, K, 3), q0 = [t, r, γ], qd0 = [ṫ, body ω, γ̇]; the world's 3D gravity,\n"
                 "ground plane and springs (options.gravity, ground_plane, springs).");
}

}  // namespace

void BindFit(py::module_& m) {
  py::class_<fit::FitReport>(m, "FitReport", "What Ceres said about a fit.")
      .def_readonly("usable", &fit::FitReport::usable)
      .def_readonly("termination", &fit::FitReport::termination)
      .def_readonly("brief_report", &fit::FitReport::brief_report)
      .def_readonly("initial_cost", &fit::FitReport::initial_cost)
      .def_readonly("final_cost", &fit::FitReport::final_cost, "½ Σ ρ(|r|²), prior included")
      .def_readonly("cost_per_iteration", &fit::FitReport::cost_per_iteration)
      .def_readonly("iterations", &fit::FitReport::iterations)
      .def_readonly("solve_seconds", &fit::FitReport::solve_seconds);

  py::class_<fit::Conditioning>(m, "FitConditioning", "How well the targets determine each coordinate.")
      .def_readonly("condition_number", &fit::Conditioning::condition_number, "cond(JᵀJ), raw J (inf: singular)")
      .def_readonly("scaled_condition_number", &fit::Conditioning::scaled_condition_number)
      .def_readonly("column_norms", &fit::Conditioning::column_norms, "|∂residuals/∂q_i|: how strongly the data sees q_i")
      .def_readonly("undetermined", &fit::Conditioning::undetermined, "modes the data cannot see")
      .def_readonly("poorly_determined", &fit::Conditioning::poorly_determined);

  py::class_<fit::PoseFitResult>(m, "PoseFitResult", "A fitted pose q with its residuals, report and conditioning.")
      .def_readonly("q", &fit::PoseFitResult::q)
      .def_readonly("report", &fit::PoseFitResult::report)
      .def_readonly("point_residuals", &fit::PoseFitResult::point_residuals)
      .def_readonly("rms_residual", &fit::PoseFitResult::rms_residual)
      .def_readonly("at_bound", &fit::PoseFitResult::at_bound, "modes that ended on a bound")
      .def_readonly("conditioning", &fit::PoseFitResult::conditioning)
      .def_readonly("rounds", &fit::PoseFitResult::rounds, "curve fits: closest-point rounds");

  BindPoseFit<2>(m);
  BindPoseFit<3>(m);

  py::class_<fit::TrajectoryFitResult>(m, "TrajectoryFitResult", "One pose per frame, fitted together with a smoothness term.")
      .def_readonly("times", &fit::TrajectoryFitResult::times)
      .def_property_readonly("q",
                             [](const fit::TrajectoryFitResult& r) {
                               Eigen::MatrixXd out(r.q.size(), r.q.empty() ? 0 : r.q[0].size());
                               for (size_t f = 0; f < r.q.size(); ++f) out.row(f) = r.q[f].transpose();
                               return out;
                             },
                             "(frames, num_q)")
      .def_readonly("report", &fit::TrajectoryFitResult::report)
      .def_readonly("frame_rms", &fit::TrajectoryFitResult::frame_rms)
      .def_readonly("rms_residual", &fit::TrajectoryFitResult::rms_residual)
      .def_readonly("linear_solver", &fit::TrajectoryFitResult::linear_solver);

  BindTrajectoryFit<2>(m);
  BindTrajectoryFit<3>(m);

  py::class_<fit::DynamicParameters>(m, "DynamicParameters", "What a dynamic fit fits: start state, mode constants, controller.")
      .def_readonly("q0", &fit::DynamicParameters::q0)
      .def_readonly("qd0", &fit::DynamicParameters::qd0)
      .def_readonly("stiffness", &fit::DynamicParameters::stiffness, "per mode K")
      .def_readonly("damping", &fit::DynamicParameters::damping, "per mode c")
      .def_readonly("graph", &fit::DynamicParameters::graph);
  py::class_<fit::DynamicFitResult>(m, "DynamicFitResult", "A dynamic fit's parameters, report and residual.")
      .def_readonly("params", &fit::DynamicFitResult::params)
      .def_readonly("report", &fit::DynamicFitResult::report)
      .def_readonly("rms_residual", &fit::DynamicFitResult::rms_residual, "simulated points to the reference, all frames")
      .def_readonly("simulations", &fit::DynamicFitResult::simulations);

  BindDynamicFit<2>(m);
  BindDynamicFit<3>(m);

  m.def(
      "fit_pose_to_curves",
      [](std::shared_ptr<BodyModel> body, const std::vector<Eigen::MatrixXd>& polylines, bool closed,
         const py::object& initial_q, const std::string& loss, double loss_scale, double prior_weight,
         std::pair<double, double> bounds, int max_iterations) {
        fit::CurveTarget target;
        for (size_t i = 0; i < polylines.size(); ++i) {
          const Eigen::MatrixXd& p = polylines[i];
          if (p.cols() != 2 || p.rows() < 1) throw InputError("polylines[" + std::to_string(i) + "]: expected (M, 2) points");
          if (!p.allFinite()) throw InputError("polylines[" + std::to_string(i) + "] is not finite");
          std::vector<Eigen::Vector2d> points;
          for (int r = 0; r < p.rows(); ++r) points.push_back(p.row(r).transpose());
          if (points.size() == 1) target.AddPoint(points[0]);
          else target.AddPolyline(points, closed);
        }
        if (polylines.empty()) throw InputError("fit_pose_to_curves: no polylines");
        const auto o = Options(*body, initial_q, loss, loss_scale, prior_weight, bounds, max_iterations);
        return WithCtrlC([&] { return fit::FitPoseToCurve(*body, target, o); });
      },
      py::arg("body"), py::arg("polylines"), py::kw_only(), py::arg("closed") = false, py::arg("initial_q") = py::none(),
      py::arg("loss") = "squared", py::arg("loss_scale") = 1.0, py::arg("prior_weight") = 0.0,
      py::arg("mode_bounds") = std::make_pair(-1.0, 1.0), py::arg("max_iterations") = 200,
      "Fits the body's outline (its drawing and mass points) to target curves, each (M, 2); a single\n"
      "point is a point target. Like `wobble fit pose --targets` with polylines.");

  m.def(
      "fit_pose_to_surface",
      [](std::shared_ptr<BodyModelN<3>> body, const py::object& vertices, const py::object& triangles,
         const py::object& cloud, const py::object& initial_q, const std::string& loss, double loss_scale,
         double prior_weight, std::pair<double, double> bounds, int max_iterations, int mesh_samples, bool two_sided) {
        fit::SurfaceTarget target;
        if (vertices.is_none() != triangles.is_none()) throw InputError("give vertices (V, 3) and triangles (T, 3) together");
        if (!vertices.is_none()) {
          const Eigen::MatrixXd v = vertices.cast<Eigen::MatrixXd>();
          const Eigen::MatrixXi t = triangles.cast<Eigen::MatrixXi>();
          if (v.cols() != 3 || t.cols() != 3) throw InputError("vertices and triangles: expected (V, 3) and (T, 3)");
          SurfaceMesh mesh;
          for (int r = 0; r < v.rows(); ++r) mesh.points.push_back(v.row(r).transpose());
          for (int r = 0; r < t.rows(); ++r) mesh.triangles.push_back({t(r, 0), t(r, 1), t(r, 2)});
          CheckSurfaceMesh(mesh);  // finite points, indices in range
          target.AddMesh(mesh);
        }
        if (!cloud.is_none()) {
          const Eigen::MatrixXd c = cloud.cast<Eigen::MatrixXd>();
          if (c.cols() != 3) throw InputError("cloud: expected (P, 3) points");
          if (!c.allFinite()) throw InputError("cloud: the points must be finite");
          for (int r = 0; r < c.rows(); ++r) target.AddPoint(c.row(r).transpose());
        }
        if (target.empty()) throw InputError("fit_pose_to_surface: no triangles and no cloud points");
        if (mesh_samples < 0) throw InputError("mesh_samples must be >= 0");
        fit::PoseFitOptions o = Options(*body, initial_q, loss, loss_scale, prior_weight, bounds, max_iterations);
        o.max_mesh_samples = mesh_samples;
        o.two_sided = two_sided;
        return WithCtrlC([&] { return fit::FitPoseToSurface(*body, target, o); });
      },
      py::arg("body"), py::kw_only(), py::arg("vertices") = py::none(), py::arg("triangles") = py::none(),
      py::arg("cloud") = py::none(), py::arg("initial_q") = py::none(), py::arg("loss") = "squared",
      py::arg("loss_scale") = 1.0, py::arg("prior_weight") = 0.0, py::arg("mode_bounds") = std::make_pair(-1.0, 1.0),
      py::arg("max_iterations") = 200, py::arg("mesh_samples") = 400, py::arg("two_sided") = true,
      "Fits a 3D body to a surface without correspondences: a target mesh (vertices (V, 3), triangles\n"
      "(T, 3)) and/or a cloud (P, 3), e.g. a scan. The body's samples are its mesh's vertices (at most\n"
      "mesh_samples; its mass points when it has no mesh). Like `wobble fit pose` with a 3D 'mesh'/'cloud' file.");
}

}  // namespace wobble::python
