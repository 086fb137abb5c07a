// Gradients through whole 3D rollouts and 3D spacetime fits from Python (fit/adjoint3.h,
// fit/spacetime.h, issue 18). Python sees a 3D state as World.q3 / qd3 do: q = [t, rotation
// vector Θ, γ] with R = exp(Θ̂), q̇ = [ṫ, body ω, γ̇]. The library works in the tangent
// coordinates z = (δt, ε, δγ, δv) with R exp(ε̂); this file converts between the two, so every
// gradient Python gets or gives is with respect to the numbers it passes.
#include <cmath>
#include <memory>

#include "gradients.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/adjoint3.h"
#include "wobble/fit/spacetime.h"

namespace wobble::python {
namespace {

struct StageCost3Handle {
  fit::StageCost3 cost;
};

// A = ∂Θ/∂ε at Θ: R exp(ε̂) = exp((Θ + A ε)^) to first order, A's columns dexp⁻¹_{−Θ}(e_i)
// (the map RotationVectorRate takes ω through; rotation3.h).
Eigen::Matrix3d RotationVectorPerTangent(const Eigen::Vector3d& theta) {
  Eigen::Matrix3d A;
  for (int i = 0; i < 3; ++i) A.col(i) = RotationVectorRate<double>(theta, Eigen::Vector3d::Unit(i));
  return A;
}

// ∂ℓ/∂z from ∂ℓ/∂q, ∂ℓ/∂q̇ at Θ: the ε part is Aᵀ ∂ℓ/∂Θ, the rest is the same numbers.
void AddTangentGradient(const Eigen::Vector3d& theta, const Eigen::VectorXd& dq, const Eigen::VectorXd& dqd,
                        Eigen::VectorXd* dz) {
  const int nq = int(dq.size());
  dz->head<3>() += dq.head<3>();
  dz->segment<3>(3) += RotationVectorPerTangent(theta).transpose() * dq.segment<3>(3);
  dz->segment(6, nq - 6) += dq.tail(nq - 6);
  dz->tail(nq) += dqd;
}

// ∂ℓ/∂q, ∂ℓ/∂q̇ from ∂ℓ/∂z at Θ: the Θ part is A⁻ᵀ ∂ℓ/∂ε.
void QGradients(const Eigen::Vector3d& theta, const Eigen::VectorXd& dz, Eigen::VectorXd* dq, Eigen::VectorXd* dqd) {
  const int nq = int(dz.size()) / 2;
  *dq = dz.head(nq);
  dq->segment<3>(3) = RotationVectorPerTangent(theta).transpose().lu().solve(Eigen::Vector3d(dz.segment<3>(3)));
  *dqd = dz.tail(nq);
}

// A Python fn(n, q, qd) -> (value, dq, dqd) in World.q3 coordinates as a 3D stage cost (the
// GIL taken for each call).
fit::StageCost3 FromPython(py::function fn) {
  std::shared_ptr<py::function> held = HoldWithGil(std::move(fn));
  return [held](int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) -> double {
    py::gil_scoped_acquire gil;
    const Eigen::VectorXd q = CoordinatesOf(s);
    Eigen::VectorXd dq, dqd;
    const double value = StageResult((*held)(n, q, Eigen::VectorXd(s.qd)), n, q.size(), &dq, &dqd);
    AddTangentGradient(q.segment<3>(3), dq, dqd, dz);
    return value;
  };
}

fit::Axes AxesOf3(const std::string& axes) {
  fit::Axes a;
  a.x = axes.find('x') != std::string::npos;
  a.y = axes.find('y') != std::string::npos;
  a.z = axes.find('z') != std::string::npos;
  if (axes.empty() || axes.find_first_not_of("xyz") != std::string::npos)
    throw InputError("axes: expected some of 'x', 'y', 'z' (such as 'xz'), got '" + axes + "'");
  return a;
}

// A 3D rollout from the keyword arguments: the options' 3D world (ground_3d, gravity_3d,
// springs_3d), integrator and dt; the start q0 = [t, Θ, γ], qd0 (rest at the lattice's pose by
// default); the gains (the body's own by default); the targets (modes, steps).
fit::ControlledRollout3 Rollout3Of(const BodyModel3& body, const WorldOptions& options, const py::object& targets,
                                   const py::object& q0, const py::object& qd0, const py::object& stiffness,
                                   const py::object& damping) {
  const int nq = body.num_q();
  fit::ControlledRollout3 r;
  r.world = Params3Of(options);
  r.integrator = options.integrator;
  CheckGradientIntegrator(r.integrator);
  r.dt = options.dt;
  r.start = StateFromCoordinates<3>(VectorOr(q0, nq, Eigen::VectorXd::Zero(nq), "q0"),
                        VectorOr(qd0, nq, Eigen::VectorXd::Zero(nq), "qd0"));
  GainsOf(body, stiffness, damping, &r.stiffness, &r.damping);
  r.targets = TargetsOf(targets, body.num_modes());
  return r;
}

// A 3D rollout's gradient as Python sees it: with respect to q0 and qd0, not tangent coordinates.
struct RolloutGradient3Py {
  fit::RolloutGradient3 g;
  Eigen::VectorXd q0, qd0;
};

template <class F> auto Checked(const char* what, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const std::invalid_argument& e) {
    throw InputError(std::string(what) + ": " + e.what());
  }
}

}  // namespace

