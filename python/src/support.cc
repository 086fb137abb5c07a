// libwobble's errors (core/errors.h, formats/parse_error.h) as Python exceptions with the same
// messages: bad input is a ValueError (InputError; ParseError and LimitExceeded are kinds of
// it), numerical trouble a RuntimeError (NumericalStop; SimulationStopped carries the world's
// status), Ctrl-C a KeyboardInterrupt.
#include "support.h"

#include "wobble/core/interrupt.h"

#include <thread>

#include "wobble/core/errors.h"
#include "wobble/formats/parse_error.h"
#include "wobble/script/interpreter.h"

namespace wobble::python {

void CheckIndex(const World& w, int body) {
  if (body < 0 || body >= w.num_bodies())
    throw InputError("body " + std::to_string(body) + ": the world has " + std::to_string(w.num_bodies()) + " bodies");
}

MaterialPoint PointOf(const World& w, int body, const py::object& mass_point, const py::object& u) {
  CheckIndex(w, body);
  if (mass_point.is_none() == u.is_none()) throw InputError("give exactly one of mass_point or u");
  if (!mass_point.is_none()) {
    const int k = mass_point.cast<int>();
    if (k < 0) throw InputError("mass_point must be at least 0");
    return MassPointOf(body, k);
  }
  return At(body, u.cast<Eigen::VectorXd>());
}

namespace {

// wobble.SimulationStopped and wobble.InputError; the module holds them, so borrowed handles
// (never freed at exit)
py::handle stopped_type, input_type;

// The thread the module was imported on: Python's main thread, the one signals reach.
std::thread::id main_thread;

}  // namespace

bool CtrlCPressed() {
  if (InterruptRequested()) return true;  // seen by another thread already
  if (std::this_thread::get_id() != main_thread) return false;
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  PyErr_Clear();
  RequestInterrupt();  // every worker of the call sees it
  return true;
}

void RunWorld(World& w, double t_end, long steps) {
  constexpr long kPollEvery = 2000;  // steps between looks at Ctrl-C (a few ms)
  bool ok = true;
  ClearInterrupt();
  {
    py::gil_scoped_release release;
    for (long n = 0; ok && (steps < 0 || n < steps) && w.time() + 0.5 * w.options().dt < t_end; ++n) {
      if (n % kPollEvery == kPollEvery - 1 && CtrlCPressed()) {
        ClearInterrupt();
        w.ThrowInterrupted();
      }
      ok = w.Step();
    }
  }
  if (!ok) RaiseStopped(w.status());
}

void RaiseStopped(const WorldStatus& status) {
  py::object exc = stopped_type(status.message);
  exc.attr("cause") = StatusCodeName(status.code);
  exc.attr("step") = status.step;
  exc.attr("time") = status.time;
  exc.attr("body") = status.body;
  PyErr_SetObject(stopped_type.ptr(), exc.ptr());
  throw py::error_already_set();
}

void BindErrors(py::module_& m) {
  main_thread = std::this_thread::get_id();
  // Registered first, so tried last: any other std::invalid_argument of the library (a pose
  // graph that does not fit, a bad keyframe, ...) is bad input too, as for the CLI (exit 2).
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(input_type.ptr(), e.what());
    }
  });
  // pybind11 tries the translators last registered first: bases before what derives from them
  auto& input = py::register_exception<InputError>(m, "InputError", PyExc_ValueError);
  input_type = input;
  input.doc() = "Bad input: a file, a value or a shape that is not what was expected (the message says which).";
  auto& parse = py::register_exception<formats::ParseError>(m, "ParseError", input.ptr());
  parse.doc() = "A file or script line that does not parse: the message starts with FILE:LINE.";
  auto& limit = py::register_exception<LimitExceeded>(m, "LimitExceeded", input.ptr());
  limit.doc() = "A run or record larger than the limits allow (max_steps, max_record_mb).";
  auto& numerical = py::register_exception<NumericalStop>(m, "NumericalStop", PyExc_RuntimeError);
  numerical.doc() = "A computation stopped on numerical trouble instead of returning NaN or inf.";
  auto& stopped = py::register_exception<script::SimulationStopped>(m, "SimulationStopped", numerical.ptr());
  stopped.doc() =
      "A simulation stopped (non-finite state, runaway penetration, singular mass, ...). When raised\n"
      "by World.step or simulate it has .cause (the status code's name), .step, .time and .body.";
  stopped_type = stopped;
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted& e) {
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    }
  });
}

void BindDeprecated(py::object scope, const char* old_name, const char* name,
                    std::function<py::object(py::object)> then) {
  const bool method = py::isinstance<py::type>(scope);
  const std::string owner = method ? scope.attr("__name__").cast<std::string>() : "wobble";
  const std::string message =
      owner + "." + old_name + " is deprecated: use " + owner + "." + name + ", which takes a 2D or a 3D body";
  const std::string doc = "Deprecated (one release): " + message + ".";
  const std::string target = name;
  auto call = [message, target, then](py::object on, py::args args, py::kwargs kwargs) -> py::object {
    if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) < 0) throw py::error_already_set();
    py::object result = on.attr(target.c_str())(*args, **kwargs);
    return then ? then(std::move(result)) : result;
  };
  if (method) {
    scope.attr(old_name) = py::cpp_function(
        [call](py::object self, py::args args, py::kwargs kwargs) { return call(self, args, kwargs); },
        py::name(old_name), py::is_method(scope), py::sibling(py::getattr(scope, old_name, py::none())),
        py::doc(doc.c_str()));
  } else {
    py::reinterpret_borrow<py::module_>(scope).def(
        old_name, [call, scope](py::args args, py::kwargs kwargs) { return call(scope, args, kwargs); }, doc.c_str());
  }
}

}  // namespace wobble::python
