// The dynamic fit on the adjoint gradient (issue 18): the fit's cost as a rollout of
// fit/adjoint.h (either dimension) with a stage cost at every frame's step, minimised
// by Ceres' BFGS line search.
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

// ½ Σ w |x_i(state_n) − target|² over the frames observed at step n, and its gradient in the
// state's tangent coordinates (adjoint.h); each dimension's formula below.
template <int Dim> struct FrameCost {
  const Reference<Dim>* ref;
  std::vector<std::vector<int>> frames_at;  // step → frames observed there
  double operator()(int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz) const;
};

// 2D: with x = t + R(θ) l (Eq. 4.2) and r = w (x − target), ∂/∂t = r, ∂/∂θ = rᵀ J (x − t) (J
// the quarter turn) and ∂/∂γ = Bᵀ Rᵀ r; nothing on q̇.
template <>
double FrameCost<2>::operator()(int n, const BodyState<2, double>& s, Eigen::VectorXd* dz) const {
  if (n >= int(frames_at.size())) return 0.0;
  const Eigen::VectorXd q = s.q;
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
      dz->head<2>() += r;
      (*dz)[2] += r.y() * arm.x() - r.x() * arm.y();
      if (D > 0) dz->segment(3, D) += p.basis.B.transpose() * (Rm.transpose() * r);
    }
  return cost;
}

// 3D: x = t + R l, l = b0 + B γ, so ∂/∂δt = r, ∂/∂ε = l × Rᵀ r (R moved to R exp(ε̂)) and
// ∂/∂γ = Bᵀ Rᵀ r.
template <>
double FrameCost<3>::operator()(int n, const BodyState<3, double>& s, Eigen::VectorXd* dz) const {
  if (n >= int(frames_at.size())) return 0.0;
  const int D = int(s.gamma().size());
  const Eigen::Matrix3d R = s.orientation().toRotationMatrix();
  double cost = 0.0;
  for (int f : frames_at[n])
    for (const auto& p : ref->points[f]) {
      const Eigen::Vector3d l = p.basis.b0 + p.basis.B * s.gamma();
      const Eigen::Vector3d x = s.translation() + R * l;
      const double w = p.sqrt_weight * p.sqrt_weight;
      const Eigen::Vector3d r = w * (x - p.target), local = R.transpose() * r;
      cost += 0.5 * w * (x - p.target).squaredNorm();
      dz->head<3>() += r;
      dz->segment<3>(3) += l.cross(local);
      if (D > 0) dz->segment(6, D) += p.basis.B.transpose() * local;
    }
  return cost;
}

// One evaluation's cost and its gradient in the fit's blocks: q0 as Blocks holds it (3D: the
// orientation chart · exp(δ̂)), q̇0, K, c and the per-step targets.
struct BlockGradient {
  double cost = 0.0;
  Eigen::VectorXd q0, qd0, stiffness, damping;
  Eigen::MatrixXd targets;
};

// step → the frames observed there
std::vector<std::vector<int>> FramesAt(const std::vector<int>& steps) {
  std::vector<std::vector<int>> at(size_t(steps.back()) + 1);
  for (size_t f = 0; f < steps.size(); ++f) at[size_t(steps[f])].push_back(int(f));
  return at;
}

// The rollout's start from the fit's blocks, and ∂cost/∂(q0's block) from ∂cost/∂z_0 (the
// start's tangent coordinates), for each dimension. 2D: q0 and q̇0 themselves.
void SetStart(const BodyModel&, const Blocks<2>&, const DynamicParameters& p, BodyState<2, double>* start) {
  start->q = p.q0;
  start->qd = p.qd0;
}
void TakeStartGradient(const BodyModel&, const Blocks<2>&, const Eigen::VectorXd& dz, BlockGradient* g) {
  const Eigen::Index nq = dz.size() / 2;
  g->q0 = dz.head(nq);
  g->qd0 = dz.tail(nq);
}

