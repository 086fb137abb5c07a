// Ground contact of the Witkin & Welch linear bodies (issue 19): the penalty ground of thesis
// §4.9 (Eq. 4.24/4.25, capped friction with a sliding anchor) at every mass point x_k = R p_k,
// exactly as FFD bodies feel it (forces.h, terrain.h), with the generalized force of a point
// force f at p_k being f p_kᵀ (W&W end of §2.2). A 2D body feels the world's Ground — the line
// or a terrain, one contact per (point, face) — and a 3D body the world's GroundPlane.
//
// Points are visited only when a bound of the lowest point's height (interval arithmetic on the
// basis terms, LinearBodyModel::basis_lo/hi) reaches the ground, so a body in the air costs O(n).
#pragma once

#include <Eigen/Core>
#include <tuple>
#include <vector>

#include "wobble/body/linear_body.h"
#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/step.h"

namespace wobble {

// The contacts of one linear body, by dimension: list<2>() on a 2D ground (sorted by point,
// then face), list<3>() on the 3D plane (sorted by point); the deepest point at the last update.
struct LinearContacts {
  std::tuple<std::vector<Contact<2, double>>, std::vector<Contact<3, double>>> lists;
  double penetration = 0.0;
  template <int Dim> std::vector<Contact<Dim, double>>& list() { return std::get<Dim - 2>(lists); }
  template <int Dim> const std::vector<Contact<Dim, double>>& list() const { return std::get<Dim - 2>(lists); }
  int size() const { return int(list<2>().size() + list<3>().size()); }
  void clear() {
    list<2>().clear();
    list<3>().clear();
    penetration = 0.0;
  }
};

// The ground a linear body of either dimension feels: `ground` in 2D, `plane` in 3D.
struct LinearGround {
  const Ground& ground;
  const GroundPlane& plane;
};

// Adds the ground's generalized force Σ f_k p_kᵀ at the state (R, Ṙ) to *Q (d × n): points in
// `contacts` keep their anchors, a point newly below the ground is anchored at its foot.
void AddLinearGroundForce(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, const LinearContacts& contacts, Eigen::MatrixXd* Q);

// After an accepted step, as UpdateContacts does for FFD bodies: points that went below the
// ground get an anchor at their entry point, points that left lose theirs, and an anchor whose
// friction hit the cap slides so that the tangential spring holds exactly the capped force.
void UpdateLinearContacts(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, LinearContacts* contacts);

// The ground's penalty energy Σ ½ K_d |x_k − anchor|² over the contacts.
double LinearGroundEnergy(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const LinearContacts& contacts);

// The ground's force on each contact (world frame, in the order of list<2>() then list<3>()): what the
// tests sum to check statics.
std::vector<Eigen::VectorXd> LinearContactForces(const LinearBodyModel& model, const LinearGround& g,
                                                 const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot,
                                                 const LinearContacts& contacts);

}  // namespace wobble
