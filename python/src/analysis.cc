// The condition number of the mass matrix (analysis/conditioning.h, thesis §4.4 and Fig. 4.7)
// from Python: of a body at a state, against the angle between two squash modes, and the
// check of a mode set that `wobble condition check` prints.
#include "support.h"

#include "wobble/analysis/conditioning.h"
#include "wobble/core/errors.h"
#include "wobble/dynamics/kinematics.h"
#include "wobble/formats/object_file.h"

namespace wobble::python {
namespace {

Eigen::VectorXd StateOrRest(const BodyModel& body, const py::object& q_in) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  if (!q_in.is_none()) {
    auto a = AsMatrix(q_in, body.num_q(), -1, "q");
    q = Eigen::Map<const Eigen::VectorXd>(a.data(), body.num_q());
    if (!q.allFinite()) throw InputError("q must be finite");
  }
  return q;
}

}  // namespace

void BindAnalysis(py::module_& m) {
  py::class_<analysis::ConditionNumber>(m, "ConditionNumber", "cond₂ of a mass matrix M(q).")
      .def_readonly("singular", &analysis::ConditionNumber::singular)
      .def_readonly("cond", &analysis::ConditionNumber::cond, "σ_max / σ_min (inf when singular)")
      .def_readonly("cond_scaled", &analysis::ConditionNumber::cond_scaled, "of S M S, S = diag(M)^(-1/2): unit-free")
      .def_readonly("singular_values", &analysis::ConditionNumber::singular_values, "descending");

  m.def(
      "condition_number",
      [](std::shared_ptr<BodyModel> body, const py::object& q) {
        return analysis::MassMatrixCondition(*body, StateOrRest(*body, q));
      },
      py::arg("body"), py::arg("q") = py::none(), "cond(M(q)) of the body (q None: at rest)");

  m.def(
      "mass_matrix",
      [](std::shared_ptr<BodyModel> body, const py::object& q) {
        MatQ<double> M;
        MassMatrix(body->moments(), VecQ<double>(StateOrRest(*body, q)), &M);
        return Eigen::MatrixXd(M);
      },
      py::arg("body"), py::arg("q") = py::none(),
      "M(q) (Eq. 4.10) from the precomputed mass moments: the kinetic energy is ½ q̇ᵀ M q̇.");

  m.def(
      "angle_sweep",
      [](const std::string& object, const std::vector<double>& phis, double compress, double expand) {
        for (double phi : phis)
          if (!std::isfinite(phi)) throw InputError("angle_sweep: every angle must be finite");
        analysis::Squash squash;
        squash.compress = compress;
        squash.expand = expand;
        const BodyDef def = formats::ReadObjectFile(object);
        const std::vector<analysis::SweepSample> samples =
            analysis::AngleSweep(def, phis, squash, Eigen::VectorXd::Zero(kRigidDofs + 2));
        Eigen::VectorXd cond(samples.size()), scaled(samples.size());
        for (size_t i = 0; i < samples.size(); ++i) {
          cond[i] = samples[i].cond.cond;
          scaled[i] = samples[i].cond.cond_scaled;
        }
        return py::make_tuple(cond, scaled);
      },
      py::arg("object"), py::arg("phis"), py::kw_only(), py::arg("compress") = 1.0, py::arg("expand") = 0.5,
      "Fig. 4.7: for each angle φ (radians), the object with two modes, the vertical squash and the\n"
      "squash at φ, and cond(M) at rest. Returns (cond, cond_scaled) arrays; inf at φ = π/2, where\n"
      "the two modes are one.");

  py::class_<analysis::ModeSetReport>(m, "ModeSetReport", "What `wobble condition check` says of a mode set.")
      .def_property_readonly("level", [](const analysis::ModeSetReport& r) { return analysis::LevelName(r.level); })
      .def_readonly("messages", &analysis::ModeSetReport::messages, "one line each, most severe first")
      .def_readonly("dofs", &analysis::ModeSetReport::dofs)
      .def_readonly("pair_angle_deg", &analysis::ModeSetReport::pair_angle_deg, "angles between the modes' fields (D x D)")
      .def_readonly("smallest_angle_deg", &analysis::ModeSetReport::smallest_angle_deg)
      .def_readonly("smallest_mode", &analysis::ModeSetReport::smallest_mode)
      .def_readonly("condition", &analysis::ModeSetReport::condition);

  m.def(
      "check_mode_set", [](const BodyModel& body) { return analysis::CheckModeSet(body); }, py::arg("body"),
      "How close the body's modes are to each other (pair angles, dependencies) and cond(M) at rest.");
}

}  // namespace wobble::python
