// The 3D FFD body against results it does not compute itself: sums over the mass points of the
// textbook per-point formulas, finite differences, the 2D body of the thesis for planar motion,
// conservation laws, the elliptic-integral period of the intermediate-axis flip, and Coulomb's
// law on an incline.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "support/test_bodies.h"
#include "wobble/dynamics/step.h"
#include "wobble/dynamics/step.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/body/linear_body.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/world/world.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

using testing::Box;

using Eigen::Matrix3d;
using Eigen::Vector3d;

double MaxAbs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }

std::string Sci(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", x);
  return text;
}

// A random 3D body: skew lattice of any size and basis, random points, masses and modes.
BodyModelN<3> RandomBody3(std::mt19937& rng, std::array<int, 3> sizes, BasisKind basis, int num_modes, int num_points,
                       double stiffness = 0.0) {
  std::uniform_real_distribution<double> u(0.0, 1.0), disp(-30.0, 30.0), mass(1.0, 80.0);
  BodyDefN<3> def;
  def.name = "random3";
  def.lattice = LatticeN<3>(Vector3d(-20, 5, 3), {Vector3d(250, 20, -10), Vector3d(-30, 120, 15), Vector3d(10, -5, 90)},
                         sizes, basis);
  for (int k = 0; k < num_points; ++k) {
    Vector3d p = def.lattice.origin();
    for (int a = 0; a < 3; ++a) p += u(rng) * def.lattice.axis(a);
    def.mass_positions.push_back(p);
    def.masses.push_back(mass(rng));
  }
  std::vector<DeformationModeN<3>> modes(num_modes);
  for (int d = 0; d < num_modes; ++d) {
    modes[d].name = "m" + std::to_string(d);
    modes[d].lattice_size = sizes;
    modes[d].stiffness = stiffness;
    for (int c = 0; c < def.lattice.size(); ++c) modes[d].displacement.push_back({disp(rng), disp(rng), disp(rng)});
  }
  return BodyModelN<3>(def, modes);
}

BodyState<3, double> RandomState3(std::mt19937& rng, const BodyModelN<3>& body, double speed = 1.0) {
  std::normal_distribution<double> n(0.0, 1.0);
  BodyState<3, double> s = RestState<3, double>(body);
  s.translation() = Vector3d(n(rng), n(rng), n(rng)) * 50.0;
  s.set_orientation(Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized());
  for (int d = 0; d < body.num_modes(); ++d) s.gamma()[d] = 0.3 * n(rng);
  for (int i = 0; i < body.num_q(); ++i) s.qd[i] = speed * n(rng) * (i < 3 ? 30.0 : 1.0);
  return s;
}

// Per-point quantities computed from the lattice weights and the mode displacements directly
// (not from BodyModelN<3>'s precomputed b0_k, B_k or its moments).
struct PointKinematics {
  Vector3d l;
  Eigen::Matrix<double, 3, Eigen::Dynamic> B;
};
PointKinematics DirectPoint(const BodyModelN<3>& body, int k, const VecD<double>& gamma) {
  const LatticeN<3>& lat = body.lattice();
  const std::vector<double> w = lat.Weights(lat.LocalCoords(body.def().mass_positions[k]));
  PointKinematics p{Vector3d::Zero(), Eigen::Matrix<double, 3, Eigen::Dynamic>::Zero(3, body.num_modes())};
  const std::vector<Vector3d> rest = lat.RestPoints();
  for (int c = 0; c < lat.size(); ++c) {
    p.l += w[c] * rest[c];
    for (int d = 0; d < body.num_modes(); ++d) {
      p.B.col(d) += w[c] * body.modes()[d].displacement[c];
      p.l += w[c] * gamma[d] * body.modes()[d].displacement[c];
    }
  }
  return p;
}

// J_k = [1 | −R[l]× | R B] of spatial_inertia.h, from its definition ẋ = ṫ + R(ω × l + B γ̇).
Eigen::MatrixXd Jacobian(const Matrix3d& R, const PointKinematics& p) {
  Eigen::MatrixXd J(3, Group<3>::kRigidDofs + p.B.cols());
  J.block<3, 3>(0, 0).setIdentity();
  for (int i = 0; i < 3; ++i) J.col(3 + i) = R * Vector3d::Unit(i).cross(p.l);
  J.rightCols(p.B.cols()) = R * p.B;
  return J;
}

TEST(Body3, FastPathMatchesSumsOverThePoints) {
  std::mt19937 rng(7);
  struct Case {
    std::array<int, 3> sizes;
    BasisKind basis;
    int modes;
  };
  for (const Case& c : {Case{{2, 2, 2}, BasisKind::kBernstein, 0}, Case{{4, 4, 4}, BasisKind::kBernstein, 3},
                        Case{{3, 5, 2}, BasisKind::kBernstein, 5}, Case{{5, 4, 6}, BasisKind::kCubicBSpline, 4}}) {
    const BodyModelN<3> body = RandomBody3(rng, c.sizes, c.basis, c.modes, 25);
    for (int trial = 0; trial < 5; ++trial) {
      const BodyState<3, double> s = RandomState3(rng, body);
      const Matrix3d R = s.orientation().toRotationMatrix();
      const int n = body.num_q();
      const Vector3d g(0.3, -9.81, 1.2);
      Eigen::MatrixXd M_ref = Eigen::MatrixXd::Zero(n, n);
      Eigen::VectorXd w_ref = Eigen::VectorXd::Zero(n), Q_ref = Eigen::VectorXd::Zero(n);
      double T_ref = 0.0;
      Vector3d P_ref = Vector3d::Zero(), L_ref = Vector3d::Zero();
      const Vector3d omega = s.qd.segment<3>(3);
      for (int k = 0; k < body.num_points(); ++k) {
        const PointKinematics p = DirectPoint(body, k, s.gamma());
        const Eigen::MatrixXd J = Jacobian(R, p);
        const double m = body.mass(k);
        const Vector3d Bgd = p.B * s.qd.tail(body.num_modes());
        // centripetal and Coriolis acceleration of the point, J̇ v = R(ω×(ω×l) + 2ω×Bγ̇)
        const Vector3d Jdot_v = R * (omega.cross(omega.cross(p.l)) + 2.0 * omega.cross(Bgd));
        const Vector3d x = s.translation() + R * p.l, xdot = J * Eigen::VectorXd(s.qd);
        M_ref += m * J.transpose() * J;
        w_ref += m * J.transpose() * Jdot_v;
        Q_ref += m * J.transpose() * g;
        T_ref += 0.5 * m * xdot.squaredNorm();
        P_ref += m * xdot;
        L_ref += m * x.cross(xdot);
      }
      const ShapeMoments<double> sm(body.moments(), s.gamma());
      MatQ<double> M;
      MassMatrix(body.moments(), sm, R, &M);
      VecQ<double> w, Q;
      VelocityTerms(body.moments(), sm, R, s.qd, &w);
      GravityForce(body.moments(), sm, R, g, &Q);
      Vector3d P, L;
      Momentum(body.moments(), sm, Frame<3, double>(s.q), s.qd, &P, &L);
      EXPECT_LE(MaxAbs(Eigen::MatrixXd(M) - M_ref), 1e-9 * MaxAbs(M_ref));
      EXPECT_LE(MaxAbs(Eigen::VectorXd(w) - w_ref), 1e-9 * MaxAbs(w_ref));
      EXPECT_LE(MaxAbs(Eigen::VectorXd(Q) - Q_ref), 1e-9 * MaxAbs(Q_ref));
      EXPECT_NEAR(KineticEnergy(body.moments(), sm, R, s.qd), T_ref, 1e-9 * T_ref);
      EXPECT_LE((P - P_ref).norm(), 1e-9 * P_ref.norm());
      EXPECT_LE((L - L_ref).norm(), 1e-9 * L_ref.norm());
    }
  }
}

