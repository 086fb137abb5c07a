#include "wobble/dynamics/linear_ground.h"

#include <algorithm>
#include <type_traits>
#include <utility>

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

// The ground a body of dimension Dim feels and the type of its faces.
template <int Dim> const auto& GroundOf(const LinearGround& g) {
  if constexpr (Dim == 2) return g.ground;
  else return g.plane;
}
template <int Dim> using FaceOf = std::conditional_t<Dim == 2, GroundFace, GroundPlane>;
template <int Dim> using VecD = Eigen::Matrix<double, Dim, 1>;

// Visits every point below the ground of dimension Dim as f(k, p, x, v, anchor, face,
// face_index), once per face it feels (ForEachFaceFelt of ground_line.h or ground_plane.h, the
// FFD bodies' rules): in the order of the points, then of the faces felt.
template <int Dim, class F>
void ForEachContact(const LinearBodyModel& m, const LinearGround& ground, const Eigen::MatrixXd& R,
                    const Eigen::MatrixXd& R_dot, const std::vector<Contact<Dim, double>>& contacts, F&& f) {
  const auto& g = GroundOf<Dim>(ground);
  if (!g.enabled || ClearOf(m, g, R)) return;
  [[maybe_unused]] const auto line = [&] {  // the 2D line's face, made once
    if constexpr (Dim == 2) return g.Face(0);
    else return 0;
  }();
  const Eigen::MatrixXd& P = m.point_bases();
  auto first = contacts.begin();
  for (int k = 0; k < m.num_points(); ++k) {
    const double* p = P.col(k).data();
    const VecD<Dim> x = Times<Dim>(R, p);
    auto velocity = [&] { return Times<Dim>(R_dot, p); };
    auto contacts_of_k = [&] {  // points come in order: the cursor only moves forward
      while (first != contacts.end() && first->point < k) ++first;
      auto last = first;
      while (last != contacts.end() && last->point == k) ++last;
      return std::make_pair(first, last);
    };
    if constexpr (Dim == 2) {
      ForEachFaceFelt(g, line, x, velocity, contacts_of_k,
                      [&](const GroundFace& face, int face_index, const Vec2<double>& anchor, const Vec2<double>& v) {
                        f(k, p, x, v, anchor, face, face_index);
                      });
    } else {
      ForEachFaceFelt(g, x, contacts_of_k, [&](int face_index, const GroundPlane& face, const Vec3<double>& anchor) {
        f(k, p, x, velocity(), anchor, face, face_index);
      });
    }
  }
}

// Q += f pᵀ (W&W end of §2.2).
template <int D> void AddPointForce(const Eigen::Matrix<double, D, 1>& f, const double* p, Eigen::MatrixXd* Q) {
  for (int j = 0; j < Q->cols(); ++j)
    for (int i = 0; i < D; ++i) (*Q)(i, j) += f[i] * p[j];
}

template <int Dim>
void AddGroundForce(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                    const Eigen::MatrixXd& R_dot, const LinearContacts& contacts, Eigen::MatrixXd* Q) {
  bool slipping;
  ForEachContact<Dim>(model, g, R, R_dot, contacts.list<Dim>(),
                      [&](int, const double* p, const VecD<Dim>& x, const VecD<Dim>& v, const VecD<Dim>& anchor,
                          const FaceOf<Dim>& face, int) {
                        AddPointForce<Dim>(GroundForce(face, x, v, anchor, &slipping), p, Q);
                      });
}

// The contacts of the state (R, Ṙ) in place of *contacts; the deepest point's depth.
template <int Dim>
double UpdateContacts(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                      const Eigen::MatrixXd& R_dot, std::vector<Contact<Dim, double>>* contacts) {
  thread_local std::vector<Contact<Dim, double>> next;  // no heap traffic while a body rests
  next.clear();
  double deepest = 0.0;
  ForEachContact<Dim>(model, g, R, R_dot, *contacts,
                      [&](int k, const double*, const VecD<Dim>& x, const VecD<Dim>& v, VecD<Dim> anchor,
                          const FaceOf<Dim>& face, int face_index) {
                        bool slipping;
                        VecD<Dim> f = GroundForce(face, x, v, anchor, &slipping);
                        if (slipping) SlipAnchor(face, x, v, &anchor, &f);
                        next.push_back({k, anchor, face_index});
                        deepest = std::max(deepest, -face.Height(x));
                      });
  contacts->swap(next);
  return deepest;
}

// Adds ½ K_d |x_k − anchor|² of each contact in list<Dim>() to *energy.
template <int Dim>
void AddGroundEnergy(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                     const LinearContacts& contacts, double* energy) {
  const Eigen::MatrixXd& P = model.point_bases();
  for (const Contact<Dim, double>& c : contacts.list<Dim>()) {
    const double stiffness = [&] {
      if constexpr (Dim == 2) return g.ground.Face(c.face).stiffness;
      else return g.plane.stiffness;  // the plane's, even where a heightfield face has its own
    }();
    *energy += 0.5 * stiffness * (Times<Dim>(R, P.col(c.point).data()) - c.anchor).squaredNorm();
  }
}

// Appends the ground's force on each contact in list<Dim>() to *forces.
template <int Dim>
void AppendContactForces(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                         const Eigen::MatrixXd& R_dot, const LinearContacts& contacts,
                         std::vector<Eigen::VectorXd>* forces) {
  const Eigen::MatrixXd& P = model.point_bases();
  bool slipping;
  for (const Contact<Dim, double>& c : contacts.list<Dim>()) {
    const double* p = P.col(c.point).data();
    const VecD<Dim> x = Times<Dim>(R, p);
    const FaceOf<Dim> face = [&] {
      if constexpr (Dim == 2) return g.ground.Face(c.face);
      else return g.plane.Face(c.face, x);
    }();
    forces->push_back(GroundForce(face, x, Times<Dim>(R_dot, p), c.anchor, &slipping));
  }
}

}  // namespace

void AddLinearGroundForce(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, const LinearContacts& contacts, Eigen::MatrixXd* Q) {
  if (model.dim() == 2) AddGroundForce<2>(model, g, R, R_dot, contacts, Q);
  else AddGroundForce<3>(model, g, R, R_dot, contacts, Q);
}

void UpdateLinearContacts(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const Eigen::MatrixXd& R_dot, LinearContacts* contacts) {
  contacts->penetration = model.dim() == 2 ? UpdateContacts<2>(model, g, R, R_dot, &contacts->list<2>())
                                           : UpdateContacts<3>(model, g, R, R_dot, &contacts->list<3>());
}

double LinearGroundEnergy(const LinearBodyModel& model, const LinearGround& g, const Eigen::MatrixXd& R,
                          const LinearContacts& contacts) {
  double energy = 0.0;
  AddGroundEnergy<2>(model, g, R, contacts, &energy);
  AddGroundEnergy<3>(model, g, R, contacts, &energy);
  return energy;
}

std::vector<Eigen::VectorXd> LinearContactForces(const LinearBodyModel& model, const LinearGround& g,
                                                 const Eigen::MatrixXd& R, const Eigen::MatrixXd& R_dot,
                                                 const LinearContacts& contacts) {
  std::vector<Eigen::VectorXd> forces;
  AppendContactForces<2>(model, g, R, R_dot, contacts, &forces);
  AppendContactForces<3>(model, g, R, R_dot, contacts, &forces);
  return forces;
}

}  // namespace wobble
