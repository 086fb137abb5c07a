// 3D FFD characters from Python (issue 15): a 3D object file with its modes (a mesh read by
// VTK's readers when the module has the pipelines), the body's mesh and its FFD, and the 3D
// body in the World with the CLI's state convention q = (t, rotation vector, γ), q̇ = (ṫ, body
// ω, γ̇).
#include "bindings.h"

#include "wobble/analysis/conditioning.h"
#include "wobble/body/body_model.h"
#include "wobble/core/errors.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::python {
namespace {

py::array_t<double> Rows3(const std::vector<Eigen::Vector3d>& points) {
  py::array_t<double> out({py::ssize_t(points.size()), py::ssize_t(3)});
  auto a = out.mutable_unchecked<2>();
  for (size_t k = 0; k < points.size(); ++k)
    for (int c = 0; c < 3; ++c) a(k, c) = points[k][c];
  return out;
}

}  // namespace

void BindBodies3(py::module_& m) {
  py::class_<BodyModelN<3>, std::shared_ptr<BodyModelN<3>>>(
      m, "BodyModel3",
      "A 3D FFD character (issue 15): a trivariate lattice, mass points, modes made by generators,\n"
      "and optionally a user's mesh. Immutable. In a World its q is [tx, ty, tz, rx, ry, rz,\n"
      "γ1..γD] (r the rotation vector) and q̇ [vx, vy, vz, ωx, ωy, ωz (body frame), γ̇1..γ̇D].\n"
      "Make one with wobble.load_body (a 'dimension 3' object file).")
      .def_property_readonly("name", &BodyModelN<3>::name)
      .def_property_readonly("num_modes", &BodyModelN<3>::num_modes)
      .def_property_readonly("num_q", [](const BodyModelN<3>& b) { return Group<3>::kRigidDofs + b.num_modes(); },
                             "6 rigid coordinates + one per mode")
      .def_property_readonly("num_points", &BodyModelN<3>::num_points, "mass points")
      .def_property_readonly("mode_names",
                             [](const BodyModelN<3>& b) {
                               std::vector<std::string> names;
                               for (const DeformationModeN<3>& d : b.modes()) names.push_back(d.name);
                               return names;
                             })
      .def_property_readonly("total_mass", [](const BodyModelN<3>& b) { return b.moments().m; })
      .def_property_readonly("masses", [](const BodyModelN<3>& b) { return b.def().masses; }, "mass of each mass point")
      .def_property_readonly("mass_positions", [](const BodyModelN<3>& b) { return Rows3(b.def().mass_positions); },
                             "(num_points, 3) mass points in the body frame")
      .def_property_readonly("mesh_points", [](const BodyModelN<3>& b) { return Rows3(b.def().mesh.points); },
                             "(V, 3) the mesh's vertices in the body frame (V = 0 without a mesh)")
      .def_property_readonly(
          "mesh_triangles",
          [](const BodyModelN<3>& b) {
            const auto& t = b.def().mesh.triangles;
            py::array_t<int> out({py::ssize_t(t.size()), py::ssize_t(3)});
            auto a = out.mutable_unchecked<2>();
            for (size_t k = 0; k < t.size(); ++k)
              for (int c = 0; c < 3; ++c) a(k, c) = t[k][size_t(c)];
            return out;
          },
          "(T, 3) vertex indices of each triangle")
      .def(
          "mesh_vertices",
          [](const BodyModelN<3>& b, const py::object& q_in) {
            const int n = Group<3>::kRigidDofs + b.num_modes();
            const Eigen::VectorXd q = q_in.is_none() ? Eigen::VectorXd::Zero(n) : AsVector(q_in, n, "q");
            const Eigen::Quaterniond R = ExpRotation<double>(Eigen::Vector3d(q.segment<3>(3)));
            const Eigen::VectorXd gamma = q.tail(b.num_modes());
            std::vector<Eigen::Vector3d> x(b.def().mesh.points.size());
            for (size_t v = 0; v < x.size(); ++v)
              x[v] = q.head<3>() + R * (b.mesh_rest_local(int(v)) + b.mesh_mode_matrix(int(v)) * gamma);
            return Rows3(x);
          },
          py::arg("q") = py::none(),
          "(V, 3) world positions of the mesh's vertices at q: x = t + R (b0 + B γ), every vertex\n"
          "moved by the FFD of its lattice")
      .def(
          "mass_points_at",
          [](const BodyModelN<3>& b, const py::object& q_in) {
            const int n = Group<3>::kRigidDofs + b.num_modes();
            const Eigen::VectorXd q = q_in.is_none() ? Eigen::VectorXd::Zero(n) : AsVector(q_in, n, "q");
            std::vector<Eigen::Vector3d> x;
            for (int k = 0; k < b.num_points(); ++k) x.push_back(fit::PointPosition(fit::BasisOf(b, k, {}), q));
            return Rows3(x);
          },
          py::arg("q") = py::none(),
          "(N, 3) world positions of the mass points at q = [t, r, γ] (r a rotation vector), as the\n"
          "fits place them (the correspondences of wobble.fit_pose with mass_points)")
      .def("__repr__", [](const BodyModelN<3>& b) {
        return "<BodyModel3 '" + b.name() + "': " + std::to_string(b.num_points()) + " points, " +
               std::to_string(b.num_modes()) + " modes, " + std::to_string(b.def().mesh.points.size()) + " mesh vertices>";
      });

  // release 0.1's 3D names: load_body and the World's methods take either body now
  BindDeprecated(m, "load_body3", "load_body");
  const py::object world = m.attr("World");
  for (const auto& [old_name, name] : {std::pair{"add_body3", "add_body"}, {"body3", "body"}, {"q3", "q"},
                                       {"qd3", "qd"}, {"set_state3", "set_state"}})
    BindDeprecated(world, old_name, name);

}

}  // namespace wobble::python
