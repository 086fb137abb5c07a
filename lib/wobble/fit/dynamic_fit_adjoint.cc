// The dynamic fit on the adjoint gradient (issue 18): the fit's cost as a rollout of
// fit/adjoint.h with a stage cost at every frame's step, minimised by Ceres' BFGS line search.
#include <ceres/gradient_problem.h>
#include <ceres/gradient_problem_solver.h>

#include <algorithm>
#include <chrono>

#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"
#include "wobble/fit/adjoint.h"
#include "wobble/fit/internal/dynamic_problem.h"
#include "wobble/fit/internal/solve_common.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble::fit::internal {

namespace {

double Logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }

constexpr double kLeastZeta = 1e-4;

// ½ Σ w |x_i(q_n) − target|² over the frames at step n, and its gradient in q: with
// x = t + R(θ) l (Eq. 4.2) and r = w (x − target), ∂/∂t = r, ∂/∂θ = rᵀ J (x − t) (J the
// quarter turn) and ∂/∂γ = Bᵀ Rᵀ r.
struct FrameCost {
  const Reference<2>* ref;
  std::vector<std::vector<int>> frames_at;  // step → frames observed there

  double operator()(int n, const Eigen::VectorXd& q, Eigen::VectorXd* dq) const {
    if (n >= int(frames_at.size())) return 0.0;
    const int D = int(q.size()) - 3;
    const Eigen::Rotation2Dd R(q[2]);
    const Eigen::Matrix2d Rm = R.toRotationMatrix();
    double cost = 0.0;
    for (int f : frames_at[n])
      for (const auto& p : ref->points[f]) {
        const Eigen::Vector2d x = PointPosition(p.basis, q.data(), int(q.size()));
        const double w = p.sqrt_weight * p.sqrt_weight;
        const Eigen::Vector2d r = w * (x - p.target);
        cost += 0.5 * w * (x - p.target).squaredNorm();
        const Eigen::Vector2d arm = x - q.head<2>();
        dq->head<2>() += r;
        (*dq)[2] += r.y() * arm.x() - r.x() * arm.y();
        if (D > 0) dq->tail(D) += p.basis.B.transpose() * (Rm.transpose() * r);
      }
    return cost;
  }
};

// The fit's free numbers as one vector x for Ceres' line search, in the order q0, q̇0, log K,
// u (ζ = u², smooth through 0; a ζ that starts at 0 starts at kLeastZeta, since u = 0 has no
// gradient), poses, y (log τ = lo + (hi − lo) σ(y)); the fixed ones stay at the start's.
// Each is divided by a scale that moves the body's points by about one length unit
// (SmoothnessScales; velocities over the motion's duration): L-BFGS starts from a multiple
// of the identity, and unscaled (positions of 100, mode amplitudes of 0.1) it stalls far
// from the optimum.
class AdjointDynamicCost final : public ceres::FirstOrderFunction {
 public:
  AdjointDynamicCost(const BodyModel& body, const Reference<2>& ref, const Blocks<2>& start, const VecD<double>& G,
                     const DynamicFitOptions& o, long* simulations)
      : body_(body), ref_(ref), start_(start), G_(G), o_(o), simulations_(simulations) {
    cost_.ref = &ref;
    cost_.frames_at.resize(ref.steps.back() + 1);
    for (size_t f = 0; f < ref.steps.size(); ++f) cost_.frames_at[ref.steps[f]].push_back(int(f));
    rollout_.world = o.world;
    rollout_.integrator = Integrator::kThesis;
    rollout_.dt = o.dt;
    log_lo_ = std::log(o.min_time);
    log_hi_ = std::log(o.max_time);
    const VecQ<double> L = SmoothnessScales(body);
    const double duration = ref.steps.back() * o.dt;
    const std::vector<int> active = control::ActiveModes(body);
    const int nq = body.num_q(), D = body.num_modes();
    for (int i = 0; o.fit_q0 && i < nq; ++i) scale_.push_back(1.0 / L[i]);
    for (int i = 0; o.fit_qd0 && i < nq; ++i) scale_.push_back(1.0 / (L[i] * duration));
    for (int d = 0; o.fit_stiffness && d < D; ++d) scale_.push_back(1.0);
    for (int d = 0; o.fit_damping && d < D; ++d) scale_.push_back(1.0);
    for (size_t i = 0; o.fit_poses && i < start.poses.size(); ++i)
      scale_.push_back(1.0 / L[kRigidDofs + active[i % active.size()]]);
    for (size_t i = 0; o.fit_times && i < start.log_times.size(); ++i) scale_.push_back(1.0);
  }

