#include "wobble/fit/internal/solve_common.h"

#include "wobble/core/distribute.h"

#include <cmath>

#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"

#include <Eigen/SVD>
#include <chrono>
#include <cmath>
#include <limits>

namespace wobble::fit {

ceres::LossFunction* MakeLoss(Loss loss, double scale) {
  switch (loss) {
    case Loss::kSquared: return nullptr;
    case Loss::kHuber: return new ceres::HuberLoss(scale);
    case Loss::kCauchy: return new ceres::CauchyLoss(scale);
  }
  return nullptr;
}

std::vector<ceres::ResidualBlockId> AddPoseTerms(const BodyModel& body, const std::vector<SegmentResidual>& data,
                                                 const std::vector<ReverseSegmentResidual>& reverse,
                                                 const PoseFitOptions& o, double* q, ceres::Problem* problem) {
  std::vector<ceres::ResidualBlockId> ids;
  // one loss object shared by every data term (Ceres deletes it once); none without terms
  ceres::LossFunction* loss = data.empty() && reverse.empty() ? nullptr : MakeLoss(o.loss, o.loss_scale);
  for (const SegmentResidual& d : data) ids.push_back(problem->AddResidualBlock(MakeSegmentCost(d), loss, q));
  for (const ReverseSegmentResidual& d : reverse)
    ids.push_back(problem->AddResidualBlock(MakeReverseSegmentCost(d), loss, q));
  if (o.prior_weight > 0 && body.num_modes() > 0) {
    RestPrior prior;
    prior.sqrt_weight = std::sqrt(o.prior_weight);
    prior.num_q = body.num_q();
    problem->AddResidualBlock(MakeRestPriorCost(prior), nullptr, q);
  }
  if (!problem->HasParameterBlock(q)) problem->AddParameterBlock(q, body.num_q());
  for (int d = 0; d < body.num_modes(); ++d) {
    problem->SetParameterLowerBound(q, kRigidDofs + d, ModeLower(o, d));
    problem->SetParameterUpperBound(q, kRigidDofs + d, ModeUpper(o, d));
  }
  return ids;
}

void SolvePoseProblem(const PoseFitOptions& o, ceres::Problem* problem, FitReport* report) {
  ceres::Solver::Options options;
  // normal equations: J has 2 rows per target but only num_q <= 15 columns; LM's damping keeps
  // them positive definite even when a mode is undetermined
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  options.max_num_iterations = o.max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  SolveAndReport(options, problem, o.on_iteration, o.full_report, report);
}

void SolveAndReport(ceres::Solver::Options options, ceres::Problem* problem,
                    const std::function<void(int, double)>& on_iteration, bool full_report, FitReport* report) {
  options.logging_type = ceres::SILENT;
  IterationForwarder forward(on_iteration);
  forward.Attach(&options);
  ceres::Solver::Summary summary;
  auto parameters_finite = [problem] {
    std::vector<double*> blocks;
    problem->GetParameterBlocks(&blocks);
    for (double* b : blocks)
      for (int i = 0; i < problem->ParameterBlockSize(b); ++i)
        if (!std::isfinite(b[i])) return false;
    return true;
  };
  if (!parameters_finite())
    throw NumericalStop("the fit's start is not finite: targets or weights so large that the start computed from "
                        "them overflowed");
  const auto start = std::chrono::steady_clock::now();
  ceres::Solve(options, problem, &summary);
  FillReport(summary, full_report, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
             report);
  if (InterruptRequested())
    throw Interrupted("the fit stopped by Ctrl-C after " + std::to_string(std::max(report->iterations, 0)) +
                      " iterations (cost " + std::to_string(summary.final_cost) + ")");
  // a cost past the largest double is no fit: say why instead of reporting inf (or crashing in
  // the conditioning's SVD of a NaN Jacobian)
  if (!std::isfinite(summary.initial_cost) || !std::isfinite(summary.final_cost))
    throw NumericalStop("the fit's cost is not finite (initial " + std::to_string(summary.initial_cost) + ", final " +
                        std::to_string(summary.final_cost) +
                        "): a target, weight or start so large that its squared residual overflows");
  if (!parameters_finite()) throw NumericalStop("the fit ended at a non-finite result");
}

void SolvePose(const BodyModel& body, const std::vector<SegmentResidual>& data,
               const std::vector<ReverseSegmentResidual>& reverse, const PoseFitOptions& o, Eigen::VectorXd* q,
               FitReport* report) {
  ceres::Problem problem;
  AddPoseTerms(body, data, reverse, o, q->data(), &problem);
  SolvePoseProblem(o, &problem, report);
}

ceres::Solver::Options TrajectorySolverOptions(const PoseFitOptions& o, std::string* linear_solver) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.sparse_linear_algebra_library_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SUITE_SPARSE : ceres::EIGEN_SPARSE;
  options.max_num_iterations = o.max_iterations;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  *linear_solver = std::string("SPARSE_NORMAL_CHOLESKY/") +
                   ceres::SparseLinearAlgebraLibraryTypeToString(options.sparse_linear_algebra_library_type);
  return options;
}

Conditioning ComputeConditioning(const BodyModel& body, const std::vector<SegmentResidual>& data,
                                 const std::vector<ReverseSegmentResidual>& reverse, const PoseFitOptions& o,
                                 const Eigen::VectorXd& q_in) {
  // the Jacobian of the data terms alone (the prior would hide what the data cannot see)
  Eigen::VectorXd q = q_in;
  ceres::Problem problem;
  PoseFitOptions data_only = o;
  data_only.prior_weight = 0;
  ceres::Problem::EvaluateOptions eval;
  eval.residual_blocks = AddPoseTerms(body, data, reverse, data_only, q.data(), &problem);
  return ConditioningOfJacobian(DataJacobian(&problem, eval), CoordinateNames(body), kRigidDofs);
}