// The step's mass solve (SolveAccelerations: elimination about the centre of mass with the
// constant factor of G_com = G − CᵀC/m and a 3x3 Schur complement, never forming M) against a
// pivoted LU solve of M summed over the points, M q̈ = Q − w with Q of gravity plus random
// generalized forces; and its condition estimate, a lower bound of cond₂(M) (from the SVD of
// that M) that is not trivially 1.
TEST(Body3, MassSolveAboutTheCentreMatchesTheDirectSolve) {
  std::mt19937 rng(41);
  std::normal_distribution<double> n(0.0, 1.0);
  struct Case {
    std::array<int, 3> sizes;
    BasisKind basis;
    int modes;
  };
  double worst = 0.0, worst_bound = 0.0;
  for (const Case& c : {Case{{2, 2, 2}, BasisKind::kBernstein, 0}, Case{{4, 4, 4}, BasisKind::kBernstein, 3},
                        Case{{3, 5, 2}, BasisKind::kBernstein, 5}, Case{{5, 4, 6}, BasisKind::kCubicBSpline, 4},
                        Case{{4, 4, 4}, BasisKind::kBernstein, 8}}) {
    const BodyModelN<3> body = RandomBody3(rng, c.sizes, c.basis, c.modes, 30);
    for (int trial = 0; trial < 5; ++trial) {
      const BodyState<3, double> s = RandomState3(rng, body);
      const Matrix3d R = s.orientation().toRotationMatrix();
      const int nq = body.num_q();
      const Vector3d g(0.3, -9.81, 1.2);
      Eigen::MatrixXd M_ref = Eigen::MatrixXd::Zero(nq, nq);
      Eigen::VectorXd w_ref = Eigen::VectorXd::Zero(nq), Q = Eigen::VectorXd::Zero(nq);
      const Vector3d omega = s.qd.segment<3>(3);
      for (int k = 0; k < body.num_points(); ++k) {
        const PointKinematics p = DirectPoint(body, k, s.gamma());
        const Eigen::MatrixXd J = Jacobian(R, p);
        const Vector3d Jdot_v =
            R * (omega.cross(omega.cross(p.l)) + 2.0 * omega.cross(p.B * s.qd.tail(body.num_modes())));
        M_ref += body.mass(k) * J.transpose() * J;
        w_ref += body.mass(k) * J.transpose() * Jdot_v;
        Q += body.mass(k) * J.transpose() * g;
      }
      for (int i = 0; i < nq; ++i) Q[i] += 100.0 * n(rng);
      const Eigen::VectorXd expected = M_ref.fullPivLu().solve(Eigen::VectorXd(Q - w_ref));
      VecQ<double> qdd;
      double cond_estimate = 0.0;
      ASSERT_TRUE(SolveAccelerations(body.moments(), s.q, s.qd, R, VecQ<double>(Q), &qdd, &cond_estimate));
      const double error = (Eigen::VectorXd(qdd) - expected).norm() / expected.norm();
      EXPECT_LT(error, 1e-10) << c.modes << " modes, trial " << trial;
      worst = std::max(worst, error);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M_ref);
      const double cond = svd.singularValues()(0) / svd.singularValues()(nq - 1);
      EXPECT_GE(cond_estimate, 1.0);
      EXPECT_LE(cond_estimate, cond * (1 + 1e-9)) << c.modes << " modes: cond " << cond;
      worst_bound = std::max(worst_bound, cond_estimate / cond);
    }
  }
  EXPECT_GT(worst_bound, 1e-3);  // a bound that follows cond₂(M), not a constant
  RecordProperty("mass_solve_error", Sci(worst));
  RecordProperty("cond_estimate_over_cond", Sci(worst_bound));
}

// The mode block about the centre of mass, G_com = G − CᵀC/m, is constant, so MassMomentsN<3>
// keeps its inverse (Witkin & Welch pre-invert their constant mass matrix) and the step's
// solves become products. The inverse against the SVD's of G_com summed over the points, and
// the whole mass solve against the full-pivot LU of M, both to ~1e-12 relative (cond(G_com)
// of these bodies is below 1e3).
TEST(Body3, PreInvertedModeBlockMatchesTheSvdInverse) {
  std::mt19937 rng(47);
  std::normal_distribution<double> n(0.0, 1.0);
  double worst_inverse = 0.0, worst_solve = 0.0;
  for (int modes : {1, 3, 5, 8}) {
    const BodyModelN<3> body = RandomBody3(rng, {4, 3, 4}, BasisKind::kBernstein, modes, 40);
    const MassMomentsN<3>& mm = body.moments();
    ASSERT_TRUE(mm.G_com_positive);
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(modes, modes), C = Eigen::MatrixXd::Zero(3, modes);
    double m = 0.0;
    for (int k = 0; k < body.num_points(); ++k) {
      const Eigen::MatrixXd B = body.mode_matrix(k);
      G += body.mass(k) * B.transpose() * B;
      C += body.mass(k) * B;
      m += body.mass(k);
    }
    const Eigen::MatrixXd G_com = G - C.transpose() * C / m;
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(G_com, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::MatrixXd inverse =
        svd.matrixV() * svd.singularValues().cwiseInverse().asDiagonal() * svd.matrixU().transpose();
    const double error = (Eigen::MatrixXd(mm.G_com_inverse) - inverse).norm() / inverse.norm();
    EXPECT_LT(error, 1e-12) << modes << " modes";
    worst_inverse = std::max(worst_inverse, error);
    for (int trial = 0; trial < 5; ++trial) {
      const BodyState<3, double> s = RandomState3(rng, body);
      const Matrix3d R = s.orientation().toRotationMatrix();
      const ShapeMoments<double> sm(mm, s.gamma());
      MatQ<double> M;
      MassMatrix(mm, sm, R, &M);
      VecQ<double> r(body.num_q());
      for (int i = 0; i < r.size(); ++i) r[i] = 100.0 * n(rng);
      const Eigen::VectorXd expected = Eigen::MatrixXd(M).fullPivLu().solve(Eigen::VectorXd(r));
      VecQ<double> a;
      double cond = 0.0;
      ASSERT_TRUE(SolveMassSystem(mm, sm, R, r, &a, &cond));
      const double solve_error = (Eigen::VectorXd(a) - expected).norm() / expected.norm();
      EXPECT_LT(solve_error, 1e-12) << modes << " modes, trial " << trial;
      worst_solve = std::max(worst_solve, solve_error);
    }
  }
  RecordProperty("inverse_error", Sci(worst_inverse));
  RecordProperty("solve_error", Sci(worst_solve));
}

// A mode that only translates the body (the same displacement at every control point) moves
// no mass relative to the centre: M is singular and the solve says so (kSingularMass).
TEST(Body3, MassSolveRefusesAModeThatIsARigidTranslation) {
  std::mt19937 rng(43);
  BodyModelN<3> random = RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 2, 20);
  std::vector<DeformationModeN<3>> modes = random.modes();
  for (auto& d : modes[1].displacement) d = {4.0, -2.0, 1.0};
  const BodyModelN<3> body(random.def(), modes);
  const BodyState<3, double> s = RandomState3(rng, body);
  VecQ<double> qdd, Q = VecQ<double>::Zero(body.num_q());
  double cond_estimate = 0.0;
  EXPECT_FALSE(SolveAccelerations(body.moments(), s.q, s.qd, Matrix3d(s.orientation().toRotationMatrix()), Q, &qdd,
                                  &cond_estimate));
}

