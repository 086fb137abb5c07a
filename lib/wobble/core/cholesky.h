// Cholesky factorization and solve for the small dense SPD systems of a step (7x7 for the
// table), templated on the matrix so the same loop serves double and ceres::Jet.
#pragma once

#include <algorithm>
#include <cmath>

#include "wobble/core/types.h"

namespace wobble {

// Factors A = L Lᵀ in place: the strict lower triangle holds L and the diagonal holds
// 1/L(j,j), so that solves multiply instead of divide (divisions dominated a 7x7 solve).
// A plain loop: for these sizes it is several times faster than Eigen's dynamic-size LLT.
// Returns false when A is not (numerically) positive definite.
template <class Mat> bool CholeskyInPlace(Mat* A_in) {
  using std::sqrt;
  using T = typename Mat::Scalar;
  Mat& A = *A_in;
  const int n = int(A.rows());
  for (int j = 0; j < n; ++j) {
    T d = A(j, j);
    const double diagonal = ScalarValue(d);
    for (int k = 0; k < j; ++k) d -= A(j, k) * A(j, k);
    // a pivot lost to cancellation (below rounding of its diagonal) means numerically singular
    if (!(ScalarValue(d) > 1e-14 * diagonal)) return false;
    const T inv = T(1.0) / sqrt(d);
    A(j, j) = inv;
    for (int i = j + 1; i < n; ++i) {
      T v = A(i, j);
      for (int k = 0; k < j; ++k) v -= A(i, k) * A(j, k);
      A(i, j) = v * inv;
    }
  }
  return true;
}

// Solves L Lᵀ x = b in place with a factor from CholeskyInPlace. L's scalar may be double
// while b holds Jets (a constant factor applied to a differentiated right-hand side).
template <class Mat, class Vec> void CholeskySolveInPlace(const Mat& L, Vec* b) {
  using T = typename Vec::Scalar;
  Vec& x = *b;
  const int n = int(L.rows());
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < i; ++k) x[i] -= T(L(i, k)) * x[k];
    x[i] *= T(L(i, i));
  }
  for (int i = n - 1; i >= 0; --i) {
    for (int k = i + 1; k < n; ++k) x[i] -= T(L(k, i)) * x[k];
    x[i] *= T(L(i, i));
  }
}

// The pivots L(j,j)² of a factor lie in [λ_min, λ_max] of A, so the ratio of the largest to
// the smallest is a cheap lower bound of cond₂(A).
template <class Mat> void CholeskyPivotRange(const Mat& L, double* lo, double* hi) {
  for (int j = 0; j < L.rows(); ++j) {
    const double inv = ScalarValue(L(j, j));
    const double pivot = 1.0 / (inv * inv);
    *lo = std::min(*lo, pivot);
    *hi = std::max(*hi, pivot);
  }
}

}  // namespace wobble
