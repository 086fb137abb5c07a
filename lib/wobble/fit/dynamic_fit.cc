#include "wobble/fit/dynamic_fit.h"

#include <ceres/ceres.h>
#include <ceres/dynamic_autodiff_cost_function.h>

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "wobble/fit/internal/dynamic_problem.h"
#include "wobble/fit/internal/solve_common.h"
#include "wobble/synth/anneal.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble::fit {

using namespace internal;  // NOLINT: the dynamic fits' shared internals

namespace {

// Jet width of the dynamic cost: 24 covers the table (7 + 7 + 4 + 4 parameters) in one pass;
// bodies with more parameters take several passes (DynamicAutoDiffCostFunction strides).
constexpr int kStride = 32;

// Residuals sqrt(w)(x_i(q_f) − target) of every frame, from the raw blocks.
template <int Dim> struct DynamicResidual {
  const BodyModelN<Dim>* passive;
  const DynamicFitOptionsN<Dim>* options;
  Eigen::Quaterniond chart;
  int num_poses, pose_size;  // the controller's blocks follow q0, q̇0, log K, ζ when num_poses > 0
  bool cyclic;
  std::vector<int> active;
  const Reference<Dim>* ref;
  VecD<double> G;
  long* simulations;

  template <class T> bool operator()(T const* const* p, T* r) const {
    const int D = passive->num_modes();
    ModeParams<T> mp;
    mp.K.resize(D);
    mp.c.resize(D);
    for (int d = 0; d < D; ++d) {
      using std::exp;
      using std::sqrt;
      mp.K[d] = exp(p[2][d]);
      mp.c[d] = p[3][d] * T(2.0) * sqrt(T(2.0 * G[d]) * mp.K[d]);
    }
    control::PoseGraphOf<T> control;
    if (num_poses > 0) {
      const int b = D > 0 ? 4 : 2;  // index of the poses block
      control.cyclic = cyclic;
      control.active = active;
      for (int i = 0; i < num_poses; ++i) {
        VecD<T> pose(pose_size);
        for (int k = 0; k < pose_size; ++k) pose[k] = p[b][i * pose_size + k];
        control.poses.push_back(pose);
        using std::exp;
        control.durations.push_back(exp(p[b + 1][i]));
      }
    }
    ++*simulations;
    int k = 0;
    return Simulate(*passive, *options, p[0], p[1], chart, mp, control, ref->steps, [&](int f, const auto& state) {
      for (const auto& s : ref->points[f]) {
        const auto x = Dimension<Dim>::Position(s.basis, state);
        for (int i = 0; i < Dim; ++i) r[k++] = T(s.sqrt_weight) * (x[i] - T(s.target[i]));
      }
    });
  }
};

}  // namespace

template <int Dim> std::vector<int> FrameSteps(const std::vector<ReferenceFrameN<Dim>>& frames, double dt) {
  if (!(dt > 0)) throw std::invalid_argument("dynamic fit: dt must be positive");
  if (frames.empty()) throw std::invalid_argument("dynamic fit: no frames");
  std::vector<int> steps;
  for (const ReferenceFrameN<Dim>& f : frames) {
    const double n = (f.time - frames[0].time) / dt;
    const double rounded = std::round(n);
    if (std::abs(n - rounded) > 1e-6 * std::max(1.0, n))
      throw std::invalid_argument("dynamic fit: frame time " + std::to_string(f.time) +
                                  " is not a whole number of steps of dt after the first frame");
    steps.push_back(int(rounded));
  }
  return steps;
}

template <int Dim>
bool SimulateWithParameters(const BodyModelN<Dim>& body, const DynamicFitOptionsN<Dim>& o, const DynamicParameters& p,
                            const std::vector<int>& frame_steps,
                            const std::function<void(int, const Eigen::VectorXd&)>& on_frame) {
  return SimulatePlain(body, o, p, frame_steps,
                       [&](int f, const auto& state) { on_frame(f, Dimension<Dim>::Q(state)); });
}

