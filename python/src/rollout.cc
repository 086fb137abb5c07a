// Batched rollouts (what mujoco.rollout is liked for): N initial states, optionally N sets of
// PD targets (constant or one per step), T steps each, on every core with the GIL released,
// into numpy arrays. Each trial is its own World (the per-body fast path, O(D²) a step), so
// trials are independent and a rollout equals the same trials stepped one by one.
#include "support.h"

#include <cmath>
#include <limits>
#include <thread>

#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"
#include "wobble/core/limits.h"
#include "wobble/core/parallel.h"
#include "wobble/scene/ffd_object.h"

namespace wobble::python {
namespace {

struct RolloutResult {
  py::array_t<double> time, q, qd, energy;
  py::array_t<long> steps_taken;
  std::vector<std::string> status, messages;
};

// (N, n) rows of a 2D array, or one row of a 1D array as N = 1.
py::array_t<double, py::array::c_style> Rows(const py::handle& h, long n, const std::string& what) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(h);
  if (!a) throw InputError(what + ": expected an array of numbers");
  if (a.ndim() == 1) return AsMatrix(a.reshape({py::ssize_t(1), a.shape(0)}), 1, n, what + " (one state)");
  if (a.ndim() != 2)
    throw InputError(what + ": expected shape (N, " + std::to_string(n) + "), got " + std::to_string(a.ndim()) + " dimensions");
  return AsMatrix(a, a.shape(0), n, what + " (N, " + std::to_string(n) + ")");
}

// A 2D body's state is (q, q̇); a 3D body's q = [t, rotation vector, γ] and q̇ = [ṫ, body ω, γ̇]
// (World.q3 / set_state3).
void SetStart(World* w, const BodyModel&, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) { w->SetState(0, q, qd); }
void SetStart(World* w, const BodyModelN<3>&, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  w->SetCoordinates(0, q, qd);
}
void ReadState(const World& w, const BodyModel&, double* q, double* qd) {
  const BodyState<2, double>& s = w.state<2>(0);
  std::copy(s.q.data(), s.q.data() + s.q.size(), q);
  std::copy(s.qd.data(), s.qd.data() + s.qd.size(), qd);
}
void ReadState(const World& w, const BodyModelN<3>&, double* q, double* qd) {
  const Eigen::VectorXd q3 = w.coordinates(0), qd3 = w.qd(0);
  std::copy(q3.data(), q3.data() + q3.size(), q);
  std::copy(qd3.data(), qd3.data() + qd3.size(), qd);
}

template <int Dim>
RolloutResult Rollout(std::shared_ptr<BodyModelN<Dim>> body, const py::object& q0_in, const py::object& qd0_in, long steps,
                      const WorldOptions& options, const py::object& targets_in, int every, int threads, bool energies,
                      long max_steps, double max_record_mb) {
  const long n = body->num_q(), D = body->num_modes();
  if (steps < 0) throw InputError("steps must be at least 0");
  if (every < 1) throw InputError("every must be at least 1");
  if (threads < 0 || threads > kMaxThreads) throw InputError("threads must be 0 (every core) to " + std::to_string(kMaxThreads));
  const auto q0 = Rows(q0_in, n, "q0");
  const long N = q0.shape(0);
  auto qd0 = qd0_in.is_none() ? py::array_t<double, py::array::c_style>(std::vector<py::ssize_t>{N, n})
                                    : AsMatrix(Rows(qd0_in, n, "qd0"), N, n, "qd0 (as many rows as q0)");
  if (qd0_in.is_none()) std::fill(qd0.mutable_data(), qd0.mutable_data() + N * n, 0.0);
  // targets: none, (N, D) held for the whole run, or (N, steps, D) one set per step
  py::array_t<double, py::array::c_style> targets;
  bool per_step = false;
  if (!targets_in.is_none()) {
    targets = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(targets_in);
    if (!targets) throw InputError("mode_targets: expected an array of numbers");
    per_step = targets.ndim() == 3;
    const std::string shape = per_step ? "(N, steps, num_modes)" : "(N, num_modes)";
    if (per_step ? !(targets.shape(0) == N && targets.shape(1) == steps && targets.shape(2) == D)
                 : !(targets.ndim() == 2 && targets.shape(0) == N && targets.shape(1) == D))
      throw InputError("mode_targets: expected shape " + shape + " = (" + std::to_string(N) +
                       (per_step ? ", " + std::to_string(steps) : std::string()) + ", " + std::to_string(D) + ")");
  }
  const Limits limits{max_steps, max_record_mb};
  CheckedCount(double(N) * double(steps), 0, limits.max_steps, "the rollout's steps (N x steps)", "raise max_steps");
  const long S = steps / every + 1;  // samples: the start, then every `every`-th step
  CheckRecordSize(double(N) * double(S) * (2.0 * n + (energies ? 1 : 0)), limits, "raise max_record_mb, or raise every");

  RolloutResult r;
  r.time = py::array_t<double>(S);
  for (long k = 0; k < S; ++k) r.time.mutable_data()[k] = double(k * every) * options.dt;
  r.q = py::array_t<double>({N, S, n});
  r.qd = py::array_t<double>({N, S, n});
  r.energy = py::array_t<double>(energies ? std::vector<py::ssize_t>{N, S} : std::vector<py::ssize_t>{0});
  r.steps_taken = py::array_t<long>(N);
  std::vector<WorldStatus> status(N);
  double* q_out = r.q.mutable_data();
  double* qd_out = r.qd.mutable_data();
  double* e_out = r.energy.mutable_data();
  long* taken = r.steps_taken.mutable_data();
  const double *q0_p = q0.data(), *qd0_p = qd0.data(), *t_p = targets_in.is_none() ? nullptr : targets.data();
  const std::shared_ptr<const BodyModelN<Dim>> model = body;
  ClearInterrupt();
  struct ClearAtEnd {
    ~ClearAtEnd() { ClearInterrupt(); }
  } clear_at_end;
  {
    py::gil_scoped_release release;
    ParallelFor(size_t(N), threads, [&](size_t i) {
      World w(options);
      w.AddBody(model);
      try {
        SetStart(&w, *model, Eigen::Map<const Eigen::VectorXd>(q0_p + i * n, n),
                 Eigen::Map<const Eigen::VectorXd>(qd0_p + i * n, n));
      } catch (const InputError& e) {
        throw InputError("trial " + std::to_string(i) + ": " + e.what());
      }
      auto sample = [&](long k) {
        ReadState(w, *model, q_out + (i * S + k) * n, qd_out + (i * S + k) * n);
        if (energies) e_out[i * S + k] = w.ComputeEnergies(0).total();
      };
      sample(0);
      if (t_p && !per_step) w.SetModeTargets(0, Eigen::Map<const Eigen::VectorXd>(t_p + i * D, D));
      long step = 0;
      for (; step < steps; ++step) {
        if (step % 2000 == 1999 && CtrlCPressed()) w.ThrowInterrupted();
        if (per_step) w.SetModeTargets(0, Eigen::Map<const Eigen::VectorXd>(t_p + (i * steps + step) * D, D));
        if (!w.Step()) break;
        if ((step + 1) % every == 0) sample((step + 1) / every);
      }
      taken[i] = step;
      status[i] = w.status();
      // samples after a stop: NaN, and status says why (never a NaN without a cause)
      for (long k = step / every + 1; k < S; ++k) {
        std::fill(q_out + (i * S + k) * n, q_out + (i * S + k + 1) * n, std::numeric_limits<double>::quiet_NaN());
        std::fill(qd_out + (i * S + k) * n, qd_out + (i * S + k + 1) * n, std::numeric_limits<double>::quiet_NaN());
        if (energies) e_out[i * S + k] = std::numeric_limits<double>::quiet_NaN();
      }
    });
  }
  for (const WorldStatus& s : status) {
    r.status.push_back(StatusCodeName(s.code));
    r.messages.push_back(s.message);
  }
  return r;
}

}  // namespace

