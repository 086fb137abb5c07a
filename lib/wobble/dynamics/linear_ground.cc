#include "wobble/dynamics/linear_ground.h"

#include <algorithm>

namespace wobble {

namespace {

// M p for a d × n state matrix and a point's basis column, without a heap allocation.
template <int D> Eigen::Matrix<double, D, 1> Times(const Eigen::MatrixXd& M, const double* p) {
  Eigen::Matrix<double, D, 1> x = Eigen::Matrix<double, D, 1>::Zero();
  for (int j = 0; j < M.cols(); ++j)
    for (int i = 0; i < D; ++i) x[i] += M(i, j) * p[j];
  return x;
}

// The least value of Σ_j c_j p_j over the body's points, from the range of each basis term.
double LowerBound(const LinearBodyModel& m, const double* c) {
  double sum = 0.0;
  for (int j = 0; j < m.basis_size(); ++j) sum += std::min(c[j] * m.basis_lo()[j], c[j] * m.basis_hi()[j]);
  return sum;
}

// True when no point of the body can be below the 2D ground (the hull test of forces.h).
bool ClearOf(const LinearBodyModel& m, const Ground& g, const Eigen::MatrixXd& R) {
  const int n = m.basis_size();
  double c[2][10], lo[2];  // n ≤ 10 (the 3D quadratic basis)
  for (int j = 0; j < n; ++j) c[0][j] = R(0, j), c[1][j] = R(1, j);
  for (int i = 0; i < 2; ++i) lo[i] = LowerBound(m, c[i]);
  if (g.terrain) {
    double neg[10];
    for (int j = 0; j < n; ++j) neg[j] = -c[0][j];
    const double hi_x = -LowerBound(m, neg);
    return lo[1] >= g.terrain->MaxHeight(lo[0], hi_x);
  }
  const GroundFace line = g.Face(0);
  double along_n[10];
  for (int j = 0; j < n; ++j) along_n[j] = line.n[0] * c[0][j] + line.n[1] * c[1][j];
  return LowerBound(m, along_n) - line.n.dot(line.point) >= 0.0;
}

bool ClearOf(const LinearBodyModel& m, const GroundPlane& g, const Eigen::MatrixXd& R) {
  double along_n[10];
  if (g.heightfield) {  // above the highest node
    for (int j = 0; j < m.basis_size(); ++j) along_n[j] = R(1, j);
    return LowerBound(m, along_n) >= g.heightfield->max_height();
  }
  for (int j = 0; j < m.basis_size(); ++j) along_n[j] = g.normal.dot(R.col(j));
  return LowerBound(m, along_n) - g.normal.dot(g.point) >= 0.0;
}

// Visits every point below the 2D ground as f(k, p, x, v, anchor, face, face_index), once per
// face it feels (ForEachFaceFelt of ground_line.h, the FFD bodies' rules).
template <class F>
void ForEachContact2(const LinearBodyModel& m, const Ground& g, const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot,
                     const std::vector<Contact<2, double>>& contacts, F&& f) {
  if (!g.enabled || ClearOf(m, g, R)) return;
  const GroundFace line = g.Face(0);
  const Eigen::MatrixXd& P = m.point_bases();
  auto first = contacts.begin();
  for (int k = 0; k < m.num_points(); ++k) {
    const double* p = P.col(k).data();
    const Vec2<double> x = Times<2>(R, p);
    auto contacts_of_k = [&] {  // points come in order: the cursor only moves forward
      while (first != contacts.end() && first->point < k) ++first;
      auto last = first;
      while (last != contacts.end() && last->point == k) ++last;
      return std::make_pair(first, last);
    };
    ForEachFaceFelt(g, line, x, [&] { return Times<2>(R_dot, p); }, contacts_of_k,
                    [&](const GroundFace& face, int face_index, const Vec2<double>& anchor, const Vec2<double>& v) {
                      f(k, p, x, v, anchor, face, face_index);
                    });
  }
}

// Visits every point below the 3D ground (plane or heightfield) as f(k, p, x, v, anchor, face,
// face_index), once per face it feels (ForEachFaceFelt of ground_plane.h, the FFD bodies' rules).
template <class F>
void ForEachContact3(const LinearBodyModel& m, const GroundPlane& g, const Eigen::MatrixXd& R,
                     const Eigen::MatrixXd& R_dot, const std::vector<Contact<3, double>>& contacts, F&& f) {
  if (!g.enabled || ClearOf(m, g, R)) return;
  const Eigen::MatrixXd& P = m.point_bases();
  for (int k = 0; k < m.num_points(); ++k) {
    const double* p = P.col(k).data();
    const Vec3<double> x = Times<3>(R, p);
    ForEachFaceFelt(g, x, [&] { return ContactsOfPoint(contacts, k); },
                     [&](int face_index, const GroundPlane& face, const Vec3<double>& anchor) {
                       f(k, p, x, Times<3>(R_dot, p), anchor, face, face_index);
                     });
  }
}

// Q += f pᵀ (W&W end of §2.2).
template <int D> void AddPointForce(const Eigen::Matrix<double, D, 1>& f, const double* p, Eigen::MatrixXd* Q) {
  for (int j = 0; j < Q->cols(); ++j)
    for (int i = 0; i < D; ++i) (*Q)(i, j) += f[i] * p[j];
}

}  // namespace

void AddLinearGroundForce(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, const LinearContacts& contacts, Eigen::MatrixXd* Q) {
  bool slipping;
  if (model.dim() == 2) {
    ForEachContact2(model, g.ground, R, R_dot, contacts.list2,
                    [&](int, const double* p, const Vec2<double>& x, const Vec2<double>& v, const Vec2<double>& anchor,
                        const GroundFace& face, int) { AddPointForce<2>(GroundForce(face, x, v, anchor, &slipping), p, Q); });
    return;
  }
  ForEachContact3(model, g.plane, R, R_dot, contacts.list3,
                  [&](int, const double* p, const Vec3<double>& x, const Vec3<double>& v, const Vec3<double>& anchor,
                      const GroundPlane& face, int) { AddPointForce<3>(GroundForce(face, x, v, anchor, &slipping), p, Q); });
}

void UpdateLinearContacts(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, LinearContacts* contacts) {
  double deepest = 0.0;
  if (model.dim() == 2) {
    thread_local std::vector<Contact<2, double>> next;  // no heap traffic while a body rests
    next.clear();
    ForEachContact2(model, g.ground, R, R_dot, contacts->list2,
                    [&](int k, const double*, const Vec2<double>& x, const Vec2<double>& v, Vec2<double> anchor,
                        const GroundFace& face, int face_index) {
                      bool slipping;
                      Vec2<double> f = GroundForce(face, x, v, anchor, &slipping);
                      if (slipping) SlipAnchor(face, x, v, &anchor, &f);
                      next.push_back({k, anchor, face_index});
                      deepest = std::max(deepest, -face.Height(x));
                    });
    contacts->list2.swap(next);
  } else {
    thread_local std::vector<Contact<3, double>> next;
    next.clear();
    ForEachContact3(model, g.plane, R, R_dot, contacts->list3,
                    [&](int k, const double*, const Vec3<double>& x, const Vec3<double>& v, Vec3<double> anchor,
                        const GroundPlane& face, int face_index) {
                      bool slipping;
                      Vec3<double> f = GroundForce(face, x, v, anchor, &slipping);
                      if (slipping) SlipAnchor(face, x, v, &anchor, &f);
                      next.push_back({k, anchor, face_index});
                      deepest = std::max(deepest, -face.Height(x));
                    });
    contacts->list3.swap(next);
  }
  contacts->penetration = deepest;
}

double LinearGroundEnergy(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const LinearContacts& contacts) {
  const Eigen::MatrixXd& P = model.point_bases();
  double energy = 0.0;
  for (const Contact<2, double>& c : contacts.list2)
    energy += 0.5 * g.ground.Face(c.face).stiffness * (Times<2>(R, P.col(c.point).data()) - c.anchor).squaredNorm();
  for (const Contact<3, double>& c : contacts.list3)
    energy += 0.5 * g.plane.stiffness * (Times<3>(R, P.col(c.point).data()) - c.anchor).squaredNorm();
  return energy;
}

std::vector<Eigen::VectorXd> LinearContactForces(const LinearBodyModel& model, const LinearGround& g,
                                                 const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot,
                                                 const LinearContacts& contacts) {
  const Eigen::MatrixXd& P = model.point_bases();
  std::vector<Eigen::VectorXd> forces;
  bool slipping;
  for (const Contact<2, double>& c : contacts.list2) {
    const double* p = P.col(c.point).data();
    forces.push_back(GroundForce(g.ground.Face(c.face), Times<2>(R, p), Times<2>(R_dot, p), c.anchor, &slipping));
  }
  for (const Contact<3, double>& c : contacts.list3) {
    const double* p = P.col(c.point).data();
    const Vec3<double> x = Times<3>(R, p);
    forces.push_back(GroundForce(g.plane.Face(c.face, x), x, Times<3>(R_dot, p), c.anchor, &slipping));
  }
  return forces;
}

}  // namespace wobble