// The per-point J̇v used above is itself checked: the central difference of ẋ_k along the motion
// (t + εṫ, R exp(εω̂), γ + εγ̇) at fixed v.
TEST(Body3, PointAccelerationFormulaMatchesFiniteDifference) {
  std::mt19937 rng(11);
  const BodyModelN<3> body = RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 3, 4);
  const BodyState<3, double> s = RandomState3(rng, body);
  auto velocity = [&](double eps, int k) {
    BodyState<3, double> moved = s;
    Group<3>::Advance(s.qd, eps, &moved.q);
    const PointKinematics p = DirectPoint(body, k, moved.gamma());
    return Vector3d(Jacobian(moved.orientation().toRotationMatrix(), p) * Eigen::VectorXd(s.qd));
  };
  const double eps = 1e-5;
  const Matrix3d R = s.orientation().toRotationMatrix();
  const Vector3d omega = s.qd.segment<3>(3);
  for (int k = 0; k < body.num_points(); ++k) {
    const PointKinematics p = DirectPoint(body, k, s.gamma());
    const Vector3d formula = R * (omega.cross(omega.cross(p.l)) + 2.0 * omega.cross(p.B * s.qd.tail(3)));
    const Vector3d numeric = (velocity(eps, k) - velocity(-eps, k)) / (2 * eps);
    EXPECT_LE((formula - numeric).norm(), 1e-7 * formula.norm());
  }
}

// ∂T/∂g of the variational integrator against central differences of T = ½ Σ m |ẋ|².
TEST(Body3, KineticGradientMatchesFiniteDifference) {
  std::mt19937 rng(5);
  const BodyModelN<3> body = RandomBody3(rng, {4, 3, 3}, BasisKind::kBernstein, 4, 20);
  const BodyState<3, double> s = RandomState3(rng, body);
  auto energy = [&](const Eigen::Quaterniond& q, const VecD<double>& gamma) {
    const ShapeMoments<double> sm(body.moments(), gamma);
    return KineticEnergy(body.moments(), sm, Matrix3d(q.toRotationMatrix()), s.qd);
  };
  const ShapeMoments<double> sm(body.moments(), s.gamma());
  VecQ<double> grad;
  KineticGradient(body.moments(), sm, Matrix3d(s.orientation().toRotationMatrix()), s.qd, &grad);
  const double h = 1e-6;
  for (int i = 0; i < 3; ++i) {
    const Vector3d e = Vector3d::Unit(i) * h;
    const double numeric = (energy(s.orientation() * ExpRotation<double>(e), s.gamma()) -
                            energy(s.orientation() * ExpRotation<double>(Vector3d(-e)), s.gamma())) / (2 * h);
    EXPECT_NEAR(grad[3 + i], numeric, 1e-6 * (1.0 + std::abs(numeric))) << "rotation " << i;
    EXPECT_EQ(grad[i], 0.0);
  }
  for (int d = 0; d < body.num_modes(); ++d) {
    VecD<double> up = s.gamma(), down = s.gamma();
    up[d] += h;
    down[d] -= h;
    const double numeric = (energy(s.orientation(), up) - energy(s.orientation(), down)) / (2 * h);
    EXPECT_NEAR(grad[Group<3>::kRigidDofs + d], numeric, 1e-6 * (1.0 + std::abs(numeric))) << "mode " << d;
  }
}

// The 2D body embedded in the plane z = 0: a lattice one layer deep (linear in z), modes with
// no z part, mass points at z = 0.
BodyModelN<3> Embed(const BodyModel& flat, double depth = 50.0) {
  const Lattice& lat = flat.lattice();
  BodyDefN<3> def;
  def.name = flat.name() + "_3d";
  auto lift = [](const Eigen::Vector2d& p) { return Vector3d(p.x(), p.y(), 0.0); };
  def.lattice = LatticeN<3>(lift(lat.origin()), {lift(lat.axis_s()), lift(lat.axis_t()), Vector3d(0, 0, depth)},
                         {lat.num_s(), lat.num_t(), 2}, lat.basis());
  for (int k = 0; k < flat.num_points(); ++k) def.mass_positions.push_back(lift(flat.def().mass_positions[k]));
  def.masses = flat.def().masses;
  std::vector<DeformationModeN<3>> modes;
  for (const DeformationMode& m2 : flat.modes()) {
    DeformationModeN<3> m;
    m.name = m2.name;
    m.stiffness = m2.stiffness;
    m.damping = m2.damping;
    m.lattice_size = def.lattice.sizes();
    m.displacement.resize(def.lattice.size());
    for (int c = 0; c < def.lattice.size(); ++c) {
      const auto cell = def.lattice.CellOf(c);
      m.displacement[c] = lift(m2.displacement[lat.Index(cell[0], cell[1])]);
    }
    modes.push_back(m);
  }
  return BodyModelN<3>(def, modes);
}

TEST(Body3, PlanarMotionReproducesThe2DBody) {
  std::mt19937 rng(3);
  const BodyModel random = testing::RandomBody(rng, 4, 4, BasisKind::kBernstein, 3, 15);
  std::vector<DeformationMode> modes = random.modes();
  for (size_t d = 0; d < modes.size(); ++d) modes[d].stiffness = 200.0 * (d + 1), modes[d].damping = 5.0;
  const BodyModel flat(random.def(), modes);
  const BodyModelN<3> body = Embed(flat);
  for (bool ground : {false, true}) {
    for (Integrator integrator : {Integrator::kThesis, Integrator::kSymplecticEuler, Integrator::kRK4,
                                  Integrator::kImplicitEuler}) {
      if (ground && integrator == Integrator::kImplicitEuler) continue;  // 2D grows its active set differently
      WorldParams w2;
      w2.ground.enabled = ground;
      w2.ground.point = Eigen::Vector2d(0, -10);
      WorldParams w3;
      w3.ground_plane.enabled = ground;
      w3.ground_plane.point = Vector3d(0, -10, 0);
      BodyState<2, double> s2;
      s2.q.setZero(flat.num_q());
      s2.qd.setZero(flat.num_q());
      s2.q << 10, 20, 0.4, 0.2, -0.1, 0.05;
      s2.qd << 30, -40, 1.5, 0.5, 0.0, -0.3;
      BodyState<3, double> s3 = RestState<3, double>(body);
      s3.translation() = Vector3d(10, 20, 0);
      s3.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3d::UnitZ())));
      s3.gamma() << 0.2, -0.1, 0.05;
      s3.qd << 30, -40, 0, 0, 0, 1.5, 0.5, 0.0, -0.3;
      const double dt = 1e-3;
      double worst = 0.0;
      int contacts_seen = 0;
      for (int step = 0; step < 3000; ++step) {
        ASSERT_TRUE(StepBody(flat, w2, 0, integrator, dt, &s2).ok());
        ASSERT_TRUE(StepBody(body, w3, 0, integrator, dt, &s3).ok());
        ASSERT_EQ(s2.contacts.size(), s3.contacts.size()) << "step " << step;
        contacts_seen += int(s3.contacts.size());
        const Frame<2, double> f2(s2.q);
        const Frame<3, double> f3(s3.q);
        for (int k = 0; k < flat.num_points(); ++k) {
          const Eigen::Vector2d x2 = WorldFromLocal(f2, LocalPosition<double>(flat.rest_local(k), flat.mode_matrix(k), s2.q));
          const Vector3d x3 = f3.t + f3.R * LocalPosition<double>(body.rest_local(k), body.mode_matrix(k), s3.q);
          worst = std::max(worst, (Vector3d(x2.x(), x2.y(), 0.0) - x3).norm());
        }
      }
      const std::string what = IntegratorName(integrator) + (ground ? " on the ground" : " in the air");
      EXPECT_LE(worst, 1e-9 * 250.0) << what;  // relative to the body's size
      if (ground) {
        EXPECT_GT(contacts_seen, 100) << what;
      }
      RecordProperty("deviation_" + IntegratorName(integrator) + (ground ? "_ground" : "_air"),
                     Sci(worst) + " after " + std::to_string(contacts_seen) + " contact-steps");
    }
  }
}

