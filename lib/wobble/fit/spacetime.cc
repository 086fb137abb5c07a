#include "wobble/fit/spacetime.h"

#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <mutex>
#include <random>
#include <stdexcept>

#include "wobble/core/parallel.h"

namespace wobble::fit {

namespace {

// Step n lies between knots j and j + 1 with weight f on j + 1.
void KnotWeights(int n, int steps, int knots, int* j, double* f) {
  const double u = double(n) * (knots - 1) / steps;
  *j = std::min(int(u), knots - 2);
  *f = u - *j;
}

double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// The problem's cost at these knots: one plain simulation, +inf when it fails.
template <int Dim>
double CostAtKnots(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem, const Eigen::MatrixXd& knots) {
  ControlledRolloutN<Dim> r = problem.rollout;
  r.targets = KnotTargets(knots, r.steps());
  return RolloutCost(body, r, problem.task) + problem.control_weight * r.dt * r.targets.squaredNorm();
}

template <int Dim> void CheckProblem(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& p) {
  const int D = body.num_modes(), steps = p.rollout.steps();
  auto fail = [](const std::string& what) { throw std::invalid_argument("spacetime fit: " + what); };
  if (D == 0) fail("the body has no modes to control");
  if (steps < 1) fail("the rollout needs at least one step (its targets' columns)");
  if (p.knots < 2 || p.knots > steps + 1) fail("knots must be from 2 to steps + 1 (" + std::to_string(steps + 1) + ")");
  if (p.lower.size() != D || p.upper.size() != D) fail("lower and upper need one bound per mode");
  for (int d = 0; d < D; ++d)
    if (!(p.lower[d] < p.upper[d]) || !std::isfinite(p.lower[d]) || !std::isfinite(p.upper[d]))
      fail("mode '" + body.modes()[d].name + "': the bounds must be finite with lower < upper");
  if (!(p.control_weight >= 0.0) || !std::isfinite(p.control_weight)) fail("the control weight must be >= 0");
  if (!p.task) fail("no task cost");
}

// The cost as Ceres sees it: x (modes × knots, column-major) → knots → targets → rollout.
template <int Dim> class SpacetimeCost final : public ceres::FirstOrderFunction {
 public:
  SpacetimeCost(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& p, long* evaluations)
      : body_(body), p_(p), rollout_(p.rollout), evaluations_(evaluations) {}

  int NumParameters() const override { return int(p_.lower.size()) * p_.knots; }

  Eigen::MatrixXd Knots(const double* x) const {
    const int D = int(p_.lower.size());
    Eigen::MatrixXd k(D, p_.knots);
    for (int j = 0; j < p_.knots; ++j)
      for (int d = 0; d < D; ++d) k(d, j) = p_.lower[d] + (p_.upper[d] - p_.lower[d]) * Logistic(x[j * D + d]);
    return k;
  }

  double ControlEnergy(const Eigen::MatrixXd& targets) const {
    return p_.control_weight * rollout_.dt * targets.squaredNorm();
  }

  bool Evaluate(const double* x, double* cost, double* gradient) const override {
    const int D = int(p_.lower.size()), steps = rollout_.steps();
    ++*evaluations_;
    if (!gradient) {
      *cost = CostAtKnots(body_, p_, Knots(x));
      return std::isfinite(*cost);
    }
    rollout_.targets = KnotTargets(Knots(x), steps);
    const RolloutGradient g = RolloutCostGradient(body_, rollout_, p_.task);
    if (!g.ok) return false;  // the line search steps back
    *cost = g.cost + ControlEnergy(rollout_.targets);
    const Eigen::MatrixXd g_targets = g.targets + (2.0 * p_.control_weight * rollout_.dt) * rollout_.targets;
    Eigen::Map<Eigen::MatrixXd> g_x(gradient, D, p_.knots);
    g_x.setZero();
    for (int n = 0; n < steps; ++n) {
      int j;
      double f;
      KnotWeights(n, steps, p_.knots, &j, &f);
      g_x.col(j) += (1.0 - f) * g_targets.col(n);
      g_x.col(j + 1) += f * g_targets.col(n);
    }
    // chain rule through knot = lo + (hi − lo) σ(x)
    for (int j = 0; j < p_.knots; ++j)
      for (int d = 0; d < D; ++d) {
        const double s = Logistic(x[j * D + d]);
        g_x(d, j) *= (p_.upper[d] - p_.lower[d]) * s * (1.0 - s);
      }
    return std::isfinite(*cost);
  }

 private:
  const BodyModelN<Dim>& body_;
  const SpacetimeProblemN<Dim>& p_;
  mutable ControlledRolloutN<Dim> rollout_;  // its targets are each evaluation's
  long* evaluations_;
};

class Progress final : public ceres::IterationCallback {
 public:
  explicit Progress(const SpacetimeOptions& o) : o_(o) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (o_.on_iteration) o_.on_iteration(s.iteration, s.cost);
    return ceres::SOLVER_CONTINUE;
  }

 private:
  const SpacetimeOptions& o_;
};

}  // namespace

Eigen::MatrixXd KnotTargets(const Eigen::MatrixXd& knots, int steps) {
  if (knots.cols() < 2 || steps < 1) throw std::invalid_argument("KnotTargets: needs two knots and a step");
  Eigen::MatrixXd targets(knots.rows(), steps);
  for (int n = 0; n < steps; ++n) {
    int j;
    double f;
    KnotWeights(n, steps, int(knots.cols()), &j, &f);
    targets.col(n) = (1.0 - f) * knots.col(j) + f * knots.col(j + 1);
  }
  return targets;
}

