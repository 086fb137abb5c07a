// The one World (world/world.h) from Python: options, the ground, FFD bodies, stepping,
// energies, contacts and constraints. States cross as numpy arrays (copies: a body's q has a
// few numbers, and the world reuses its buffers between steps).
#include "support.h"

#include <limits>

#include "wobble/core/errors.h"
#include "wobble/control/controllers.h"
#include "wobble/formats/heightfield_file.h"
#include "wobble/world/world.h"

namespace wobble::python {
namespace {

void CheckBody(const World& w, int body) {
  CheckIndex(w, body);
  if (w.kind(body) != BodyKind::kFfd) throw InputError("body " + std::to_string(body) + " is not an FFD body");
}

// A 2D-only call (keyframes, the 2D controllers' lattice coordinates) on a 2D FFD body.
void Check2D(const World& w, int body, const char* what) {
  CheckBody(w, body);
  if (w.dim(body) != 2) throw InputError(std::string(what) + ": body " + std::to_string(body) + " is a 3D body (2D only)");
}

void CheckLinear(const World& w, int body) {
  CheckIndex(w, body);
  if (w.kind(body) != BodyKind::kLinear) throw InputError("body " + std::to_string(body) + " is not a linear body");
}

template <int Dim> py::dict ForcesDict(const ForceBreakdown<Dim, double>& f) {
  py::dict d;
  d["gravity"] = Eigen::VectorXd(f.gravity);
  d["modes"] = Eigen::VectorXd(f.modes);
  d["ground"] = Eigen::VectorXd(f.ground);
  d["springs"] = Eigen::VectorXd(f.springs);
  d["total"] = Eigen::VectorXd(f.total);
  return d;
}

// A controller written in Python: the world calls its before_step/after_step, with the GIL
// (steps run without it) and the world by reference.
class PyController : public Controller {
 public:
  void BeforeStep(World& w) override { Call("before_step", w); }
  void AfterStep(World& w) override { Call("after_step", w); }

 private:
  void Call(const char* name, World& w) {
    py::gil_scoped_acquire gil;
    if (py::function f = py::get_override(static_cast<const Controller*>(this), name))
      f(py::cast(&w, py::return_value_policy::reference));
  }
};

// WorldOptions.gravity from 2 (z = 0) or 3 components.
void SetGravity(WorldOptions& o, const Eigen::VectorXd& g) {
  if (g.size() != 2 && g.size() != 3) throw InputError("gravity takes 2 or 3 components, got " + std::to_string(g.size()));
  o.params.gravity.setZero();
  o.params.gravity.head(g.size()) = g;
}

void WarnDeprecated(const char* message) {
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message, 1) < 0) throw py::error_already_set();
}

}  // namespace

