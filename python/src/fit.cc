// Fits from Python (fit/pose_fit.h, Ceres): mode amplitudes and placement from target points
// (mass points or lattice points matched to world positions) or from target curves, with the
// report and the conditioning of the fit (which modes the data cannot see).
#include "support.h"

#include <cmath>

#include "wobble/core/errors.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::python {
namespace {

fit::PoseFitOptions Options(const BodyModel& body, const py::object& initial_q, const std::string& loss, double loss_scale,
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
  const std::string error = fit::ValidateOptions(o, body.num_modes());
  if (!error.empty()) throw InputError("pose fit: " + error);
  return o;
}

// Target points: positions (K, 2), each on a mass point (mass_points, K ints) or at lattice
// coordinates (lattice_coords, K x 2); weights > 0.
std::vector<fit::Correspondence> Targets(const BodyModel& body, const py::object& positions_in, const py::object& mass_points,
                                         const py::object& lattice_coords, const py::object& weights_in) {
  auto probe = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(positions_in);
  if (!probe || probe.ndim() != 2) throw InputError("points: expected an array (K, 2) of world positions");
  const long K = probe.shape(0);
  auto positions = AsMatrix(probe, K, 2, "points");
  if (mass_points.is_none() == lattice_coords.is_none())
    throw InputError("give the body's points as exactly one of mass_points (K,) or lattice_coords (K, 2)");
  std::vector<fit::Correspondence> out(K);
  std::vector<long> which;
  if (!mass_points.is_none()) which = mass_points.cast<std::vector<long>>();
  py::array_t<double, py::array::c_style> st;
  if (!lattice_coords.is_none()) st = AsMatrix(lattice_coords, K, 2, "lattice_coords");
  if (!mass_points.is_none() && long(which.size()) != K)
    throw InputError("mass_points: expected " + std::to_string(K) + " indices, one per point, got " + std::to_string(which.size()));
  std::vector<double> weights(K, 1.0);
  if (!weights_in.is_none()) {
    auto w = AsMatrix(weights_in, K, -1, "weights");
    weights.assign(w.data(), w.data() + K);
  }
  for (long k = 0; k < K; ++k) {
    fit::Correspondence& c = out[k];
    c.position = Eigen::Vector2d(positions.at(k, 0), positions.at(k, 1));
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
      c.lattice_coords = Eigen::Vector2d(st.at(k, 0), st.at(k, 1));
      if (!c.lattice_coords.allFinite()) throw InputError("lattice_coords[" + std::to_string(k) + "] is not finite");
    }
  }
  return out;
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

  m.def(
      "fit_pose",
      [](std::shared_ptr<BodyModel> body, const py::object& points, const py::object& mass_points,
         const py::object& lattice_coords, const py::object& weights, const py::object& initial_q, const std::string& loss,
         double loss_scale, double prior_weight, std::pair<double, double> bounds, int max_iterations) {
        const auto targets = Targets(*body, points, mass_points, lattice_coords, weights);
        const auto o = Options(*body, initial_q, loss, loss_scale, prior_weight, bounds, max_iterations);
        py::gil_scoped_release release;
        return fit::FitPose(*body, targets, o);
      },
      py::arg("body"), py::arg("points"), py::kw_only(), py::arg("mass_points") = py::none(),
      py::arg("lattice_coords") = py::none(), py::arg("weights") = py::none(), py::arg("initial_q") = py::none(),
      py::arg("loss") = "squared", py::arg("loss_scale") = 1.0, py::arg("prior_weight") = 0.0,
      py::arg("mode_bounds") = std::make_pair(-1.0, 1.0), py::arg("max_iterations") = 200,
      "Fits q = [tx, ty, θ, γ...] so that the body's points land on `points` (K, 2): point k is mass\n"
      "point mass_points[k], or the lattice point lattice_coords[k] = (s, t). Like `wobble fit pose`.\n"
      "loss: squared, huber or cauchy (robust, scale loss_scale); prior_weight pulls γ to 0.");

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
        py::gil_scoped_release release;
        return fit::FitPoseToCurve(*body, target, o);
      },
      py::arg("body"), py::arg("polylines"), py::kw_only(), py::arg("closed") = false, py::arg("initial_q") = py::none(),
      py::arg("loss") = "squared", py::arg("loss_scale") = 1.0, py::arg("prior_weight") = 0.0,
      py::arg("mode_bounds") = std::make_pair(-1.0, 1.0), py::arg("max_iterations") = 200,
      "Fits the body's outline (its drawing and mass points) to target curves, each (M, 2); a single\n"
      "point is a point target. Like `wobble fit pose --targets` with polylines.");
}

}  // namespace wobble::python