// The contact scan's shortcuts (the convex-hull test, then point groups for big bodies) visit
// exactly the points below the plane that a scan of every point finds.
TEST(Body3, PointGroupsFindExactlyThePointsBelowTheGround) {
  std::mt19937 rng(23);
  const BodyModelN<3> body = RandomBody3(rng, {4, 4, 4}, BasisKind::kBernstein, 3, 3000);
  ASSERT_GT(body.clusters().size(), 8u);
  GroundPlane g;
  g.enabled = true;
  g.normal = Vector3d(0.2, 1.0, -0.1).normalized();
  std::normal_distribution<double> n(0.0, 1.0);
  int found = 0;
  for (int trial = 0; trial < 20; ++trial) {
    BodyState<3, double> s = RandomState3(rng, body);
    s.translation() = Vector3d(n(rng), n(rng), n(rng)) * 60.0;
    const Frame<3, double> frame(s.q);
    std::vector<int> visited, below;
    ForEachPointInContact(body, g, s, frame, [&](int k, const Vector3d&, const Vector3d&, const Vector3d&, const Vector3d&, const GroundPlane&, int) { visited.push_back(k); },
                           ContactSet::kDetect);
    for (int k = 0; k < body.num_points(); ++k) {
      const PointKinematics p = DirectPoint(body, k, s.gamma());
      if (g.Height(Vector3d(frame.t + frame.R * p.l)) < 0.0) below.push_back(k);
    }
    std::sort(visited.begin(), visited.end());
    EXPECT_EQ(visited, below) << "trial " << trial;
    found += int(below.size());
  }
  EXPECT_GT(found, 1000);  // the states do reach into the ground
}

// A 3D body thrown tumbling onto a tilted plane (bouncing, rolling, deforming) for 4,000 steps
// from `s`: every step's scan visits exactly the points an exact test of every point, taken in
// `order` (the order the scan visits them), finds below the plane, x = t + R (b0 + B γ), and
// the contacts the step leaves are those points. Counts the steps touching the plane and those
// with fewer than num_points / few_below_divisor points below it.
// Each step is also redone from the same state without the memo of earlier walks of the point
// tree (PlaneScanMemo): the contacts, anchors and ground force must be the same bit for bit.
struct ScanRun {
  int touching = 0, partial = 0, reused = 0;
};
ScanRun CheckScanAgainstTheExactTest(const BodyModelN<3>& body, BodyState<3, double> s, const std::vector<int>& order,
                                     int few_below_divisor) {
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.normal = Vector3d(0.2, 1.0, -0.1).normalized();
  ScanRun r;
  for (int step = 0; step < 4000; ++step) {
    const BodyState<3, double> before = s;
    EXPECT_TRUE(StepBody(body, w, 0, Integrator::kThesis, 0.002, &s).ok()) << "step " << step;
    const Frame<3, double> frame(s.q);
    std::vector<int> visited, expected;
    ForEachPointInContact(body, w.ground_plane, s, frame,
                          [&](int k, const Vector3d&, const Vector3d&, const Vector3d&, const Vector3d&,
                              const GroundPlane&, int) { visited.push_back(k); });
    for (int k : order) {
      const Vector3d x = frame.t + frame.R * LocalPosition<double>(body.rest_local(k), body.mode_matrix(k), s.q);
      if (w.ground_plane.Height(x) < 0.0) expected.push_back(k);
    }
    EXPECT_EQ(visited, expected) << "step " << step;
    std::vector<int> contacts;
    for (const Contact<3, double>& c : s.contacts) contacts.push_back(c.point);
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(contacts, expected) << "step " << step;
    BodyState<3, double> fresh = s;
    fresh.contacts = before.contacts;
    fresh.scan_memo = PlaneScanMemo<3>();
    UpdateContacts(body, w.ground_plane, &fresh);
    EXPECT_EQ(fresh.contacts.size(), s.contacts.size()) << "step " << step;
    for (size_t i = 0; i < std::min(fresh.contacts.size(), s.contacts.size()); ++i)
      EXPECT_TRUE(fresh.contacts[i].point == s.contacts[i].point && fresh.contacts[i].face == s.contacts[i].face &&
                  fresh.contacts[i].anchor == s.contacts[i].anchor)
          << "step " << step << ", contact " << i;
    EXPECT_TRUE(fresh.ground_cache.force == s.ground_cache.force && fresh.penetration == s.penetration)
        << "step " << step;
    if (::testing::Test::HasFailure()) return r;  // one step's report is enough
    r.touching += !expected.empty();
    r.partial += !expected.empty() && int(expected.size()) < body.num_points() / few_below_divisor;
    r.reused += !expected.empty() && before.scan_memo.valid && s.scan_memo.offset == before.scan_memo.offset;
  }
  return r;
}

BodyState<3, double> ThrownOntoThePlane(const BodyModelN<3>& body, const Vector3d& v, const Vector3d& omega) {
  BodyState<3, double> s = RestState<3, double>(body);
  s.translation() = Vector3d(0.0, 40.0, 0.0);
  s.set_orientation(Eigen::AngleAxisd(0.3, Vector3d(0.3, 0.2, 1.0).normalized()));
  s.qd.head<3>() = v;
  s.qd.segment<3>(3) = omega;
  return s;
}

// A 3,000-point body in point groups: the tree's scan visits the points in the groups' order,
// and the contacts and the ground force are the full scan's, bit for bit.
TEST(Body3, TreeScanMatchesTheFullScanOverALongTumblingRun) {
  std::mt19937 rng(29);
  const BodyModelN<3> body = RandomBody3(rng, {4, 4, 4}, BasisKind::kBernstein, 3, 3000, 1e9);
  ASSERT_GT(body.clusters().size(), 8u);
  // turning about its centre of mass c, which moves at (60, 0, −30): ṫ = v − R(ω × c)
  const Vector3d omega(0.2, 0.1, -0.3), c = body.moments().c0 / body.moments().m;
  BodyState<3, double> s = ThrownOntoThePlane(body, Vector3d::Zero(), omega);
  s.qd.head<3>() = Vector3d(60.0, 0.0, -30.0) - s.orientation().toRotationMatrix() * omega.cross(c);
  std::vector<int> order;
  for (const PointClusterN<3>& cluster : body.clusters()) order.insert(order.end(), cluster.points.begin(), cluster.points.end());
  const ScanRun r = CheckScanAgainstTheExactTest(body, s, order, 20);
  EXPECT_GT(r.touching, 1000);  // of 4,000 steps
  EXPECT_GT(r.partial, 100);
  RecordProperty("steps_touching", r.touching);
  RecordProperty("steps_with_few_points_below", r.partial);
  RecordProperty("steps_reusing_the_walk", r.reused);
}

// A small body (one point group: every point is tested): the per-point bound before the exact
// test (PointClearOfPlane) skips only points the exact test rejects, so the scan visits, in
// point order, exactly the points below the plane (the resting-table references check the same
// bit for bit).
TEST(Body3, PointBoundScanMatchesTheFullScanOfASmallBody) {
  std::mt19937 rng(31);
  const BodyModelN<3> body = RandomBody3(rng, {4, 4, 4}, BasisKind::kBernstein, 3, 40, 1e9);
  ASSERT_EQ(body.clusters().size(), 1u);
  std::vector<int> order(size_t(body.num_points()));
  for (int k = 0; k < body.num_points(); ++k) order[size_t(k)] = k;
  const ScanRun r = CheckScanAgainstTheExactTest(
      body, ThrownOntoThePlane(body, Vector3d(60.0, 0.0, -30.0), Vector3d(0.2, 0.1, -0.3)), order, 2);
  EXPECT_GT(r.touching, 1000);  // of 4,000 steps
  EXPECT_GT(r.partial, 100);
}

