#include "wobble/fit/residuals.h"

namespace wobble::fit {

PointBasis BasisOf(const BodyModel& body, int mass_point, const Eigen::Vector2d& lattice_coords) {
  PointBasis p;
  if (mass_point >= 0) {
    p.b0 = body.rest_local(mass_point);
    p.B = body.mode_matrix(mass_point);
  } else {
    body.LocalBasis(lattice_coords, &p.b0, &p.B);
  }
  return p;
}

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

ceres::CostFunction* MakeRestPriorCost(const RestPrior& r) {
  return WithNumQ(r.num_q, [&](auto n) -> ceres::CostFunction* {
    constexpr int N = decltype(n)::value;
    if constexpr (N == kRigidDofs) {
      return nullptr;  // no modes, no prior
    } else {
      return new ceres::AutoDiffCostFunction<RestPrior, N - kRigidDofs, N>(new RestPrior(r));
    }
  });
}

ceres::CostFunction* MakeSecondDifferenceCost(const SecondDifference& r) {
  return WithNumQ(int(r.scale.size()), [&](auto n) -> ceres::CostFunction* {
    constexpr int N = decltype(n)::value;
    return new ceres::AutoDiffCostFunction<SecondDifference, N, N, N, N>(new SecondDifference(r));
  });
}

}  // namespace wobble::fit
