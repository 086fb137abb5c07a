// Gradients through whole rollouts and spacetime control fits from Python (fit/adjoint.h,
// fit/spacetime.h, issue 18), for a 2D or a 3D body (the functions dispatch on the body's type),
// and the target schedule files that scripts play (`schedule`).
// A stage cost is one StageCost class for both bodies: a task term of a body serves its
// dimension; upright_at, still_at and a Python fn(n, q, qd) -> (value, dq, dqd) (called with the
// GIL taken for each step) serve both. Every gradient Python gives or gets is with respect to
// the numbers it passes (q in World coordinates, 3D with its rotation vector); the library
// works in the state's tangent coordinates (PyCoordinates converts). The 3D-suffixed names of
// before are deprecated aliases.
#include <cmath>
#include <memory>
#include <string>

#include "support.h"
#include "wobble/core/errors.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/adjoint.h"
#include "wobble/fit/spacetime.h"
#include "wobble/formats/target_schedule.h"

namespace wobble::python {

// A Python callable kept by C++ copies of a stage cost: dropped with the GIL taken, since the
// library drops std::functions on threads that do not hold it.
std::shared_ptr<py::function> HoldWithGil(py::function fn);
// A Python stage cost's result (value, dq, dqd) at step n, each gradient `size` finite numbers or
// None (zero); the value must be finite. InputError otherwise.
double StageResult(const py::object& result, int n, long size, Eigen::VectorXd* dq, Eigen::VectorXd* dqd);
// The rollout's integrator (thesis or symplectic) and targets (modes, steps).
void CheckGradientIntegrator(Integrator integrator);
Eigen::MatrixXd TargetsOf(const py::object& targets, int modes);

namespace {

// A StageCost as Python holds it: one cost for each dimension it serves. A task term of a body
// serves that body's dimension; upright_at, still_at and a Python fn serve both (a 2D and a 3D
// form of the same term); a sum serves the dimensions both terms do.
struct StageCostHandle {
  fit::StageCostN<2> plane;  // empty: not for a 2D body
  fit::StageCostN<3> space;  // empty: not for a 3D body
  template <int Dim> const fit::StageCostN<Dim>& Of() const {
    if constexpr (Dim == 2) {
      if (!plane) throw InputError("this stage cost is a 3D body's; the rollout's body is 2D");
      return plane;
    } else {
      if (!space) throw InputError("this stage cost is a 2D body's; the rollout's body is 3D");
      return space;
    }
  }
};

// How the numbers Python passes and gets (q: World coordinates, q̇) meet a state's tangent
// coordinates z (fit/adjoint.h). 2D: z = (q, q̇), the same numbers. 3D: q = [t, rotation vector
// Θ, γ] with R = exp(Θ̂), q̇ = [ṫ, body ω, γ̇], and z = (δt, ε, δγ, δv) with R exp(ε̂).
//   AddTangentGradient(q, dq, dqd, &dz): dz += ∂ℓ/∂z from ∂ℓ/∂q, ∂ℓ/∂q̇ at q
//   CoordinateGradients(q, dz, &dq, &dqd): ∂ℓ/∂q, ∂ℓ/∂q̇ from ∂ℓ/∂z at q
template <int Dim> struct PyCoordinates;
template <> struct PyCoordinates<2> {
  static void AddTangentGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& dq, const Eigen::VectorXd& dqd,
                                 Eigen::VectorXd* dz) {
    dz->head(q.size()) += dq;
    dz->tail(q.size()) += dqd;
  }
  static void CoordinateGradients(const Eigen::VectorXd& q, const Eigen::VectorXd& dz, Eigen::VectorXd* dq,
                                  Eigen::VectorXd* dqd) {
    *dq = dz.head(q.size());
    *dqd = dz.tail(q.size());
  }
};
template <> struct PyCoordinates<3> {
  static void AddTangentGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& dq, const Eigen::VectorXd& dqd,
                                 Eigen::VectorXd* dz);
  static void CoordinateGradients(const Eigen::VectorXd& q, const Eigen::VectorXd& dz, Eigen::VectorXd* dq,
                                  Eigen::VectorXd* dqd);
};

// The gains: the body's own when None.
template <class Body>
void GainsOf(const Body& body, const py::object& stiffness, const py::object& damping, Eigen::VectorXd* K,
             Eigen::VectorXd* c) {
  const int D = body.num_modes();
  Eigen::VectorXd own_K, own_c;
  body.ModeGains(&own_K, &own_c);
  *K = VectorOr(stiffness, D, own_K, "stiffness");
  *c = VectorOr(damping, D, own_c, "damping");
}