// Spinning about its centre of mass (ṫ chosen so the centre stays put), no gravity.
BodyState<3, double> Spinning(const BodyModelN<3>& body, const Vector3d& omega) {
  BodyState<3, double> s = RestState<3, double>(body);
  s.qd.segment<3>(3) = omega;
  const Vector3d com_local = body.moments().c0 / body.moments().m;
  s.qd.head<3>() = -(omega.cross(com_local));  // ẋ_com = ṫ + R(ω × c/m) = 0
  return s;
}

double TotalEnergy(const BodyModelN<3>& body, const BodyState<3, double>& s) {
  const ShapeMoments<double> sm(body.moments(), s.gamma());
  double V = 0.0;
  for (int d = 0; d < body.num_modes(); ++d) V += body.modes()[d].stiffness * s.gamma()[d] * s.gamma()[d];
  return KineticEnergy(body.moments(), sm, Matrix3d(s.orientation().toRotationMatrix()), s.qd) + V;
}

Vector3d AngularMomentum(const BodyModelN<3>& body, const BodyState<3, double>& s, Vector3d* linear = nullptr) {
  const ShapeMoments<double> sm(body.moments(), s.gamma());
  Vector3d P, L;
  Momentum(body.moments(), sm, Frame<3, double>(s.q), s.qd, &P, &L);
  if (linear) *linear = P;
  return L;
}

TEST(Body3, TorqueFreeTumblingKeepsEnergyAndMomentumOver1e5Steps) {
  const BodyModelN<3> body = Box(1.0, 2.0, 3.0);
  WorldParams w;
  w.gravity_on = false;
  BodyState<3, double> s = Spinning(body, Vector3d(0.8, 1.5, -0.6));
  const double E0 = TotalEnergy(body, s);
  const Vector3d L0 = AngularMomentum(body, s);
  double worst_energy = 0.0, worst_momentum = 0.0, energy_at_half = 0.0;
  const int steps = 100000;
  for (int step = 1; step <= steps; ++step) {
    ASSERT_TRUE(StepBody(body, w, 0, Integrator::kVariational, 0.01, &s).ok());
    const double dE = std::abs(TotalEnergy(body, s) - E0) / E0;
    worst_energy = std::max(worst_energy, dE);
    worst_momentum = std::max(worst_momentum, (AngularMomentum(body, s) - L0).norm() / L0.norm());
    if (step == steps / 2) energy_at_half = worst_energy;
  }
  // symplectic: the energy error oscillates at O(Δt²) and does not grow with time
  EXPECT_LT(worst_energy, 2e-3);
  EXPECT_LE(worst_energy, 1.05 * energy_at_half + 1e-12) << "energy error still growing after half the run";
  EXPECT_LT(worst_momentum, 1e-9);
  RecordProperty("energy_drift", Sci(worst_energy));
  RecordProperty("momentum_drift", Sci(worst_momentum));
}

// Landau & Lifshitz §37: for I1 < I2 < I3, energy E and momentum L with L² > 2 E I2,
// ω2 = A sn(λ t, k) with λ² = (I3 − I2)(L² − 2E I1)/(I1 I2 I3) and
// k² = (I2 − I1)(2E I3 − L²)/((I3 − I2)(L² − 2E I1)): ω2 has period 4 K(k)/λ.
double CompleteEllipticK(double k) {
  double a = 1.0, b = std::sqrt(1.0 - k * k);  // K = π / (2 AGM(1, √(1−k²)))
  for (int i = 0; i < 40; ++i) {
    const double an = 0.5 * (a + b);
    b = std::sqrt(a * b);
    a = an;
  }
  return M_PI / (2.0 * a);
}

TEST(Body3, IntermediateAxisFlipPeriodMatchesTheEllipticIntegral) {
  const double a = 1.0, b = 2.0, c = 3.0, m = 1.0;
  const BodyModelN<3> body = Box(a, b, c, m);
  // principal moments about the centre, from the eight corners (±a/2, ±b/2, ±c/2)
  const double I1 = 8 * m * (b * b + c * c) / 4, I2 = 8 * m * (a * a + c * c) / 4, I3 = 8 * m * (a * a + b * b) / 4;
  ASSERT_TRUE(I3 < I2 && I2 < I1);  // the box's axes in increasing inertia: z, y, x
  WorldParams w;
  w.gravity_on = false;
  for (Integrator integrator : {Integrator::kRK4, Integrator::kVariational}) {
    // spin about y (intermediate) with a small push about x and z
    BodyState<3, double> s = Spinning(body, Vector3d(0.02, 2.0, 0.03));
    const Vector3d w0 = s.qd.segment<3>(3);
    // in the notation above: smallest inertia first
    const double J1 = I3, J2 = I2, J3 = I1;
    const Vector3d wj(w0.z(), w0.y(), w0.x());
    const double E = 0.5 * (J1 * wj[0] * wj[0] + J2 * wj[1] * wj[1] + J3 * wj[2] * wj[2]);
    const double L2 = std::pow(J1 * wj[0], 2) + std::pow(J2 * wj[1], 2) + std::pow(J3 * wj[2], 2);
    double lambda2, k2;
    if (L2 > 2 * E * J2) {
      lambda2 = (J3 - J2) * (L2 - 2 * E * J1) / (J1 * J2 * J3);
      k2 = (J2 - J1) * (2 * E * J3 - L2) / ((J3 - J2) * (L2 - 2 * E * J1));
    } else {  // the same with the roles of the smallest and largest moments exchanged
      lambda2 = (J2 - J1) * (2 * E * J3 - L2) / (J1 * J2 * J3);
      k2 = (J3 - J2) * (L2 - 2 * E * J1) / ((J2 - J1) * (2 * E * J3 - L2));
    }
    const double period = 4.0 * CompleteEllipticK(std::sqrt(k2)) / std::sqrt(lambda2);
    // measure: times at which ω_y crosses zero going down
    const double dt = 1e-3;
    std::vector<double> crossings;
    double previous = s.qd[4];
    for (int step = 1; step <= int(3.2 * period / dt) && crossings.size() < 3; ++step) {
      ASSERT_TRUE(StepBody(body, w, 0, integrator, dt, &s).ok());
      const double now = s.qd[4];
      if (previous > 0 && now <= 0) crossings.push_back(dt * (step - 1 + previous / (previous - now)));
      previous = now;
    }
    ASSERT_GE(crossings.size(), 2u) << IntegratorName(integrator);
    const double measured = crossings[1] - crossings[0];
    EXPECT_NEAR(measured, period, 0.01 * period) << IntegratorName(integrator) << ": closed form " << period;
    RecordProperty("flip_period_" + IntegratorName(integrator), Sci(measured / period - 1.0));
  }
}

