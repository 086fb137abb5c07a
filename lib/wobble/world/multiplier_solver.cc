#include "wobble/world/multiplier_solver.h"

#include <Eigen/Cholesky>
#include <sstream>

namespace wobble {

const char* MultiplierMethodName(MultiplierMethod m) {
  switch (m) {
    case MultiplierMethod::kAuto: return "auto";
    case MultiplierMethod::kDense: return "dense";
    case MultiplierMethod::kSparse: return "sparse";
  }
  return "?";
}

namespace {
// A pivot below this fraction of the largest means the rows of J are (numerically) dependent.
constexpr double kRelativePivot = 1e-10;

bool PivotsOk(const Eigen::VectorXd& D, std::string* why) {
  if (D.size() == 0) return true;
  const double largest = D.cwiseAbs().maxCoeff();
  int bad = 0;
  for (int i = 0; i < D.size(); ++i)
    if (!(D[i] > kRelativePivot * largest)) ++bad;
  if (bad == 0) return true;
  if (why) {
    std::ostringstream s;
    s << "the constraint set is redundant or conflicting: J W J^T (" << D.size() << " rows) has " << bad
      << " zero pivot(s), i.e. " << bad << " constraint row(s) repeat what others already fix";
    *why = s.str();
  }
  return false;
}
}  // namespace

bool MultiplierSolver::Factor(const Eigen::SparseMatrix<double>& A, MultiplierMethod method, std::string* why) {
  factored_ = false;
  method_ = method;
  rows_ = int(A.rows());
  if (rows_ == 0) {  // no constraints: nothing to factor, nothing counted
    factored_ = true;
    return true;
  }
  ++factorizations_;
  if (method == MultiplierMethod::kDense) {
    const Eigen::MatrixXd dense(A);
    Eigen::LDLT<Eigen::MatrixXd> ldlt(dense);
    if (ldlt.info() != Eigen::Success || !PivotsOk(ldlt.vectorD(), why)) return false;
    inverse_ = ldlt.solve(Eigen::MatrixXd::Identity(rows_, rows_));  // Y = A⁻¹ (Eq. 10)
  } else {
    ldlt_.compute(A);
    if (ldlt_.info() != Eigen::Success || !PivotsOk(ldlt_.vectorD(), why)) {
      if (why && why->empty()) *why = "the constraint set is redundant or conflicting: J W J^T is singular";
      return false;
    }
  }
  factored_ = true;
  return true;
}

void MultiplierSolver::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) const {
  if (rows_ == 0) {
    x->resize(0);
    return;
  }
  if (method_ == MultiplierMethod::kDense) {
    // a few rows (Fig. 2: 6): the coefficient-wise product beats Eigen's gemv kernel there
    if (rows_ <= 32)
      x->noalias() = inverse_.lazyProduct(b);
    else
      x->noalias() = inverse_ * b;
  } else {
    *x = ldlt_.solve(b);
  }
}

}  // namespace wobble