// std::invalid_argument from the library as InputError, prefixed with what was called.
template <class F> auto Checked(const std::string& what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    throw InputError(what + ": " + e.what());
  }
}


// A = ∂Θ/∂ε at Θ: R exp(ε̂) = exp((Θ + A ε)^) to first order, A's columns dexp⁻¹_{−Θ}(e_i)
// (the map RotationVectorRate takes ω through; rotation3.h).
Eigen::Matrix3d RotationVectorPerTangent(const Eigen::Vector3d& theta) {
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) A.col(i) = RotationVectorRate<double>(theta, Eigen::Vector3d::Unit(i));
  return A;
}

// A Python fn(n, q, qd) -> (value, dq, dqd) in World coordinates as a stage cost of dimension
// Dim (the GIL taken for each call).
template <int Dim> fit::StageCostN<Dim> FromPython(std::shared_ptr<py::function> held) {
  return [held](int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz) -> double {
    py::gil_scoped_acquire gil;
    const Eigen::VectorXd q = CoordinatesOf(s);
    Eigen::VectorXd dq, dqd;
    const double value = StageResult((*held)(n, q, Eigen::VectorXd(s.qd)), n, q.size(), &dq, &dqd);
    PyCoordinates<Dim>::AddTangentGradient(q, dq, dqd, dz);
    return value;
  };
}

// The axes a centre-of-mass term measures: 2D 'x', 'y' or 'xy'; 3D some of 'x', 'y', 'z'.
template <int Dim> fit::Axes AxesOf(const std::string& axes) {
  fit::Axes a;
  a.x = axes.find('x') != std::string::npos;
  a.y = axes.find('y') != std::string::npos;
  a.z = axes.find('z') != std::string::npos;
  if constexpr (Dim == 2) {
    if (axes != "x" && axes != "y" && axes != "xy")
      throw InputError("axes: expected 'x', 'y' or 'xy', got '" + axes + "'");
  } else {
    if (axes.empty() || axes.find_first_not_of("xyz") != std::string::npos)
      throw InputError("axes: expected some of 'x', 'y', 'z' (such as 'xz'), got '" + axes + "'");
  }
  return a;
}

// (value, dq, dqd) of a cost of dimension Dim at (q, q̇) in World coordinates.
template <int Dim>
py::tuple CallAt(const fit::StageCostN<Dim>& cost, int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  constexpr int kRigid = Group<Dim>::kRigidDofs;
  if (q.size() != qd.size() || q.size() < kRigid)
    throw InputError("q and qd must have the same size, at least " + std::to_string(kRigid));
  Eigen::VectorXd dz = Eigen::VectorXd::Zero(2 * q.size()), dq, dqd;
  const double value = cost(n, StateFromCoordinates<Dim>(q, qd), &dz);
  PyCoordinates<Dim>::CoordinateGradients(q, dz, &dq, &dqd);
  return py::make_tuple(value, dq, dqd);
}

// A handle of a cost of one dimension.
StageCostHandle HandleOf(fit::StageCostN<2> c) { return StageCostHandle{std::move(c), {}}; }
StageCostHandle HandleOf(fit::StageCostN<3> c) { return StageCostHandle{{}, std::move(c)}; }