// A spring at the centre of mass of a rigid box moves it as a harmonic oscillator,
// x(t) = A cos(√(k/m) t), without turning it.
TEST(Body3, SpringAtTheCentreOscillatesWithTheClosedFormPeriod) {
  const BodyModelN<3> box = Box(1.0, 2.0, 3.0, 0.5);
  const double m = box.moments().m, k = 40.0, A = 0.1;
  const Vector3d centre(0.5, 1.0, 1.5);
  WorldParams w;
  w.gravity_on = false;
  w.springs.push_back(MakeSpring(box, Vector3d::Constant(0.5), centre + Vector3d(A, 0, 0), k));
  BodyState<3, double> s = RestState<3, double>(box);  // the centre starts A from the anchor, at rest
  const double omega = std::sqrt(k / m), dt = 1e-3;
  double worst = 0.0;
  for (int step = 1; step <= int(2 * M_PI / omega / dt); ++step) {
    ASSERT_TRUE(StepBody(box, w, 0, Integrator::kRK4, dt, &s).ok());
    const double expected = A - A * std::cos(omega * step * dt);  // the centre's x
    worst = std::max(worst, std::abs(s.translation().x() - expected));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(std::abs(s.orientation().w() - 1.0), 1e-12);
}

// A spring pulls toward its anchor only: angular momentum about the anchor is kept, and with
// no damping so is the energy (variational integrator), for a point off the centre.
TEST(Body3, OffCentreSpringKeepsMomentumAboutTheAnchor) {
  std::mt19937 rng(29);
  const BodyModelN<3> body = RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 2, 20, 3000.0);
  WorldParams w;
  w.gravity_on = false;
  const Vector3d anchor(40, -30, 20);
  w.springs.push_back(MakeSpring(body, Vector3d(0.2, 0.9, 0.4), anchor, 50.0, 0.0, 10.0));
  BodyState<3, double> s = RandomState3(rng, body, 0.3);
  auto about_anchor = [&](const BodyState<3, double>& st) {
    Vector3d P;
    const Vector3d L = AngularMomentum(body, st, &P);
    return Vector3d(L - anchor.cross(P));
  };
  auto energy = [&](const BodyState<3, double>& st) {
    const Frame<3, double> f(st.q);
    const Spring& sp = w.springs[0];
    const Vector3d x = f.t + f.R * LocalPosition<double>(sp.rest_local, sp.mode_matrix, st.q);
    const double stretch = (x - anchor).norm() - sp.rest_length;
    return TotalEnergy(body, st) + 0.5 * sp.stiffness * stretch * stretch;
  };
  const Vector3d L0 = about_anchor(s);
  const double E0 = energy(s);
  double worst_L = 0.0, worst_E = 0.0;
  for (int step = 0; step < 5000; ++step) {
    ASSERT_TRUE(StepBody(body, w, 0, Integrator::kVariational, 2e-3, &s).ok());
    worst_L = std::max(worst_L, (about_anchor(s) - L0).norm() / L0.norm());
    worst_E = std::max(worst_E, std::abs(energy(s) - E0) / E0);
  }
  EXPECT_LT(worst_L, 1e-9);
  EXPECT_LT(worst_E, 1e-2);
}

TEST(Body3, VibratingBodyTumblingKeepsItsMomenta) {
  std::mt19937 rng(17);
  const BodyModelN<3> body = RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 4, 30, 2000.0);
  WorldParams w;
  w.gravity_on = false;
  BodyState<3, double> s = RandomState3(rng, body, 0.5);
  Vector3d P0;
  const Vector3d L0 = AngularMomentum(body, s, &P0);
  const double E0 = TotalEnergy(body, s);
  double worst_L = 0.0, worst_P = 0.0, worst_E = 0.0, gamma_range = 0.0;
  for (int step = 0; step < 5000; ++step) {
    ASSERT_TRUE(StepBody(body, w, 0, Integrator::kVariational, 2e-3, &s).ok());
    Vector3d P;
    const Vector3d L = AngularMomentum(body, s, &P);
    worst_L = std::max(worst_L, (L - L0).norm() / L0.norm());
    worst_P = std::max(worst_P, (P - P0).norm() / P0.norm());
    worst_E = std::max(worst_E, std::abs(TotalEnergy(body, s) - E0) / E0);
    gamma_range = std::max(gamma_range, s.gamma().cwiseAbs().maxCoeff());
  }
  EXPECT_GT(gamma_range, 0.1);  // it does vibrate
  EXPECT_LT(worst_L, 1e-9);
  EXPECT_LT(worst_P, 1e-9);
  EXPECT_LT(worst_E, 1e-2);
  RecordProperty("vibrating_momentum_drift", Sci(std::max(worst_L, worst_P)));
  RecordProperty("vibrating_energy_error", Sci(worst_E));
}

// A block on an incline of angle α (the plane tilted, gravity −y): below the friction cap
// (tan α < μ) it stays; above it, it slides with acceleration g (sin α − μ cos α).
TEST(Body3, BlockOnAnInclineHoldsBelowTheCapAndSlidesAbove) {
  const BodyModelN<3> block = Box(0.4, 0.2, 0.3, 0.5);
  const double mu = 0.4, g = 9.81;
  for (double alpha_deg : {15.0, 35.0}) {
    const double alpha = alpha_deg * M_PI / 180.0;
    WorldParams w;
    w.ground_plane.enabled = true;
    w.ground_plane.friction_cap = mu;
    w.ground_plane.stiffness = 2e4;
    w.ground_plane.normal_damping = 100.0;
    w.ground_plane.friction_damping = 100.0;
    // the plane through 0 tilted about z: downhill is −x' = (−cos α, −sin α, 0)... normal n
    w.ground_plane.normal = Vector3d(-std::sin(alpha), std::cos(alpha), 0.0);
    const Vector3d downhill(-std::cos(alpha), -std::sin(alpha), 0.0);
    BodyState<3, double> s = RestState<3, double>(block);
    s.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(alpha, Vector3d::UnitZ())));
    s.translation() = w.ground_plane.normal * 1e-4;  // resting on the plane
    const double dt = 2e-4;
    auto com_velocity = [&] {
      Vector3d P;
      AngularMomentum(block, s, &P);
      return Vector3d(P / block.moments().m);
    };
    double v_at_1 = 0.0;
    for (int step = 1; step <= int(2.0 / dt); ++step) {
      ASSERT_TRUE(StepBody(block, w, 0, Integrator::kSymplecticEuler, dt, &s).ok());
      if (step == int(1.0 / dt)) v_at_1 = com_velocity().dot(downhill);
    }
    const double v_at_2 = com_velocity().dot(downhill);
    const bool slides = std::tan(alpha) > mu;
    if (!slides) {
      EXPECT_LT(std::abs(v_at_2), 1e-3) << alpha_deg << " degrees";
    } else {
      const double expected = g * (std::sin(alpha) - mu * std::cos(alpha));
      EXPECT_NEAR(v_at_2 - v_at_1, expected, 0.01 * expected) << alpha_deg << " degrees";
    }
    EXPECT_EQ(s.contacts.size(), 4u) << "the four corners on the plane";
  }
}

