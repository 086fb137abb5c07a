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

void CheckProblem(const BodyModel& body, const SpacetimeProblem& p) {
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
class SpacetimeCost final : public ceres::FirstOrderFunction {
 public:
  SpacetimeCost(const BodyModel& body, const SpacetimeProblem& p, long* evaluations)
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
      *cost = SpacetimeCostOf(body_, p_, Knots(x));
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
  const BodyModel& body_;
  const SpacetimeProblem& p_;
  mutable ControlledRollout rollout_;  // its targets are each evaluation's
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

void CheckTerm(int step, double weight, const char* what) {
  if (step < 0) throw std::invalid_argument(std::string(what) + ": the step must be >= 0");
  if (!(weight >= 0.0) || !std::isfinite(weight)) throw std::invalid_argument(std::string(what) + ": the weight must be >= 0");
}

}  // namespace

StageCost CentreOfMassAt(const BodyModel& body, int step, const Eigen::Vector2d& goal, double weight, Axes axes) {
  CheckTerm(step, weight, "CentreOfMassAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassAt: the goal must be finite");
  const MassMoments mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const Eigen::VectorXd& q, const Eigen::VectorXd&, Eigen::VectorXd* dq,
                                        Eigen::VectorXd*) {
    if (n != step) return 0.0;
    const int D = int(q.size()) - kRigidDofs;
    const Eigen::Vector2d c = (mm.c0 + mm.C * q.tail(D)) / mm.m;  // body frame
    const Eigen::Rotation2Dd R(q[2]);
    const Eigen::Vector2d Rc = R * c, x = q.head<2>() + Rc;
    Eigen::Vector2d miss = x - goal;
    if (!axes.x) miss.x() = 0.0;
    if (!axes.y) miss.y() = 0.0;
    const Eigen::Vector2d r = weight * miss;
    dq->head<2>() += r;                                 // ∂x/∂t = I
    (*dq)[2] += r.y() * Rc.x() - r.x() * Rc.y();        // ∂x/∂θ = S R c
    dq->tail(D) += mm.C.transpose() * (R.inverse() * r) / mm.m;  // ∂x/∂γ = R C / m
    return 0.5 * weight * miss.squaredNorm();
  };
}

StageCost CentreOfMassVelocityAt(const BodyModel& body, int step, const Eigen::Vector2d& goal, double weight,
                                 Axes axes) {
  CheckTerm(step, weight, "CentreOfMassVelocityAt");
  if (!goal.allFinite()) throw std::invalid_argument("CentreOfMassVelocityAt: the goal must be finite");
  const MassMoments mm = body.moments();
  return [mm, step, goal, weight, axes](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                        Eigen::VectorXd* dq, Eigen::VectorXd* dqd) {
    if (n != step) return 0.0;
    const int D = int(q.size()) - kRigidDofs;
    Eigen::Matrix2d S;
    S << 0.0, -1.0, 1.0, 0.0;
    const Eigen::Matrix2d R = Eigen::Rotation2Dd(q[2]).toRotationMatrix();
    const Eigen::Vector2d c = (mm.c0 + mm.C * q.tail(D)) / mm.m, cd = mm.C * qd.tail(D) / mm.m;
    const double thd = qd[2];
    const Eigen::Vector2d v = qd.head<2>() + thd * (S * R * c) + R * cd;
    Eigen::Vector2d miss = v - goal;
    if (!axes.x) miss.x() = 0.0;
    if (!axes.y) miss.y() = 0.0;
    const Eigen::Vector2d r = weight * miss;
    // ∂v/∂ṫ = I, ∂v/∂θ̇ = S R c, ∂v/∂γ̇ = R C/m; ∂v/∂θ = θ̇ S S R c + S R ċ, ∂v/∂γ = θ̇ S R C/m
    dqd->head<2>() += r;
    (*dqd)[2] += r.dot(S * R * c);
    dqd->tail(D) += mm.C.transpose() * (R.transpose() * r) / mm.m;
    (*dq)[2] += r.dot(thd * (S * S * R * c) + S * R * cd);
    dq->tail(D) += thd * mm.C.transpose() * ((S * R).transpose() * r) / mm.m;
    return 0.5 * weight * miss.squaredNorm();
  };
}

StageCost UprightAt(int step, double weight, double time_scale) {
  CheckTerm(step, weight, "UprightAt");
  if (!(time_scale >= 0.0) || !std::isfinite(time_scale)) throw std::invalid_argument("UprightAt: the time scale must be >= 0");
  return [step, weight, time_scale](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* dq,
                                    Eigen::VectorXd* dqd) {
    if (n != step) return 0.0;
    const double s2 = time_scale * time_scale;
    (*dq)[2] += weight * q[2];
    (*dqd)[2] += weight * s2 * qd[2];
    return 0.5 * weight * (q[2] * q[2] + s2 * qd[2] * qd[2]);
  };
}

StageCost StillAt(int step, double weight) {
  CheckTerm(step, weight, "StillAt");
  return [step, weight](int n, const Eigen::VectorXd&, const Eigen::VectorXd& qd, Eigen::VectorXd*, Eigen::VectorXd* dqd) {
    if (n != step) return 0.0;
    *dqd += weight * qd;
    return 0.5 * weight * qd.squaredNorm();
  };
}

StageCost SumOf(std::vector<StageCost> terms) {
  for (const StageCost& t : terms)
    if (!t) throw std::invalid_argument("SumOf: an empty term");
  return [terms = std::move(terms)](int n, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::VectorXd* dq,
                                     Eigen::VectorXd* dqd) {
    double total = 0.0;
    for (const StageCost& t : terms) total += t(n, q, qd, dq, dqd);
    return total;
  };
}

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

double SpacetimeCostOf(const BodyModel& body, const SpacetimeProblem& problem, const Eigen::MatrixXd& knots) {
  ControlledRollout r = problem.rollout;
  r.targets = KnotTargets(knots, r.steps());
  return RolloutCost(body, r, problem.task) + problem.control_weight * r.dt * r.targets.squaredNorm();
}

namespace {

// One L-BFGS descent from x (the logistic coordinates of the knots); `progress` may be null.
SpacetimeResult DescendFrom(const BodyModel& body, const SpacetimeProblem& problem, int max_iterations,
                            Eigen::VectorXd x, ceres::IterationCallback* progress) {
  SpacetimeResult r;
  auto* cost = new SpacetimeCost(body, problem, &r.gradients);
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

SpacetimeResult FitSpacetime(const BodyModel& body, const SpacetimeProblem& problem, const SpacetimeOptions& options) {
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

}  // namespace wobble::fit
