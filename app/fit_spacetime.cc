// `wobble fit spacetime`: the PD targets of a whole motion (fit/spacetime.h) for a 2D or 3D
// object from its start, with the task given as flags; the targets go to a schedule file that a
// script plays with `schedule FILE` (formats/target_schedule.h).
#include <unistd.h>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>

#include "fit.h"
#include "progress.h"
#include "wobble/fit/spacetime.h"
#include "wobble/formats/atomic_file.h"
#include "wobble/formats/csv.h"
#include "wobble/formats/line_reader.h"
#include "wobble/formats/target_schedule.h"

namespace wobble::app {

namespace {

// A time of the run as its step, which must be a whole one.
int StepAt(double t, double dt, int steps, const std::string& flag) {
  const double n = t / dt;
  if (!(t >= 0.0) || std::abs(n - std::round(n)) > 1e-6 * std::max(1.0, n) || std::round(n) > steps)
    throw UsageError(flag + ": the time must be a whole number of steps of --dt within --duration");
  return int(std::round(n));
}

template <class Mode> std::vector<std::string> ModeNames(const std::vector<Mode>& modes) {
  std::vector<std::string> names;
  for (const Mode& m : modes) names.push_back(m.name);
  return names;
}

// The body's own gains, which the fitted targets drive (as a script's `schedule` plays them).
template <class Problem> void SetBounds(const FitSpacetimeArgs& a, int D, Problem* p) {
  p->knots = a.knots;
  p->lower = Eigen::VectorXd::Constant(D, -a.bound);
  p->upper = Eigen::VectorXd::Constant(D, a.bound);
  p->control_weight = a.effort;
}

// What the command's problem takes of each dimension's object: its body, where its centre of
// mass starts and how --reach reads.
template <int Dim> struct SpacetimeObject;
template <> struct SpacetimeObject<2> {
  static const BodyModel& Body(const StartingWorld& start) { return *start.body<2>(); }
  static Eigen::Vector2d CentreOfMass(const BodyModel& body, const BodyState<2, double>& s) {
    const MassMoments& mm = body.moments();
    const Eigen::VectorXd q0 = s.q;
    const int D = body.num_modes();
    return q0.head<2>() + Eigen::Rotation2Dd(q0[2]) * ((mm.c0 + mm.C * q0.tail(D)) / mm.m);
  }
  static constexpr const char* kReach = "--reach takes \"X Y T\" for a 2D object";
};
template <> struct SpacetimeObject<3> {
  static const BodyModelN<3>& Body(const StartingWorld& start) { return *start.body<3>(); }
  static Eigen::Vector3d CentreOfMass(const BodyModelN<3>& body, const BodyState<3, double>& s) {
    const MassMomentsN<3>& mm = body.moments();
    return s.translation() + s.orientation() * ((mm.c0 + mm.C * s.gamma()) / mm.m);
  }
  static constexpr const char* kReach = "--reach takes \"X Y Z T\" for a 3D object";
};

// The object's problem from the flags: --reach "X Y T" (3D "X Y Z T"); in 3D --upright leaves
// the heading free.
template <int Dim>
fit::SpacetimeResult FitOf(const FitSpacetimeArgs& a, const StartingWorld& start, const Eigen::MatrixXd& first_guess,
                           const fit::SpacetimeOptions& o, nlohmann::json* task) {
  using Object = SpacetimeObject<Dim>;
  using Vec = Eigen::Matrix<double, Dim, 1>;
  const BodyModelN<Dim>& body = Object::Body(start);
  const int steps = int(first_guess.cols()), D = body.num_modes();
  fit::SpacetimeProblemN<Dim> p;
  p.rollout.world = start.options.params;
  p.rollout.integrator = Integrator::kThesis;
  p.rollout.dt = a.dt;
  p.rollout.start = StateFromCoordinates<Dim>(start.q0, start.qd0);
  body.ModeGains(&p.rollout.stiffness, &p.rollout.damping);
  p.rollout.targets = first_guess;
  SetBounds(a, D, &p);
  std::vector<fit::StageCostN<Dim>> terms;
  const Vec com0 = Object::CentreOfMass(body, p.rollout.start);
  if (!a.rise.empty()) {
    const std::vector<double> v = ParseNumbers(a.rise, "--rise");
    if (v.size() != 2) throw UsageError("--rise takes \"DY T\"");
    fit::Axes y_only;
    y_only.x = y_only.z = false;
    const int top = StepAt(v[1], a.dt, steps, "--rise");
    Vec height = Vec::Zero();
    height.y() = com0.y() + v[0];
    terms.push_back(fit::CentreOfMassAt(body, top, height, a.weight, y_only));
    // at the top: not rising any more (a velocity of 1 weighs as a height of 0.1)
    terms.push_back(fit::CentreOfMassVelocityAt(body, top, Vec::Zero(), 0.01 * a.weight, y_only));
    (*task)["rise"] = {{"dy", v[0]}, {"t", v[1]}};
  }
  if (!a.reach.empty()) {
    const std::vector<double> v = ParseNumbers(a.reach, "--reach");
    if (v.size() != size_t(Dim + 1)) throw UsageError(Object::kReach);
    const Vec goal = Eigen::Map<const Vec>(v.data());
    terms.push_back(fit::CentreOfMassAt(body, StepAt(v[Dim], a.dt, steps, "--reach"), goal, a.weight));
    (*task)["reach"] = {{"x", v[0]}, {"y", v[1]}, {"t", v[Dim]}};
    if (Dim == 3) (*task)["reach"]["z"] = v[2];
  }
  if (a.upright) terms.push_back(fit::UprightAt<Dim>(steps, a.weight, 0.1)), (*task)["upright"] = true;
  if (a.still) terms.push_back(fit::StillAt<Dim>(steps, a.weight)), (*task)["still"] = true;
  p.task = fit::SumOf(terms);
  return fit::FitSpacetime(body, p, o);
}

}  // namespace

CLI::App* AddFitSpacetimeCommand(CLI::App* fit, FitSpacetimeArgs* a) {
  CLI::App* c = fit->add_subcommand("spacetime", "Fit the PD targets of a whole motion to a task (2D or 3D; README: Gradients)");
  AddBodyFlags(c, &a->files);
  AddWorldFlags(c, &a->world);
  c->add_option("--q", a->q, "Start q \"tx ty theta g1 ..\" (3D: \"tx ty tz rx ry rz g1 ..\"; default: rest at the origin)")->type_name("\"NUMS\"");
  c->add_option("--qdot", a->qdot, "Start q-dot (default 0)")->type_name("\"NUMS\"");
  c->add_option("--dt", a->dt, "Time step (thesis integrator)")->capture_default_str();
  c->add_option("--duration", a->duration, "Length of the motion, seconds")->capture_default_str();
  c->add_option("--knots", a->knots, "Targets at this many evenly spaced knots, linear between")->capture_default_str();
  c->add_option("--rise", a->rise, "Task: the centre of mass at the top of a rise of DY above its start at time T")
      ->type_name("\"DY T\"");
  c->add_option("--reach", a->reach, "Task: the centre of mass at (X, Y) at time T (3D: \"X Y Z T\")")->type_name("\"X Y T\"");
  c->add_flag("--upright", a->upright, "Task: upright and not turning at the end");
  c->add_flag("--still", a->still, "Task: at rest at the end");
  c->add_option("--weight", a->weight, "Weight of every task term")->capture_default_str();
  c->add_option("--bound", a->bound, "Every target within +-BOUND")->capture_default_str();
  c->add_option("--effort", a->effort, "Weight of the control energy (sum of squared targets x dt)")->capture_default_str();
  c->add_option("--max-iterations", a->max_iterations, "L-BFGS iterations (of each start)")->capture_default_str();
  c->add_option("--starts", a->starts,
                "Multi-start: descend from this many first guesses, the given one and the rest perturbed at random; "
                "the lowest cost wins")
      ->capture_default_str()->check(CLI::PositiveNumber);
  c->add_option("--start-spread", a->start_spread,
                "Perturbation of the further starts (standard deviation on each knot's logistic coordinate: 1 moves "
                "a mid-range target by about a quarter of the bounds' span)")
      ->capture_default_str()->check(CLI::NonNegativeNumber);
  c->add_option("--seed", a->seed, "Seed of the perturbations (a fit repeats exactly)")->capture_default_str();
  c->add_option("--threads", a->threads, "Threads sharing the starts (0: every core)")->capture_default_str();
  c->add_option("--start", a->start, "Start from these targets (a --targets file of the same object and --dt; "
                                     "default zero): continue from an easier task's solution")
      ->type_name("FILE.csv");
  c->add_option("--targets", a->targets, "The fitted targets of every step, for `schedule` (written atomically)")
      ->type_name("FILE.csv");
  c->add_option("--out", a->out, "Result JSON (written atomically)")->type_name("FILE.json");
  c->footer(
      "Example (a hop from a standing start; data/hop.wob plays and draws it):\n"
      "  wobble fit spacetime --object data/table.obj --modes data/hop_modes.def --ground-stiffness 45000 \\\n"
      "      --ground-damping 3000 --friction-damping 3000 --friction-cap 0.5 --duration 1 --knots 21 \\\n"
      "      --rise \"2 0.7\" --upright --targets out/hop_targets.csv --out out/hop_fit.json");
  return c;
}

int RunFitSpacetime(const FitSpacetimeArgs& a) {
  RequirePositive(a.dt, "--dt");
  RequirePositive(a.duration, "--duration");
  RequirePositive(a.weight, "--weight");
  RequirePositive(a.bound, "--bound");
  RequireNonNegative(a.effort, "--effort");
  if (a.max_iterations < 1) throw UsageError("--max-iterations must be at least 1");
  if (a.rise.empty() && a.reach.empty() && !a.upright && !a.still)
    throw UsageError("no task: give --rise, --reach, --upright and/or --still");
  CheckOutputFile("--targets", a.targets);
  CheckOutputFile("--out", a.out);
  const StartingWorld start = LoadStartingWorld(a.files, a.q, a.qdot, a.world, Integrator::kThesis, a.dt);
  const int steps = int(std::lround(a.duration / a.dt));
  if (steps < 1)
    throw UsageError("--duration " + formats::detail::FormatNumber(a.duration) + " is shorter than half a step (--dt " +
                     formats::detail::FormatNumber(a.dt) + "): there is no step to fit");
  const std::vector<std::string> names = start.OnBody([](const auto& body) { return ModeNames(body.modes()); });
  const int D = int(names.size());
  if (D == 0) throw UsageError("the object has no modes to control (--modes)");
  if (a.knots < 2 || a.knots > steps + 1)
    throw UsageError("--knots must be from 2 to " + std::to_string(steps + 1) + " (the steps + 1)");

  // the first guess: zero, or a schedule's steps with its last one held past its end
  Eigen::MatrixXd first_guess = Eigen::MatrixXd::Zero(D, steps);
  if (!a.start.empty()) {
    const Eigen::MatrixXd given = formats::ReadTargetSchedule(a.start, names, a.dt);
    for (int n = 0; n < steps; ++n) first_guess.col(n) = given.col(std::min<Eigen::Index>(n, given.cols() - 1));
  }
  fit::SpacetimeOptions o;
  o.max_iterations = a.max_iterations;
  o.starts = a.starts;
  o.start_spread = a.start_spread;
  o.seed = a.seed;
  o.threads = a.threads;
  Progress bar(isatty(STDERR_FILENO) == 1, "best cost");
  if (a.starts == 1) {
    o.on_iteration = IterationLine();
  } else {
    o.on_start = [&bar](int done, int starts, double best) { bar.Update(double(done) / starts, best); };
  }
  nlohmann::json task;
  const fit::SpacetimeResult r = start.dim() == 3 ? FitOf<3>(a, start, first_guess, o, &task) : FitOf<2>(a, start, first_guess, o, &task);
  if (a.starts == 1) EndIterationLine();
  bar.Finish();
  const std::string body_name = start.OnBody([](const auto& body) { return body.name(); });

  if (!a.targets.empty()) formats::WriteTargetSchedule(a.targets, names, a.dt, r.targets);
  nlohmann::json j;
  j["kind"] = "spacetime";
  j["body"] = body_name;
  j["modes"] = names;
  j["dt"] = a.dt;
  j["steps"] = steps;
  j["task"] = task;
  j["ok"] = r.ok;
  j["message"] = r.message;
  j["initial_cost"] = r.initial_cost;
  j["cost"] = r.cost;
  j["control_energy"] = r.control_energy;
  j["iterations"] = r.iterations;
  j["gradients"] = r.gradients;
  if (a.starts > 1) {
    j["starts"] = {{"count", a.starts}, {"spread", a.start_spread}, {"seed", a.seed}, {"best", r.best_start},
                   {"costs", r.start_costs}};
  }
  j["knots"] = nlohmann::json::array();
  for (int k = 0; k < r.knots.cols(); ++k) {
    nlohmann::json col = nlohmann::json::array();
    for (int d = 0; d < D; ++d) col.push_back(r.knots(d, k));
    j["knots"].push_back(col);
  }
  if (!a.out.empty()) formats::WriteTextAtomically(a.out, j.dump(2) + "\n");
  std::cout << body_name << ": spacetime fit of " << D << " x " << a.knots << " knot targets over " << steps
            << " steps: " << r.message << "\ncost " << r.initial_cost << " -> " << r.cost << " (control energy "
            << r.control_energy << ") with " << r.gradients << " gradients.";
  if (a.starts > 1) std::cout << "\nbest of " << a.starts << " starts: start " << r.best_start;
  if (!a.targets.empty()) std::cout << "\ntargets: " << a.targets << " (a script plays them with `schedule`)";
  std::cout << std::endl;
  if (!r.ok) {
    std::cerr << "wobble: the spacetime fit failed: " << r.message << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace wobble::app