// A table (top slab and four legs of mass points) dropped flat lands on its four feet and
// settles level.
TEST(Body3, TableDroppedFlatLandsOnItsFourLegsAndSettles) {
  BodyDefN<3> def;
  def.name = "table3";
  def.lattice = LatticeN<3>(Vector3d::Zero(), {Vector3d(1.2, 0, 0), Vector3d(0, 0.8, 0), Vector3d(0, 0, 0.6)}, {4, 4, 4},
                         BasisKind::kBernstein);
  std::vector<int> feet;
  for (double x : {0.0, 0.4, 0.8, 1.2})
    for (double z : {0.0, 0.3, 0.6}) def.mass_positions.push_back(Vector3d(x, 0.8, z));  // the top
  for (double x : {0.0, 1.2})
    for (double z : {0.0, 0.6})
      for (double y : {0.0, 0.4}) {
        if (y == 0.0) feet.push_back(int(def.mass_positions.size()));
        def.mass_positions.push_back(Vector3d(x, y, z));
      }
  def.masses.assign(def.mass_positions.size(), 2.0);
  const BodyModelN<3> table(def, {});
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.stiffness = 2e4;
  w.ground_plane.normal_damping = 300.0;
  w.ground_plane.friction_damping = 300.0;
  w.ground_plane.friction_cap = 0.5;
  BodyState<3, double> s = RestState<3, double>(table);
  s.translation() = Vector3d(0, 0.5, 0);
  for (int step = 0; step < int(3.0 / 5e-4); ++step) ASSERT_TRUE(StepBody(table, w, 0, Integrator::kSymplecticEuler, 5e-4, &s).ok());
  std::vector<int> touching;
  for (const Contact<3, double>& c : s.contacts) touching.push_back(c.point);
  EXPECT_EQ(touching, feet);
  EXPECT_LT(s.qd.norm(), 1e-3);
  // level: the top's normal still points up
  EXPECT_GT((s.orientation() * Vector3d::UnitY()).y(), 1.0 - 1e-9);
  // each foot carries a quarter of the weight: sinks mg/(4K)
  const double sink = table.moments().m * 9.81 / (4 * w.ground_plane.stiffness);
  EXPECT_NEAR(s.translation().y(), -sink, 0.02 * sink);
}


// ---- in the World ----

// One world with a 2D table, a 3D table and a Witkin & Welch box: each steps as it would alone.
TEST(Body3InWorld, StepsBesideTheOtherKindsAsItDoesAlone) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  auto table3 = std::make_shared<const BodyModelN<3>>(
      def, formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table3_modes.def3", def.lattice));
  WorldOptions o;
  o.params.ground_plane.enabled = true;
  o.integrator = Integrator::kSymplecticEuler;
  o.dt = 0.005;
  World world(o);
  world.AddBody(std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(4e6, 1e6)));
  const int b3 = world.AddBody(table3);
  EXPECT_EQ(world.kind(b3), BodyKind::kFfd);
  EXPECT_EQ(world.dim(b3), 3);
  EXPECT_EQ(world.body<3>(b3).num_q(), 10);
  Eigen::VectorXd gamma(4), v(10);
  gamma << 0.05, 0.0, -0.02, 0.01;
  v << 10, -20, 5, 0.1, 0.3, -0.2, 0, 0, 0, 0;
  world.SetState(b3, PositionsOf(Vector3d(0, 30, 0), Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Vector3d::UnitX())), gamma), v);
  // the same body alone, by StepBody3
  WorldParams p;
  p.ground_plane = o.params.ground_plane;
  BodyState<3, double> alone = world.state<3>(b3);
  for (int step = 0; step < 2000; ++step) {
    ASSERT_TRUE(world.Step()) << world.status().message;
    ASSERT_TRUE(StepBody(*table3, p, 0, o.integrator, o.dt, &alone).ok());
  }
  EXPECT_EQ(world.state<3>(b3).translation(), alone.translation());
  EXPECT_EQ(world.state<3>(b3).qd, alone.qd);
  EXPECT_FALSE(world.state<3>(b3).contacts.empty());  // it landed
  EXPECT_TRUE(std::isfinite(world.ComputeEnergies(b3).total()));
}

TEST(Body3InWorld, RefusesBadStatesAndPoints) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  World world;
  const int b = world.AddBody(std::make_shared<const BodyModelN<3>>(def, std::vector<DeformationModeN<3>>{}));
  EXPECT_THROW(world.body<2>(b), std::invalid_argument);  // not a 2D FFD body
  EXPECT_THROW(world.AddNail(At(b, Eigen::Vector2d(0.5, 0.5))), std::invalid_argument);  // (s, t, u) needed
  EXPECT_THROW(world.AddNail(At(b, Eigen::Vector3d(0.5, 1.5, 0.5))), std::invalid_argument);
  EXPECT_THROW(world.ApplyPointForce(MassPointOf(b, 0), Eigen::Vector2d(1, 0)), std::invalid_argument);  // 3 components
  Eigen::VectorXd none(0), v = Eigen::VectorXd::Zero(6);
  EXPECT_THROW(world.SetState(b, PositionsOf(Vector3d(0, 0, 0), Eigen::Quaterniond::Identity(), none), Eigen::VectorXd::Zero(5)),
               std::invalid_argument);
  v[0] = NAN;
  EXPECT_THROW(world.SetState(b, PositionsOf(Vector3d(0, 0, 0), Eigen::Quaterniond::Identity(), none), v), std::invalid_argument);
  v[0] = 1e160;  // finite, but its kinetic energy is not
  EXPECT_THROW(world.SetState(b, PositionsOf(Vector3d(0, 0, 0), Eigen::Quaterniond::Identity(), none), v), std::invalid_argument);
  EXPECT_EQ(world.state<3>(b).qd[0], 0.0);  // the refused states left it as it was
}

// A point force for one step from rest gives the body exactly its impulse. The explicit step
// solves M(q0) v1 = dt Q with Q = Jᵀ f, so for every rigid motion u, v1ᵀ M(q0) u = dt fᵀ J u:
// the linear momentum Σ m_k ẋ_k is f dt and the angular momentum about the origin
// Σ m_k x_k × ẋ_k is x_p × f dt, with x_k and ẋ_k = ṫ + R (ω × l_k + B_k γ̇) summed over the mass
// points at the step's start configuration. On the free path and on the constrained one (a
// nail on another body makes every body step together).
TEST(Body3InWorld, APointForceGivesTheBodyItsImpulse) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  auto table3 = std::make_shared<const BodyModelN<3>>(
      def, formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table3_modes.def3", def.lattice));
  for (const bool constrained : {false, true}) {
    const char* path = constrained ? "constrained" : "free";
    WorldOptions o;
    o.params.gravity_on = false;
    o.integrator = Integrator::kThesis;
    o.dt = 0.01;
    World world(o);
    const int b = world.AddBody(table3);
    const Vector3d t0(1, 2, 3);
    const Eigen::Quaterniond R0(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 0.5).normalized()));
    const Eigen::VectorXd gamma0 = Eigen::VectorXd::Constant(4, 0.05);
    world.SetState(b, PositionsOf(t0, R0, gamma0), Eigen::VectorXd::Zero(10));
    if (constrained) world.AddNail(MassPointOf(world.AddBody(table3), 0));
    const MaterialPoint p = MassPointOf(b, 7);
    const Vector3d f(30, -50, 20), x_p = world.PointPosition(p);
    world.ApplyPointForce(p, f);
    ASSERT_TRUE(world.Step()) << world.status().message;
    const Eigen::VectorXd v = world.state<3>(b).qd;
    auto momenta = [&](const Eigen::VectorXd& vel, Vector3d* P, Vector3d* L) {
      P->setZero();
      L->setZero();
      for (int k = 0; k < table3->num_points(); ++k) {
        const Vector3d l = table3->rest_local(k) + table3->mode_matrix(k) * gamma0;
        const Vector3d x = t0 + R0 * l;
        const Vector3d xd = vel.head<3>() + R0 * (Vector3d(vel.segment<3>(3)).cross(l) + table3->mode_matrix(k) * vel.tail(4));
        *P += table3->mass(k) * xd;
        *L += table3->mass(k) * x.cross(xd);
      }
    };
    Vector3d P, L;
    momenta(v, &P, &L);
    EXPECT_LT((P - f * o.dt).norm(), 1e-12 * f.norm() * o.dt) << path;
    EXPECT_LT((L - x_p.cross(f) * o.dt).norm(), 1e-12 * (x_p.norm() * f.norm() * o.dt)) << path;
    // the force acts for one step only: the next step is that of a twin given the same state
    World twin(o);
    const int tb = twin.AddBody(table3);
    if (constrained) twin.AddNail(MassPointOf(twin.AddBody(table3), 0));
    const BodyState<3, double>& s1 = world.state<3>(b);
    twin.SetState(tb, PositionsOf(s1.translation(), s1.orientation(), s1.gamma()), s1.qd);
    ASSERT_TRUE(world.Step());
    ASSERT_TRUE(twin.Step());
    EXPECT_EQ(world.state<3>(b).qd, twin.state<3>(tb).qd) << path;
  }
}