namespace {

template <int Dim>
DynamicFitResult FitDynamic(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                            const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o) {
  if (frames.empty()) throw std::invalid_argument("dynamic fit: no frames");
  const DynamicParameters start = Completed(body, frames, initial);
  CheckParameters(body, start);
  const BodyModelN<Dim> passive = body.WithoutModeGains();
  const Reference<Dim> ref = MakeReference(body, frames, o.dt);
  const VecD<double> G = ModeMasses(body);
  Blocks<Dim> blocks = Blocks<Dim>::From(start, G);
  const int nq = body.num_q(), D = body.num_modes();

  DynamicFitResult result;
  if ((o.fit_poses || o.fit_times) && start.graph.empty())
    throw std::invalid_argument("dynamic fit: fitting poses or times needs a pose graph to start from");
  if (o.fit_times && !(o.switch_width > 0))
    throw std::invalid_argument("dynamic fit: fitting transition times needs a switch width > 0 (a hard switch has no gradient)");
  const int num_poses = int(start.graph.poses.size());
  auto* cost = new ceres::DynamicAutoDiffCostFunction<DynamicResidual<Dim>, kStride>(
      new DynamicResidual<Dim>{&passive, &o, blocks.chart, num_poses, blocks.pose_size, start.graph.cyclic,
                               control::ActiveModes(body), &ref, G, &result.simulations});
  std::vector<double*> params = {blocks.q0.data(), blocks.qd0.data()};
  cost->AddParameterBlock(nq);
  cost->AddParameterBlock(nq);
  if (D > 0) {
    cost->AddParameterBlock(D);
    cost->AddParameterBlock(D);
    params.push_back(blocks.log_k.data());
    params.push_back(blocks.zeta.data());
  }
  if (num_poses > 0) {
    if (D == 0) throw std::invalid_argument("dynamic fit: a pose graph needs modes");
    cost->AddParameterBlock(int(blocks.poses.size()));
    cost->AddParameterBlock(num_poses);
    params.push_back(blocks.poses.data());
    params.push_back(blocks.log_times.data());
  }
  cost->SetNumResiduals(ref.num_residuals);
  ceres::Problem problem;
  problem.AddResidualBlock(cost, nullptr, params);
  if (!o.fit_q0) problem.SetParameterBlockConstant(blocks.q0.data());
  if (!o.fit_qd0) problem.SetParameterBlockConstant(blocks.qd0.data());
  if (D > 0) {
    if (!o.fit_stiffness) problem.SetParameterBlockConstant(blocks.log_k.data());
    if (!o.fit_damping) problem.SetParameterBlockConstant(blocks.zeta.data());
    for (int d = 0; d < D; ++d) problem.SetParameterLowerBound(blocks.zeta.data(), d, 0.0);
  }
  if (num_poses > 0) {
    if (!o.fit_poses) problem.SetParameterBlockConstant(blocks.poses.data());
    if (!o.fit_times) problem.SetParameterBlockConstant(blocks.log_times.data());
    for (int i = 0; i < num_poses; ++i) {
      problem.SetParameterLowerBound(blocks.log_times.data(), i, std::log(o.min_time));
      problem.SetParameterUpperBound(blocks.log_times.data(), i, std::log(o.max_time));
    }
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = o.max_iterations;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-12;
  SolveAndReport(options, &problem, o.on_iteration, o.full_report, &result.report);
  result.params = blocks.To(G);
  const double c = CostOf(body, frames, result.params, o);
  result.rms_residual = std::sqrt(2.0 * c / (ref.num_residuals / Dim));
  return result;
}

}  // namespace

template <int Dim>
double DynamicCost(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames, const DynamicParameters& p,
                   const DynamicFitOptionsN<Dim>& o) {
  return CostOf(body, frames, p, o);
}

template <int Dim>
DynamicFitResult FitDynamicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                      const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o) {
  if (o.gradient == FitGradient::kAdjoint) return FitDynamicByAdjoint(body, frames, initial, o);
  return FitDynamic(body, frames, initial, o);
}

template <int Dim>
AnnealingResult AnnealPoseGraph(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o, long budget,
                                std::uint64_t seed) {
  const DynamicParameters start = Completed(body, frames, initial);
  CheckParameters(body, start);
  if (start.graph.empty()) throw std::invalid_argument("anneal: needs a pose graph to start from");
  // the synthesis problem of lib/wobble/synth with this fit's cost in place of Table 5.1's
  synth::Problem problem;
  problem.set_body(std::make_shared<const BodyModelN<Dim>>(body));
  problem.custom_cost = [&](const control::PoseGraph& g) {
    DynamicParameters p = start;
    p.graph = g;
    return CostOf(body, frames, p, o);
  };
  synth::AnnealOptions a;
  a.seed = seed;
  a.iterations = int(std::max<long>(0, budget - 1));
  a.batch = 1;
  a.threads = 1;
  a.optimize = o.fit_poses && o.fit_times ? synth::Optimize::kBoth
               : o.fit_times              ? synth::Optimize::kTimes
                                          : synth::Optimize::kPoses;
  a.min_time = o.min_time;
  a.max_time = o.max_time;
  a.pose_step = 0.02;  // the scale of the perturbations the fit starts from
  a.time_step = 0.05;
  const synth::AnnealResult r = synth::Anneal(problem, start.graph, a);
  AnnealingResult out;
  out.params = start;
  out.params.graph = r.best;
  out.cost = r.best_outcome.cost;
  out.simulations = r.trials;
  return out;
}

