#include "wobble/body/linear_body.h"

#include <cmath>

#include <stdexcept>

#include "wobble/core/limits.h"

namespace wobble {

int LinearBasisSize(int dim, LinearOrder order) {
  if (order == LinearOrder::kAffine) return dim + 1;
  return dim == 2 ? 6 : 10;
}

Eigen::VectorXd LinearBasis(LinearOrder order, const Eigen::VectorXd& u) {
  const int d = int(u.size());
  Eigen::VectorXd p(LinearBasisSize(d, order));
  p.head(d) = u;
  p[d] = 1.0;
  if (order == LinearOrder::kQuadratic) {
    if (d == 2) {
      p.tail(3) << u[0] * u[1], u[0] * u[0], u[1] * u[1];
    } else {
      p.tail(6) << u[0] * u[1], u[0] * u[2], u[1] * u[2], u[0] * u[0], u[1] * u[1], u[2] * u[2];
    }
  }
  return p;
}

LinearBodyDef MakeBoxBody(const std::string& name, int dim, LinearOrder order, const Eigen::VectorXd& half_extents,
                          int per_side, double mass) {
  if (dim != 2 && dim != 3) throw std::invalid_argument("box body '" + name + "': dim must be 2 or 3");
  if (half_extents.size() != dim) throw std::invalid_argument("box body '" + name + "': half extents need " +
                                                              std::to_string(dim) + " entries");
  if (per_side < 2) throw std::invalid_argument("box body '" + name + "': need at least 2 points per side");
  CheckedCount(std::pow(double(per_side), dim), 1, kMaxLinearPoints, "box body '" + name + "': its mass points (grid^dim)");
  LinearBodyDef def;
  def.name = name;
  def.dim = dim;
  def.order = order;
  const int count = dim == 2 ? per_side * per_side : per_side * per_side * per_side;
  for (int i = 0; i < count; ++i) {
    Eigen::VectorXd u(dim);
    int rest = i;
    for (int a = 0; a < dim; ++a) {
      const int k = rest % per_side;
      rest /= per_side;
      u[a] = half_extents[a] * (-1.0 + 2.0 * k / (per_side - 1));
    }
    def.points.push_back(u);
    def.masses.push_back(mass / count);
  }
  return def;
}

LinearBodyModel::LinearBodyModel(LinearBodyDef def) : def_(std::move(def)) {
  const std::string who = "linear body '" + def_.name + "': ";
  if (def_.dim != 2 && def_.dim != 3) throw std::invalid_argument(who + "dim must be 2 or 3, got " + std::to_string(def_.dim));
  if (def_.points.size() != def_.masses.size())
    throw std::invalid_argument(who + std::to_string(def_.points.size()) + " points but " +
                                std::to_string(def_.masses.size()) + " masses");
  n_ = LinearBasisSize(def_.dim, def_.order);
  M_.setZero(n_, n_);
  first_moment_.setZero(n_);
  point_bases_.resize(n_, num_points());
  for (int k = 0; k < num_points(); ++k) {
    if (def_.points[k].size() != def_.dim || !def_.points[k].allFinite())
      throw std::invalid_argument(who + "point " + std::to_string(k) + " needs " + std::to_string(def_.dim) +
                                  " finite coordinates");
    const double m = def_.masses[k];
    if (!(m > 0.0) || !std::isfinite(m))
      throw std::invalid_argument(who + "mass " + std::to_string(k) + " must be positive and finite");
    const Eigen::VectorXd p = Basis(def_.points[k]);
    point_bases_.col(k) = p;
    M_ += m * p * p.transpose();  // M_jk = Σ m p_j p_k (§2.2)
    first_moment_ += m * p;
    total_mass_ += m;
  }
  // the points must span the basis, else some deformation moves no mass (M singular)
  Eigen::LDLT<Eigen::MatrixXd> ldlt(M_);
  const Eigen::VectorXd D = ldlt.vectorD();
  const double largest = D.cwiseAbs().maxCoeff();
  if (num_points() == 0 || ldlt.info() != Eigen::Success || !(D.minCoeff() > 1e-12 * largest))
    throw std::invalid_argument(who + "the " + std::to_string(num_points()) +
                                " mass points do not span the deformation (mass matrix singular): an affine body needs " +
                                std::to_string(def_.dim + 1) + " points not on one " +
                                (def_.dim == 2 ? "line" : "plane") + ", a quadratic one more, spread over the body");
  W_ = ldlt.solve(Eigen::MatrixXd::Identity(n_, n_));  // inverted once (Eq. 5)
  W_ = 0.5 * (W_ + W_.transpose());
  basis_lo_ = point_bases_.rowwise().minCoeff();
  basis_hi_ = point_bases_.rowwise().maxCoeff();
  const Eigen::VectorXd sides = basis_hi_.head(def_.dim) - basis_lo_.head(def_.dim);  // p starts with u
  half_thickness_ = 0.5 * sides.minCoeff();
}

Eigen::VectorXd LinearBodyModel::centre_of_mass() const { return first_moment_.head(def_.dim) / total_mass_; }

Eigen::MatrixXd LinearBodyModel::RestState() const {
  return PlacedState(Eigen::MatrixXd::Identity(dim(), dim()), Eigen::VectorXd::Zero(dim()));
}

Eigen::MatrixXd LinearBodyModel::PlacedState(const Eigen::MatrixXd& rotation, const Eigen::VectorXd& translation) const {
  if (rotation.rows() != dim() || rotation.cols() != dim() || translation.size() != dim())
    throw std::invalid_argument("linear body '" + def_.name + "': placement needs a " + std::to_string(dim()) + "x" +
                                std::to_string(dim()) + " rotation and a " + std::to_string(dim()) + "-vector");
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(dim(), n_);
  R.leftCols(dim()) = rotation;
  R.col(dim()) = translation;
  return R;
}

}  // namespace wobble
