// The size-3 instances (a body without modes) contain the mode loops `for d < num_q − 3`,
// which never run there (num_q == 3) but which GCC cannot prove empty: silence its
// -Warray-bounds false positive for this file's instantiations only.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Warray-bounds"
#endif

#include "wobble/fit/internal/residuals.h"

#include <algorithm>
#include <stdexcept>
#include <string>


namespace wobble::fit {

ceres::CostFunction* MakeSegmentCost(const SegmentResidual& r) {
  return WithNumQ(r.num_q, [&](auto n) -> ceres::CostFunction* {
    return new ceres::AutoDiffCostFunction<SegmentResidual, 2, decltype(n)::value>(new SegmentResidual(r));
  });
}

ceres::CostFunction* MakeReverseSegmentCost(const ReverseSegmentResidual& r) {
  return WithNumQ(r.num_q, [&](auto n) -> ceres::CostFunction* {
    return new ceres::AutoDiffCostFunction<ReverseSegmentResidual, 2, decltype(n)::value>(new ReverseSegmentResidual(r));
  });
}

int NearestSegment(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b,
                   const Eigen::Vector2d& x) {
  int best = 0;
  double best_d2 = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < a.size(); ++i) {
    const double d2 = (x - ClosestOnSegment<double>(x, a[i], b[i])).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = int(i);
    }
  }
  return best;
}

ceres::CostFunction* MakeNearestSegmentCost(const NearestSegmentResidual& r) {
  return WithNumQ(r.num_q, [&](auto n) -> ceres::CostFunction* {
    return new ceres::AutoDiffCostFunction<NearestSegmentResidual, 2, decltype(n)::value>(new NearestSegmentResidual(r));
  });
}

ceres::CostFunction* MakeNearestBodySegmentCost(const NearestBodySegmentResidual& r) {
  return WithNumQ(r.num_q, [&](auto n) -> ceres::CostFunction* {
    return new ceres::AutoDiffCostFunction<NearestBodySegmentResidual, 2, decltype(n)::value>(
        new NearestBodySegmentResidual(r));
  });
}

namespace {

class RestPriorCost : public ceres::CostFunction {
 public:
  explicit RestPriorCost(const RestPrior& r) : r_(r) {
    set_num_residuals(r.num_q - r.num_rigid);
    mutable_parameter_block_sizes()->push_back(r.num_q);
  }
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const int n = r_.num_q, rigid = r_.num_rigid, D = n - rigid;
    for (int d = 0; d < D; ++d) residuals[d] = r_.sqrt_weight * p[0][rigid + d];
    if (jacobians && jacobians[0]) {
      std::fill(jacobians[0], jacobians[0] + D * n, 0.0);
      for (int d = 0; d < D; ++d) jacobians[0][d * n + rigid + d] = r_.sqrt_weight;
    }
    return true;
  }

 private:
  RestPrior r_;
};

class SecondDifferenceCost : public ceres::CostFunction {
 public:
  explicit SecondDifferenceCost(const SecondDifference& r) : r_(r) {
    const int n = int(r.scale.size());
    set_num_residuals(n);
    for (int b = 0; b < 3; ++b) mutable_parameter_block_sizes()->push_back(n);
  }
  bool Evaluate(double const* const* p, double* residuals, double** jacobians) const override {
    const int n = int(r_.scale.size());
    const double c[3] = {r_.c0, r_.c1, r_.c2};
    for (int i = 0; i < n; ++i) residuals[i] = r_.scale[i] * (c[0] * p[0][i] + c[1] * p[1][i] + c[2] * p[2][i]);
    if (jacobians)
      for (int b = 0; b < 3; ++b) {
        if (!jacobians[b]) continue;
        std::fill(jacobians[b], jacobians[b] + n * n, 0.0);
        for (int i = 0; i < n; ++i) jacobians[b][i * n + i] = r_.scale[i] * c[b];
      }
    return true;
  }

 private:
  SecondDifference r_;
};

}  // namespace

ceres::CostFunction* MakeRestPriorCost(const RestPrior& r) {
  return r.num_q > r.num_rigid ? new RestPriorCost(r) : nullptr;
}

ceres::CostFunction* MakeSecondDifferenceCost(const SecondDifference& r) { return new SecondDifferenceCost(r); }

}  // namespace wobble::fit