template <int Dim>
AnnealingResult AnnealDynamicTrajectory(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                        const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o, long budget,
                                        unsigned seed) {
  const DynamicParameters start = Completed(body, frames, initial);
  CheckParameters(body, start);
  const VecD<double> G = ModeMasses(body);
  const int nq = body.num_q(), D = body.num_modes();
  const double duration = std::max(o.dt, frames.back().time - frames.front().time);
  // step sizes that move the points by about one length unit (SmoothnessScales)
  const auto L = SmoothnessScales(body);
  struct Coordinate {
    double* value;
    double step;
  };
  Blocks<Dim> x = Blocks<Dim>::From(start, G);
  std::vector<Coordinate> coords;
  for (int i = 0; i < nq; ++i) {
    if (o.fit_q0) coords.push_back({&x.q0[i], 1.0 / L[i]});
    if (o.fit_qd0) coords.push_back({&x.qd0[i], 1.0 / (L[i] * duration)});
  }
  for (int d = 0; d < D; ++d) {
    if (o.fit_stiffness) coords.push_back({&x.log_k[d], 0.05});
    if (o.fit_damping) coords.push_back({&x.zeta[d], 0.02});
  }
  AnnealingResult best;
  double current = CostOf(body, frames, x.To(G), o);
  best.params = x.To(G);
  best.cost = current;
  best.simulations = 1;
  if (coords.empty()) return best;
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_int_distribution<size_t> pick(0, coords.size() - 1);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  // geometric cooling from 10% of the starting cost down by 1e6 over the budget; step sizes
  // adapt to keep about a third of the moves accepted
  const double t_start = 0.1 * current, t_ratio = 1e-6;
  double scale = 1.0;
  int accepted_window = 0, window = 0;
  for (long k = 1; k < budget; ++k) {
    const double temperature = t_start * std::pow(t_ratio, double(k) / double(budget));
    Coordinate& c = coords[pick(rng)];
    const double old = *c.value;
    if (c.value >= x.zeta.data() && c.value < x.zeta.data() + x.zeta.size()) {
      *c.value = std::abs(old + scale * c.step * normal(rng));  // ζ >= 0
    } else {
      *c.value = old + scale * c.step * normal(rng);
    }
    const double trial = CostOf(body, frames, x.To(G), o);
    ++best.simulations;
    if (trial < current || uniform(rng) < std::exp(-(trial - current) / temperature)) {
      current = trial;
      ++accepted_window;
      if (trial < best.cost) {
        best.cost = trial;
        best.params = x.To(G);
      }
    } else {
      *c.value = old;
    }
    if (++window == 50) {
      scale *= accepted_window > 17 ? 1.3 : 0.7;
      accepted_window = window = 0;
    }
  }
  return best;
}

template std::vector<int> FrameSteps(const std::vector<ReferenceFrameN<2>>&, double);
template bool SimulateWithParameters(const BodyModelN<2>&, const DynamicFitOptionsN<2>&, const DynamicParameters&,
                                     const std::vector<int>&, const std::function<void(int, const Eigen::VectorXd&)>&);
template DynamicFitResult FitDynamicTrajectory(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                               const DynamicParameters&, const DynamicFitOptionsN<2>&);
template AnnealingResult AnnealPoseGraph(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                         const DynamicParameters&, const DynamicFitOptionsN<2>&, long, std::uint64_t);
template AnnealingResult AnnealDynamicTrajectory(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&,
                                                 const DynamicParameters&, const DynamicFitOptionsN<2>&, long, unsigned);
template double DynamicCost(const BodyModelN<2>&, const std::vector<ReferenceFrameN<2>>&, const DynamicParameters&,
                            const DynamicFitOptionsN<2>&);
template std::vector<int> FrameSteps(const std::vector<ReferenceFrameN<3>>&, double);
template bool SimulateWithParameters(const BodyModelN<3>&, const DynamicFitOptionsN<3>&, const DynamicParameters&,
                                     const std::vector<int>&, const std::function<void(int, const Eigen::VectorXd&)>&);
template DynamicFitResult FitDynamicTrajectory(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                               const DynamicParameters&, const DynamicFitOptionsN<3>&);
template AnnealingResult AnnealPoseGraph(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                         const DynamicParameters&, const DynamicFitOptionsN<3>&, long, std::uint64_t);
template AnnealingResult AnnealDynamicTrajectory(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&,
                                                 const DynamicParameters&, const DynamicFitOptionsN<3>&, long, unsigned);
template double DynamicCost(const BodyModelN<3>&, const std::vector<ReferenceFrameN<3>>&, const DynamicParameters&,
                            const DynamicFitOptionsN<3>&);

}  // namespace wobble::fit

