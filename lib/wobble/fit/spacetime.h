// Spacetime control fits (issue 18; thesis §3.1 after Witkin & Kass): the PD targets of a whole
// motion solved for at once, minimising control energy plus task terms that say where and when
// the body must be, with bounds on the targets.
//
// The unknowns are targets at `knots` evenly spaced knots over the run, linear between them
// (every step its own knot when knots == steps + 1 … any count ≥ 2). The cost is
//     ρ Σ_n |γ0(n)|² Δt  +  Σ_n ℓ_n(q_n, q̇_n)
// (control energy, then the task as a stage cost: reach a point at a time, land upright, …).
// Its gradient with respect to every knot comes from one adjoint sweep (adjoint.h),
// so the solver is Ceres' L-BFGS on the gradient alone; the bounds lo ≤ γ0 ≤ hi are kept by
// solving for x with knot = lo + (hi − lo) σ(x), σ the logistic function. One fit serves the 2D
// and the 3D body (FitSpacetime<Dim>); only their task terms' formulas differ.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "wobble/fit/adjoint.h"

namespace wobble::fit {

template <int Dim> struct SpacetimeProblemN {
  ControlledRolloutN<Dim> rollout;  // world, integrator, dt, start, gains; targets: the first guess
  int knots = 2;                    // ≥ 2, at most steps + 1
  Eigen::VectorXd lower, upper;     // per mode bounds of the targets, lower < upper
  double control_weight = 0.0;      // ρ
  StageCostN<Dim> task;             // ℓ_n, with its gradient
};
using SpacetimeProblem = SpacetimeProblemN<2>;

struct SpacetimeOptions {
  int max_iterations = 100;  // per start
  // Multi-start, against local minima: start 0 is the problem's first guess, start k > 0 the
  // same plus N(0, start_spread²) on each knot's logistic coordinate x (±1 moves a mid-range
  // target by about a quarter of its span), from a generator seeded by (seed, k), so a fit
  // repeats bit for bit on any number of threads. The starts share `threads` (0: every core);
  // the lowest final cost wins.
  int starts = 1;
  double start_spread = 1.0;
  unsigned seed = 1;
  int threads = 0;
  std::function<void(int iteration, double cost)> on_iteration;  // progress of a single start
  std::function<void(int done, int starts, double best)> on_start;  // progress of a multi-start
};

struct SpacetimeResult {
  bool ok = false;
  std::string message;     // Ceres' summary line, or why the first rollout failed
  Eigen::MatrixXd knots;   // modes × knots
  Eigen::MatrixXd targets; // modes × steps, the rollout's targets
  double initial_cost = 0.0, cost = 0.0, control_energy = 0.0;
  int iterations = 0;
  long gradients = 0;      // cost-and-gradient evaluations (one simulation + one adjoint sweep each), all starts
  int best_start = 0;               // which start won (message, iterations are its)
  std::vector<double> start_costs;  // every start's final cost (NaN: it failed); empty for one start
};

// The targets of each step from knots (modes × knots): linear between evenly spaced knots,
// the first at step 0 and the last at step `steps`.
Eigen::MatrixXd KnotTargets(const Eigen::MatrixXd& knots, int steps);

// Ready-made task terms (each a stage cost with its exact gradient in the state's tangent
// coordinates, adjoint.h), and their sum; one name for both bodies (the 2D and 3D formulas):
//   CentreOfMassAt: w/2 |x_c − goal|² on the axes asked for, x_c = t + R c/m the centre of mass
//                   (c = c0 + C γ, the mass moments of Eq. 4.9; 3D spatial_inertia.h): "be there then".
//   CentreOfMassVelocityAt: w/2 |v_c − goal|² on the axes asked for, v_c the velocity of the
//                   centre of mass (2D ṫ + θ̇ S R c/m + R C γ̇/m; 3D ṫ + R (ω × c + C γ̇)/m, ω in
//                   the body frame): with goal 0 on y, "at the top of a hop".
//   UprightAt<Dim>: 2D w/2 (θ_n² + τ² θ̇_n²); 3D w/2 (|R e_y − e_y|² + τ² |ω|²), the body's up
//                   axis up and not turning, any heading: "land upright and without spinning",
//                   τ a time scale.
//   StillAt<Dim>:   w/2 |q̇_n|² (every coordinate's rate; 3D v = (ṫ, ω, γ̇)): "be at rest".
// n is a step index (0 … steps). Throws std::invalid_argument on a negative step or weight.
struct Axes {
  bool x = true, y = true, z = true;  // z: 3D terms only
};
StageCostN<2> CentreOfMassAt(const BodyModelN<2>& body, int step, const Eigen::Vector2d& goal, double weight,
                             Axes axes = {});
StageCostN<3> CentreOfMassAt(const BodyModelN<3>& body, int step, const Eigen::Vector3d& goal, double weight,
                             Axes axes = {});
StageCostN<2> CentreOfMassVelocityAt(const BodyModelN<2>& body, int step, const Eigen::Vector2d& goal, double weight,
                                     Axes axes = {});
StageCostN<3> CentreOfMassVelocityAt(const BodyModelN<3>& body, int step, const Eigen::Vector3d& goal, double weight,
                                     Axes axes = {});
template <int Dim> StageCostN<Dim> UprightAt(int step, double weight, double time_scale = 0.0);
template <int Dim> StageCostN<Dim> StillAt(int step, double weight);
StageCostN<2> SumOf(std::vector<StageCostN<2>> terms);
StageCostN<3> SumOf(std::vector<StageCostN<3>> terms);

// The problem's cost at these knots (modes × knots, not bounded here): one plain simulation,
// +inf when it fails. What FitSpacetime minimises, for other optimisers to compare on.
template <int Dim>
double SpacetimeCostOf(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem, const Eigen::MatrixXd& knots);

// Throws std::invalid_argument on inconsistent sizes, bounds or knot counts. Dim = 2 or 3.
template <int Dim>
SpacetimeResult FitSpacetime(const BodyModelN<Dim>& body, const SpacetimeProblemN<Dim>& problem,
                             const SpacetimeOptions& options = SpacetimeOptions());

}  // namespace wobble::fit