void BindRollout(py::module_& m) {
  py::class_<RolloutResult>(m, "RolloutResult",
                            "What rollout() returns. Samples after a trial stopped are NaN; status and\n"
                            "messages say why and where (status 'ok': it ran to the end).")
      .def_readonly("time", &RolloutResult::time, "(S,) sample times from the start")
      .def_readonly("q", &RolloutResult::q, "(N, S, num_q)")
      .def_readonly("qd", &RolloutResult::qd, "(N, S, num_q)")
      .def_readonly("energy", &RolloutResult::energy, "(N, S) total energy when asked for (energies=True)")
      .def_readonly("steps_taken", &RolloutResult::steps_taken, "(N,) steps each trial took")
      .def_readonly("status", &RolloutResult::status, "per trial: 'ok' or the cause it stopped for")
      .def_readonly("messages", &RolloutResult::messages, "per trial: the world's status message");

  m.def("rollout", &Rollout<2>, py::arg("body"), py::arg("q0"), py::arg("qd0") = py::none(), py::arg("steps") = 1,
        py::kw_only(), py::arg("options") = WorldOptions(), py::arg("mode_targets") = py::none(), py::arg("every") = 1,
        py::arg("threads") = 0, py::arg("energies") = false, py::arg("max_steps") = Limits().max_steps,
        py::arg("max_record_mb") = Limits().max_record_mb,
        "Simulates N trials of one FFD body for `steps` steps each, in parallel on `threads` threads\n"
        "(0: every core) with the GIL released. q0, qd0: (N, num_q) start states (qd0 None: at rest);\n"
        "mode_targets: None, (N, num_modes) PD targets held throughout, or (N, steps, num_modes)\n"
        "one set per step (applied before it). Samples the start and every `every`-th step.\n"
        "Equal, bit for bit, to stepping each trial's World alone, whatever the thread count.");
  m.def("rollout", &Rollout<3>, py::arg("body"), py::arg("q0"), py::arg("qd0") = py::none(), py::arg("steps") = 1,
        py::kw_only(), py::arg("options") = WorldOptions(), py::arg("mode_targets") = py::none(), py::arg("every") = 1,
        py::arg("threads") = 0, py::arg("energies") = false, py::arg("max_steps") = Limits().max_steps,
        py::arg("max_record_mb") = Limits().max_record_mb,
        "The same for a 3D FFD body (a BodyModel of dim 3): q = [t, rotation vector, γ] (|r| <= π as read\n"
        "back), q̇ = [ṫ, body ω, γ̇], as World.q/qd/set_state; the world's 3D ground and gravity\n"
        "(options.ground_plane, gravity).");
}

}  // namespace wobble::python