namespace {


// One L-BFGS descent from x (the logistic coordinates of the knots); `progress` may be null.
template <int Dim>
SpacetimeResult DescendFrom(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem, int max_iterations,
                            Eigen::VectorXd x, ceres::IterationCallback* progress) {
  SpacetimeResult r;
  auto* cost = new SpacetimeCost<Dim>(body, problem, &r.gradients);
  ceres::GradientProblem ceres_problem(cost);  // owns cost
  double first = 0.0;
  if (!cost->Evaluate(x.data(), &first, nullptr)) {
    r.message = "the rollout of the first guess failed";
    return r;
  }
  r.initial_cost = first;
  ceres::GradientProblemSolver::Options o;
  o.line_search_direction_type = ceres::LBFGS;
  o.max_num_iterations = max_iterations;
  // the logistic map flattens near a bound: Ceres' default tolerances (1e-6 on the cost's
  // relative change) stop there long before the optimum
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-14;  // x starts at 0 (targets mid-range): a relative test stops at once
  o.logging_type = ceres::SILENT;
  if (progress) o.callbacks.push_back(progress);
  ceres::GradientProblemSolver::Summary summary;
  ceres::Solve(o, ceres_problem, x.data(), &summary);
  r.knots = cost->Knots(x.data());
  r.targets = KnotTargets(r.knots, problem.rollout.steps());
  r.control_energy = cost->ControlEnergy(r.targets);
  r.cost = summary.final_cost;
  r.iterations = int(summary.iterations.size());
  r.message = summary.BriefReport();
  r.ok = summary.IsSolutionUsable();
  return r;
}

}  // namespace

template <int Dim>
SpacetimeResult FitSpacetime(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem,
                             const SpacetimeOptions& options) {
  CheckProblem(body, problem);
  if (options.starts < 1) throw std::invalid_argument("spacetime fit: starts must be >= 1");
  if (!(options.start_spread >= 0.0) || !std::isfinite(options.start_spread))
    throw std::invalid_argument("spacetime fit: the start spread must be >= 0");
  const int D = body.num_modes(), steps = problem.rollout.steps();
  // the first guess: the given targets at the knots, kept inside the bounds
  Eigen::VectorXd x0(D * problem.knots);
  for (int j = 0; j < problem.knots; ++j) {
    const int n = std::min(steps - 1, int(std::lround(double(j) * steps / (problem.knots - 1))));
    for (int d = 0; d < D; ++d) {
      const double span = problem.upper[d] - problem.lower[d];
      const double s = std::clamp((problem.rollout.targets(d, n) - problem.lower[d]) / span, 1e-3, 1.0 - 1e-3);
      x0[j * D + d] = std::log(s / (1.0 - s));
    }
  }
  if (options.starts == 1) {
    Progress progress(options);
    return DescendFrom(body, problem, options.max_iterations, x0, &progress);
  }
  // Multi-start: start k perturbs the first guess by its own seeded generator, so the result
  // does not depend on which thread ran which start.
  std::vector<SpacetimeResult> runs(size_t(options.starts));
  std::mutex done_mutex;
  int done = 0;
  double best = std::numeric_limits<double>::infinity();
  ParallelFor(runs.size(), options.threads, [&](size_t k) {
    Eigen::VectorXd x = x0;
    if (k > 0) {
      std::seed_seq seq{uint64_t(options.seed), uint64_t(k)};
      std::mt19937_64 generator(seq);
      std::normal_distribution<double> normal(0.0, options.start_spread);
      for (Eigen::Index i = 0; i < x.size(); ++i) x[i] += normal(generator);
    }
    runs[k] = DescendFrom(body, problem, options.max_iterations, x, nullptr);
    std::lock_guard<std::mutex> lock(done_mutex);
    ++done;
    if (runs[k].ok) best = std::min(best, runs[k].cost);
    if (options.on_start) options.on_start(done, options.starts, best);
  });
  // the lowest usable cost wins; ties go to the lower start index
  size_t winner = 0;
  for (size_t k = 1; k < runs.size(); ++k)
    if (runs[k].ok && (!runs[winner].ok || runs[k].cost < runs[winner].cost)) winner = k;
  SpacetimeResult r = runs[winner];
  r.best_start = int(winner);
  r.initial_cost = runs[0].initial_cost;  // the given first guess's
  r.gradients = 0;
  r.start_costs.clear();
  for (const SpacetimeResult& run : runs) {
    r.gradients += run.gradients;
    r.start_costs.push_back(run.ok ? run.cost : std::numeric_limits<double>::quiet_NaN());
  }
  return r;
}

template <int Dim>
double SpacetimeCostOf(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem, const Eigen::MatrixXd& knots) {
  return CostAtKnots(body, problem, knots);
}

template double SpacetimeCostOf<2>(const BodyModelN<2>&, const SpacetimeProblemN<2>&, const Eigen::MatrixXd&);
template double SpacetimeCostOf<3>(const BodyModelN<3>&, const SpacetimeProblemN<3>&, const Eigen::MatrixXd&);
template SpacetimeResult FitSpacetime<2>(const BodyModelN<2>&, const SpacetimeProblemN<2>&, const SpacetimeOptions&);
template SpacetimeResult FitSpacetime<3>(const BodyModelN<3>&, const SpacetimeProblemN<3>&, const SpacetimeOptions&);

}  // namespace wobble::fit