template <int Dim> void BindBodyTerms(py::module_& m) {
  using Body = BodyModelN<Dim>;
  using Vec = Eigen::Matrix<double, Dim, 1>;
  const char* all = Dim == 2 ? "xy" : "xyz";
  m.def(
      "centre_of_mass_at",
      [](std::shared_ptr<Body> body, int step, const Vec& goal, double weight, const std::string& axes) {
        return Checked("centre_of_mass_at",
                       [&] { return HandleOf(fit::CentreOfMassAt(*body, step, goal, weight, AxesOf<Dim>(axes))); });
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = all,
      "w/2 |centre of mass at step n - goal|^2 on the axes asked for (2D 'x', 'y', 'xy'; 3D 'xyz', 'xz',\n"
      "'y', ...): be there then. A term of the body's dimension.");
  m.def(
      "centre_of_mass_velocity_at",
      [](std::shared_ptr<Body> body, int step, const Vec& goal, double weight, const std::string& axes) {
        return Checked("centre_of_mass_velocity_at", [&] {
          return HandleOf(fit::CentreOfMassVelocityAt(*body, step, goal, weight, AxesOf<Dim>(axes)));
        });
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = all,
      "w/2 |centre-of-mass velocity at step n - goal|^2 (goal 0 on 'y': the top of a hop)");
}


void PyCoordinates<3>::AddTangentGradient(const Eigen::VectorXd& q, const Eigen::VectorXd& dq,
                                          const Eigen::VectorXd& dqd, Eigen::VectorXd* dz) {
  const int nq = int(dq.size());
  const Eigen::Vector3d theta = q.segment<3>(3);
  dz->head<3>() += dq.head<3>();
  dz->segment<3>(3) += RotationVectorPerTangent(theta).transpose() * dq.segment<3>(3);
  dz->segment(6, nq - 6) += dq.tail(nq - 6);
  dz->tail(nq) += dqd;
}

void PyCoordinates<3>::CoordinateGradients(const Eigen::VectorXd& q, const Eigen::VectorXd& dz, Eigen::VectorXd* dq,
                                           Eigen::VectorXd* dqd) {
  const int nq = int(dz.size()) / 2;
  const Eigen::Vector3d theta = q.segment<3>(3);
  *dq = dz.head(nq);
  dq->segment<3>(3) = RotationVectorPerTangent(theta).transpose().lu().solve(Eigen::Vector3d(dz.segment<3>(3)));
  *dqd = dz.tail(nq);
}

void BindStageCosts(py::module_& m) {
  py::class_<StageCostHandle>(
      m, "StageCost",
      "A cost l_n(q, qd) of one step of a rollout with its gradient, for a 2D or a 3D body: a task term\n"
      "(centre_of_mass_at, upright_at, ...), a sum (a + b), or StageCost(fn) with a Python\n"
      "fn(n, q, qd) -> (value, dq, dqd) in World coordinates (3D: q = [t, rotation vector, gamma],\n"
      "qd = [t dot, body omega, gamma dot]; dq, dqd: num_q arrays or None).")
      .def(py::init([](py::function fn) {
             std::shared_ptr<py::function> held = HoldWithGil(std::move(fn));
             return StageCostHandle{FromPython<2>(held), FromPython<3>(held)};
           }),
           py::arg("fn"))
      .def(
          "__call__",
          [](const StageCostHandle& c, int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, int dim) {
            if (dim != 0 && dim != 2 && dim != 3) throw InputError("dim: expected 2, 3 or 0 (the cost's own)");
            if (dim == 0) dim = c.plane ? 2 : 3;
            return dim == 2 ? CallAt<2>(c.Of<2>(), n, q, qd) : CallAt<3>(c.Of<3>(), n, q, qd);
          },
          py::arg("n"), py::arg("q"), py::arg("qd"), py::kw_only(), py::arg("dim") = 0,
          "(value, dq, dqd) at step n in World coordinates; dim: which body's form (0: the cost's own,\n"
          "2D when it serves both)")
      .def("__add__", [](const StageCostHandle& a, const StageCostHandle& b) {
        StageCostHandle sum;
        if (a.plane && b.plane) sum.plane = fit::SumOf({a.plane, b.plane});
        if (a.space && b.space) sum.space = fit::SumOf({a.space, b.space});
        if (!sum.plane && !sum.space) throw InputError("a 2D body's stage cost and a 3D body's cannot be summed");
        return sum;
      });

  BindBodyTerms<2>(m);
  BindBodyTerms<3>(m);
  m.def(
      "upright_at",
      [](int step, double weight, double time_scale) {
        return Checked("upright_at", [&] {
          return StageCostHandle{fit::UprightAt<2>(step, weight, time_scale), fit::UprightAt<3>(step, weight, time_scale)};
        });
      },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, py::arg("time_scale") = 0.0,
      "At step n: upright and not spinning. 2D w/2 (theta^2 + tau^2 thetadot^2); 3D\n"
      "w/2 (|R e_y - e_y|^2 + tau^2 |omega|^2), the body's up axis up and not turning (any heading).");
  m.def(
      "still_at",
      [](int step, double weight) {
        return Checked("still_at",
                       [&] { return StageCostHandle{fit::StillAt<2>(step, weight), fit::StillAt<3>(step, weight)}; });
      },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, "w/2 |qd|^2 at step n: at rest");
}



// A rollout from the keyword arguments: the options' world, integrator and dt; the start q0, qd0
// in World coordinates (at rest at the lattice's pose by default); the gains (the body's own by
// default); the targets (modes, steps).
template <int Dim>
fit::ControlledRolloutN<Dim> RolloutOf(const BodyModelN<Dim>& body, const WorldOptions& options,
                                       const py::object& targets, const py::object& q0, const py::object& qd0,
                                       const py::object& stiffness, const py::object& damping) {
  const int nq = body.num_q();
  fit::ControlledRolloutN<Dim> r;
  r.world = options.params;
  r.integrator = options.integrator;
  CheckGradientIntegrator(r.integrator);
  r.dt = options.dt;
  r.start = StateFromCoordinates<Dim>(VectorOr(q0, nq, Eigen::VectorXd::Zero(nq), "q0"),
                                      VectorOr(qd0, nq, Eigen::VectorXd::Zero(nq), "qd0"));
  GainsOf(body, stiffness, damping, &r.stiffness, &r.damping);
  r.targets = TargetsOf(targets, body.num_modes());
  return r;
}

// A rollout's gradient as Python sees it: with respect to q0 and qd0 in World coordinates, not
// the start's tangent coordinates (the same numbers in 2D).
struct RolloutGradientPy {
  fit::RolloutGradient g;
  Eigen::VectorXd q0, qd0;
};

// fit_spacetime's bounds (every target within ±bound), control weight and options.
template <class Problem> void SetSpacetimeBounds(int modes, double bound, double control_weight, Problem* p) {
  if (!(bound > 0) || !std::isfinite(bound)) throw InputError("bound must be a finite number > 0");
  if (!(control_weight >= 0) || !std::isfinite(control_weight)) throw InputError("control_weight must be >= 0");
  p->lower = Eigen::VectorXd::Constant(modes, -bound);
  p->upper = Eigen::VectorXd::Constant(modes, bound);
  p->control_weight = control_weight;
}
fit::SpacetimeOptions SpacetimeOptionsOf(int max_iterations, int starts, double start_spread, unsigned seed,
                                         int threads) {
  fit::SpacetimeOptions o;
  o.max_iterations = max_iterations;
  o.starts = starts;
  o.start_spread = start_spread;
  o.seed = seed;
  o.threads = threads;
  return o;
}

template <int Dim> void BindRollouts(py::module_& m) {
  using Body = BodyModelN<Dim>;
  m.def(
      "rollout_gradient",
      [](std::shared_ptr<Body> body, const StageCostHandle& cost, const py::object& targets, const WorldOptions& options,
         const py::object& q0, const py::object& qd0, const py::object& stiffness, const py::object& damping,
         int checkpoint_interval) {
        const fit::ControlledRolloutN<Dim> r = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        const fit::StageCostN<Dim>& c = cost.Of<Dim>();
        RolloutGradientPy out;
        {
          py::gil_scoped_release release;  // a Python stage cost takes it back for its own calls
          out.g = Checked("rollout_gradient", [&] { return fit::RolloutCostGradient(*body, r, c, checkpoint_interval); });
        }
        if (out.g.start.size() > 0)
          PyCoordinates<Dim>::CoordinateGradients(CoordinatesOf(r.start), out.g.start, &out.q0, &out.qd0);
        return out;
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), py::arg("checkpoint_interval") = 0,
      "The cost sum_n l_n(q_n, qd_n) of a rollout of the body, 2D or 3D (PD targets (modes, steps), one\n"
      "per step; gains K, c per mode; the options' world (gravity, the ground of the body's\n"
      "dimension: 3D ground_plane; springs), dt and integrator: thesis or symplectic) and its gradient with respect to\n"
      "q0, qd0 (World coordinates; 3D q0 = [t, rotation vector, gamma]), K, c and every target, by one\n"
      "adjoint sweep: its cost does not grow with the number of parameters (README: Gradients).\n"
      "checkpoint_interval: 0 keeps the whole run when it fits in 4 MiB, else checkpoints every\n"
      "ceil(sqrt(steps)) steps; -1 always does; N > 0 every N steps.");
  m.def(
      "rollout_cost",
      [](std::shared_ptr<Body> body, const StageCostHandle& cost, const py::object& targets, const WorldOptions& options,
         const py::object& q0, const py::object& qd0, const py::object& stiffness, const py::object& damping) {
        const fit::ControlledRolloutN<Dim> r = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        const fit::StageCostN<Dim>& c = cost.Of<Dim>();
        py::gil_scoped_release release;
        return Checked("rollout_cost", [&] { return fit::RolloutCost(*body, r, c); });
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), "The same rollout's cost alone (one plain simulation; inf when a step fails).");
  m.def(
      "fit_spacetime",
      [](std::shared_ptr<Body> body, const StageCostHandle& task, const py::object& targets, int knots, double bound,
         double control_weight, const WorldOptions& options, const py::object& q0, const py::object& qd0,
         const py::object& stiffness, const py::object& damping, int max_iterations, int starts, double start_spread,
         unsigned seed, int threads) {
        fit::SpacetimeProblemN<Dim> p;
        p.rollout = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        p.knots = knots;
        SetSpacetimeBounds(body->num_modes(), bound, control_weight, &p);
        p.task = task.Of<Dim>();
        const fit::SpacetimeOptions o = SpacetimeOptionsOf(max_iterations, starts, start_spread, seed, threads);
        return Checked("fit_spacetime", [&] { return WithCtrlC([&] { return fit::FitSpacetime(*body, p, o); }); });
      },
      py::arg("body"), py::arg("task"), py::kw_only(), py::arg("targets"), py::arg("knots") = 21, py::arg("bound") = 0.3,
      py::arg("control_weight") = 1.0, py::arg("options") = WorldOptions(), py::arg("q0") = py::none(),
      py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(), py::arg("damping") = py::none(),
      py::arg("max_iterations") = 100, py::arg("starts") = 1, py::arg("start_spread") = 1.0, py::arg("seed") = 1u,
      py::arg("threads") = 0,
      "Spacetime control (thesis 3.1 after Witkin & Kass) of a 2D or 3D body: every mode's PD targets over\n"
      "the whole run, at `knots` evenly spaced knots within +-bound, minimising control_weight * sum\n"
      "|target|^2 dt plus the task, by L-BFGS on the adjoint gradient; the options' world of the body's\n"
      "dimension. targets (modes, steps): the first guess and the run's length. starts > 1: multi-start,\n"
      "the further starts perturbed by a seeded Gaussian of start_spread on each knot's logistic\n"
      "coordinate, run on `threads` (0: every core), the lowest cost wins (best_start, start_costs). Like\n"
      "`wobble fit spacetime`; write_target_schedule(result.targets) for a script's schedule.");
}

}  // namespace

std::shared_ptr<py::function> HoldWithGil(py::function fn) {
  return std::shared_ptr<py::function>(new py::function(std::move(fn)), [](py::function* f) {
    py::gil_scoped_acquire gil;
    delete f;
  });
}

double StageResult(const py::object& r, int n, long size, Eigen::VectorXd* dq, Eigen::VectorXd* dqd) {
  if (!py::isinstance<py::tuple>(r) || py::len(r) != 3)
    throw InputError("a stage cost must return (value, dq, dqd), got " + std::string(py::str(r)));
  const py::tuple t = r.cast<py::tuple>();
  const double value = t[0].cast<double>();
  if (!std::isfinite(value)) throw InputError("a stage cost returned " + std::to_string(value) + " at step " + std::to_string(n));
  const char* names[2] = {"dq", "dqd"};
  Eigen::VectorXd* out[2] = {dq, dqd};
  for (int i = 0; i < 2; ++i) {
    *out[i] = Eigen::VectorXd::Zero(size);
    if (t[i + 1].is_none()) continue;
    *out[i] = t[i + 1].cast<Eigen::VectorXd>();
    if (out[i]->size() != size || !out[i]->allFinite())
      throw InputError(std::string("a stage cost's ") + names[i] + " must be " + std::to_string(size) +
                       " finite numbers (num_q)");
  }
  return value;
}

void CheckGradientIntegrator(Integrator integrator) {
  if (integrator != Integrator::kThesis && integrator != Integrator::kSymplecticEuler)
    throw InputError("gradients need the thesis or the symplectic integrator (options.integrator), got " +
                     IntegratorName(integrator));
}

Eigen::MatrixXd TargetsOf(const py::object& targets, int modes) {
  auto probe = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(targets);
  if (!probe || probe.ndim() != 2 || probe.shape(0) != modes || probe.shape(1) < 1)
    throw InputError("targets: expected (modes, steps) = (" + std::to_string(modes) + ", steps >= 1)");
  Eigen::MatrixXd t = probe.cast<Eigen::MatrixXd>();
  if (!t.allFinite()) throw InputError("targets must be finite");
  return t;
}

void BindGradients(py::module_& m) {
  BindStageCosts(m);
  py::class_<RolloutGradientPy>(m, "RolloutGradient",
                                "A rollout's cost and its gradient with respect to every parameter (q0, qd0 in World\n"
                                "coordinates, as the rollout was given them).")
      .def_property_readonly("ok", [](const RolloutGradientPy& r) { return r.g.ok; })
      .def_property_readonly("message", [](const RolloutGradientPy& r) { return r.g.message; })
      .def_property_readonly("cost", [](const RolloutGradientPy& r) { return r.g.cost; })
      .def_readonly("q0", &RolloutGradientPy::q0, "d cost / d q0 (3D q0 = [t, rotation vector, gamma])")
      .def_readonly("qd0", &RolloutGradientPy::qd0, "d cost / d qd0 (3D qd0 = [t dot, body omega, gamma dot])")
      .def_property_readonly("stiffness", [](const RolloutGradientPy& r) { return r.g.stiffness; })
      .def_property_readonly("damping", [](const RolloutGradientPy& r) { return r.g.damping; })
      .def_property_readonly("targets", [](const RolloutGradientPy& r) { return r.g.targets; },
                             "(modes, steps): d cost / d target of each step")
      .def_property_readonly("states_held", [](const RolloutGradientPy& r) { return r.g.states_held; },
                             "the most states held at once (checkpoints)");

  py::class_<fit::SpacetimeResult>(m, "SpacetimeResult", "A spacetime fit's targets and costs.")
      .def_readonly("ok", &fit::SpacetimeResult::ok)
      .def_readonly("message", &fit::SpacetimeResult::message)
      .def_readonly("knots", &fit::SpacetimeResult::knots, "(modes, knots)")
      .def_readonly("targets", &fit::SpacetimeResult::targets, "(modes, steps): what a script's schedule plays")
      .def_readonly("initial_cost", &fit::SpacetimeResult::initial_cost)
      .def_readonly("cost", &fit::SpacetimeResult::cost)
      .def_readonly("control_energy", &fit::SpacetimeResult::control_energy)
      .def_readonly("iterations", &fit::SpacetimeResult::iterations)
      .def_readonly("gradients", &fit::SpacetimeResult::gradients, "cost-and-gradient evaluations, all starts")
      .def_readonly("best_start", &fit::SpacetimeResult::best_start)
      .def_readonly("start_costs", &fit::SpacetimeResult::start_costs, "every start's final cost (NaN: failed)");

  BindRollouts<2>(m);
  BindRollouts<3>(m);

  // The 3D names of before, one release (python/wobble/__init__.pyi marks them deprecated; the
  // classes' old names, StageCost3 and RolloutGradient3, are wobble/__init__.py's _DEPRECATED).
  BindDeprecated(m, "rollout_gradient3", "rollout_gradient");
  BindDeprecated(m, "rollout_cost3", "rollout_cost");
  BindDeprecated(m, "fit_spacetime3", "fit_spacetime");
  BindDeprecated(m, "centre_of_mass_at3", "centre_of_mass_at");
  BindDeprecated(m, "centre_of_mass_velocity_at3", "centre_of_mass_velocity_at");
  // the old 3D-only StageCost: the 2D form dropped
  auto only_3d = [](py::object cost) {
    StageCostHandle h = cost.cast<StageCostHandle>();
    h.plane = nullptr;
    return py::cast(h);
  };
  BindDeprecated(m, "upright_at3", "upright_at", only_3d);
  BindDeprecated(m, "still_at3", "still_at", only_3d);

  m.def(
      "write_target_schedule",
      [](const std::string& path, const std::vector<std::string>& modes, double dt, const Eigen::MatrixXd& targets) {
        if (targets.rows() != long(modes.size()))
          throw InputError("targets: expected one row per mode (" + std::to_string(modes.size()) + "), got " +
                           std::to_string(targets.rows()));
        if (!(dt > 0) || !targets.allFinite()) throw InputError("write_target_schedule: dt > 0 and finite targets");
        formats::WriteTargetSchedule(path, modes, dt, targets);
      },
      py::arg("path"), py::arg("modes"), py::arg("dt"), py::arg("targets"),
      "Writes targets (modes, steps) as the schedule file a script plays with `schedule FILE`.");
  m.def("read_target_schedule", &formats::ReadTargetSchedule, py::arg("path"), py::arg("modes"), py::arg("dt"),
        "Reads a schedule file (modes, steps); ParseError naming the file and line.");
}

}  // namespace wobble::python