  int NumParameters() const override { return int(scale_.size()); }

  // x from the blocks, and back
  Eigen::VectorXd ToX(const Blocks<2>& b) const {
    std::vector<double> v;
    auto take = [&](bool free, const std::vector<double>& block) {
      if (free) v.insert(v.end(), block.begin(), block.end());
    };
    take(o_.fit_q0, b.q0);
    take(o_.fit_qd0, b.qd0);
    take(o_.fit_stiffness, b.log_k);
    if (o_.fit_damping)
      for (double z : b.zeta) v.push_back(std::sqrt(std::max(z, kLeastZeta)));
    take(o_.fit_poses, b.poses);
    if (o_.fit_times)
      for (double lt : b.log_times) {
        const double s = std::clamp((lt - log_lo_) / (log_hi_ - log_lo_), 1e-9, 1.0 - 1e-9);
        v.push_back(std::log(s / (1.0 - s)));
      }
    Eigen::VectorXd x(v.size());
    for (size_t i = 0; i < v.size(); ++i) x[Eigen::Index(i)] = v[i] / scale_[i];
    return x;
  }
  Blocks<2> FromX(const double* x) const {
    Blocks<2> b = start_;
    int k = 0;
    auto give = [&](bool free, std::vector<double>* block) {
      if (free)
        for (double& e : *block) e = x[k] * scale_[k], ++k;
    };
    give(o_.fit_q0, &b.q0);
    give(o_.fit_qd0, &b.qd0);
    give(o_.fit_stiffness, &b.log_k);
    give(o_.fit_damping, &b.zeta);
    if (o_.fit_damping)
      for (double& u : b.zeta) u = u * u;
    give(o_.fit_poses, &b.poses);
    if (o_.fit_times)
      for (double& lt : b.log_times) lt = log_lo_ + (log_hi_ - log_lo_) * Logistic(x[k] * scale_[k]), ++k;
    return b;
  }

  bool Evaluate(const double* x, double* cost, double* gradient) const override {
    const int D = body_.num_modes(), steps = ref_.steps.back();
    const DynamicParameters p = FromX(x).To(G_);
    rollout_.q0 = p.q0;
    rollout_.qd0 = p.qd0;
    rollout_.stiffness = p.stiffness;
    rollout_.damping = p.damping;
    rollout_.targets = Eigen::MatrixXd::Zero(D, steps);
    if (!p.graph.empty()) {
      const auto c = control::PoseGraphOf<double>::From(body_, p.graph);
      for (int n = 0; n < steps; ++n) rollout_.targets.col(n) = control::SmoothPoseTargets(c, D, n * o_.dt, o_.switch_width);
    }
    const StageCost stage = [this](int n, const Eigen::VectorXd& q, const Eigen::VectorXd&, Eigen::VectorXd* dq,
                                   Eigen::VectorXd*) { return cost_(n, q, dq); };
    ++*simulations_;
    if (!gradient) {
      *cost = RolloutCost(body_, rollout_, stage);
      return std::isfinite(*cost);
    }
    const RolloutGradient g = RolloutCostGradient(body_, rollout_, stage);
    if (!g.ok) return false;  // the line search steps back
    *cost = g.cost;
    int k = 0;
    auto put = [&](bool free, const Eigen::VectorXd& v) {
      if (free)
        for (int i = 0; i < v.size(); ++i) gradient[k++] = v[i];
    };
    put(o_.fit_q0, g.q0);
    put(o_.fit_qd0, g.qd0);
    // K = e^{log K}, c = ζ 2 sqrt(2 G K): ∂c/∂log K = c / 2, ∂c/∂ζ = 2 sqrt(2 G K)
    Eigen::VectorXd g_log_k(D), g_u(D);  // g_u: ∂/∂ζ here, times ∂ζ/∂u = 2u below
    for (int d = 0; d < D; ++d) {
      g_log_k[d] = g.stiffness[d] * p.stiffness[d] + g.damping[d] * 0.5 * p.damping[d];
      g_u[d] = g.damping[d] * 2.0 * std::sqrt(2.0 * G_[d] * p.stiffness[d]);
    }
    put(o_.fit_stiffness, g_log_k);
    if (o_.fit_damping)
      for (int d = 0; d < D; ++d) {
        gradient[k] = g_u[d] * 2.0 * x[k] * scale_[k];
        ++k;
      }
    if (o_.fit_poses || o_.fit_times) {
      const PoseGraphGradient pg = PoseGraphGradientOf(body_, p.graph, o_.dt, o_.switch_width, g.targets);
      if (o_.fit_poses)
        for (const Eigen::VectorXd& pose : pg.poses) put(true, pose);
      if (o_.fit_times)
        for (size_t i = 0; i < pg.durations.size(); ++i) {
          const double s = Logistic(x[k] * scale_[k]);
          gradient[k++] = pg.durations[i] * p.graph.durations[i] * (log_hi_ - log_lo_) * s * (1.0 - s);
        }
    }
    for (int i = 0; i < k; ++i) gradient[i] *= scale_[i];  // d/dx = scale · d/d(value)
    return std::isfinite(*cost);
  }