// 3D: the start as Dimension<3>::Start makes it: t, chart · exp(δ̂), γ, v.
void SetStart(const BodyModelN<3>& body, const Blocks<3>& b, const DynamicParameters& p, BodyState<3, double>* start) {
  const int D = body.num_modes();
  const Eigen::Vector3d delta(b.q0[3], b.q0[4], b.q0[5]);
  *start = RestState<3, double>(body);
  start->translation() = Eigen::Vector3d(b.q0[0], b.q0[1], b.q0[2]);
  Group<3>::SetOrientation(Eigen::Quaterniond(b.chart * ExpRotation<double>(delta)).normalized(), &start->q);
  for (int d = 0; d < D; ++d) start->gamma()[d] = b.q0[size_t(Group<3>::kRigidDofs + d)];
  start->qd = p.qd0;
}
// z = (δt, ε, δγ, δv); the block's δ moves R = chart exp(δ̂) by ε = J_r(δ) δδ
void TakeStartGradient(const BodyModelN<3>& body, const Blocks<3>& b, const Eigen::VectorXd& dz, BlockGradient* g) {
  const int D = body.num_modes();
  const Eigen::Vector3d delta(b.q0[3], b.q0[4], b.q0[5]);
  g->q0.resize(Group<3>::kRigidDofs + D);
  g->q0.head<3>() = dz.head<3>();
  g->q0.segment<3>(3) = RightJacobianExp<double>(delta).transpose() * dz.segment<3>(3);
  g->q0.tail(D) = dz.segment(6, D);
  g->qd0 = dz.tail(Group<3>::kRigidDofs + D);
}

// The fit's rollout: Run fills *g (with gradient) or only g->cost; false when the simulation
// fails.
template <int Dim> class FitRollout {
 public:
  FitRollout(const Reference<Dim>& ref, const DynamicFitOptionsN<Dim>& o) {
    cost_.ref = &ref;
    cost_.frames_at = FramesAt(ref.steps);
    rollout_.world = o.world;
    rollout_.integrator = Integrator::kThesis;
    rollout_.dt = o.dt;
  }
  bool Run(const BodyModelN<Dim>& body, const Blocks<Dim>& b, const DynamicParameters& p, Eigen::MatrixXd targets,
           bool gradient, BlockGradient* g) {
    SetStart(body, b, p, &rollout_.start);
    rollout_.stiffness = p.stiffness;
    rollout_.damping = p.damping;
    rollout_.targets = std::move(targets);
    const StageCostN<Dim> stage = [this](int n, const BodyState<Dim, double>& s, Eigen::VectorXd* dz) {
      return cost_(n, s, dz);
    };
    if (!gradient) {
      g->cost = RolloutCost(body, rollout_, stage);
      return std::isfinite(g->cost);
    }
    RolloutGradient r = RolloutCostGradient(body, rollout_, stage);
    if (!r.ok) return false;
    g->cost = r.cost;
    g->stiffness = std::move(r.stiffness);
    g->damping = std::move(r.damping);
    g->targets = std::move(r.targets);
    TakeStartGradient(body, b, r.start, g);
    return true;
  }

 private:
  FrameCost<Dim> cost_;
  ControlledRolloutN<Dim> rollout_;
};

