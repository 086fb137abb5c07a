// Internals shared by the fits (not part of the public API): bounds, losses, the Ceres solve
// of a pose, the summary → FitReport copy and the conditioning analysis.
#pragma once

#include <ceres/ceres.h>

#include "wobble/core/interrupt.h"

#include <functional>
#include <vector>

#include "wobble/fit/internal/residuals.h"
#include "wobble/fit/pose_fit.h"

namespace wobble::fit {

inline double ModeLower(const PoseFitOptions& o, int d) { return o.mode_lower.empty() ? o.gamma_lower : o.mode_lower[d]; }
inline double ModeUpper(const PoseFitOptions& o, int d) { return o.mode_upper.empty() ? o.gamma_upper : o.mode_upper[d]; }

// Fills r->at_bound: the modes whose fitted amplitude r->q[rigid + d] (rigid: 3 in 2D, 6 in 3D)
// ended on one of its bounds.
template <int Dim> void FillAtBound(const BodyModelN<Dim>& body, const PoseFitOptions& o, PoseFitResult* r) {
  const int rigid = body.num_q() - body.num_modes();
  r->at_bound.clear();
  for (int d = 0; d < body.num_modes(); ++d) {
    const double g = r->q[rigid + d];
    const double tol = 1e-9 * (ModeUpper(o, d) - ModeLower(o, d));
    if (g <= ModeLower(o, d) + tol || g >= ModeUpper(o, d) - tol) r->at_bound.push_back(body.modes()[d].name);
  }
}

// A new loss function for Problem (which takes ownership); nullptr for squared.
ceres::LossFunction* MakeLoss(Loss loss, double scale);

// Adds the data terms (and the rest prior) of one pose of a 2D curve fit to `problem` over q,
// with the mode bounds. Returns the data residual blocks.
// `reverse` holds the target-to-body terms of a two-sided curve fit.
std::vector<ceres::ResidualBlockId> AddPoseTerms(const BodyModel& body, const std::vector<SegmentResidual>& data,
                                                 const std::vector<ReverseSegmentResidual>& reverse,
                                                 const PoseFitOptions& o, double* q, ceres::Problem* problem);

// Forwards Ceres' iterations to an on_iteration function; attach with Attach().
// Every fit's iteration callback: forwards (iteration, cost) to on_iteration when there is one,
// and aborts the solve on Ctrl-C (core/interrupt.h) between two iterations; SolveAndReport then
// throws Interrupted.
class IterationForwarder : public ceres::IterationCallback {
 public:
  explicit IterationForwarder(std::function<void(int, double)> f) : f_(std::move(f)) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& s) override {
    if (f_) f_(s.iteration, s.cost);
    return InterruptRequested() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }
  void Attach(ceres::Solver::Options* options) { options->callbacks.push_back(this); }

 private:
  std::function<void(int, double)> f_;
};

// Copies what people need from a Ceres summary (least squares or line search).
template <class Summary> void FillReport(const Summary& summary, bool full, double seconds, FitReport* report) {
  report->usable = summary.IsSolutionUsable();
  report->termination = ceres::TerminationTypeToString(summary.termination_type);
  report->brief_report = summary.BriefReport();
  if (full) report->full_report = summary.FullReport();
  report->initial_cost = summary.initial_cost;
  report->final_cost = summary.final_cost;
  report->cost_per_iteration.clear();
  for (const ceres::IterationSummary& it : summary.iterations) report->cost_per_iteration.push_back(it.cost);
  report->iterations = int(summary.iterations.size()) - 1;
  report->solve_seconds = seconds;
}

// A report as bytes and back, exactly: multi-start fits solve their starts through
// DistributedMap (core/distribute.h).
std::string EncodeFitReport(const FitReport& report);
FitReport DecodeFitReport(const std::string& bytes);

// Every fit's last move: silent logging, on_iteration attached, ceres::Solve timed, the report filled.
void SolveAndReport(ceres::Solver::Options options, ceres::Problem* problem,
                    const std::function<void(int, double)>& on_iteration, bool full_report, FitReport* report);

// The kinematic trajectory fits' solver (2D and 3D): sparse normal Cholesky (SuiteSparse when
// Ceres has it), the fit's tight tolerances; `linear_solver` gets its name for the result.
ceres::Solver::Options TrajectorySolverOptions(const PoseFitOptions& o, std::string* linear_solver);

// Solves a pose problem built by the caller (dense normal equations, the fit's tolerances).
void SolvePoseProblem(const PoseFitOptions& o, ceres::Problem* problem, FitReport* report);

// Solves one pose of a 2D curve fit (dense: a handful of unknowns), q in and out.
void SolvePose(const BodyModel& body, const std::vector<SegmentResidual>& data,
               const std::vector<ReverseSegmentResidual>& reverse, const PoseFitOptions& o, Eigen::VectorXd* q,
               FitReport* report);

// Conditioning of a 2D curve fit's data terms at q (see Conditioning in pose_fit.h).
Conditioning ComputeConditioning(const BodyModel& body, const std::vector<SegmentResidual>& data,
                                 const std::vector<ReverseSegmentResidual>& reverse, const PoseFitOptions& o,
                                 const Eigen::VectorXd& q);

// The Jacobian of the residual blocks eval names, dense (a pose has a handful of unknowns).
Eigen::MatrixXd DataJacobian(ceres::Problem* problem, const ceres::Problem::EvaluateOptions& eval);

// The conditioning analysis of a data Jacobian J whose columns are the coordinates `names`,
// the first `num_rigid` of them rigid (the rest modes), for 2D and 3D fits alike.
Conditioning ConditioningOfJacobian(Eigen::MatrixXd J, const std::vector<std::string>& names, int num_rigid);

}  // namespace wobble::fit