 private:
  const BodyModel& body_;
  const Reference<2>& ref_;
  const Blocks<2> start_;
  const VecD<double> G_;
  const DynamicFitOptions& o_;
  long* simulations_;
  FrameCost cost_;
  double log_lo_ = 0, log_hi_ = 0;
  std::vector<double> scale_;  // of each x
  mutable ControlledRollout rollout_;  // its parameters are each evaluation's
};

}  // namespace

DynamicFitResult FitDynamicByAdjoint(const BodyModel& body, const std::vector<ReferenceFrame>& frames,
                                     const DynamicParameters& initial, const DynamicFitOptions& o) {
  if (frames.empty()) throw std::invalid_argument("dynamic fit: no frames");
  const DynamicParameters start = Completed(body, frames, initial);
  CheckParameters(body, start);
  if ((o.fit_poses || o.fit_times) && start.graph.empty())
    throw std::invalid_argument("dynamic fit: fitting poses or times needs a pose graph to start from");
  if ((o.fit_poses || o.fit_times) && !(o.switch_width > 0))
    throw std::invalid_argument("dynamic fit: the adjoint fits a pose graph through a smoothed switch (width > 0)");
  const Reference<2> ref = MakeReference(body, frames, o.dt);
  DynamicFitResult result;
  if (ref.steps.back() < 1) throw std::invalid_argument("dynamic fit: the frames span no step");
  const VecD<double> G = ModeMasses(body);
  auto* cost = new AdjointDynamicCost(body, ref, Blocks<2>::From(start, G), G, o, &result.simulations);
  ceres::GradientProblem problem(cost);  // owns cost
  Eigen::VectorXd x = cost->ToX(Blocks<2>::From(start, G));
  if (x.size() == 0) throw std::invalid_argument("dynamic fit: nothing to fit");
  ceres::GradientProblemSolver::Options options;
  // a dense BFGS matrix is cheap beside a simulation for a few hundred unknowns, and converges
  // in far fewer iterations than L-BFGS' 20 pairs
  options.line_search_direction_type = x.size() <= 400 ? ceres::BFGS : ceres::LBFGS;
  options.max_num_iterations = o.max_iterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-12;
  options.logging_type = ceres::SILENT;
  IterationForwarder forward(o.on_iteration);
  options.callbacks.push_back(&forward);
  ceres::GradientProblemSolver::Summary summary;
  const auto clock = std::chrono::steady_clock::now();
  ceres::Solve(options, problem, x.data(), &summary);
  FitReport& report = result.report;
  FillReport(summary, o.full_report, std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count(),
             &report);
  if (InterruptRequested())
    throw Interrupted("the fit stopped by Ctrl-C after " + std::to_string(std::max(report.iterations, 0)) +
                      " iterations (cost " + std::to_string(summary.final_cost) + ")");
  if (!std::isfinite(summary.initial_cost)) throw NumericalStop("the fit's start does not simulate to a finite cost");
  result.params = cost->FromX(x.data()).To(G);
  const double c = CostOf(body, frames, result.params, o);
  result.rms_residual = std::sqrt(2.0 * c / (ref.num_residuals / 2));
  return result;
}

}  // namespace wobble::fit::internal