// The fit's free numbers as one vector x for Ceres' line search, in the order q0, q̇0, log K,
// u (ζ = u², smooth through 0; a ζ that starts at 0 starts at kLeastZeta, since u = 0 has no
// gradient), poses, y (log τ = lo + (hi − lo) σ(y)); the fixed ones stay at the start's.
// Each is divided by a scale that moves the body's points by about one length unit
// (SmoothnessScales; velocities over the motion's duration): L-BFGS starts from a multiple
// of the identity, and unscaled (positions of 100, mode amplitudes of 0.1) it stalls far
// from the optimum.
template <int Dim> class AdjointDynamicCost final : public ceres::FirstOrderFunction {
 public:
  AdjointDynamicCost(const BodyModelN<Dim>& body, const Reference<Dim>& ref, const Blocks<Dim>& start,
                     const VecD<double>& G, const DynamicFitOptionsN<Dim>& o, long* simulations)
      : body_(body), ref_(ref), start_(start), G_(G), o_(o), simulations_(simulations), rollout_(ref, o) {
    log_lo_ = std::log(o.min_time);
    log_hi_ = std::log(o.max_time);
    const auto L = SmoothnessScales(body);
    const double duration = ref.steps.back() * o.dt;
    const std::vector<int> active = control::ActiveModes(body);
    const int nq = body.num_q(), D = body.num_modes();
    for (int i = 0; o.fit_q0 && i < nq; ++i) scale_.push_back(1.0 / L[i]);
    for (int i = 0; o.fit_qd0 && i < nq; ++i) scale_.push_back(1.0 / (L[i] * duration));
    for (int d = 0; o.fit_stiffness && d < D; ++d) scale_.push_back(1.0);
    for (int d = 0; o.fit_damping && d < D; ++d) scale_.push_back(1.0);
    for (size_t i = 0; o.fit_poses && i < start.poses.size(); ++i)
      scale_.push_back(1.0 / L[body.num_q() - body.num_modes() + active[i % active.size()]]);
    for (size_t i = 0; o.fit_times && i < start.log_times.size(); ++i) scale_.push_back(1.0);
  }

  int NumParameters() const override { return int(scale_.size()); }

  // x from the blocks, and back
  Eigen::VectorXd ToX(const Blocks<Dim>& b) const {
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
  Blocks<Dim> FromX(const double* x) const {
    Blocks<Dim> b = start_;
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
    const Blocks<Dim> blocks = FromX(x);
    const DynamicParameters p = blocks.To(G_);
    Eigen::MatrixXd targets = Eigen::MatrixXd::Zero(D, steps);
    if (!p.graph.empty()) targets = PoseGraphTargets(body_, p.graph, o_.dt, steps, o_.switch_width);
    ++*simulations_;
    BlockGradient g;
    if (!rollout_.Run(body_, blocks, p, std::move(targets), gradient != nullptr, &g)) return false;  // the line search steps back
    *cost = g.cost;
    if (!gradient) return true;
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
  const BodyModelN<Dim>& body_;
  const Reference<Dim>& ref_;
  const Blocks<Dim> start_;
  const VecD<double> G_;
  const DynamicFitOptionsN<Dim>& o_;
  long* simulations_;
  double log_lo_ = 0, log_hi_ = 0;
  std::vector<double> scale_;  // of each x
  mutable FitRollout<Dim> rollout_;  // its parameters are each evaluation's
};

}  // namespace

template <int Dim>
DynamicFitResult FitDynamicByAdjoint(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                              const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o) {
  if (frames.empty()) throw std::invalid_argument("dynamic fit: no frames");
  const DynamicParameters start = Completed(body, frames, initial);
  CheckParameters(body, start);
  if ((o.fit_poses || o.fit_times) && start.graph.empty())
    throw std::invalid_argument("dynamic fit: fitting poses or times needs a pose graph to start from");
  if ((o.fit_poses || o.fit_times) && !(o.switch_width > 0))
    throw std::invalid_argument("dynamic fit: the adjoint fits a pose graph through a smoothed switch (width > 0)");
  const Reference<Dim> ref = MakeReference(body, frames, o.dt);
  if (ref.steps.back() < 1) throw std::invalid_argument("dynamic fit: the frames span no step");
  const VecD<double> G = ModeMasses(body);
  // A growing horizon: the first 4 frames, then 8, 16, … and all, each from the last one's
  // answer. Over the whole motion from a rough start (q̇0 from two pose fits) the line search
  // can take a step into a basin where the body spins a whole turn between frames and stop
  // there (the tumbling chair of fit3_test: cost 35 against 0); over a few frames there is no
  // such basin near, and each longer horizon starts close to its answer. Least squares with
  // Jets does not need this: its trust region keeps the steps small. Not for a pose graph's
  // poses and times: a short horizon does not see the later switches and moves them anywhere
  // (the pose graph of check_fit.py ended 7.3 off).
  std::vector<size_t> horizons;
  if (!o.fit_poses && !o.fit_times)
    for (size_t m = 4; m < frames.size(); m *= 2) horizons.push_back(m);
  horizons.push_back(frames.size());
  DynamicFitResult result;
  DynamicParameters current = start;
  FitReport& report = result.report;
  int iterations = 0;
  double seconds = 0.0;
  for (size_t m : horizons) {
    const std::vector<ReferenceFrameN<Dim>> part(frames.begin(), frames.begin() + std::ptrdiff_t(m));
    const Reference<Dim> part_ref = MakeReference(body, part, o.dt);
    if (part_ref.steps.back() < 1) continue;  // frames at one time: nothing to simulate yet
    auto* cost = new AdjointDynamicCost<Dim>(body, part_ref, Blocks<Dim>::From(current, G), G, o, &result.simulations);
    ceres::GradientProblem problem(cost);  // owns cost
    Eigen::VectorXd x = cost->ToX(Blocks<Dim>::From(current, G));
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
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
    FillReport(summary, o.full_report, seconds, &report);  // the last horizon's, with every horizon's time
    iterations += std::max(report.iterations, 0);
    if (InterruptRequested())
      throw Interrupted("the fit stopped by Ctrl-C after " + std::to_string(iterations) + " iterations (cost " +
                        std::to_string(summary.final_cost) + ")");
    if (!std::isfinite(summary.initial_cost)) throw NumericalStop("the fit's start does not simulate to a finite cost");
    current = cost->FromX(x.data()).To(G);
  }
  report.iterations = iterations;
  result.params = current;
  const double c = CostOf(body, frames, result.params, o);
  result.rms_residual = std::sqrt(2.0 * c / (ref.num_residuals / Dim));
  return result;
}

template DynamicFitResult FitDynamicByAdjoint(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                              const DynamicParameters&, const DynamicFitOptionsN<2>&);
template DynamicFitResult FitDynamicByAdjoint(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                              const DynamicParameters&, const DynamicFitOptionsN<3>&);

}  // namespace wobble::fit::internal
