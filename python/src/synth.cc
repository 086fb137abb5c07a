// Motion synthesis (Faloutsos 1995 ch. 5) from Python: pose graphs, a synthesis problem (the
// one a script's `anneal` would solve), batches of trials on every core, and annealing.
#include "support.h"

#include <chrono>

#include "wobble/core/errors.h"
#include "wobble/core/limits.h"
#include "wobble/synth/anneal.h"
#ifdef WOBBLE_HAVE_PAGMO
#include "wobble/synth/cmaes.h"
#endif

namespace wobble::python {
namespace {

using control::PoseGraph;
using synth::Problem;

PoseGraph MakeGraph(const Eigen::MatrixXd& poses, const std::vector<double>& durations, bool cyclic) {
  PoseGraph g;
  for (int p = 0; p < poses.rows(); ++p) g.poses.push_back(poses.row(p).transpose());
  g.durations = durations;
  g.cyclic = cyclic;
  if (g.poses.empty()) throw InputError("a pose graph needs at least one pose");
  const std::string error = g.Validate(int(poses.cols()));
  if (!error.empty()) throw InputError("pose graph: " + error);
  return g;
}

Eigen::MatrixXd PosesOf(const PoseGraph& g) {
  Eigen::MatrixXd out(g.poses.size(), g.poses.empty() ? 0 : g.poses[0].size());
  for (size_t p = 0; p < g.poses.size(); ++p) out.row(p) = g.poses[p].transpose();
  return out;
}

int NumActive(const Problem& p) {
  return int(p.dim() == 3 ? control::ActiveModes(*p.body<3>()).size() : control::ActiveModes(*p.body<2>()).size());
}

struct TrialResults {
  py::array_t<double> cost, distance, speed, energy;
  py::array_t<bool> ok;
  std::vector<std::string> failures;
  double seconds = 0;  // wall time of the simulations alone (synth::RunTrials)
};

// The trials of `graphs` (a list of PoseGraph), or of a batch of poses (N, P, A) with shared
// (P,) or per-trial (N, P) durations, on `threads` threads.
TrialResults RunTrials(const Problem& problem, const py::object& graphs_or_poses, const py::object& durations_in,
                       bool cyclic, int threads) {
  if (threads < 0 || threads > kMaxThreads) throw InputError("threads must be 0 (every core) to " + std::to_string(kMaxThreads));
  const int A = NumActive(problem);
  std::vector<PoseGraph> graphs;
  if (py::isinstance<py::list>(graphs_or_poses) || py::isinstance<py::tuple>(graphs_or_poses)) {
    for (const py::handle& h : graphs_or_poses) graphs.push_back(h.cast<PoseGraph>());
  } else {
    auto poses = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(graphs_or_poses);
    if (!poses || poses.ndim() != 3 || poses.shape(2) != A)
      throw InputError("poses: expected a list of PoseGraph or an array (N, poses, " + std::to_string(A) +
                       " active modes)");
    const long N = poses.shape(0), P = poses.shape(1);
    if (durations_in.is_none()) throw InputError("durations: needed with an array of poses, (P,) or (N, P)");
    auto d = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(durations_in);
    const bool shared = d && d.ndim() == 1;
    if (!d || !(shared ? d.shape(0) == P : (d.ndim() == 2 && d.shape(0) == N && d.shape(1) == P)))
      throw InputError("durations: expected shape (" + std::to_string(P) + ",) or (" + std::to_string(N) + ", " +
                       std::to_string(P) + ")");
    for (long i = 0; i < N; ++i) {
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> pi(poses.data() + i * P * A, P, A);
      const double* di = d.data() + (shared ? 0 : i * P);
      try {
        graphs.push_back(MakeGraph(pi, std::vector<double>(di, di + P), cyclic));
      } catch (const InputError& e) {
        throw InputError("trial " + std::to_string(i) + ": " + e.what());
      }
    }
  }
  for (size_t i = 0; i < graphs.size(); ++i) {
    const std::string error = graphs[i].Validate(A);
    if (!error.empty()) throw InputError("trial " + std::to_string(i) + ": " + error);
  }
  std::vector<synth::TrialOutcome> out;
  TrialResults r;
  // on a worker while this thread watches for Ctrl-C: the trials not started then are skipped
  // and KeyboardInterrupt says how many ran
  out = WithCtrlC([&] {
    const auto start = std::chrono::steady_clock::now();
    std::vector<synth::TrialOutcome> o = synth::RunTrials(problem, graphs, threads);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (InterruptRequested()) {
      long ran = 0;
      for (const synth::TrialOutcome& t : o) ran += t.failure != synth::kInterruptedTrial;
      throw Interrupted("run_trials stopped by Ctrl-C after " + std::to_string(ran) + " of " +
                        std::to_string(o.size()) + " trials");
    }
    return o;
  });
  const py::ssize_t N = py::ssize_t(out.size());
  r.cost = py::array_t<double>(N);
  r.distance = py::array_t<double>(N);
  r.speed = py::array_t<double>(N);
  r.energy = py::array_t<double>(N);
  r.ok = py::array_t<bool>(N);
  for (py::ssize_t i = 0; i < N; ++i) {
    r.cost.mutable_data()[i] = out[i].cost;
    r.distance.mutable_data()[i] = out[i].distance;
    r.speed.mutable_data()[i] = out[i].speed;
    r.energy.mutable_data()[i] = out[i].energy;
    r.ok.mutable_data()[i] = out[i].ok;
    r.failures.push_back(out[i].failure);
  }
  return r;
}

// The problem's body, of whichever dimension it has (None before one is set).
py::object ProblemBody(const synth::Problem& p) {
  if (p.body<3>()) return WrapBody(p.body<3>());
  if (p.body<2>()) return WrapBody(p.body<2>());
  return py::none();
}

}  // namespace

void BindSynth(py::module_& m) {
  py::class_<PoseGraph>(m, "PoseGraph",
                        "A pose-graph controller (§5.1): PD targets of the active modes, one row per pose, held\n"
                        "for each pose's duration, in a cycle when cyclic.")
      .def(py::init(&MakeGraph), py::arg("poses"), py::arg("durations"), py::arg("cyclic") = true,
           "poses: (P, active modes); durations: P transition times > 0")
      .def_property_readonly("poses", &PosesOf)
      .def_readonly("durations", &PoseGraph::durations)
      .def_readonly("cyclic", &PoseGraph::cyclic)
      .def_property_readonly("period", &PoseGraph::Period)
      .def("pose_at", &PoseGraph::PoseAt, py::arg("t"), "index of the pose active at time t");

  py::class_<synth::TrialOutcome>(m, "TrialOutcome", "One synthesis trial: its cost (Table 5.1) and what went into it.")
      .def_readonly("ok", &synth::TrialOutcome::ok)
      .def_readonly("distance", &synth::TrialOutcome::distance, "q_x: the centre of mass' travel along x")
      .def_readonly("speed", &synth::TrialOutcome::speed, "q̇_x at the end")
      .def_readonly("energy", &synth::TrialOutcome::energy, "control energy consumed")
      .def_readonly("cost", &synth::TrialOutcome::cost)
      .def_readonly("failure", &synth::TrialOutcome::failure);

  py::class_<Problem>(m, "SynthesisProblem",
                      "A body, its world and start state, the trial length and the cost: what `anneal` solves.\n"
                      "Get the one a script set up with Interpreter.synthesis_problem().")
      .def_property_readonly("body", &ProblemBody,
                             "the body, a BodyModel of dim 2 or 3; a 3D problem's q0, qd0 are [t, rotation "
                             "vector, γ], [ṫ, ω, γ̇]")
      .def_property_readonly(
          "body3",
          [](const Problem& p) {
            if (PyErr_WarnEx(PyExc_DeprecationWarning, "SynthesisProblem.body3 is deprecated: use SynthesisProblem.body",
                             1) < 0)
              throw py::error_already_set();
            return ProblemBody(p);
          },
          "deprecated: body")
      .def_readwrite("options", &Problem::world)
      .def_readwrite("q0", &Problem::q0)
      .def_readwrite("qd0", &Problem::qd0)
      .def_readwrite("steps", &Problem::steps, "steps of one trial (thesis: 1200 of 0.01)")
      .def_property_readonly("num_active", &NumActive, "active modes: the columns of a pose")
      .def("run", [](const Problem& p, const PoseGraph& g) {
        py::gil_scoped_release release;
        return synth::RunTrial(p, g);
      }, py::arg("graph"), "One trial.");

  py::class_<TrialResults>(m, "TrialResults", "The outcomes of a batch of trials, as arrays in input order.")
      .def_readonly("cost", &TrialResults::cost)
      .def_readonly("distance", &TrialResults::distance)
      .def_readonly("speed", &TrialResults::speed)
      .def_readonly("energy", &TrialResults::energy)
      .def_readonly("ok", &TrialResults::ok)
      .def_readonly("failures", &TrialResults::failures, "why each trial stopped ('' when it ran to the end)")
      .def_readonly("seconds", &TrialResults::seconds,
                    "wall time of the simulations alone, without the conversions (what Python adds is the rest)");

  m.def("run_trials", &RunTrials, py::arg("problem"), py::arg("graphs"), py::arg("durations") = py::none(),
        py::kw_only(), py::arg("cyclic") = true, py::arg("threads") = 0,
        "Simulates a batch of controllers from the problem's start, on `threads` threads (0: every\n"
        "core) with the GIL released: `graphs` is a list of PoseGraph, or an array (N, P, active modes)\n"
        "of poses with `durations` (P,) shared or (N, P). The same outcomes as one trial at a time.");

  py::class_<synth::AnnealResult>(m, "AnnealResult", "The best controller annealing found, and how it got there.")
      .def_readonly("best", &synth::AnnealResult::best)
      .def_readonly("best_outcome", &synth::AnnealResult::best_outcome)
      .def_readonly("initial_outcome", &synth::AnnealResult::initial_outcome)
      .def_readonly("trials", &synth::AnnealResult::trials)
      .def_readonly("interrupted", &synth::AnnealResult::interrupted)
      .def_property_readonly(
          "history",
          [](const synth::AnnealResult& r) {
            const std::vector<std::vector<double>> rows = synth::HistoryRows(r.history);
            Eigen::MatrixXd out(rows.size(), synth::HistoryHeader().size());
            for (size_t i = 0; i < rows.size(); ++i)
              for (size_t j = 0; j < rows[i].size(); ++j) out(i, j) = rows[i][j];
            return out;
          },
          "(iterations + 1, 7): iteration, trials, candidate, current, best, temperature, accepted");

  m.def(
      "anneal",
      [](const Problem& p, const PoseGraph& initial, std::uint64_t seed, int iterations, int batch, double cooling,
         const std::string& optimize, int threads, long max_steps) {
        synth::AnnealOptions o;
        o.seed = seed;
        o.iterations = iterations;
        o.batch = batch;
        o.cooling = cooling;
        o.threads = threads;
        if (!synth::ParseOptimize(optimize, &o.optimize)) throw InputError("optimize: '" + optimize + "' is not poses, times or both");
        const std::string error = o.Validate();
        if (!error.empty()) throw InputError("anneal: " + error);
        CheckedCount((double(iterations) * double(batch) + 1) * double(p.steps), 0, max_steps,
                     "anneal's trials x steps", "lower iterations or batch, or raise max_steps");
        return WithCtrlC([&] { return synth::Anneal(p, initial, o); });
      },
      py::arg("problem"), py::arg("initial"), py::kw_only(), py::arg("seed") = 1, py::arg("iterations") = 60,
      py::arg("batch") = 1, py::arg("cooling") = 0.9, py::arg("optimize") = "both", py::arg("threads") = 0,
      py::arg("max_steps") = Limits().max_steps,
      "Simulated annealing of a pose graph (Fig. 5.2), `batch` neighbours per iteration in parallel.\n"
      "The same seed gives the same result, on any number of threads. Ctrl-C ends it after the\n"
      "batch running then: the result has the best so far and interrupted = True.");

#ifdef WOBBLE_HAVE_PAGMO
  m.def(
      "cmaes",
      [](const Problem& p, const PoseGraph& initial, std::uint64_t seed, int generations, int population, double sigma0,
         const std::string& optimize, long max_steps) {
        synth::CmaesOptions o;
        o.seed = seed;
        o.generations = generations;
        o.population = population;
        o.sigma0 = sigma0;
        if (!synth::ParseOptimize(optimize, &o.optimize)) throw InputError("optimize: '" + optimize + "' is not poses, times or both");
        const std::string error = o.Validate();
        if (!error.empty()) throw InputError("cmaes: " + error);
        CheckedCount((double(generations) + 1) * double(population) * double(p.steps), 0, max_steps,
                     "cmaes' trials x steps", "lower generations or population, or raise max_steps");
        return WithCtrlC([&] { return synth::Cmaes(p, initial, o); });
      },
      py::arg("problem"), py::arg("initial"), py::kw_only(), py::arg("seed") = 1, py::arg("generations") = 60,
      py::arg("population") = 8, py::arg("sigma0") = 0.1, py::arg("optimize") = "both",
      py::arg("max_steps") = Limits().max_steps,
      "CMA-ES (pagmo2) over a pose graph's poses and times: the alternative to anneal, same result type\n"
      "(Ctrl-C: the best so far, interrupted = True).");
#endif
}

}  // namespace wobble::python