void BindGradients3(py::module_& m) {
  py::class_<StageCost3Handle>(m, "StageCost3",
                               "A cost l_n(q, qd) of one step of a 3D rollout with its gradient: a task term\n"
                               "(centre_of_mass_at3, upright_at3, ...), a sum (a + b), or StageCost3(fn) with a\n"
                               "Python fn(n, q, qd) -> (value, dq, dqd) in World.q3 / qd3 coordinates\n"
                               "(q = [t, rotation vector, gamma]; dq, dqd: num_q arrays or None).")
      .def(py::init([](py::function fn) { return StageCost3Handle{FromPython(std::move(fn))}; }), py::arg("fn"))
      .def(
          "__call__",
          [](const StageCost3Handle& c, int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
            if (q.size() != qd.size() || q.size() < Group<3>::kRigidDofs)
              throw InputError("q and qd must have the same size, at least 6");
            Eigen::VectorXd dz = Eigen::VectorXd::Zero(2 * q.size()), dq, dqd;
            const double value = c.cost(n, StateFromCoordinates<3>(q, qd), &dz);
            QGradients(q.segment<3>(3), dz, &dq, &dqd);
            return py::make_tuple(value, dq, dqd);
          },
          py::arg("n"), py::arg("q"), py::arg("qd"), "(value, dq, dqd) at step n")
      .def("__add__", [](const StageCost3Handle& a, const StageCost3Handle& b) {
        return StageCost3Handle{fit::SumOf3({a.cost, b.cost})};
      });

  m.def(
      "centre_of_mass_at3",
      [](std::shared_ptr<BodyModel3> body, int step, const Eigen::Vector3d& goal, double weight, const std::string& axes) {
        return Checked("centre_of_mass_at3",
                       [&] { return StageCost3Handle{fit::CentreOfMassAt3(*body, step, goal, weight, AxesOf3(axes))}; });
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = "xyz",
      "w/2 |centre of mass at step n - goal|^2 on the axes asked for ('xyz', 'xz', 'y', ...): be there then");
  m.def(
      "centre_of_mass_velocity_at3",
      [](std::shared_ptr<BodyModel3> body, int step, const Eigen::Vector3d& goal, double weight, const std::string& axes) {
        return Checked("centre_of_mass_velocity_at3", [&] {
          return StageCost3Handle{fit::CentreOfMassVelocityAt3(*body, step, goal, weight, AxesOf3(axes))};
        });
      },
      py::arg("body"), py::arg("step"), py::arg("goal"), py::kw_only(), py::arg("weight") = 1.0, py::arg("axes") = "xyz",
      "w/2 |centre-of-mass velocity at step n - goal|^2 (goal 0 on 'y': the top of a hop)");
  m.def(
      "upright_at3",
      [](int step, double weight, double time_scale) {
        return Checked("upright_at3", [&] { return StageCost3Handle{fit::UprightAt3(step, weight, time_scale)}; });
      },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, py::arg("time_scale") = 0.0,
      "w/2 (|R e_y - e_y|^2 + tau^2 |omega|^2) at step n: the body's up axis up and not turning (any heading)");
  m.def(
      "still_at3",
      [](int step, double weight) { return Checked("still_at3", [&] { return StageCost3Handle{fit::StillAt3(step, weight)}; }); },
      py::arg("step"), py::kw_only(), py::arg("weight") = 1.0, "w/2 |qd|^2 at step n: at rest");

  py::class_<RolloutGradient3Py>(m, "RolloutGradient3",
                                 "A 3D rollout's cost and its gradient with respect to every parameter.")
      .def_property_readonly("ok", [](const RolloutGradient3Py& r) { return r.g.ok; })
      .def_property_readonly("message", [](const RolloutGradient3Py& r) { return r.g.message; })
      .def_property_readonly("cost", [](const RolloutGradient3Py& r) { return r.g.cost; })
      .def_readonly("q0", &RolloutGradient3Py::q0, "d cost / d q0, q0 = [t, rotation vector, gamma]")
      .def_readonly("qd0", &RolloutGradient3Py::qd0, "d cost / d qd0, qd0 = [t dot, body omega, gamma dot]")
      .def_property_readonly("stiffness", [](const RolloutGradient3Py& r) { return r.g.stiffness; })
      .def_property_readonly("damping", [](const RolloutGradient3Py& r) { return r.g.damping; })
      .def_property_readonly("targets", [](const RolloutGradient3Py& r) { return r.g.targets; },
                             "(modes, steps): d cost / d target of each step")
      .def_property_readonly("states_held", [](const RolloutGradient3Py& r) { return r.g.states_held; },
                             "the most states held at once (checkpoints)");

  m.def(
      "rollout_gradient3",
      [](std::shared_ptr<BodyModel3> body, const StageCost3Handle& cost, const py::object& targets,
         const WorldOptions& options, const py::object& q0, const py::object& qd0, const py::object& stiffness,
         const py::object& damping, int checkpoint_interval) {
        const fit::ControlledRollout3 r = Rollout3Of(*body, options, targets, q0, qd0, stiffness, damping);
        RolloutGradient3Py out;
        {
          py::gil_scoped_release release;  // a Python stage cost takes it back for its own calls
          out.g = Checked("rollout_gradient3", [&] { return fit::RolloutCostGradient3(*body, r, cost.cost, checkpoint_interval); });
        }
        if (out.g.ok) QGradients(LogRotation<double>(r.start.orientation()), out.g.start, &out.q0, &out.qd0);
        return out;
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), py::arg("checkpoint_interval") = 0,
      "The cost sum_n l_n(q_n, qd_n) of a rollout of the 3D body (PD targets (modes, steps), one per\n"
      "step; gains K, c per mode; options' 3D world (ground_3d, gravity_3d, springs_3d), dt and integrator:\n"
      "thesis or symplectic) and its gradient with respect to q0, qd0, K, c and every target, by one\n"
      "adjoint sweep: its cost does not grow with the number of parameters (README: Gradients).\n"
      "checkpoint_interval: 0 keeps the whole run when it fits in 64 MiB, else checkpoints every\n"
      "ceil(sqrt(steps)) steps; -1 always does; N > 0 every N steps.");
  m.def(
      "rollout_cost3",
      [](std::shared_ptr<BodyModel3> body, const StageCost3Handle& cost, const py::object& targets,
         const WorldOptions& options, const py::object& q0, const py::object& qd0, const py::object& stiffness,
         const py::object& damping) {
        const fit::ControlledRollout3 r = Rollout3Of(*body, options, targets, q0, qd0, stiffness, damping);
        py::gil_scoped_release release;
        return Checked("rollout_cost3", [&] { return fit::RolloutCost3(*body, r, cost.cost); });
      },
      py::arg("body"), py::arg("cost"), py::kw_only(), py::arg("targets"), py::arg("options") = WorldOptions(),
      py::arg("q0") = py::none(), py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(),
      py::arg("damping") = py::none(), "The same rollout's cost alone (one plain simulation; inf when a step fails).");

  m.def(
      "fit_spacetime3",
      [](std::shared_ptr<BodyModel3> body, const StageCost3Handle& task, const py::object& targets, int knots,
         double bound, double control_weight, const WorldOptions& options, const py::object& q0, const py::object& qd0,
         const py::object& stiffness, const py::object& damping, int max_iterations, int starts, double start_spread,
         unsigned seed, int threads) {
        fit::SpacetimeProblem3 p;
        p.rollout = Rollout3Of(*body, options, targets, q0, qd0, stiffness, damping);
        p.knots = knots;
        SetSpacetimeBounds(body->num_modes(), bound, control_weight, &p);
        p.task = task.cost;
        const fit::SpacetimeOptions o = SpacetimeOptionsOf(max_iterations, starts, start_spread, seed, threads);
        return Checked("fit_spacetime3", [&] { return WithCtrlC([&] { return fit::FitSpacetime3(*body, p, o); }); });
      },
      py::arg("body"), py::arg("task"), py::kw_only(), py::arg("targets"), py::arg("knots") = 21, py::arg("bound") = 0.3,
      py::arg("control_weight") = 1.0, py::arg("options") = WorldOptions(), py::arg("q0") = py::none(),
      py::arg("qd0") = py::none(), py::arg("stiffness") = py::none(), py::arg("damping") = py::none(),
      py::arg("max_iterations") = 100, py::arg("starts") = 1, py::arg("start_spread") = 1.0, py::arg("seed") = 1u,
      py::arg("threads") = 0,
      "fit_spacetime for the 3D body: every mode's PD targets over the whole run at `knots` knots within\n"
      "+-bound, minimising control_weight * sum |target|^2 dt plus the task (a StageCost3), by L-BFGS on\n"
      "the 3D adjoint gradient; the options' 3D world. Returns a SpacetimeResult.");
}

}  // namespace wobble::python
