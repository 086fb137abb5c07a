// Goal-directed behaviours from Python (Witkin & Welch §4.2, control/behaviours.h): anchors,
// and a Behaviours controller that chains chase, connect, grab, release, switch, wait,
// impulse, keyframed follow and wait_for (a Python predicate) in a world built from Python,
// as a script's scene does.
#include "support.h"

#include <pybind11/functional.h>

#include "wobble/control/behaviours.h"

namespace wobble::python {
namespace {

using control::Anchor;
using control::BehaviourController;

// A Python object held by C++ code that may drop it on a thread without the GIL (a behaviour
// finishes inside a step): it takes the GIL to let go.
std::shared_ptr<py::object> Held(py::object o) {
  return std::shared_ptr<py::object>(new py::object(std::move(o)), [](py::object* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
}

std::optional<Eigen::VectorXd> OptionalVelocity(const py::object& v) {
  if (v.is_none()) return std::nullopt;
  Eigen::VectorXd out = v.cast<Eigen::VectorXd>();
  if (!out.allFinite()) throw InputError("final_velocity must be finite");
  return out;
}

void CheckDuration(double d, const std::string& what) {
  if (!(d > 0) || !std::isfinite(d)) throw InputError(what + " must be a finite number > 0");
}

}  // namespace

void BindBehaviours(py::module_& m) {
  auto& error = py::register_exception<control::BehaviourError>(m, "BehaviourError", PyExc_RuntimeError);
  error.doc() = "A behaviour that cannot act (an unknown constraint name, conflicting impulse goals).";
  py::class_<Anchor>(m, "Anchor",
                     "Where a behaviour looks: a material point of a body, or a fixed place in the world.")
      .def_static(
          "point",
          [](const World& w, int body, const py::object& mass_point, const py::object& u, const std::string& name) {
            const MaterialPoint p = PointOf(w, body, mass_point, u);
            w.PointPosition(p);  // checks the point now (InputError), not at the behaviour's step
            return control::PointAnchor(name.empty() ? "body" + std::to_string(body) : name, p);
          },
          py::arg("world"), py::arg("body"), py::arg("mass_point") = py::none(), py::kw_only(), py::arg("u") = py::none(),
          py::arg("name") = "", "A material point (mass_point k, or u) of a body of `world`.")
      .def_static(
          "place",
          [](const Eigen::VectorXd& place, const std::string& name) {
            if (!place.allFinite()) throw InputError("place must be finite");
            return control::PlaceAnchor(name.empty() ? "place" : name, place);
          },
          py::arg("place"), py::kw_only(), py::arg("name") = "", "A fixed place (a sky point: zero velocity).")
      .def_readonly("name", &Anchor::name, "the name behaviours and their log use")
      .def("position", &Anchor::Position, py::arg("world"), "where it is now in `world`")
      .def("velocity", &Anchor::Velocity, py::arg("world"), "its velocity now (zero for a place)");

  py::class_<BehaviourController, Controller, std::shared_ptr<BehaviourController>>(
      m, "Behaviours",
      "A queue of goal behaviours (§4.2) run one after another before every step; add it with\n"
      "World.add_controller. Instant behaviours (connect, release, switch, impulse) chained after a\n"
      "chase act at its contact time. A behaviour that cannot act stops the step with BehaviourError.")
      .def(py::init<>())
      .def(
          "chase",
          [](BehaviourController& b, const Anchor& chaser, const Anchor& target, double duration,
             const py::object& final_velocity) {
            CheckDuration(duration, "duration");
            b.sequencer().Add(std::make_unique<control::Chase>(chaser, target, duration, OptionalVelocity(final_velocity)));
          },
          py::arg("chaser"), py::arg("target"), py::arg("duration"), py::kw_only(), py::arg("final_velocity") = py::none(),
          "Leads `chaser` to the target's predicted place in `duration` along a cubic re-planned every step.")
      .def(
          "connect",
          [](BehaviourController& b, const Anchor& point, const Anchor& target, const std::string& name) {
            b.sequencer().Add(std::make_unique<control::Connect>(point, target, name));
          },
          py::arg("point"), py::arg("target"), py::kw_only(), py::arg("name") = "",
          "A velocity-matching impulse, then an attachment (a nail for a place), named `name`.")
      .def(
          "grab",
          [](BehaviourController& b, const Anchor& point, const Anchor& target, double duration,
             const py::object& final_velocity, const std::string& name) {
            CheckDuration(duration, "duration");
            b.sequencer().AddGrab(point, target, duration, OptionalVelocity(final_velocity), name);
          },
          py::arg("point"), py::arg("target"), py::arg("duration"), py::kw_only(), py::arg("final_velocity") = py::none(),
          py::arg("name") = "", "chase, then connect")
      .def(
          "release",
          [](BehaviourController& b, const std::string& name) { b.sequencer().Add(std::make_unique<control::Release>(name)); },
          py::arg("name"), "Removes the named constraint (a connect's, a follow's).")
      .def(
          "switch",
          [](BehaviourController& b, const std::string& name, bool on) {
            b.sequencer().Add(std::make_unique<control::Switch>(name, on));
          },
          py::arg("name"), py::arg("on"), "Turns the named constraint on or off.")
      .def(
          "wait",
          [](BehaviourController& b, double duration) {
            CheckDuration(duration, "duration");
            b.sequencer().Add(std::make_unique<control::Wait>(duration));
          },
          py::arg("duration"))
      .def(
          "impulse",
          [](BehaviourController& b, const Anchor& point, const Eigen::VectorXd& velocity) {
            if (!velocity.allFinite()) throw InputError("velocity must be finite");
            b.sequencer().Add(std::make_unique<control::Impulse>(point, velocity));
          },
          py::arg("point"), py::arg("velocity"), "The point moves with `velocity` afterwards (zero: stop dead).")
      .def(
          "follow",
          [](BehaviourController& b, const Anchor& point, const std::vector<double>& times,
             const std::vector<Eigen::VectorXd>& positions, double onset, double preroll, const std::string& name) {
            const std::string error = control::KeyframeSpline::Validate(times, positions, {});
            if (!error.empty()) throw InputError("follow: " + error);
            if (!(preroll >= 0) || !std::isfinite(preroll) || !std::isfinite(onset))
              throw InputError("follow: onset must be finite and preroll >= 0");
            auto path = std::make_shared<control::KeyframeSpline>(times, positions);
            b.sequencer().Add(std::make_unique<control::Follow>(point, path, onset, preroll, name.empty() ? "follow" : name));
          },
          py::arg("point"), py::arg("times"), py::arg("positions"), py::kw_only(), py::arg("onset") = 0.0,
          py::arg("preroll") = 0.0, py::arg("name") = "",
          "Keyframed control (§4.1): from `onset` the point follows the spline through (times, positions)\n"
          "under a trajectory constraint named `name`; preroll > 0 joins its state to the path first.")
      .def(
          "wait_for",
          [](BehaviourController& b, const std::string& description, const py::function& predicate) {
            const std::shared_ptr<py::object> f = Held(predicate);
            b.sequencer().Add(std::make_unique<control::WaitFor>(description, [f](const World& w) {
              py::gil_scoped_acquire gil;  // steps run without the GIL
              return (*f)(py::cast(&w, py::return_value_policy::reference)).cast<bool>();
            }));
          },
          py::arg("description"), py::arg("predicate"),
          "Blocks until predicate(world) is true (checked before every step, with the GIL).")
      .def_property_readonly("idle", [](BehaviourController& b) { return b.sequencer().idle(); })
      .def_property_readonly("pending", [](BehaviourController& b) { return b.sequencer().pending(); })
      .def_property_readonly(
          "current",
          [](BehaviourController& b) -> py::object {
            const control::Behaviour* c = b.sequencer().current();
            return c ? py::cast(c->Describe()) : py::none();
          },
          "the running behaviour's description, or None")
      .def_property_readonly("names", &BehaviourController::names, "constraint ids by name, of the constraints made")
      .def_property_readonly("log", &BehaviourController::log, "'t = ..: <behaviour>' as each started");
}

}  // namespace wobble::python
