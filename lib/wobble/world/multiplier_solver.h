// The constraint matrix A = J W Jᵀ of Eq. 8–10, factored once and reused.
//
// Two ways to hold it, chosen by size (ConstrainedWorldOptions::dense_max_rows):
//  - dense: the explicit inverse Y = A⁻¹, as the paper does (Eq. 10: λ = −Y(...)); a solve is
//    then one matrix–vector product, O(m²), but forming Y costs O(m³) and m² memory;
//  - sparse: a cached Eigen::SimplicialLDLT of the sparse A. A chain of attached links gives a
//    banded A, so both the factorization and each solve cost O(m).
// A singular A (redundant or conflicting constraints) is reported, never solved into NaNs.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <Eigen/SparseCholesky>
#include <string>

namespace wobble {

enum class MultiplierMethod { kAuto, kDense, kSparse };
const char* MultiplierMethodName(MultiplierMethod m);

class MultiplierSolver {
 public:
  MultiplierSolver() = default;
  // Copies keep a dense inverse; Eigen's sparse factorization cannot be copied, so a copy of a
  // sparse solver is unfactored (its owner refactors at the next use, and counts it).
  MultiplierSolver(const MultiplierSolver& o) { *this = o; }
  MultiplierSolver& operator=(const MultiplierSolver& o) {
    if (this == &o) return *this;
    method_ = o.method_;
    rows_ = o.rows_;
    factorizations_ = o.factorizations_;
    inverse_ = o.inverse_;
    factored_ = o.factored_ && (method_ == MultiplierMethod::kDense || rows_ == 0);
    return *this;
  }

  // Factors A (symmetric positive semi-definite by construction). Returns false with *why set
  // when A is singular to within a relative pivot of 1e-10 (redundant constraints) or not
  // positive. `method` must be kDense or kSparse. Counts every non-empty A in factorizations().
  bool Factor(const Eigen::SparseMatrix<double>& A, MultiplierMethod method, std::string* why);
  // x = A⁻¹ b with the last successful factorization.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) const;

  int rows() const { return rows_; }
  bool factored() const { return factored_; }
  MultiplierMethod method() const { return method_; }
  long factorizations() const { return factorizations_; }
  void Invalidate() { factored_ = false; }

 private:
  MultiplierMethod method_ = MultiplierMethod::kSparse;
  int rows_ = 0;
  bool factored_ = false;
  long factorizations_ = 0;
  Eigen::MatrixXd inverse_;  // dense: Y = A⁻¹
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt_;
};

}  // namespace wobble