// A rigid box nailed at the middle of its top face is a physical pendulum: small swings about
// z have the period 2π √(I_pivot / (m g d)), d the distance from the nail to the centre.
TEST(Body3InWorld, NailedBoxSwingsWithThePhysicalPendulumPeriod) {
  const double a = 1.0, b = 2.0, c = 3.0, m = 0.5, g = 9.81;
  auto box = std::make_shared<const BodyModelN<3>>(Box(a, b, c, m));
  WorldOptions o;
  o.dt = 1e-4;
  World world(o);
  const int body = world.AddBody(box);
  const double theta0 = 0.05;
  // turned by θ0 about the nail (a/2, b, c/2): t = pivot − R pivot
  const Vector3d pivot(a / 2, b, c / 2);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(theta0, Vector3d::UnitZ()));
  world.SetState(body, PositionsOf(pivot - turn * pivot, turn, Eigen::VectorXd(0)), Eigen::VectorXd::Zero(6));
  world.AddNail(At(body, Vector3d(0.5, 1.0, 0.5)));
  const double M = 8 * m, d = b / 2, I_pivot = 8 * m * (a * a + b * b) / 4 + M * d * d;
  const double period = 2 * M_PI * std::sqrt(I_pivot / (M * g * d)) * (1 + theta0 * theta0 / 16);
  std::vector<double> crossings;
  double previous = world.state<3>(body).qd[5], worst_violation = 0.0;
  while (world.time() < 2.2 * period) {
    ASSERT_TRUE(world.Step()) << world.status().message;
    const double now = world.state<3>(body).qd[5];
    if (previous > 0 && now <= 0) crossings.push_back(world.time() - o.dt * now / (now - previous));
    previous = now;
    worst_violation = std::max(worst_violation, world.MaxViolation());
  }
  ASSERT_GE(crossings.size(), 2u);
  EXPECT_NEAR(crossings[1] - crossings[0], period, 2e-3 * period);
  EXPECT_LT(worst_violation, 1e-4);
  RecordProperty("pendulum_period_error", Sci((crossings[1] - crossings[0]) / period - 1.0));
}

// A soft character of several parts (thesis §6.2): a 3D FFD body attached to a second one and
// to a Witkin & Welch box, tumbling with no gravity for 1 s. The attachments are internal
// forces, so total linear and angular momentum are constant in the continuous motion; the
// world's semi-implicit Euler keeps them to O(Δt) (the momenta depend on the configuration),
// so the drift must halve with Δt, and the joints must hold.
struct AttachedRun {
  double drift_P = 0, drift_L = 0, violation = 0;
};
AttachedRun RunAttached(double dt) {
  std::mt19937 rng(31);
  auto body_a = std::make_shared<const BodyModelN<3>>(RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 2, 20, 3000.0));
  auto body_b = std::make_shared<const BodyModelN<3>>(RandomBody3(rng, {3, 3, 3}, BasisKind::kBernstein, 2, 20, 3000.0));
  auto slab = std::make_shared<const LinearBodyModel>(
      MakeBoxBody("slab", 3, LinearOrder::kAffine, Eigen::Vector3d(40, 15, 25), 3, 200.0));
  WorldOptions o;
  o.params.gravity_on = false;
  o.dt = dt;
  World world(o);
  const int a = world.AddBody(body_a), b = world.AddBody(body_b), s = world.AddLinearBody(slab);
  BodyState<3, double> sa = RandomState3(rng, *body_a, 0.2), sb = RandomState3(rng, *body_b, 0.2);
  world.SetState(a, PositionsOf(Vector3d::Zero(), Eigen::Quaterniond::Identity(), sa.gamma()), sa.qd);
  // b and the slab placed so that their joint points coincide with a's
  const Vector3d joint_ab = world.PointPosition(At(a, Vector3d(1, 0.5, 0.5)));
  world.SetState(b, PositionsOf(Vector3d::Zero(), Eigen::Quaterniond::Identity(), sb.gamma()), sb.qd);
  const Vector3d b_local = world.PointPosition(At(b, Vector3d(0, 0.5, 0.5)));
  world.SetState(b, PositionsOf(joint_ab - b_local, Eigen::Quaterniond::Identity(), sb.gamma()), sb.qd);
  const Vector3d joint_as = world.PointPosition(At(a, Vector3d(0.5, 1, 0.5)));
  Eigen::MatrixXd R = slab->RestState();
  R.col(3) = joint_as - Vector3d(0, -15, 0);  // x = u + R.col(3): the slab point (0, −15, 0) at the joint
  world.SetLinearState(s, R, Eigen::MatrixXd::Zero(R.rows(), R.cols()));
  world.AddAttachment(At(a, Vector3d(1, 0.5, 0.5)), At(b, Vector3d(0, 0.5, 0.5)));
  world.AddAttachment(At(a, Vector3d(0.5, 1, 0.5)), At(s, Vector3d(0, -15, 0)));
  EXPECT_TRUE(world.ProjectVelocities());
  auto momenta = [&](Vector3d* P) {
    Vector3d L = Vector3d::Zero();
    P->setZero();
    for (int i : {a, b}) {
      Vector3d Pi;
      L += AngularMomentum(world.body<3>(i), world.state<3>(i), &Pi);
      *P += Pi;
    }
    // the linear body, from its mass points: P = Σ m ẋ, L = Σ m x × ẋ
    const LinearBodyModel& m = world.linear_model(s);
    for (int k = 0; k < m.num_points(); ++k) {
      const Eigen::VectorXd p = m.Basis(m.def().points[k]);
      const Vector3d x = world.linear_R(s) * p, v = world.linear_R_dot(s) * p;
      *P += m.def().masses[k] * v;
      L += m.def().masses[k] * x.cross(v);
    }
    return L;
  };
  Vector3d P0;
  const Vector3d L0 = momenta(&P0);
  AttachedRun run;
  while (world.time() < 1.0 - 1e-9) {
    EXPECT_TRUE(world.Step()) << world.status().message;
    Vector3d P;
    const Vector3d L = momenta(&P);
    run.drift_P = std::max(run.drift_P, (P - P0).norm() / P0.norm());
    run.drift_L = std::max(run.drift_L, (L - L0).norm() / L0.norm());
    run.violation = std::max(run.violation, world.MaxViolation());
  }
  return run;
}

TEST(Body3InWorld, AttachedToEachOtherAndToALinearBodyKeepsMomentum) {
  const AttachedRun coarse = RunAttached(2e-4), fine = RunAttached(1e-4);
  EXPECT_LT(coarse.drift_P, 1e-4);
  EXPECT_LT(coarse.drift_L, 1e-4);
  EXPECT_NEAR(coarse.drift_P / fine.drift_P, 2.0, 0.2);  // first order in Δt
  EXPECT_NEAR(coarse.drift_L / fine.drift_L, 2.0, 0.2);
  EXPECT_LT(coarse.violation, 1e-2);
  RecordProperty("attached_momentum_drift", Sci(coarse.drift_P) + " / " + Sci(fine.drift_P) + " linear, " +
                                                Sci(coarse.drift_L) + " / " + Sci(fine.drift_L) + " angular");
}

}  // namespace
}  // namespace wobble
