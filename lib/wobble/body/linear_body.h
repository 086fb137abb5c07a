// Witkin–Welch linear-deformation bodies (§2.2–2.3): x = R p(u).
//
// u is a material point in undeformed (body) coordinates, p(u) a fixed polynomial basis and
// the d×n matrix R the generalized coordinates. Because x is linear in R the mass matrix
//   M_jk = Σ m p_j(u) p_k(u)                     (§2.2, kinetic energy T = ½ Ṙ_ij Ṙ_ik M_jk)
// is constant, so its inverse W is computed once here (Eq. 5: R̈ = Q W), and a world force f at
// u gives the generalized force Q = f pᵀ (end of §2.2).
//
// Dimension is a run-time value (2 or 3) with Eigen dynamic sizes rather than a template
// parameter: one World holds 2D and 3D bodies side by side (and the 2D FFD bodies),
// and the multiplier solve flattens every body into one global vector anyway, so a template
// would only move the dimension switch into type erasure. The sizes are tiny (n ≤ 10).
//
// Basis order (ours, chosen so that the affine basis is a prefix of the quadratic one and the
// columns of R read as [m | t | quadratic terms]):
//   affine     2D: [x, y, 1]                      3D: [x, y, z, 1]                (§2.3)
//   quadratic  2D: [x, y, 1, xy, x², y²]          3D: [x, y, z, 1, xy, xz, yz, x², y², z²]
// The paper writes the 3D quadratic basis as [1, x, y, z, xy, xz, yz, x², y², z²]: the same
// terms in another order. At rest R = [I | 0 | 0], so x = u.
#pragma once

#include <Eigen/Core>
#include <Eigen/Cholesky>
#include <string>
#include <vector>

namespace wobble {

enum class LinearOrder { kAffine, kQuadratic };

// Number of basis terms n of p(u): affine d+1, quadratic 6 (2D) or 10 (3D).
int LinearBasisSize(int dim, LinearOrder order);

// p(u) in the order above. u must have `dim` entries.
Eigen::VectorXd LinearBasis(LinearOrder order, const Eigen::VectorXd& u);

// What a linear body is made of: mass points (u_k, m_k) in undeformed coordinates.
struct LinearBodyDef {
  std::string name;
  int dim = 2;  // 2 or 3
  LinearOrder order = LinearOrder::kAffine;
  std::vector<Eigen::VectorXd> points;  // u_k, each of size dim
  std::vector<double> masses;           // m_k > 0
};

// A box [-half, half] (per axis) filled with a grid of `per_side` points per axis (≥ 2),
// of total mass `mass`, equal point masses. The usual way to make a link or a block.
LinearBodyDef MakeBoxBody(const std::string& name, int dim, LinearOrder order, const Eigen::VectorXd& half_extents,
                          int per_side, double mass);

// The immutable model of a linear body (MuJoCo's mjModel): basis, mass matrix and its inverse.
class LinearBodyModel {
 public:
  // Throws std::invalid_argument naming the body when dim is not 2 or 3, a point has the wrong
  // size, a mass is not positive and finite, or the points do not span the basis (M singular:
  // e.g. collinear points for an affine 2D body, or too few points for a quadratic one).
  explicit LinearBodyModel(LinearBodyDef def);

  const std::string& name() const { return def_.name; }
  const LinearBodyDef& def() const { return def_; }
  int dim() const { return def_.dim; }
  LinearOrder order() const { return def_.order; }
  int basis_size() const { return n_; }           // n
  int num_q() const { return def_.dim * n_; }     // d·n generalized coordinates
  int num_points() const { return int(def_.masses.size()); }
  double total_mass() const { return total_mass_; }
  Eigen::VectorXd Basis(const Eigen::VectorXd& u) const { return LinearBasis(def_.order, u); }

  const Eigen::MatrixXd& mass_matrix() const { return M_; }          // M (n×n), Eq. 5
  const Eigen::MatrixXd& inverse_mass_matrix() const { return W_; }  // W = M⁻¹, inverted once
  // Σ m_k p(u_k): gravity's generalized force is g μᵀ, its energy −g·(R μ).
  const Eigen::VectorXd& first_moment() const { return first_moment_; }
  // Σ m_k u_k / Σ m_k in undeformed coordinates.
  Eigen::VectorXd centre_of_mass() const;
  // p(u_k) of every mass point, one column each (n × points): x_k = R p_k, made once.
  const Eigen::MatrixXd& point_bases() const { return point_bases_; }
  // The range of each basis term over the mass points: any point's height above a plane is
  // at least Σ_j min(c_j lo_j, c_j hi_j) with c = nᵀR, a bound the ground test takes before
  // visiting points (interval arithmetic: the terms bounded separately, so it is never above).
  const Eigen::VectorXd& basis_lo() const { return basis_lo_; }
  const Eigen::VectorXd& basis_hi() const { return basis_hi_; }
  // Half the shortest side of the mass points' box at rest: how deep a point may go into the
  // ground before the run stops (runaway penetration), as half a lattice side for FFD bodies.
  double half_thickness() const { return half_thickness_; }

  // R of the rest shape placed by a rotation (d×d) and translation: R = [rot | t | 0].
  Eigen::MatrixXd PlacedState(const Eigen::MatrixXd& rotation, const Eigen::VectorXd& translation) const;
  Eigen::MatrixXd RestState() const;

 private:
  LinearBodyDef def_;
  int n_ = 0;
  double total_mass_ = 0;
  Eigen::MatrixXd M_, W_;
  Eigen::VectorXd first_moment_;
  Eigen::MatrixXd point_bases_;
  Eigen::VectorXd basis_lo_, basis_hi_;
  double half_thickness_ = 0;
};

// Kinematics of a material point with basis vector p (=Basis(u)).
inline Eigen::VectorXd LinearPointPosition(const Eigen::MatrixXd& R, const Eigen::VectorXd& p) { return R * p; }
inline Eigen::VectorXd LinearPointVelocity(const Eigen::MatrixXd& R_dot, const Eigen::VectorXd& p) { return R_dot * p; }
// Q = f pᵀ (end of §2.2): the generalized force of a world force f at the point.
inline Eigen::MatrixXd LinearPointForce(const Eigen::VectorXd& f, const Eigen::VectorXd& p) { return f * p.transpose(); }

}  // namespace wobble