Eigen::MatrixXd DataJacobian(ceres::Problem* problem, const ceres::Problem::EvaluateOptions& eval) {
  ceres::CRSMatrix crs;
  problem->Evaluate(eval, nullptr, nullptr, nullptr, &crs);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int k = crs.rows[r]; k < crs.rows[r + 1]; ++k) J(r, crs.cols[k]) = crs.values[k];
  return J;
}

Conditioning ConditioningOfJacobian(Eigen::MatrixXd J, const std::vector<std::string>& names, int num_rigid) {
  const int n = int(J.cols());
  Conditioning c;
  if (!J.allFinite()) throw NumericalStop("the fit's Jacobian at its result is not finite: no conditioning to report");
  // J / max|J|: the condition numbers do not change, and the SVD never squares a 1e160 (a
  // target that far overflowed inside JacobiSVD, which then crashed on the NaN)
  const double scale = J.size() ? J.cwiseAbs().maxCoeff() : 0.0;
  if (scale > 0) J /= scale;
  // raw condition number of JᵀJ
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues();
  const double smax = sv.size() ? sv[0] : 0.0, smin = sv.size() == n ? sv[n - 1] : 0.0;
  c.condition_number = smin > 0 ? (smax / smin) * (smax / smin) : std::numeric_limits<double>::infinity();

  // column scaling; columns far below the largest are coordinates the data cannot see
  c.column_norms.resize(n);
  double max_norm = 0;
  for (int i = 0; i < n; ++i) max_norm = std::max(max_norm, c.column_norms[i] = J.col(i).norm());
  std::vector<int> seen;
  std::vector<bool> undetermined(n, false), poor(n, false);
  for (int i = 0; i < n; ++i) {
    if (c.column_norms[i] > Conditioning::kUndetermined * max_norm) {
      seen.push_back(i);
    } else {
      undetermined[i] = true;
      WeakDirection w;
      w.relative_singular_value = max_norm > 0 ? c.column_norms[i] / max_norm : 0.0;
      w.coordinates = {names[i]};
      w.vector = Eigen::VectorXd::Unit(n, i);
      c.weak.push_back(w);
    }
  }
  if (!seen.empty()) {
    Eigen::MatrixXd Js(J.rows(), seen.size());
    for (size_t j = 0; j < seen.size(); ++j) Js.col(j) = J.col(seen[j]) / c.column_norms[seen[j]];
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeFullV);
    const Eigen::VectorXd s = svd.singularValues();
    const int m = int(seen.size());
    // a tall J has m singular values; fewer rows than columns leave the rest zero
    Eigen::VectorXd s_full = Eigen::VectorXd::Zero(m);
    s_full.head(s.size()) = s;
    c.scaled_condition_number =
        s_full[m - 1] > 0 ? std::pow(s_full[0] / s_full[m - 1], 2) : std::numeric_limits<double>::infinity();
    for (int j = m - 1; j >= 0; --j) {
      const double rel = s_full[0] > 0 ? s_full[j] / s_full[0] : 0.0;
      if (rel >= Conditioning::kPoorlyDetermined) break;
      WeakDirection w;
      w.relative_singular_value = rel;
      w.vector = Eigen::VectorXd::Zero(n);
      for (int k = 0; k < m; ++k) w.vector[seen[k]] = svd.matrixV()(k, j);
      for (int i = 0; i < n; ++i)
        if (std::abs(w.vector[i]) > 0.3) {
          w.coordinates.push_back(names[i]);
          (rel < Conditioning::kUndetermined ? undetermined : poor)[i] = true;
        }
      c.weak.push_back(w);
    }
  } else {
    c.scaled_condition_number = std::numeric_limits<double>::infinity();
  }
  std::sort(c.weak.begin(), c.weak.end(),
            [](const WeakDirection& a, const WeakDirection& b) { return a.relative_singular_value < b.relative_singular_value; });
  if (scale > 0)
    for (double& norm : c.column_norms) norm *= scale;  // reported as the columns of J itself
  for (int i = num_rigid; i < n; ++i) {
    if (undetermined[i]) {
      c.undetermined.push_back(names[i]);
    } else if (poor[i]) {
      c.poorly_determined.push_back(names[i]);
    }
  }
  return c;
}

std::string EncodeFitReport(const FitReport& f) {
  return ByteWriter()
      .Put<std::uint8_t>(f.usable)
      .PutString(f.termination)
      .PutString(f.brief_report)
      .PutString(f.full_report)
      .Put(f.initial_cost)
      .Put(f.final_cost)
      .PutDoubles(f.cost_per_iteration)
      .Put<std::int32_t>(f.iterations)
      .Put(f.solve_seconds)
      .Take();
}

FitReport DecodeFitReport(const std::string& bytes) {
  ByteReader in(bytes);
  FitReport f;
  f.usable = in.Get<std::uint8_t>() != 0;
  f.termination = in.GetString();
  f.brief_report = in.GetString();
  f.full_report = in.GetString();
  f.initial_cost = in.Get<double>();
  f.final_cost = in.Get<double>();
  f.cost_per_iteration = in.GetDoubles();
  f.iterations = in.Get<std::int32_t>();
  f.solve_seconds = in.Get<double>();
  return f;
}

}  // namespace wobble::fit
