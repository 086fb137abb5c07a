// The pieces of the Python module `wobble` (module.cc puts them together), one per area of
// libwobble. Shared helpers for numpy conversion live here too.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <string>

#include "wobble/analysis/conditioning.h"
#include "wobble/body/body_model.h"
#include "wobble/core/errors.h"

namespace wobble::python {

namespace py = pybind11;

void BindErrors(py::module_& m);   // exceptions (errors.cc)
void BindBodies(py::module_& m);   // BodyModel (2D and 3D), modes, loading (bodies.cc)
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

// What Python's one class wobble.BodyModel holds: an FFD body of either dimension (exactly one of
// b2, b3 is set; Python never changes a body). The bindings keep taking and returning
// std::shared_ptr<BodyModelN<Dim>> (or <const ...>): the casters at the end of this file load
// one from a wobble.BodyModel of that dimension (and refuse the other, so overloads on the
// dimension dispatch) and wrap one into a wobble.BodyModel.
struct PyBody {
  std::shared_ptr<const BodyModelN<2>> b2;
  std::shared_ptr<const BodyModelN<3>> b3;

  int dim() const { return b3 ? 3 : 2; }
  template <int Dim> const std::shared_ptr<const BodyModelN<Dim>>& get() const {
    if constexpr (Dim == 2) return b2;
    else return b3;
  }
  // The body of dimension Dim, or InputError: "<what> needs a <Dim>D body; this BodyModel is <d>D".
  template <int Dim> const BodyModelN<Dim>& Need(const char* what) const {
    if (!get<Dim>())
      throw InputError(std::string(what) + " needs a " + std::to_string(Dim) + "D body; this BodyModel '" + name() +
                       "' is " + std::to_string(dim()) + "D");
    return *get<Dim>();
  }
  const std::string& name() const { return b3 ? b3->name() : b2->name(); }
};

// A wobble.BodyModel for `body` (None for null): the same Python object while one for the body
// is alive, as pybind11 gives for a registered class (bodies.cc).
py::object WrapBody(std::shared_ptr<const BodyModelN<2>> body);
py::object WrapBody(std::shared_ptr<const BodyModelN<3>> body);
// The body of dimension Dim in `h`, or null when h is not a wobble.BodyModel of that dimension.
template <int Dim> std::shared_ptr<const BodyModelN<Dim>> UnwrapBody(py::handle h) {
  if (!h || !py::isinstance<PyBody>(h)) return nullptr;
  return h.cast<const PyBody&>().get<Dim>();
}

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

// The casters of FFD bodies (pybind11's custom type casters, docs: advanced/cast/custom): a
// binding takes or returns std::shared_ptr<BodyModelN<Dim>> or std::shared_ptr<const
// BodyModelN<Dim>>, or takes a BodyModelN<Dim> by reference or pointer; Python sees the one class
// wobble.BodyModel. Loading fails (no conversion) for a body of the other dimension.
namespace pybind11::detail {

template <int Dim, class Ptr> struct WobbleBodyPtrCaster {
  PYBIND11_TYPE_CASTER(Ptr, const_name("BodyModel (") + const_name<Dim>() + const_name("D)"));
  bool load(handle src, bool) {
    auto body = wobble::python::UnwrapBody<Dim>(src);
    if (!body) return false;
    value = std::const_pointer_cast<typename Ptr::element_type>(body);
    return true;
  }
  static handle cast(const Ptr& src, return_value_policy, handle) {
    return wobble::python::WrapBody(std::shared_ptr<const wobble::BodyModelN<Dim>>(src)).release();
  }
};

template <int Dim>
class type_caster<std::shared_ptr<wobble::BodyModelN<Dim>>>
    : public WobbleBodyPtrCaster<Dim, std::shared_ptr<wobble::BodyModelN<Dim>>> {};
template <int Dim>
class type_caster<std::shared_ptr<const wobble::BodyModelN<Dim>>>
    : public WobbleBodyPtrCaster<Dim, std::shared_ptr<const wobble::BodyModelN<Dim>>> {};

// By reference or pointer (Python to C++ only: returning one needs its shared owner, so return
// the shared_ptr instead).
template <int Dim> class type_caster<wobble::BodyModelN<Dim>> {
  using Body = wobble::BodyModelN<Dim>;

 public:
  static constexpr auto name = const_name("BodyModel (") + const_name<Dim>() + const_name("D)");
  template <typename T> using cast_op_type = pybind11::detail::cast_op_type<T>;
  bool load(handle src, bool) {
    held_ = wobble::python::UnwrapBody<Dim>(src);
    return bool(held_);
  }
  operator Body*() { return const_cast<Body*>(held_.get()); }
  operator Body&() { return const_cast<Body&>(*held_); }
  template <typename T> static handle cast(T&&, return_value_policy, handle) {
    static_assert(sizeof(T) == 0, "return std::shared_ptr<BodyModelN<Dim>> to Python, not a body by value or reference");
    return {};
  }

 private:
  std::shared_ptr<const Body> held_;
};

}  // namespace pybind11::detail
