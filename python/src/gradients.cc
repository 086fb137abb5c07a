// Gradients through whole rollouts and spacetime control fits from Python (fit/adjoint.h,
// fit/spacetime.h, issue 18), and the target schedule files that scripts play (`schedule`).
// A stage cost is a StageCost: one of the task terms, a sum of them (`+`), or a Python callable
// fn(n, q, qd) -> (value, dq, dqd) called with the GIL taken for each step.
#include "gradients.h"

#include <cmath>
#include <memory>

#include "wobble/core/errors.h"
#include "wobble/fit/adjoint.h"
#include "wobble/fit/spacetime.h"
#include "wobble/formats/target_schedule.h"

namespace wobble::python {
namespace {

struct StageCostHandle {
  fit::StageCost cost;
};

// A Python fn(n, q, qd) -> (value, dq, dqd) as a stage cost (the GIL taken for each call).
fit::StageCost FromPython(py::function fn) {
  std::shared_ptr<py::function> held = HoldWithGil(std::move(fn));
  return [held](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* dq,
                Eigen::VectorXd* dqd) -> double {
    py::gil_scoped_acquire gil;
    Eigen::VectorXd g_q, g_qd;
    const double value = StageResult((*held)(n, q, qd), n, q.size(), &g_q, &g_qd);
    *dq += g_q;
    *dqd += g_qd;
    return value;
  };
}

fit::Axes AxesOf(const std::string& axes) {
  if (axes != "x" && axes != "y" && axes != "xy") throw InputError("axes: expected 'x', 'y' or 'xy', got '" + axes + "'");
  fit::Axes a;
  a.x = axes.find('x') != std::string::npos;
  a.y = axes.find('y') != std::string::npos;
  return a;
}

// A rollout from the keyword arguments: the options' world, integrator and dt; the start (at
// rest in the body frame by default); the gains (the body's own by default); the targets
// (modes, steps).
fit::ControlledRollout RolloutOf(const BodyModel& body, const WorldOptions& options, const py::object& targets,
                                 const py::object& q0, const py::object& qd0, const py::object& stiffness,
                                 const py::object& damping) {
  const int nq = body.num_q();
  fit::ControlledRollout r;
  r.world = options.params;
  r.integrator = options.integrator;
  CheckGradientIntegrator(r.integrator);
  r.dt = options.dt;
  r.q0 = VectorOr(q0, nq, Eigen::VectorXd::Zero(nq), "q0");
  r.qd0 = VectorOr(qd0, nq, Eigen::VectorXd::Zero(nq), "qd0");
  GainsOf(body, stiffness, damping, &r.stiffness, &r.damping);
  r.targets = TargetsOf(targets, body.num_modes());
  return r;
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

fit::SpacetimeOptions SpacetimeOptionsOf(int max_iterations, int starts, double start_spread, unsigned seed, int threads) {
  fit::SpacetimeOptions o;
  o.max_iterations = max_iterations;
  o.starts = starts;
  o.start_spread = start_spread;
  o.seed = seed;
  o.threads = threads;
  return o;
}

void BindGradients(py::module_& m) {
  py::class_<StageCostHandle>(m, "StageCost",
                              "A cost l_n(q, qd) of one step of a rollout with its gradient: a task term\n"
                              "(centre_of_mass_at, upright_at, ...), a sum (a + b), or StageCost(fn) with a\n"
                              "Python fn(n, q, qd) -> (value, dq, dqd) (dq, dqd: num_q arrays or None).")
      .def(py::init([](py::function fn) { return StageCostHandle{FromPython(std::move(fn))}; }), py::arg("fn"))
      .def(
          "__call__",
          [](const StageCostHandle& c, int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
            if (q.size() != qd.size()) throw InputError("q and qd must have the same size");
            Eigen::VectorXd dq = Eigen::VectorXd::Zero(q.size()), dqd = Eigen::VectorXd::Zero(q.size());
            const double value = c.cost(n, q, qd, &dq, &dqd);
            return py::make_tuple(value, dq, dqd);
          },
          py::arg("n"), py::arg("q"), py::arg("qd"), "(value, dq, dqd) at step n")
      .def("__add__", [](const StageCostHandle& a, const StageCostHandle& b) {
        return StageCostHandle{fit::SumOf({a.cost, b.cost})};
      });

  m.def(
      "centre_of_mass_at",
      [](std::shared_ptr<BodyModel> body, int step, const Eigen::Vector2d& goal, double weight, const std::string& axes) {
        try {
          return StageCostHandle{fit::CentreOfMassAt(*body, step, goal, weight, AxesOf(axes))};
        } catch (const std::invalid_argument& e) {
          throw InputError(e.what());
        }
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = "xy",
      "w/2 |centre of mass at step n - goal|^2 on the axes asked for ('x', 'y', 'xy'): be there then");
  m.def(
      "centre_of_mass_velocity_at",
      [](std::shared_ptr<BodyModel> body, int step, const Eigen::Vector2d& goal, double weight, const std::string& axes) {
        try {
          return StageCostHandle{fit::CentreOfMassVelocityAt(*body, step, goal, weight, AxesOf(axes))};
        } catch (const std::invalid_argument& e) {
          throw InputError(e.what());
        }
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = "xy",
      "w/2 |centre-of-mass velocity at step n - goal|^2 (goal 0 on 'y': the top of a hop)");
  m.def(
      "upright_at",
      [](int step, double weight, double time_scale) {
        try {
          return StageCostHandle{fit::UprightAt(step, weight, time_scale)};
        } catch (const std::invalid_argument& e) {
          throw InputError(e.what());
        }
      },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, py::arg("time_scale") = 0.0,
      "w/2 (theta^2 + tau^2 thetadot^2) at step n: upright and not spinning");
  m.def(
      "still_at",
      [](int step, double weight) {
        try {
          return StageCostHandle{fit::StillAt(step, weight)};
        } catch (const std::invalid_argument& e) {
          throw InputError(e.what());
        }
      },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, "w/2 |qd|^2 at step n: at rest");

  py::class_<fit::RolloutGradient>(m, "RolloutGradient", "A rollout's cost and its gradient with respect to every parameter.")
      .def_readonly("ok", &fit::RolloutGradient::ok)
      .def_readonly("message", &fit::RolloutGradient::message)
      .def_readonly("cost", &fit::RolloutGradient::cost)
      .def_readonly("q0", &fit::RolloutGradient::q0)
      .def_readonly("qd0", &fit::RolloutGradient::qd0)
      .def_readonly("stiffness", &fit::RolloutGradient::stiffness)
      .def_readonly("damping", &fit::RolloutGradient::damping)
      .def_readonly("targets", &fit::RolloutGradient::targets, "(modes, steps): d cost / d target of each step")
      .def_readonly("states_held", &fit::RolloutGradient::states_held, "the most states held at once (checkpoints)");

  m.def(
      "rollout_gradient",
      [](std::shared_ptr<BodyModel> body, const StageCostHandle& cost, const py::object& targets, const WorldOptions& options,
         const py::object& q0, const py::object& qd0, const py::object& stiffness, const py::object& damping,
         int checkpoint_interval) {
        const fit::ControlledRollout r = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        py::gil_scoped_release release;  // a Python stage cost takes it back for its own calls
        return fit::RolloutCostGradient(*body, r, cost.cost, checkpoint_interval);
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), py::arg("checkpoint_interval") = 0,
      "The cost sum_n l_n(q_n, qd_n) of a rollout of the 2D body (PD targets (modes, steps), one per\n"
      "step; gains K, c per mode; options' world, dt and integrator: thesis or symplectic) and its\n"
      "gradient with respect to q0, qd0, K, c and every target, by one adjoint sweep (about 2-4\n"
      "simulations whatever the number of parameters).\n"
      "checkpoint_interval: 0 keeps the whole run when it fits in 64 MiB, else checkpoints every\n"
      "ceil(sqrt(steps)) steps; -1 always does; N > 0 every N steps.");
  m.def(
      "rollout_cost",
      [](std::shared_ptr<BodyModel> body, const StageCostHandle& cost, const py::object& targets, const WorldOptions& options,
         const py::object& q0, const py::object& qd0, const py::object& stiffness, const py::object& damping) {
        const fit::ControlledRollout r = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        py::gil_scoped_release release;
        return fit::RolloutCost(*body, r, cost.cost);
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), "The same rollout's cost alone (one plain simulation; inf when a step fails).");

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

  m.def(
      "fit_spacetime",
      [](std::shared_ptr<BodyModel> body, const StageCostHandle& task, const py::object& targets, int knots, double bound,
         double control_weight, const WorldOptions& options, const py::object& q0, const py::object& qd0,
         const py::object& stiffness, const py::object& damping, int max_iterations, int starts, double start_spread,
         unsigned seed, int threads) {
        fit::SpacetimeProblem p;
        p.rollout = RolloutOf(*body, options, targets, q0, qd0, stiffness, damping);
        p.knots = knots;
        SetSpacetimeBounds(body->num_modes(), bound, control_weight, &p);
        p.task = task.cost;
        const fit::SpacetimeOptions o = SpacetimeOptionsOf(max_iterations, starts, start_spread, seed, threads);
        try {
          return WithCtrlC([&] { return fit::FitSpacetime(*body, p, o); });
        } catch (const std::invalid_argument& e) {
          throw InputError(std::string("fit_spacetime: ") + e.what());
        }
      },
      py::arg("body"), py::arg("task"), py::kw_only(), py::arg("targets"), py::arg("knots") = 21, py::arg("bound") = 0.3,
      py::arg("control_weight") = 1.0, py::arg("options") = WorldOptions(), py::arg("q0") = py::none(),
      py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(), py::arg("damping") = py::none(),
      py::arg("max_iterations") = 100, py::arg("starts") = 1, py::arg("start_spread") = 1.0, py::arg("seed") = 1u,
      py::arg("threads") = 0,
      "Spacetime control (thesis 3.1 after Witkin & Kass): every mode's PD targets over the whole run,\n"
      "at `knots` evenly spaced knots within +-bound, minimising control_weight * sum |target|^2 dt plus\n"
      "the task, by L-BFGS on the adjoint gradient. targets (modes, steps): the first guess and the run's\n"
      "length. starts > 1: multi-start, the further starts perturbed by a seeded Gaussian of start_spread on\n"
      "each knot's logistic coordinate, run on `threads` (0: every core), the lowest cost wins (best_start,\n"
      "start_costs). Like `wobble fit spacetime`; write_target_schedule(result.targets) for a script's schedule.");

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
