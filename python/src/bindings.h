// The pieces of the Python module `wobble` (module.cc puts them together), one per area of
// libwobble. Shared helpers for numpy conversion live here too.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <functional>
#include <string>

#include "wobble/analysis/conditioning.h"
#include "wobble/core/errors.h"

namespace wobble::python {

namespace py = pybind11;

void BindErrors(py::module_& m);   // exceptions (errors.cc)
void BindBodies(py::module_& m);   // BodyModel, BodyModel3 (3D), modes, loading (bodies.cc)
void BindWorld(py::module_& m);    // WorldOptions, Ground, World, Energies (world.cc)
void BindBehaviours(py::module_& m);  // anchors and goal behaviours as a controller (behaviours.cc)
void BindRecord(py::module_& m);   // Trajectory, simulate (record.cc)
void BindRollout(py::module_& m);  // batched rollouts (rollout.cc)
void BindScript(py::module_& m);   // Interpreter, scenes (script.cc)
void BindSynth(py::module_& m);    // pose graphs, trials, annealing (synth.cc)
void BindFit(py::module_& m);      // pose fits (fit.cc)
void BindGradients(py::module_& m);  // rollout gradients, spacetime fits, schedules (gradients.cc)
void BindAnalysis(py::module_& m); // condition numbers, mode-set checks (analysis.cc)
void BindRender(py::module_& m);   // pictures and exports through pipelines/ (render.cc; with VTK)

// A C-contiguous float64 array of `rows` x `cols` (cols < 0: a vector of `rows`), or
// InputError naming `what` and the shape expected.
// A name of release 0.1 kept one release more (python/wobble/__init__.pyi marks it): warns
// DeprecationWarning naming its replacement, then calls scope.name (scope: the module, or a
// class whose method it becomes); `then`, when given, adjusts the result.
void BindDeprecated(py::object scope, const char* old_name, const char* name,
                    std::function<py::object(py::object)> then = nullptr);

py::array_t<double, py::array::c_style> AsMatrix(const py::handle& a, long rows, long cols, const std::string& what);
// An optional keyword vector: `otherwise` for None, else a finite vector of n (InputError naming
// `what` otherwise).
Eigen::VectorXd VectorOr(const py::object& v, long n, const Eigen::VectorXd& otherwise, const std::string& what);
// What `wobble simulate` does with a loaded mode set, for load_body and load_body3: a set that
// cannot be simulated is an InputError naming the object file; warnings become Python's.
template <class Body> void CheckLoadedModeSet(const Body& body, const std::string& object) {
  const analysis::ModeSetReport report = analysis::CheckModeSet(body);
  if (report.level == analysis::ModeSetReport::Level::kError) {
    std::string msg = "the modes of " + object + " cannot be simulated:";
    for (const std::string& line : report.messages) msg += "\n  " + line;
    throw InputError(msg + "\n(wobble condition check explains the mode set)");
  }
  for (const std::string& line : report.messages) PyErr_WarnEx(PyExc_UserWarning, line.c_str(), 1);
}

// The same for a vector of n numbers, copied.
Eigen::VectorXd AsVector(const py::handle& h, long n, const std::string& what);

}  // namespace wobble::python