void BindWorld(py::module_& m) {
  py::class_<Ground>(m, "Ground",
                     "The ground line of §4.9: a penalty spring–damper (Eq. 4.24/4.25) with friction capped\n"
                     "at friction_cap times the normal force.")
      .def(py::init<>())
      .def_readwrite("enabled", &Ground::enabled)
      .def_readwrite("point", &Ground::point, "a point of the ground line")
      .def_readwrite("slope", &Ground::slope, "radians, counter-clockwise")
      .def_readwrite("stiffness", &Ground::stiffness, "K_d (appendix C: grconst)")
      .def_readwrite("normal_damping", &Ground::normal_damping, "C_dam (grdam)")
      .def_readwrite("friction_damping", &Ground::friction_damping, "FR_dam (frconst)")
      .def_readwrite("friction_cap", &Ground::friction_cap, "tan θ: |friction| / normal force never exceeds it")
      .def_readwrite("max_penetration", &Ground::max_penetration, "deeper stops the run; 0: half the shorter lattice side")
      .def_property_readonly("normal", &Ground::normal)
      .def_property_readonly("tangent", &Ground::tangent);

  py::class_<Heightfield, std::shared_ptr<Heightfield>>(
      m, "Heightfield",
      "The 3D ground y = h(x, z) on a regular grid, two flat triangles per cell, level beyond it\n"
      "(README: Heightfield terrain). Set it as options.ground_plane.heightfield.")
      .def(py::init([](const Eigen::Vector2d& origin, const Eigen::Vector2d& spacing, const Eigen::MatrixXd& heights) {
             std::vector<double> h;  // heights[j, i] is node (i, j): a row per z
             for (Eigen::Index j = 0; j < heights.rows(); ++j)
               for (Eigen::Index i = 0; i < heights.cols(); ++i) h.push_back(heights(j, i));
             return std::const_pointer_cast<Heightfield>(
                 Heightfield::Make(origin, spacing, int(heights.cols()), int(heights.rows()), std::move(h)));
           }),
           py::arg("origin"), py::arg("spacing"), py::arg("heights"),
           "origin (x0, z0), spacing (dx, dz), heights (nz, nx): heights[j, i] at (x0 + i dx, z0 + j dz)")
      .def_property_readonly("origin", [](const Heightfield& f) { return f.origin(); })
      .def_property_readonly("spacing", [](const Heightfield& f) { return f.spacing(); })
      .def_property_readonly("heights",
                             [](const Heightfield& f) {
                               Eigen::MatrixXd h(f.nz(), f.nx());
                               for (int j = 0; j < f.nz(); ++j)
                                 for (int i = 0; i < f.nx(); ++i) h(j, i) = f.Node(i, j);
                               return h;
                             })
      .def("height_at", &Heightfield::HeightAt, py::arg("x"), py::arg("z"), "the surface's height over (x, z)");
  m.def(
      "read_heightfield",
      [](const std::string& path) { return std::const_pointer_cast<Heightfield>(formats::ReadHeightfieldFile(path)); },
      py::arg("path"), "a heightfield file ('origin X0 Z0', 'spacing DX DZ', a row of heights per z)");

  py::class_<GroundPlane>(m, "GroundPlane",
                          "The 3D FFD bodies' ground: a plane of any normal with the penalty contact and capped\n"
                          "friction of §4.9 in two tangent directions (off by default).")
      .def(py::init<>())
      .def_readwrite("enabled", &GroundPlane::enabled)
      .def_readwrite("point", &GroundPlane::point, "a point of the plane")
      .def_property(
          "normal", [](const GroundPlane& g) { return g.normal; },
          [](GroundPlane& g, const Eigen::Vector3d& n) {
            if (!(n.norm() > 0) || !n.allFinite()) throw InputError("ground_plane.normal must be a finite, non-zero vector");
            g.normal = n.normalized();
          },
          "unit normal out of the ground (normalized when set)")
      .def_readwrite("stiffness", &GroundPlane::stiffness)
      .def_readwrite("normal_damping", &GroundPlane::normal_damping)
      .def_readwrite("friction_damping", &GroundPlane::friction_damping)
      .def_readwrite("friction_cap", &GroundPlane::friction_cap)
      .def_property(
          "heightfield", [](const GroundPlane& g) { return std::const_pointer_cast<Heightfield>(g.heightfield); },
          [](GroundPlane& g, std::shared_ptr<Heightfield> f) { g.heightfield = std::move(f); },
          "a Heightfield in place of the plane (None: the plane)");

  py::class_<WorldOptions>(m, "WorldOptions", "What a World is made with; every field is also a keyword of the constructor.")
      .def(py::init<>())
      .def_readwrite("dt", &WorldOptions::dt, "time step (s)")
      .def_property(
          "integrator", [](const WorldOptions& o) { return IntegratorName(o.integrator); },
          [](WorldOptions& o, const std::string& name) {
            if (!ParseIntegrator(name, &o.integrator))
              throw InputError("integrator: '" + name + "' is not one of " + IntegratorNames());
          },
          "every body's integrator: thesis (Eq. 4.22/4.23), symplectic, rk4, implicit, variational; constraints are a "
          "stage of it (variational refuses a constrained step)")
      .def_property(
          "gravity", [](const WorldOptions& o) { return o.params.gravity; }, SetGravity,
          "gravity (m/s², x y z), one for bodies of both dimensions: a 2D body feels x and y; set\n"
          "with 3 components, or 2 (z = 0)")
      .def_property(
          "gravity_on", [](const WorldOptions& o) { return o.params.gravity_on; },
          [](WorldOptions& o, bool on) { o.params.gravity_on = on; })
      .def_property(
          "ground", [](WorldOptions& o) -> Ground& { return o.params.ground; },
          [](WorldOptions& o, const Ground& g) { o.params.ground = g; }, py::return_value_policy::reference_internal,
          "the ground (changed in place: options.ground.stiffness = ...)")
      .def_property(
          "max_condition", [](const WorldOptions& o) { return o.params.max_condition; },
          [](WorldOptions& o, double c) { o.params.max_condition = c; },
          "runs stop when the estimated condition number of M exceeds this")
      .def_readwrite("feedback_rate", &WorldOptions::feedback_rate, "constraint drift feedback (Witkin & Welch Eq. 10)")
      .def_property(
          "ground_plane", [](WorldOptions& o) -> GroundPlane& { return o.params.ground_plane; },
          [](WorldOptions& o, const GroundPlane& g) { o.params.ground_plane = g; },
          py::return_value_policy::reference_internal,
          "the ground the 3D bodies stand on (changed in place: options.ground_plane.enabled = True)")
      // one release: the 3D twins of ground_plane and gravity warn
      .def_property(
          "ground_3d",
          [](WorldOptions& o) -> GroundPlane& {
            WarnDeprecated("WorldOptions.ground_3d is deprecated: use WorldOptions.ground_plane");
            return o.params.ground_plane;
          },
          [](WorldOptions& o, const GroundPlane& g) {
            WarnDeprecated("WorldOptions.ground_3d is deprecated: use WorldOptions.ground_plane");
            o.params.ground_plane = g;
          },
          py::return_value_policy::reference_internal, "Deprecated (one release): WorldOptions.ground_plane.")
      .def_property(
          "gravity_3d",
          [](const WorldOptions& o) {
            WarnDeprecated("WorldOptions.gravity_3d is deprecated: use WorldOptions.gravity (one for both dimensions)");
            return o.params.gravity;
          },
          [](WorldOptions& o, const Eigen::VectorXd& g) {
            WarnDeprecated("WorldOptions.gravity_3d is deprecated: use WorldOptions.gravity (one for both dimensions)");
            SetGravity(o, g);
          },
          "Deprecated (one release): WorldOptions.gravity.");

  py::class_<Energies>(m, "Energies", "Every energy term of one body (J); total() is their sum.")
      .def_readonly("kinetic", &Energies::kinetic, "½ q̇ᵀ M q̇ (Eq. 4.9)")
      .def_readonly("gravity", &Energies::gravity)
      .def_readonly("modes", &Energies::modes, "Σ K (γ − γ0)²")
      .def_readonly("ground", &Energies::ground, "the penalty springs of the contacts")
      .def_readonly("springs", &Energies::springs)
      .def_readonly("per_mode", &Energies::per_mode)
      .def("total", &Energies::total)
      .def("__repr__", [](const Energies& e) { return "<Energies " + EnergyTerms(e) + ">"; });

  py::class_<WorldStatus>(m, "WorldStatus", "Why the world stopped, and where (ok when it did not).")
      .def_property_readonly("ok", &WorldStatus::ok)
      .def_property_readonly("cause", [](const WorldStatus& s) { return StatusCodeName(s.code); })
      .def_readonly("step", &WorldStatus::step)
      .def_readonly("time", &WorldStatus::time)
      .def_readonly("body", &WorldStatus::body)
      .def_readonly("message", &WorldStatus::message);

  py::class_<Controller, PyController, std::shared_ptr<Controller>>(
      m, "Controller",
      "Something the world calls around every step (world/controller.h): subclass it in Python\n"
      "and define before_step(world) and/or after_step(world), then World.add_controller. Steps run\n"
      "without the GIL; a Python controller takes it for its calls (so it costs a few µs a step),\n"
      "and an exception it raises stops the step and comes out of World.step.")
      .def(py::init<>())
      .def("before_step", &Controller::BeforeStep, py::arg("world"), "at the step's start time, before any body moves")
      .def("after_step", &Controller::AfterStep, py::arg("world"), "after the step was accepted");
  py::class_<control::PoseGraphController, Controller, std::shared_ptr<control::PoseGraphController>>(
      m, "PoseGraphController", "Drives a body's active modes through a pose graph (§5.1); add it with World.add_controller.")
      .def(py::init([](const World& w, int body, const control::PoseGraph& graph, double switch_width) {
             CheckBody(w, body);
             if (!(switch_width >= 0)) throw InputError("switch_width must be at least 0");
             return std::make_shared<control::PoseGraphController>(w, body, graph, switch_width);
           }),
           py::arg("world"), py::arg("body"), py::arg("graph"), py::arg("switch_width") = 0.0,
           "switch_width > 0: smoothed switches (the set point moves in about 4 widths)")
      .def_property_readonly("pose", &control::PoseGraphController::pose, "the pose active now")
      .def_property_readonly("steps", &control::PoseGraphController::steps);

  py::class_<control::KeyframeController, Controller, std::shared_ptr<control::KeyframeController>>(
      m, "KeyframeController",
      "Keyframed mode amplitudes (§4.10.1) on one body, which it makes kinematic; a held point stays\n"
      "in place (a foot on the ground). When finished(), release(world) hands the body back to the\n"
      "simulation with its keyframed q and q̇.")
      .def(py::init([](World& w, int body, const std::vector<double>& times, const Eigen::MatrixXd& amplitudes,
                       const std::string& interpolation, const py::object& hold) {
             Check2D(w, body, "KeyframeController");
             control::Keyframes keys;
             keys.times = times;
             for (int k = 0; k < amplitudes.rows(); ++k) keys.amplitudes.push_back(amplitudes.row(k).transpose());
             if (interpolation == "smooth") keys.interpolation = control::Interpolation::kSmooth;
             else if (interpolation != "linear") throw InputError("interpolation: '" + interpolation + "' is not linear or smooth");
             const std::string error = keys.Validate(w.body<2>(body).num_modes());
             if (!error.empty()) throw InputError("keyframes: " + error);
             control::HeldPoint held;
             if (!hold.is_none()) {
               held.enabled = true;
               held.lattice_coords.head<2>() = AsVector(hold, 2, "hold");
             }
             return std::make_shared<control::KeyframeController>(w, body, keys, held);
           }),
           py::arg("world"), py::arg("body"), py::arg("times"), py::arg("amplitudes"), py::arg("interpolation") = "linear",
           py::arg("hold") = py::none(),
           "times: K key times from 0, increasing; amplitudes: (K, num_modes); hold: lattice (s, t) of the held point")
      .def("finished", &control::KeyframeController::Finished)
      .def("release", &control::KeyframeController::Release, py::arg("world"));

  py::class_<WorldData>(m, "WorldData",
                        "Everything a World's steps change (states, contacts, pending forces, multipliers,\n"
                        "clock, status), apart from its model: World.data() takes a copy, World.set_data(d)\n"
                        "puts one back into that world or one with the same bodies and constraints.")
      .def(py::init<const WorldData&>(), py::arg("other"), "a copy")
      .def("__copy__", [](const WorldData& d) { return WorldData(d); })
      .def("__deepcopy__", [](const WorldData& d, py::dict) { return WorldData(d); }, py::arg("memo"))
      .def_property_readonly("time", [](const WorldData& d) { return d.time; })
      .def_property_readonly("steps", [](const WorldData& d) { return d.steps; })
      .def("__repr__", [](const WorldData& d) { return py::str("<WorldData t={} steps={}>").format(d.time, d.steps); });

  py::class_<World>(m, "World",
                    "THE world: FFD bodies of either dimension (2D q = [tx, ty, θ, γ1..γD], Eq. 4.4; 3D q =\n"
                    "[tx, ty, tz, rx, ry, rz, γ1..γD], r the rotation vector, q̇ = [ṫ, body ω, γ̇]), linear\n"
                    "bodies, the ground, springs, constraints,\n"
                    "one clock and one status. Every accepted state is finite, or the world stops and\n"
                    "step() raises SimulationStopped. Not thread-safe: one World per thread (steps\n"
                    "release the GIL).")
      .def(py::init<WorldOptions>(), py::arg("options") = WorldOptions())
      .def("add_body", [](World& w, std::shared_ptr<BodyModel> body) { return w.AddBody(body); }, py::arg("body"),
           "Adds an FFD body (2D or 3D) at q = 0 (its lattice's pose), at rest; returns its index.")
      .def("add_body", [](World& w, std::shared_ptr<BodyModelN<3>> body) { return w.AddBody(body); }, py::arg("body"))
      .def_property_readonly("num_bodies", &World::num_bodies)
      .def_property_readonly("time", &World::time)
      .def_property_readonly("steps", &World::steps)
      .def_property(
          "options", [](const World& w) { return w.options(); },
          [](World& w, const WorldOptions& o) { w.mutable_options() = o; },
          "a copy; assign a changed one to change dt, gravity, the ground or the integrator between steps")
      .def_property_readonly("status", &World::status)
      .def(
          "body",
          [](const World& w, int body) -> py::object {
            CheckBody(w, body);
            if (w.dim(body) == 3) return WrapBody(w.shared_body<3>(body));
            return WrapBody(w.shared_body<2>(body));
          },
          py::arg("body"), "the FFD body's model (a BodyModel, 2D or 3D; the object added, while Python holds it)")
      .def(
          "q", [](const World& w, int body) { CheckBody(w, body); return w.coordinates(body); },
          py::arg("body") = 0, "a copy of the body's q (3D: [t, rotation vector, γ])")
      .def(
          "qd", [](const World& w, int body) { CheckBody(w, body); return Eigen::VectorXd(w.qd(body)); },
          py::arg("body") = 0, "a copy of the body's q̇ (3D: [ṫ, body ω, γ̇])")
      .def(
          "set_state",
          [](World& w, int body, const py::object& q, const py::object& qd) {
            CheckBody(w, body);
            const long n = w.dim(body) == 3 ? w.body<3>(body).num_q() : w.body<2>(body).num_q();
            w.SetCoordinates(body, AsVector(q, n, "q"), qd.is_none() ? Eigen::VectorXd::Zero(n) : AsVector(qd, n, "qd"));
          },
          py::arg("body"), py::arg("q"), py::arg("qd") = py::none(),
          "Sets q and q̇ (zero when not given); InputError for a wrong shape or a non-finite value.")
      .def(
          "set_mode_targets",
          [](World& w, int body, const py::object& targets) {
            CheckIndex(w, body);
            if (w.kind(body) == BodyKind::kLinear) throw InputError("body " + std::to_string(body) + " is not an FFD body");
            const int D = w.num_modes(body);
            w.SetModeTargets(body, AsVector(targets, D, "targets"));
          },
          py::arg("body"), py::arg("targets"), "PD targets γ0 of the body's modes (chapter 5), 2D or 3D FFD bodies")
      .def(
          "step",
          [](World& w, long n) {
            if (n < 0) throw InputError("step: n must be at least 0, got " + std::to_string(n));
            RunWorld(w, std::numeric_limits<double>::infinity(), n);
          },
          py::arg("n") = 1, "Takes n steps of dt (the GIL is released meanwhile).")
      .def(
          "run_until",
          [](World& w, double t_end) { RunWorld(w, t_end, -1); },
          py::arg("t_end"), "Steps until the time reaches t_end (to half a step).")
      .def(
          "energies", [](const World& w, int body) { CheckIndex(w, body); return w.ComputeEnergies(body); },
          py::arg("body") = 0)
      .def("total_energy", &World::TotalEnergy, "every body's every term")
      .def("data", [](const World& w) { return WorldData(w.data()); },
           "a copy of everything the steps change (WorldData): set_data puts it back")
      .def("set_data", [](World& w, const WorldData& d) { w.SetData(d); }, py::arg("data"),
           "Puts back a copy of data taken from this world or one with the same bodies and constraints;\n"
           "InputError (a ValueError) when its bodies, sizes or constraints do not fit. Controllers are not called.")
      .def(
          "contacts",
          [](const World& w, int body) {
            CheckIndex(w, body);
            if (w.kind(body) == BodyKind::kLinear) throw InputError("body " + std::to_string(body) + " is not an FFD body");
            // (point, anchor) of either dimension's contacts
            auto table = [](const auto& contacts, int dim) {
              py::array_t<int> points(contacts.size());
              py::array_t<double> anchors({py::ssize_t(contacts.size()), py::ssize_t(dim)});
              auto p = points.mutable_unchecked<1>();
              auto a = anchors.mutable_unchecked<2>();
              for (size_t k = 0; k < contacts.size(); ++k) {
                p(k) = contacts[k].point;
                for (int i = 0; i < dim; ++i) a(k, i) = contacts[k].anchor[i];
              }
              return py::make_tuple(points, anchors);
            };
            if (w.dim(body) == 3) return table(w.state<3>(body).contacts, 3);
            return table(w.state<2>(body).contacts, 2);
          },
          py::arg("body") = 0,
          "(points, anchors): the mass points below the ground and their entry points (Fig. 4.5); anchors\n"
          "(n, 2), or (n, 3) for a 3D FFD body")
      .def(
          "penetration",
          [](const World& w, int body) {
            CheckIndex(w, body);
            if (w.kind(body) == BodyKind::kLinear) throw InputError("body " + std::to_string(body) + " is not an FFD body");
            return w.Penetration(body);
          },
          py::arg("body") = 0, "the deepest contact (2D or 3D FFD bodies)")
      .def(
          "point_positions",
          [](const World& w, int body) {
            CheckBody(w, body);
            auto rows = [](const auto& x) {
              Eigen::MatrixXd out(x.size(), x.empty() ? 0 : x[0].size());
              for (size_t k = 0; k < x.size(); ++k) out.row(long(k)) = x[k].transpose();
              return out;
            };
            return w.dim(body) == 3 ? rows(w.PointPositions<3>(body)) : rows(w.PointPositions<2>(body));
          },
          py::arg("body") = 0, "(num_points, 2 or 3) world positions of the mass points")
      .def(
          "forces",
          [](const World& w, int body) {
            CheckBody(w, body);
            return w.dim(body) == 3 ? ForcesDict(w.Forces<3>(body)) : ForcesDict(w.Forces<2>(body));
          },
          py::arg("body") = 0, "generalized forces by source: gravity, modes, ground, springs, total")
      .def(
          "accelerations", [](const World& w, int body) { CheckBody(w, body); return w.Accelerations(body); },
          py::arg("body") = 0, "free q̈ = M⁻¹ (Q − velocity terms), no constraint forces")
      .def(
          "add_nail",
          [](World& w, int body, const py::object& mass_point, const py::object& u, const py::object& where) {
            const MaterialPoint p = PointOf(w, body, mass_point, u);
            return w.AddNail(p, where.is_none() ? Eigen::VectorXd() : AsVector(where, w.dim(body), "where"));
          },
          py::arg("body"), py::arg("mass_point") = py::none(), py::kw_only(), py::arg("u") = py::none(),
          py::arg("where") = py::none(),
          "Nails a material point (mass_point k, or u) where it is now, or at `where`; returns the\n"
          "constraint's id. Constraints are held by Lagrange multipliers (Witkin & Welch Eq. 6-10).")
      .def(
          "apply_point_force",
          [](World& w, int body, const py::object& mass_point, const py::object& u, const Eigen::VectorXd& force) {
            w.ApplyPointForce(PointOf(w, body, mass_point, u), force);
          },
          py::arg("body"), py::arg("mass_point") = py::none(), py::kw_only(), py::arg("u") = py::none(),
          py::arg("force"),
          "A world force (2 or 3 components, the body's dimension) at a material point during the next\n"
          "step only (Jᵀ f for FFD bodies of either dimension, f pᵀ for linear ones).")
      .def(
          "add_attachment",
          [](World& w, int a, int b, const py::object& a_mass_point, const py::object& a_u, const py::object& b_mass_point,
             const py::object& b_u) { return w.AddAttachment(PointOf(w, a, a_mass_point, a_u), PointOf(w, b, b_mass_point, b_u)); },
          py::arg("a"), py::arg("b"), py::kw_only(), py::arg("a_mass_point") = py::none(), py::arg("a_u") = py::none(),
          py::arg("b_mass_point") = py::none(), py::arg("b_u") = py::none(),
          "Joins a point of body a to a point of body b; returns the constraint's id.")
      .def(
          "point_position",
          [](const World& w, int body, const py::object& mass_point, const py::object& u) {
            return w.PointPosition(PointOf(w, body, mass_point, u));
          },
          py::arg("body"), py::arg("mass_point") = py::none(), py::kw_only(), py::arg("u") = py::none(),
          "World position of a material point of any body")
      .def(
          "add_linear_body",
          [](World& w, std::shared_ptr<LinearBodyModel> model, double rigidity, double volume, double damping,
             double bending, bool ground) {
            for (double v : {rigidity, volume, damping, bending})
              if (!(v >= 0) || !std::isfinite(v)) throw InputError("material constants must be finite and >= 0");
            const int b = w.AddLinearBody(model, AffineMaterial{rigidity, volume, damping, bending});
            w.SetGroundContact(b, ground);
            return b;
          },
          py::arg("model"), py::kw_only(), py::arg("rigidity") = 0.0, py::arg("volume") = 0.0, py::arg("damping") = 0.0,
          py::arg("bending") = 0.0, py::arg("ground") = false,
          "Adds a Witkin & Welch body at its rest state, at rest, with the affine energies k_e, k_c, k_d,\n"
          "k_q (rigidity, volume, damping, bending); returns its index. ground=True: its mass points touch\n"
          "the ground (the 2D ground or terrain; in 3D the ground plane), as an FFD body's do.")
      .def(
          "linear_contacts",
          [](const World& w, int body) {
            CheckLinear(w, body);
            const LinearContacts& c = w.linear_contacts(body);
            py::list out;
            for (const Contact<2, double>& k : c.list<2>()) out.append(py::make_tuple(k.point, k.face, Eigen::VectorXd(k.anchor)));
            for (const Contact<3, double>& k : c.list<3>()) out.append(py::make_tuple(k.point, k.face, Eigen::VectorXd(k.anchor)));
            return out;
          },
          py::arg("body"), "A linear body's ground contacts: (mass point, face, anchor) each")
      .def(
          "linear_state",
          [](const World& w, int body) {
            CheckLinear(w, body);
            return py::make_tuple(Eigen::MatrixXd(w.linear_R(body)), Eigen::MatrixXd(w.linear_R_dot(body)));
          },
          py::arg("body"), "(R, Ṙ) of a linear body, each d x n: x = R p(u)")
      .def(
          "set_linear_state",
          [](World& w, int body, const Eigen::MatrixXd& R, const py::object& R_dot) {
            CheckLinear(w, body);
            const Eigen::MatrixXd& now = w.linear_R(body);
            if (R.rows() != now.rows() || R.cols() != now.cols())
              throw InputError("R: expected shape (" + std::to_string(now.rows()) + ", " + std::to_string(now.cols()) + ")");
            Eigen::MatrixXd Rd = R_dot.is_none() ? Eigen::MatrixXd::Zero(R.rows(), R.cols()) : R_dot.cast<Eigen::MatrixXd>();
            if (Rd.rows() != R.rows() || Rd.cols() != R.cols()) throw InputError("R_dot: expected the shape of R");
            w.SetLinearState(body, R, Rd);
          },
          py::arg("body"), py::arg("R"), py::arg("R_dot") = py::none(), "Sets R and Ṙ (zero when not given).")
      .def("kind", [](const World& w, int body) { CheckIndex(w, body); return w.kind(body) == BodyKind::kFfd ? "ffd" : "linear"; },
           py::arg("body"), "'ffd' or 'linear'")
      .def("add_controller", &World::AddController, py::arg("controller"), py::keep_alive<1, 2>(),
           "Calls the controller around every step from now on.")
      .def(
          "remove_controller", [](World& w, const std::shared_ptr<Controller>& c) { w.RemoveController(c.get()); },
          py::arg("controller"))
      .def("set_enabled", &World::SetEnabled, py::arg("id"), py::arg("enabled"))
      .def("max_violation", &World::MaxViolation, "the largest |c| of the enabled constraints")
      .def("constraint_error", &World::ConstraintError, py::arg("id"));

  // release 0.1's 3D names: the methods take either body now
  const py::object world = m.attr("World");
  for (const auto& [old_name, name] : {std::pair{"add_body3", "add_body"}, {"body3", "body"}, {"q3", "q"},
                                       {"qd3", "qd"}, {"set_state3", "set_state"}})
    BindDeprecated(world, old_name, name);
}

}  // namespace wobble::python
