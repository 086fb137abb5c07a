// Witkin–Welch bodies and constraints (lib/wobble/body/linear_body, affine_energy,
// lib/wobble/constraints): physics checked against closed forms (physical pendulum period,
// energy conservation, the single-body impulse formula), finite differences for the energy
// gradients, and the FFD bodies' own dynamics.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "support/test_bodies.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::shared_ptr<const LinearBodyModel> Bar2D(double half_length = 0.5, double half_width = 0.1, double mass = 1.0,
                                             LinearOrder order = LinearOrder::kAffine) {
  return std::make_shared<LinearBodyModel>(
      MakeBoxBody("bar", 2, order, Eigen::Vector2d(half_length, half_width), order == LinearOrder::kAffine ? 3 : 4, mass));
}

Eigen::Matrix2d Rot2(double a) { return Eigen::Rotation2Dd(a).toRotationMatrix(); }

// Moment of inertia of a 2D body's mass points about a point (in undeformed coordinates).
double InertiaAbout(const LinearBodyModel& m, const Eigen::VectorXd& pivot) {
  double I = 0;
  for (int k = 0; k < m.num_points(); ++k) I += m.def().masses[k] * (m.def().points[k] - pivot).squaredNorm();
  return I;
}

// ---------------------------------------------------------------- the canonical example

TEST(World, HelloPendulum) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const int bar = world.AddLinearBody(Bar2D(), AffineMaterial{200.0, 200.0, 0.0, 0.0});
  const int nail = world.AddNail(At(bar, Eigen::Vector2d(-0.5, 0.0)));  // left end stays where it is
  ASSERT_TRUE(world.RunUntil(0.5)) << world.status().message;  // about a quarter swing
  EXPECT_LT(world.MaxViolation(), 1e-9);
  EXPECT_LT(world.PointPosition(At(bar, Eigen::Vector2d(0.5, 0.0)))[1], -0.5);  // the free end swung down
  EXPECT_EQ(world.factorizations(), 1);
  world.SetEnabled(nail, false);  // let go: the bar falls freely
  const double y0 = world.PointPosition(At(bar, Eigen::Vector2d(-0.5, 0.0)))[1];
  ASSERT_TRUE(world.RunUntil(0.7)) << world.status().message;
  EXPECT_LT(world.PointPosition(At(bar, Eigen::Vector2d(-0.5, 0.0)))[1], y0 - 0.1);
  EXPECT_EQ(world.factorizations(), 1);  // no constraint left: nothing to refactor
}

// ---------------------------------------------------------------- linear bodies

TEST(LinearBody, BasisSizesAndMassMatrix) {
  EXPECT_EQ(LinearBasisSize(2, LinearOrder::kAffine), 3);
  EXPECT_EQ(LinearBasisSize(3, LinearOrder::kAffine), 4);
  EXPECT_EQ(LinearBasisSize(2, LinearOrder::kQuadratic), 6);
  EXPECT_EQ(LinearBasisSize(3, LinearOrder::kQuadratic), 10);
  const Eigen::VectorXd p = LinearBasis(LinearOrder::kQuadratic, Eigen::Vector3d(2, 3, 5));
  Eigen::VectorXd expected(10);
  expected << 2, 3, 5, 1, 6, 10, 15, 4, 9, 25;
  EXPECT_EQ(p, expected);
  // M = Σ m p pᵀ summed independently; W M = I
  const auto body = std::make_shared<LinearBodyModel>(
      MakeBoxBody("q", 3, LinearOrder::kQuadratic, Eigen::Vector3d(1, 2, 0.5), 3, 27.0));
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(10, 10);
  for (int k = 0; k < body->num_points(); ++k) {
    const Eigen::VectorXd pk = LinearBasis(LinearOrder::kQuadratic, body->def().points[k]);
    M += body->def().masses[k] * pk * pk.transpose();
  }
  EXPECT_LT((M - body->mass_matrix()).norm(), 1e-12);
  EXPECT_LT((body->inverse_mass_matrix() * M - Eigen::MatrixXd::Identity(10, 10)).norm(), 1e-9);
  // kinetic energy ½ tr(Ṙ M Ṙᵀ) equals Σ ½ m |Ṙ p_k|² over the points
  World world(testing::WitkinWelchOptions());
  const int b = world.AddLinearBody(body);
  std::mt19937 rng(3);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd Rd(3, 10);
  for (int i = 0; i < Rd.size(); ++i) Rd.data()[i] = n01(rng);
  world.SetLinearState(b, body->RestState(), Rd);
  double T = 0;
  for (int k = 0; k < body->num_points(); ++k)
    T += 0.5 * body->def().masses[k] * (Rd * LinearBasis(LinearOrder::kQuadratic, body->def().points[k])).squaredNorm();
  EXPECT_NEAR(world.KineticEnergy(b), T, 1e-10 * T);
}

TEST(LinearBody, RefusesPointsThatDoNotSpan) {
  LinearBodyDef def;
  def.name = "stick";
  def.points = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(2, 0)};  // collinear
  def.masses = {1, 1, 1};
  try {
    LinearBodyModel m(def);
    FAIL() << "collinear points accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'stick'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("do not span"), std::string::npos) << e.what();
  }
  def.points[2] = Eigen::Vector2d(0, 1);
  def.masses[1] = -1;
  EXPECT_THROW(LinearBodyModel{def}, std::invalid_argument);
}

// A free body in gravity: every point falls with g (Q = g μᵀ, R̈ = Q W).
TEST(LinearBody, FreeFallIsUniform3D) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const auto model = std::make_shared<LinearBodyModel>(
      MakeBoxBody("cube", 3, LinearOrder::kQuadratic, Eigen::Vector3d(1, 1, 1), 3, 5.0));
  const int b = world.AddLinearBody(model);
  ASSERT_TRUE(world.RunUntil(1.0));
  // symplectic Euler: y_n = −g h² n(n+1)/2
  const double n = 1000, h = 1e-3;
  const double expected = -9.81 * h * h * n * (n + 1) / 2;
  for (const Eigen::Vector3d& u : {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(-1, 0.3, 0.2)}) {
    const Eigen::VectorXd x = world.PointPosition(At(b, u));
    EXPECT_NEAR(x[1] - u[1], expected, 1e-9);
    EXPECT_NEAR(x[0], u[0], 1e-12);
    EXPECT_NEAR(x[2], u[2], 1e-12);
  }
}

// Linear bodies step with the world's integrator: a free fall from rest under each, against
// its closed form after n steps (constant force): velocity-first and implicit Euler
// y_n = −g h² n(n+1)/2, position-first −g h² n(n−1)/2, RK4 and the variational (velocity-
// first for a constant M) step, exact −g (nh)²/2 and −g h² n(n+1)/2.
TEST(LinearBody, FreeFallUnderEachIntegratorMatchesItsClosedForm) {
  const double n = 1000, h = 1e-3, g = 9.81;
  struct Expect {
    Integrator integrator;
    double y;
  };
  for (const Expect& e : {Expect{Integrator::kThesis, -g * h * h * n * (n + 1) / 2},
                          Expect{Integrator::kSymplecticEuler, -g * h * h * n * (n - 1) / 2},
                          Expect{Integrator::kRK4, -g * (n * h) * (n * h) / 2},
                          Expect{Integrator::kImplicitEuler, -g * h * h * n * (n + 1) / 2},
                          Expect{Integrator::kVariational, -g * h * h * n * (n + 1) / 2}}) {
    WorldOptions opt = testing::WitkinWelchOptions();
    opt.dt = h;
    opt.integrator = e.integrator;
    World world(opt);
    const int b = world.AddLinearBody(std::make_shared<LinearBodyModel>(
        MakeBoxBody("cube", 3, LinearOrder::kQuadratic, Eigen::Vector3d(1, 1, 1), 3, 5.0)));
    ASSERT_TRUE(world.RunUntil(1.0)) << world.status().message;
    const Eigen::VectorXd x = world.PointPosition(At(b, Eigen::Vector3d(-1, 0.3, 0.2)));
    EXPECT_NEAR(x[1] - 0.3, e.y, 1e-9) << IntegratorName(e.integrator);
    EXPECT_NEAR(x[0], -1.0, 1e-12) << IntegratorName(e.integrator);
  }
}

// ---------------------------------------------------------------- affine energies (§2.4)

Eigen::MatrixXd RandomR(std::mt19937& rng, int d, int n) {
  std::normal_distribution<double> n01;
  Eigen::MatrixXd R(d, n);
  for (int i = 0; i < R.size(); ++i) R.data()[i] = n01(rng);
  R.leftCols(d) += Eigen::MatrixXd::Identity(d, d);
  return R;
}

TEST(AffineEnergy, ZeroAndStationaryAtRotations) {
  const AffineMaterial mat{3.0, 5.0, 0.7, 0.0};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ang(-kPi, kPi);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::MatrixXd R2 = Eigen::MatrixXd::Zero(2, 3);
    R2.leftCols(2) = Rot2(ang(rng));
    R2.col(2) = Eigen::Vector2d(ang(rng), ang(rng));
    EXPECT_NEAR(AffineEnergy(mat, R2), 0.0, 1e-24);
    EXPECT_LT(AffineEnergyGradient(mat, R2).norm(), 1e-12);
    Eigen::MatrixXd R3 = Eigen::MatrixXd::Zero(3, 4);
    R3.leftCols(3) = Eigen::AngleAxisd(ang(rng), Eigen::Vector3d(ang(rng), ang(rng), 1.0).normalized()).toRotationMatrix();
    EXPECT_NEAR(AffineEnergy(mat, R3), 0.0, 1e-24);
    EXPECT_LT(AffineEnergyGradient(mat, R3).norm(), 1e-12);
  }
  // and positive away from them: a stretch, a shear, a reflection (det −1)
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(2, 3);
  S.leftCols(2) << 1.1, 0, 0, 1;
  EXPECT_GT(AffineEnergy(mat, S), 0.0);
  S.leftCols(2) << 1, 0.1, 0, 1;
  EXPECT_GT(AffineEnergy(mat, S), 0.0);
  S.leftCols(2) << -1, 0, 0, 1;
  EXPECT_NEAR(AffineEnergy(mat, S), 5.0 * 4.0, 1e-12);  // rigidity 0, volume k_c (−1 − 1)²
}

TEST(AffineEnergy, GradientMatchesFiniteDifferences) {
  std::mt19937 rng(11);
  const AffineMaterial mat{2.5, 4.0, 0.0, 1.5};
  for (int d : {2, 3})
    for (int n : {d + 1, d == 2 ? 6 : 10})
      for (int trial = 0; trial < 5; ++trial) {
        const Eigen::MatrixXd R = RandomR(rng, d, n);
        const Eigen::MatrixXd g = AffineEnergyGradient(mat, R);
        for (int i = 0; i < R.size(); ++i) {
          const double eps = 1e-6;
          Eigen::MatrixXd Rp = R, Rm = R;
          Rp.data()[i] += eps;
          Rm.data()[i] -= eps;
          const double fd = (AffineEnergy(mat, Rp) - AffineEnergy(mat, Rm)) / (2 * eps);
          EXPECT_NEAR(g.data()[i], fd, 1e-6 * (1.0 + std::abs(fd))) << "d " << d << " n " << n << " entry " << i;
        }
      }
}

// The damping form Q = −k_d V̇ ∂V/∂R removes energy at exactly the rate k_d V̇².
TEST(AffineEnergy, DampingRemovesEnergyAtRateKdVdotSquared) {
  std::mt19937 rng(5);
  const AffineMaterial mat{2.0, 3.0, 0.4, 0.0};
  AffineMaterial undamped = mat;
  undamped.damping = 0;
  const Eigen::MatrixXd R = RandomR(rng, 3, 4), Rd = RandomR(rng, 3, 4);
  const Eigen::MatrixXd grad = AffineEnergyGradient(mat, R);
  const double v_dot = (grad.array() * Rd.array()).sum();
  const Eigen::MatrixXd damping = AffineForce(mat, R, Rd) - AffineForce(undamped, R, Rd);
  EXPECT_NEAR((damping.array() * Rd.array()).sum(), -mat.damping * v_dot * v_dot, 1e-10 * (1 + v_dot * v_dot));
}

// Small vibrations about the rest shape: started along the stiffest mode of H v = ω² M v, a
// free body (no gravity) oscillates with period 2π/ω_max; and stepping at StableTimeStep stays
// bounded for a large initial deformation.
TEST(AffineEnergy, VibrationFrequencyMatchesSimulation) {
  const auto model = Bar2D(0.5, 0.1, 1.0);
  const AffineMaterial mat{100.0, 60.0, 0.0, 0.0};
  const Eigen::VectorXd w = VibrationFrequencies(*model, mat);
  EXPECT_NEAR(w[0], 0.0, 1e-3);  // rigid motions: 2 translations and a rotation
  EXPECT_NEAR(w[2], 0.0, 1e-3);
  EXPECT_GT(w[3], 1.0);
  // the stiffest mode in the flattened coordinates, by inverse iteration on the same problem
  const int N = 6;
  Eigen::MatrixXd H(N, N), M = Eigen::MatrixXd::Zero(N, N);
  for (int a = 0; a < N; ++a) {
    Eigen::MatrixXd Rp = model->RestState(), Rm = Rp;
    Rp(a / 3, a % 3) += 1e-6;
    Rm(a / 3, a % 3) -= 1e-6;
    const Eigen::MatrixXd dg = (AffineEnergyGradient(mat, Rp) - AffineEnergyGradient(mat, Rm)) / 2e-6;
    for (int b = 0; b < N; ++b) H(b, a) = dg(b / 3, b % 3);
  }
  for (int i = 0; i < 2; ++i) M.block(3 * i, 3 * i, 3, 3) = model->mass_matrix();
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(0.5 * (H + H.transpose()), M);
  const Eigen::VectorXd v = es.eigenvectors().col(N - 1);
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.params.gravity_on = false;
  opt.dt = 0.01 / w.maxCoeff();
  World world(opt);
  const int b = world.AddLinearBody(model, mat);
  Eigen::MatrixXd R = model->RestState();
  const double amp = 1e-4 / v.cwiseAbs().maxCoeff();
  for (int a = 0; a < N; ++a) R(a / 3, a % 3) += amp * v[a];
  world.SetLinearState(b, R, Eigen::MatrixXd::Zero(2, 3));
  // period from the sign changes of the modal coordinate vᵀ M (R − R0)
  auto coord = [&] {
    const Eigen::MatrixXd D = world.linear_R(b) - model->RestState();
    Eigen::VectorXd x(N);
    for (int a = 0; a < N; ++a) x[a] = D(a / 3, a % 3);
    return v.dot(M * x);
  };
  std::vector<double> crossings;
  double prev = coord();
  const double T = 2 * kPi / w.maxCoeff();
  while (world.time() < 5.2 * T) {
    ASSERT_TRUE(world.Step());
    const double c = coord();
    if (prev < 0 && c >= 0) crossings.push_back(world.time() - opt.dt * c / (c - prev));
    prev = c;
  }
  ASSERT_GE(crossings.size(), 4u);
  EXPECT_NEAR((crossings.back() - crossings.front()) / (crossings.size() - 1), T, 1e-3 * T);
  // at the suggested step a 20 % stretch stays bounded over many vibration periods
  WorldOptions fast = testing::WitkinWelchOptions();
  fast.params.gravity_on = false;
  fast.dt = StableTimeStep(*model, mat);
  EXPECT_NEAR(fast.dt, 1.0 / w.maxCoeff(), 1e-12);
  World w2(fast);
  const int b2 = w2.AddLinearBody(model, mat);
  w2.SetLinearState(b2, model->PlacedState(Eigen::Vector2d(1.2, 0.8).asDiagonal().toDenseMatrix(), Eigen::Vector2d::Zero()),
                    Eigen::MatrixXd::Zero(2, 3));
  const double E0 = w2.TotalEnergy();
  ASSERT_TRUE(w2.RunUntil(200 * fast.dt * 2 * kPi)) << w2.status().message;
  EXPECT_LT(std::abs(w2.TotalEnergy() - E0), 0.2 * E0);
}

// ---------------------------------------------------------------- pendulums

// A stiff affine bar nailed at one end swings as a physical pendulum: T = 2π √(I_pivot / (m g L))
// (times 1 + θ0²/16 for the amplitude θ0), with I_pivot = Σ m_k |u_k − pivot|² of its points.
TEST(World, SmallAnglePendulumPeriodMatchesPhysicalPendulum) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-4;
  World world(opt);
  const auto model = Bar2D(0.5, 0.1, 1.0);
  const int bar = world.AddLinearBody(model, AffineMaterial{2e4, 2e4, 0.0, 0.0});
  const Eigen::Vector2d pivot(-0.5, 0.0);
  // hang the bar down from the pivot at origin, turned by θ0 from the vertical
  const double theta0 = 0.05;
  const Eigen::Matrix2d rot = Rot2(-kPi / 2 + theta0);
  world.SetLinearState(bar, model->PlacedState(rot, -rot * pivot), Eigen::MatrixXd::Zero(2, 3));
  world.AddNail(At(bar, pivot), Eigen::Vector2d::Zero());
  const double m = model->total_mass(), L = 0.5, g = 9.81;
  const double T_expected = 2 * kPi * std::sqrt(InertiaAbout(*model, pivot) / (m * g * L)) * (1 + theta0 * theta0 / 16);
  // angle of the centre of mass from straight down; period from successive upward zero crossings
  auto angle = [&] {
    const Eigen::VectorXd c = world.PointPosition(At(bar, Eigen::Vector2d(0, 0)));
    return std::atan2(c[0], -c[1]);
  };
  std::vector<double> crossings;
  double prev = angle();
  while (world.time() < 3.5 * T_expected) {
    ASSERT_TRUE(world.Step()) << world.status().message;
    const double a = angle();
    if (prev < 0 && a >= 0) crossings.push_back(world.time() - opt.dt * a / (a - prev));
    prev = a;
  }
  ASSERT_GE(crossings.size(), 3u);
  const double T_measured = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  EXPECT_NEAR(T_measured, T_expected, 1e-3 * T_expected) << "expected " << T_expected;
  EXPECT_LT(world.MaxViolation(), 1e-9);
}

// A nailed pendulum of either dimension, frictionless and undamped: 2D, an affine bar turned
// 30° from the horizontal and nailed at its left end (it swings 60°, deforming); 3D, an affine
// slab tilted about an oblique axis and nailed at a corner (a spherical pendulum that also turns
// about its own axis). `scale`: m g × the pivot-to-centre distance, the swing's energy scale.
struct NailedSlab {
  World world;
  double scale = 0;
  int body = -1;
};

NailedSlab MakeNailedSlab(int dim, WorldOptions opt) {
  NailedSlab n{World(opt)};
  const AffineMaterial mat{500.0, 500.0, 0.0, 0.0};
  if (dim == 2) {
    const auto model = Bar2D(0.5, 0.1, 2.0);
    n.body = n.world.AddLinearBody(model, mat);
    n.world.SetLinearState(n.body, model->PlacedState(Rot2(-kPi / 6), Eigen::Vector2d::Zero()), Eigen::MatrixXd::Zero(2, 3));
    n.world.AddNail(At(n.body, Eigen::Vector2d(-0.5, 0.0)));
    n.scale = model->total_mass() * 9.81 * 0.5;
  } else {
    const auto model = std::make_shared<LinearBodyModel>(
        MakeBoxBody("slab", 3, LinearOrder::kAffine, Eigen::Vector3d(0.5, 0.15, 0.25), 3, 2.0));
    EXPECT_LE(opt.dt, StableTimeStep(*model, mat));
    n.body = n.world.AddLinearBody(model, mat);
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, 0.2, 1.0).normalized()).toRotationMatrix();
    n.world.SetLinearState(n.body, model->PlacedState(tilt, Eigen::Vector3d::Zero()), Eigen::MatrixXd::Zero(3, 4));
    n.world.AddNail(At(n.body, Eigen::Vector3d(-0.5, 0.15, 0.25)));
    n.scale = model->total_mass() * 9.81 * 0.6;
  }
  return n;
}

// The dimension as a type, for the tests written once over it.
template <class T> class OverTheDimension : public ::testing::Test {
 public:
  static constexpr int kDim = T::value;
};
using Dimensions = ::testing::Types<std::integral_constant<int, 2>, std::integral_constant<int, 3>>;
TYPED_TEST_SUITE(OverTheDimension, Dimensions);

// The constraint force does no work: the nailed pendulum keeps its total energy over 20 s with
// either multiplier solve; the bound is the O(Δt) oscillation of velocity-first Euler.
TYPED_TEST(OverTheDimension, NailedPendulumConservesEnergy) {
  for (MultiplierMethod method : {MultiplierMethod::kDense, MultiplierMethod::kSparse}) {
    WorldOptions opt = testing::WitkinWelchOptions();
    opt.dt = 5e-4;
    opt.method = method;
    NailedSlab n = MakeNailedSlab(TestFixture::kDim, opt);
    const double E0 = n.world.TotalEnergy();
    double worst = 0, worst_c = 0;
    ASSERT_TRUE(n.world.RunUntil(20.0, [&](World& w) {
      worst = std::max(worst, std::abs(w.TotalEnergy() - E0));
      worst_c = std::max(worst_c, w.MaxViolation());
    })) << n.world.status().message;
    EXPECT_LT(worst, 2e-3 * n.scale) << MultiplierMethodName(method);
    EXPECT_LT(worst_c, 1e-9) << MultiplierMethodName(method);
    EXPECT_EQ(n.world.last_method(), method);
    std::printf("%dD, %s: max |E - E0| = %.3g (m g L = %.3g), max |c| = %.3g over 40000 steps\n", TestFixture::kDim,
                MultiplierMethodName(method), worst, n.scale, worst_c);
  }
}

// Fig. 2: a triple pendulum of affine parts attached end to end, nailed at the top; long run.
World TriplePendulum(MultiplierMethod method, double dt, std::vector<int>* links,
                     Integrator integrator = Integrator::kThesis) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = dt;
  opt.method = method;
  opt.integrator = integrator;
  World world(opt);
  const auto model = Bar2D(0.5, 0.15, 1.0);
  for (int i = 0; i < 3; ++i) {
    const int b = world.AddLinearBody(model, AffineMaterial{300.0, 300.0, 0.05, 0.0});
    world.SetLinearState(b, model->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(0.5 + i, 0)),
                         Eigen::MatrixXd::Zero(2, 3));
    links->push_back(b);
  }
  world.AddNail(At((*links)[0], Eigen::Vector2d(-0.5, 0)));
  for (int i = 0; i + 1 < 3; ++i) world.AddAttachment(At((*links)[i], Eigen::Vector2d(0.5, 0)), At((*links)[i + 1], Eigen::Vector2d(-0.5, 0)));
  return world;
}

TEST(World, TriplePendulumViolationStaysAtRoundOff) {
  std::vector<int> links;
  World world = TriplePendulum(MultiplierMethod::kAuto, 1e-3, &links);
  double worst = 0;
  ASSERT_TRUE(world.RunUntil(30.0, [&](World& w) { worst = std::max(worst, w.MaxViolation()); }))
      << world.status().message;
  EXPECT_LT(worst, 1e-8);
  EXPECT_EQ(world.factorizations(), 1);  // 30000 steps, one factorization
  EXPECT_EQ(world.per_step_factorizations(), 0);
  // the chain hangs below the nail and has not flown apart
  EXPECT_LT(world.PointPosition(At(links[2], Eigen::Vector2d(0.5, 0)))[1], 0.0);
}

TEST(World, DenseAndSparsePathsAgree) {
  std::vector<int> l1, l2;
  World dense = TriplePendulum(MultiplierMethod::kDense, 1e-3, &l1);
  World sparse = TriplePendulum(MultiplierMethod::kSparse, 1e-3, &l2);
  ASSERT_TRUE(dense.RunUntil(2.0));
  ASSERT_TRUE(sparse.RunUntil(2.0));
  for (int b = 0; b < 3; ++b) EXPECT_LT((dense.linear_R(b) - sparse.linear_R(b)).norm(), 1e-8);
  EXPECT_EQ(dense.last_method(), MultiplierMethod::kDense);
  EXPECT_EQ(sparse.last_method(), MultiplierMethod::kSparse);
}

// Constraints are a stage of every integrator (item 4 of the one-stack issue): the multiplier
// solve gives the constrained q̈ wherever an integrator evaluates accelerations. Fig. 2's
// triple pendulum against a fine RK4 reference: thesis (velocity-first Euler) and implicit Euler
// converge at first order, symplectic Euler too, RK4 at fourth; every one keeps the joints at
// round-off (J is constant for linear bodies, so c and ċ are linear in the state and every
// stage's c̈ = 0 keeps them). Implicit Euler loses energy (it damps), the others hold it.
struct ChainRun {
  Eigen::MatrixXd tip;  // the three links' R at t_end, stacked
  double violation = 0, energy_gain = 0;
};

ChainRun RunChain(Integrator integrator, double dt, double t_end) {
  std::vector<int> links;
  World world = TriplePendulum(MultiplierMethod::kAuto, dt, &links, integrator);
  ChainRun r;
  const double E0 = world.TotalEnergy();
  EXPECT_TRUE(world.RunUntil(t_end, [&](World& w) {
    r.violation = std::max(r.violation, w.MaxViolation());
    r.energy_gain = std::max(r.energy_gain, w.TotalEnergy() - E0);
  })) << IntegratorName(integrator) << ": " << world.status().message;
  r.tip.resize(6, 3);
  for (int b = 0; b < 3; ++b) r.tip.middleRows(2 * b, 2) = world.linear_R(links[size_t(b)]);
  return r;
}

TEST(ConstraintStage, Fig2ConvergesAtEachIntegratorsOrder) {
  const double t_end = 1.0;
  const ChainRun reference = RunChain(Integrator::kRK4, 1.25e-4, t_end);
  struct Expect {
    Integrator integrator;
    double dt, order;
  };
  for (const Expect& e : {Expect{Integrator::kThesis, 5e-4, 1.0}, Expect{Integrator::kSymplecticEuler, 5e-4, 1.0},
                          Expect{Integrator::kImplicitEuler, 5e-4, 1.0}, Expect{Integrator::kRK4, 1e-3, 4.0}}) {
    const ChainRun coarse = RunChain(e.integrator, 2 * e.dt, t_end), fine = RunChain(e.integrator, e.dt, t_end);
    const double err_coarse = (coarse.tip - reference.tip).norm(), err_fine = (fine.tip - reference.tip).norm();
    const double order = std::log2(err_coarse / err_fine);
    std::printf("Fig. 2, %-10s dt %.4g: |R - R_ref| = %.3g (dt %.4g: %.3g), order %.2f, max |c| %.2g, max energy gain %.2g J\n",
                IntegratorName(e.integrator).c_str(), e.dt, err_fine, 2 * e.dt, err_coarse, order, fine.violation,
                fine.energy_gain);
    EXPECT_NEAR(order, e.order, 0.35) << IntegratorName(e.integrator);
    EXPECT_LT(fine.violation, 1e-9) << IntegratorName(e.integrator);
    EXPECT_LT(coarse.violation, 1e-9) << IntegratorName(e.integrator);
    if (e.integrator == Integrator::kImplicitEuler) {
      EXPECT_LT(fine.energy_gain, 1e-9);  // it only damps
    }
  }
  // at the same dt, RK4 is far closer than the Euler forms
  const ChainRun thesis = RunChain(Integrator::kThesis, 1e-3, t_end), rk4 = RunChain(Integrator::kRK4, 1e-3, t_end);
  EXPECT_LT((rk4.tip - reference.tip).norm(), 1e-3 * (thesis.tip - reference.tip).norm());
}

// The constraint force does no work: RK4 holds a nailed pendulum's energy far better than the
// O(Δt) bound of velocity-first Euler (NailedPendulumConservesEnergy), in 2D and 3D.
double NailedSlabEnergyError(int dim, Integrator integrator, double dt) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = dt;
  opt.integrator = integrator;
  NailedSlab n = MakeNailedSlab(dim, opt);
  const double E0 = n.world.TotalEnergy();
  double worst = 0, worst_c = 0;
  EXPECT_TRUE(n.world.RunUntil(5.0, [&](World& w) {
    worst = std::max(worst, std::abs(w.TotalEnergy() - E0));
    worst_c = std::max(worst_c, w.MaxViolation());
  })) << n.world.status().message;
  EXPECT_LT(worst_c, 1e-9);
  return worst / n.scale;
}

TEST(ConstraintStage, Rk4HoldsANailedSlabsEnergy) {
  for (int dim : {2, 3}) {
    const double euler = NailedSlabEnergyError(dim, Integrator::kThesis, 5e-4);
    const double rk4 = NailedSlabEnergyError(dim, Integrator::kRK4, 5e-4);
    const double rk4_coarse = NailedSlabEnergyError(dim, Integrator::kRK4, 1e-3);
    std::printf("%dD nailed slab, 5 s: max |dE|/(m g L) thesis %.3g, rk4 %.3g (dt 1e-3: %.3g)\n", dim, euler, rk4,
                rk4_coarse);
    EXPECT_LT(rk4, 1e-3 * euler);
    EXPECT_GT(rk4_coarse / rk4, 8.0);  // fourth order, less the round-off floor
  }
}

// A variational step has no constraint stage: refused by name, never silently another scheme.
TEST(ConstraintStage, VariationalIsRefusedByName) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.integrator = Integrator::kVariational;
  World world(opt);
  const int bar = world.AddLinearBody(Bar2D(), AffineMaterial{200.0, 200.0, 0.0, 0.0});
  const Eigen::MatrixXd R0 = world.linear_R(bar);
  world.AddNail(At(bar, Eigen::Vector2d(-0.5, 0.0)));
  EXPECT_FALSE(world.Step());
  EXPECT_EQ(world.status().code, StatusCode::kUnsupported);
  EXPECT_NE(world.status().message.find("variational"), std::string::npos) << world.status().message;
  EXPECT_EQ(world.linear_R(bar), R0);  // nothing moved
}

// Feedback pulls a violated start back: begin 5 cm off the nail; c decays like the critically
// damped c̈ = −α c − β ċ (time constant Δt / rate = 10 steps).
TEST(World, FeedbackRemovesAnInitialViolation) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const int bar = world.AddLinearBody(Bar2D(), AffineMaterial{1000.0, 1000.0, 0.0, 0.0});
  const int nail = world.AddNail(At(bar, Eigen::Vector2d(-0.5, 0.0)), Eigen::Vector2d(-0.5, 0.05));
  EXPECT_NEAR(world.ConstraintError(nail).norm(), 0.05, 1e-12);
  ASSERT_TRUE(world.RunUntil(0.2));
  EXPECT_LT(world.ConstraintError(nail).norm(), 1e-6);
}

// ---------------------------------------------------------------- trajectories and switching

TEST(World, TrajectoryControlFollowsPathAndSwitchingRefactorsOnlyThen) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const int bar = world.AddLinearBody(Bar2D(), AffineMaterial{100.0, 100.0, 0.05, 0.0});
  const MaterialPoint tip = At(bar, Eigen::Vector2d(0.5, 0.0));
  // a circle of radius 0.3 through the tip's rest position, starting with the tip's velocity (0)
  const double r = 0.3, w = 2.0;
  auto circle = std::make_shared<FunctionPath>(2, [=](double t) {
    const double a = w * t * t / 2;  // angle with zero start speed, constant angular acceleration
    const double ad = w * t, add = w;
    PathSample s;
    s.n = Eigen::Vector2d(0.5 - r + r * std::cos(a), r * std::sin(a));
    s.n_dot = Eigen::Vector2d(-r * std::sin(a) * ad, r * std::cos(a) * ad);
    s.n_ddot = Eigen::Vector2d(-r * std::cos(a) * ad * ad - r * std::sin(a) * add, -r * std::sin(a) * ad * ad + r * std::cos(a) * add);
    return s;
  });
  const int control = world.AddTrajectory(tip, circle);
  // a second, independent pendulum keeps the set non-empty while the control is off
  const int other = world.AddLinearBody(Bar2D(), AffineMaterial{100.0, 100.0, 0.0, 0.0});
  world.SetLinearState(other, Bar2D()->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(5, 0)), Eigen::MatrixXd::Zero(2, 3));
  const int other_nail = world.AddNail(At(other, Eigen::Vector2d(-0.5, 0.0)));
  double worst = 0;
  ASSERT_TRUE(world.RunUntil(2.0, [&](World& wd) { worst = std::max(worst, wd.ConstraintError(control).norm()); }));
  std::printf("circle path: max |c| = %.3g over 2 s\n", worst);
  // The largest error is the onset transient: the staggered start velocity 0 differs from
  // ṅ(−Δt/2) = −½Δt n̈(0), so it is O(Δt²) (9e-7 here, 2.3e-7 at half the step, 3.6e-6 at twice).
  EXPECT_LT(worst, 2e-6);
  EXPECT_EQ(world.factorizations(), 1);
  // replacing the path (a behaviour rebuilding its curve) keeps the factorization
  world.SetPath(control, circle);
  ASSERT_TRUE(world.RunUntil(2.1));
  EXPECT_EQ(world.factorizations(), 1);
  // off: the tip goes ballistic; one refactor
  world.SetEnabled(control, false);
  ASSERT_TRUE(world.RunUntil(2.3));
  EXPECT_EQ(world.factorizations(), 2);
  world.SetEnabled(control, false);  // no change, no refactor
  // on again, holding the tip where it is now (a behaviour would preroll to its path instead)
  world.SetPath(control, std::make_shared<FixedPath>(world.PointPosition(tip)));
  world.SetEnabled(control, true);
  ASSERT_TRUE(world.ProjectVelocities());  // Eq. 9: match the path's velocity at once (the refactor)
  EXPECT_LT(world.ConstraintVelocityError(control).norm(), 1e-9);
  ASSERT_TRUE(world.RunUntil(2.5)) << world.status().message;
  EXPECT_EQ(world.factorizations(), 3);
  // control off and a nail on: one refactor for both changes
  world.SetEnabled(control, false);
  const int nail = world.AddNail(At(bar, Eigen::Vector2d(-0.5, 0.0)));
  ASSERT_TRUE(world.RunUntil(2.6));
  EXPECT_EQ(world.factorizations(), 4);
  world.SetNailPosition(nail, world.PointPosition(At(bar, Eigen::Vector2d(-0.5, 0.0))) + Eigen::Vector2d(0.01, 0));
  ASSERT_TRUE(world.RunUntil(2.7));
  EXPECT_EQ(world.factorizations(), 4);  // moving a nail keeps J
  world.Remove(nail);
  EXPECT_FALSE(world.exists(nail));
  ASSERT_TRUE(world.RunUntil(2.8));
  EXPECT_EQ(world.factorizations(), 5);
  world.SetEnabled(other_nail, false);
  ASSERT_TRUE(world.RunUntil(2.9));
  EXPECT_EQ(world.factorizations(), 5);  // no constraints left: nothing to factor
  EXPECT_LT(world.steps(), 2905);
}

// ---------------------------------------------------------------- impulses (Eq. 9)

// One free body: the impulse I = λ pᵀ that changes the velocity at p by Δv is ΔṘ = Δv (W p)ᵀ / (pᵀ W p).
TEST(Impulse, StopDeadOnAFreeBodyMatchesClosedForm) {
  World world(testing::WitkinWelchOptions());
  const auto model = Bar2D();
  const int bar = world.AddLinearBody(model);
  Eigen::MatrixXd Rd(2, 3);
  Rd << 0.3, -0.2, 1.0, 0.5, 0.1, -2.0;
  world.SetLinearState(bar, model->RestState(), Rd);
  const Eigen::Vector2d u(0.4, 0.05);
  const Eigen::VectorXd p = model->Basis(u), Wp = model->inverse_mass_matrix() * p;
  const Eigen::VectorXd v_before = world.PointVelocity(At(bar, u));
  ASSERT_TRUE(world.ApplyImpulse({{At(bar, u), MaterialPoint(), Eigen::Vector2d::Zero()}}));
  EXPECT_LT(world.PointVelocity(At(bar, u)).norm(), 1e-12);
  const Eigen::MatrixXd expected = Rd - v_before * Wp.transpose() / p.dot(Wp);
  EXPECT_LT((world.linear_R_dot(bar) - expected).norm(), 1e-12);
}

// Impulses with constraints: a pendulum's tip bounces (velocity reversed) and another is stopped
// dead; the nail keeps ċ = 0 through the jumps; conflicting goals are refused with nothing changed.
TEST(Impulse, BounceAndStopKeepConstraints3D) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const auto model = std::make_shared<LinearBodyModel>(
      MakeBoxBody("slab", 3, LinearOrder::kAffine, Eigen::Vector3d(0.5, 0.1, 0.2), 3, 1.0));
  const int a = world.AddLinearBody(model, AffineMaterial{500, 500, 0, 0});
  const int nail = world.AddNail(At(a, Eigen::Vector3d(-0.5, 0, 0)));
  ASSERT_TRUE(world.RunUntil(0.3));
  const MaterialPoint tip = At(a, Eigen::Vector3d(0.5, 0, 0));
  const Eigen::VectorXd v = world.PointVelocity(tip);
  ASSERT_GT(v.norm(), 0.5);
  ASSERT_TRUE(world.ApplyImpulse({{tip, MaterialPoint(), -v}}));
  EXPECT_LT((world.PointVelocity(tip) + v).norm(), 1e-10);
  EXPECT_LT(world.ConstraintVelocityError(nail).norm(), 1e-10);
  ASSERT_TRUE(world.ApplyImpulse({{tip, MaterialPoint(), Eigen::Vector3d::Zero()}}));
  EXPECT_LT(world.PointVelocity(tip).norm(), 1e-10);
  EXPECT_LT(world.ConstraintVelocityError(nail).norm(), 1e-10);
  // the nailed point cannot be given a velocity: refused, state untouched
  const Eigen::MatrixXd Rd = world.linear_R_dot(a);
  std::string error;
  EXPECT_FALSE(world.ApplyImpulse({{At(a, Eigen::Vector3d(-0.5, 0, 0)), MaterialPoint(), Eigen::Vector3d(1, 0, 0)}}, &error));
  EXPECT_NE(error.find("conflict"), std::string::npos) << error;
  EXPECT_EQ(world.linear_R_dot(a), Rd);
  ASSERT_TRUE(world.RunUntil(1.0));
  EXPECT_LT(world.MaxViolation(), 1e-9);
}

// Connect (§4.2): a velocity-matching impulse between two bodies, then an attachment.
TEST(Impulse, ConnectMatchesVelocitiesThenAttaches) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  World world(opt);
  const auto model = Bar2D();
  const int a = world.AddLinearBody(model, AffineMaterial{500, 500, 0, 0});
  const int b = world.AddLinearBody(model, AffineMaterial{500, 500, 0, 0});
  world.SetLinearState(a, model->RestState(), model->PlacedState(Eigen::Matrix2d::Zero(), Eigen::Vector2d(1.0, 0.0)));
  world.SetLinearState(b, model->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(1.0, 0.0)),
                       model->PlacedState(Eigen::Matrix2d::Zero(), Eigen::Vector2d(-1.0, 2.0)));
  const MaterialPoint pa = At(a, Eigen::Vector2d(0.5, 0)), pb = At(b, Eigen::Vector2d(-0.5, 0));
  const double p_before = 0.0;  // total momentum Σ m v of the centres: 1·(1,0) + 1·(−1,2)
  (void)p_before;
  ASSERT_TRUE(world.ApplyImpulse({{pa, pb, Eigen::Vector2d::Zero()}}));
  EXPECT_LT((world.PointVelocity(pa) - world.PointVelocity(pb)).norm(), 1e-12);
  // an internal impulse keeps the total momentum Σ m_k ẋ_k = Ṙ μ summed over the bodies
  const Eigen::VectorXd momentum = world.linear_R_dot(a) * model->first_moment() + world.linear_R_dot(b) * model->first_moment();
  EXPECT_LT((momentum - Eigen::Vector2d(0.0, 2.0)).norm(), 1e-12);
  world.AddAttachment(pa, pb);
  ASSERT_TRUE(world.RunUntil(2.0));
  EXPECT_LT(world.MaxViolation(), 1e-9);
}

// ---------------------------------------------------------------- bad input

TEST(World, BadInputIsReportedNotNaN) {
  World world(testing::WitkinWelchOptions());
  const auto model = Bar2D();
  const int bar = world.AddLinearBody(model);
  EXPECT_THROW(world.AddNail(At(7, Eigen::Vector2d(0, 0))), std::invalid_argument);           // unknown body
  EXPECT_THROW(world.AddNail(MassPointOf(bar, 99)), std::invalid_argument);                   // no such point
  EXPECT_THROW(world.AddNail(At(bar, Eigen::Vector3d(0, 0, 0))), std::invalid_argument);      // wrong size
  EXPECT_THROW(world.SetEnabled(42, false), std::invalid_argument);                           // unknown constraint
  const auto cube = std::make_shared<LinearBodyModel>(MakeBoxBody("cube", 3, LinearOrder::kAffine, Eigen::Vector3d(1, 1, 1), 2, 1));
  const int c3 = world.AddLinearBody(cube);
  EXPECT_THROW(world.AddAttachment(At(bar, Eigen::Vector2d(0, 0)), At(c3, Eigen::Vector3d(0, 0, 0))), std::invalid_argument);
  try {
    world.AddNail(MassPointOf(bar, 99));
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no point 99"), std::string::npos) << e.what();
  }
  // redundant constraints: a 2D affine body has 6 coordinates; 3 nails fix it, a 4th is redundant
  for (double x : {-0.5, 0.5}) world.AddNail(At(bar, Eigen::Vector2d(x, -0.1)));
  world.AddNail(At(bar, Eigen::Vector2d(0.5, 0.1)));
  ASSERT_TRUE(world.Step()) << world.status().message;
  const int extra = world.AddNail(At(bar, Eigen::Vector2d(0.0, 0.0)));
  const Eigen::MatrixXd R = world.linear_R(bar);
  EXPECT_FALSE(world.Step());
  EXPECT_EQ(world.status().code, WorldStatus::Code::kSingularConstraints);
  EXPECT_NE(world.status().message.find("redundant"), std::string::npos) << world.status().message;
  EXPECT_EQ(world.linear_R(bar), R);  // nothing moved, nothing NaN
  // switching the redundant nail off makes the set legal again
  world.SetEnabled(extra, false);
  world.ClearStatus();
  EXPECT_TRUE(world.Step()) << world.status().message;
  EXPECT_TRUE(world.linear_R(bar).allFinite());
  // a path that returns NaN stops the run with the cause, before anything moves
  {
    World w3(testing::WitkinWelchOptions());
    const int b = w3.AddLinearBody(model);
    w3.AddTrajectory(At(b, Eigen::Vector2d(0.5, 0)), std::make_shared<FunctionPath>(2, [](double t) {
      const double v = t > 0.01 ? std::nan("") : 0.0;
      return PathSample{Eigen::Vector2d(0.5, v), Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()};
    }));
    EXPECT_FALSE(w3.RunUntil(1.0));
    EXPECT_EQ(w3.status().code, WorldStatus::Code::kBadPath);
    EXPECT_NE(w3.status().message.find("non-finite sample"), std::string::npos) << w3.status().message;
    EXPECT_TRUE(w3.linear_R(b).allFinite());
  }
  // the same point nailed twice is also redundant (dense and sparse)
  for (MultiplierMethod method : {MultiplierMethod::kDense, MultiplierMethod::kSparse}) {
    WorldOptions opt = testing::WitkinWelchOptions();
    opt.method = method;
    World w2(opt);
    const int b = w2.AddLinearBody(model);
    w2.AddNail(At(b, Eigen::Vector2d(0.5, 0)));
    w2.AddNail(At(b, Eigen::Vector2d(0.5, 0)));
    EXPECT_FALSE(w2.Step());
    EXPECT_EQ(w2.status().code, WorldStatus::Code::kSingularConstraints) << MultiplierMethodName(method);
    EXPECT_TRUE(w2.linear_R(b).allFinite());
  }
}

// ---------------------------------------------------------------- FFD bodies

std::shared_ptr<const BodyModel> Table(double stiffness, double damping) {
  return std::make_shared<BodyModel>(testing::TableDef(), testing::TableModes(stiffness, damping));
}

// The table of the thesis nailed at its top-left corner, ground off, no damping: it swings and
// wobbles. J depends on q here, so the nail is held by the feedback against O(Δt²) curvature
// drift, and the energy error is the O(Δt) error of the step itself (the same Störmer step as the
// thesis integrator, which is not symplectic for a q-dependent M; an unconstrained table shows
// the same order). Halving Δt must divide the violation by about 4 and the energy error by
// about 2: both vanish as Δt → 0, so the nail does no work.
struct FfdRun {
  double violation = 0, energy = 0;  // max |c| (m), max |E − E0| / (m g L)
  long steps = 0, per_step_factorizations = 0;
  Eigen::VectorXd far_corner;
};

FfdRun RunNailedTable(double dt, Integrator integrator = Integrator::kThesis) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = dt;
  opt.integrator = integrator;
  opt.params.ground.enabled = false;
  World world(opt);  // the project's units: g = 9.81, lattice units are metres
  const int table = world.AddBody(Table(4e6, 0.0));  // K of data/table_modes.def
  const int nail = world.AddNail(At(table, Eigen::Vector2d(0.0, 1.0)));  // top-left corner
  EXPECT_LT(world.ConstraintError(nail).norm(), 1e-12);
  const double E0 = world.TotalEnergy();
  const double scale = 550.0 * 9.81 * 150.0;  // m g × half the table: the swing's energy scale
  FfdRun r;
  EXPECT_TRUE(world.RunUntil(20.0, [&](World& w) {
    r.energy = std::max(r.energy, std::abs(w.TotalEnergy() - E0) / scale);
    r.violation = std::max(r.violation, w.MaxViolation());
  })) << world.status().message;
  r.steps = world.steps();
  r.per_step_factorizations = world.per_step_factorizations();
  r.far_corner = world.PointPosition(At(table, Eigen::Vector2d(1.0, 1.0)));
  return r;
}

TEST(FfdConstraints, TableNailedAtCornerHoldsAndConservesEnergy) {
  const FfdRun coarse = RunNailedTable(0.01), fine = RunNailedTable(0.005);
  std::printf("FFD table nailed, dt 0.01: max |c| = %.3g m, max |dE|/(m g L) = %.3g\n", coarse.violation, coarse.energy);
  std::printf("FFD table nailed, dt 0.005: max |c| = %.3g m, max |dE|/(m g L) = %.3g\n", fine.violation, fine.energy);
  EXPECT_GT(coarse.violation / fine.violation, 3.0);  // second order
  EXPECT_GT(coarse.energy / fine.energy, 1.7);        // first order
  EXPECT_LT(fine.violation, 5e-3);                    // m, on a 300 m table (measured 1.7e-3)
  EXPECT_LT(fine.energy, 2e-3);                       // measured 3.8e-4
  EXPECT_EQ(fine.per_step_factorizations, fine.steps);  // q-dependent A: one factorization per step
  EXPECT_LT(fine.far_corner[1], 0.0);                   // it really swung down
}

// The same table stepped by RK4 through the constraint stage. J depends on q, so the nail is
// held by the feedback, and its gains are per step (α = (rate/Δt)², β = 2 rate/Δt): the
// constrained equations themselves change with Δt, stiffening as it falls, so the violation (and
// the energy error it brings) falls as Δt², as with the thesis integrator (measured 7.8e-8 m
// and 1.9e-8 m), but a thousand times lower, and the energy error a million times lower.
TEST(ConstraintStage, Rk4NailedFfdTable) {
  const FfdRun thesis = RunNailedTable(0.005), coarse = RunNailedTable(0.01, Integrator::kRK4),
               fine = RunNailedTable(0.005, Integrator::kRK4);
  std::printf("FFD table nailed, rk4: dt 0.01 max |c| = %.3g m, max |dE|/(m g L) = %.3g; dt 0.005: %.3g m, %.3g\n",
              coarse.violation, coarse.energy, fine.violation, fine.energy);
  EXPECT_LT(fine.energy, 1e-4 * thesis.energy);
  EXPECT_LT(fine.violation, 1e-3 * thesis.violation);
  EXPECT_GT(coarse.violation / fine.violation, 3.0);  // second order, through the feedback
  EXPECT_GT(coarse.energy / fine.energy, 3.0);
  EXPECT_LT(fine.far_corner[1], 0.0);  // it really swung down
}

// Impulses on an FFD body (J at the current q, W through its mass solve): the swinging table's
// far corner stops dead while the nailed corner keeps ċ = 0.
TEST(FfdConstraints, ImpulseStopsAnFfdPointDead) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 0.005;
  opt.params.ground.enabled = false;
  World world(opt);
  const int table = world.AddBody(Table(4e6, 0.0));
  const int nail = world.AddNail(At(table, Eigen::Vector2d(0.0, 1.0)));
  ASSERT_TRUE(world.RunUntil(3.0)) << world.status().message;
  const MaterialPoint far = At(table, Eigen::Vector2d(1.0, 0.0));
  ASSERT_GT(world.PointVelocity(far).norm(), 1.0);
  ASSERT_TRUE(world.ApplyImpulse({{far, MaterialPoint(), Eigen::Vector2d::Zero()}}));
  EXPECT_LT(world.PointVelocity(far).norm(), 1e-9);
  EXPECT_LT(world.ConstraintVelocityError(nail).norm(), 1e-9);
  ASSERT_TRUE(world.RunUntil(4.0)) << world.status().message;
}

// An FFD table hanging by its top-right corner from the end of a nailed affine bar.
double RunTableOnBar(double dt, Eigen::VectorXd* gap) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = dt;
  opt.params.ground.enabled = false;
  World world(opt);
  const int table = world.AddBody(Table(4e6, 1e6));  // data/table_modes.def's K and c
  const auto bar_model = Bar2D(100.0, 30.0, 200.0);
  const AffineMaterial stiff{1e7, 1e7, 0.0, 0.0};
  EXPECT_LE(dt, StableTimeStep(*bar_model, stiff));
  const int bar = world.AddLinearBody(bar_model, stiff);
  // the bar lies from (300, 100) to (500, 100): its left end on the table's top-right corner
  world.SetLinearState(bar, bar_model->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(400, 100)),
                       Eigen::MatrixXd::Zero(2, 3));
  world.AddNail(At(bar, Eigen::Vector2d(100, 0)));
  const int joint = world.AddAttachment(At(table, Eigen::Vector2d(1.0, 1.0)), At(bar, Eigen::Vector2d(-100, 0)));
  EXPECT_LT(world.ConstraintError(joint).norm(), 1e-9);
  double worst = 0, lowest = 1e9;
  EXPECT_TRUE(world.RunUntil(20.0, [&](World& w) {
    worst = std::max(worst, w.MaxViolation());
    lowest = std::min(lowest, w.PointPosition(At(bar, Eigen::Vector2d(-100, 0)))[1]);
  })) << world.status().message;
  EXPECT_LT(lowest, 0.0);  // the bar swung down under the table's weight
  *gap = world.ConstraintError(joint);
  return worst;
}

TEST(FfdConstraints, TableAttachedToLinearBody) {
  Eigen::VectorXd gap;
  const double coarse = RunTableOnBar(0.01, &gap), fine = RunTableOnBar(0.005, &gap);
  std::printf("FFD table on an affine bar: max |c| = %.3g m (dt 0.01), %.3g m (dt 0.005)\n", coarse, fine);
  EXPECT_GT(coarse / fine, 3.0);  // second order in dt
  EXPECT_LT(fine, 0.02);          // m, on a 300 m table (measured 8e-3)
  EXPECT_LT(gap.norm(), 0.02);
}

// Fig. 1: a 3D quadratic body held at its right corners and pulled left at its left end bends.
TEST(World, QuadraticBodyHeldAndPulledBends3D) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  opt.params.gravity_on = false;
  World world(opt);
  const auto model = std::make_shared<LinearBodyModel>(
      MakeBoxBody("block", 3, LinearOrder::kQuadratic, Eigen::Vector3d(1.0, 0.3, 0.3), 3, 10.0));
  const int b = world.AddLinearBody(model, AffineMaterial{200, 200, 2.0, 50});
  for (double y : {-0.3, 0.3})
    for (double z : {-0.3, 0.3}) world.AddNail(At(b, Eigen::Vector3d(1.0, y, z)));
  double worst = 0;
  ASSERT_TRUE(world.RunUntil(3.0, [&](World& w) {
    w.ApplyPointForce(At(b, Eigen::Vector3d(-1.0, 0.3, 0.0)), Eigen::Vector3d(-40.0, 0, 0));
    worst = std::max(worst, w.MaxViolation());
  })) << world.status().message;
  EXPECT_LT(worst, 1e-9);
  const Eigen::MatrixXd& R = world.linear_R(b);
  EXPECT_GT(R.rightCols(6).norm(), 1e-3);  // quadratic terms in play: it bends, not only shears
  EXPECT_LT(world.PointPosition(At(b, Eigen::Vector3d(-1.0, 0.3, 0.0)))[0], -1.0);
}

// ---------------------------------------------------------------- model and data

// Every body kind, a nail and a pending point force: going back to a saved WorldData and
// stepping again repeats the run to the last bit (the data is all a run changes), and data
// that does not fit the world is refused by name.
TEST(WorldData, PuttingBackTheDataRepeatsTheRunExactly) {
  WorldOptions opt = testing::WitkinWelchOptions();
  opt.dt = 1e-3;
  opt.params.ground_plane.enabled = true;
  World world(opt);
  const int table = world.AddBody(std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(4e6, 1e6)));
  const int box = world.AddBody(std::make_shared<const BodyModelN<3>>(testing::Box(1.0, 0.5, 0.8, 3.0)));
  world.SetCoordinates(box, (Eigen::VectorXd(6) << 0, 0.05, 0, 0.1, 0, 0).finished(), Eigen::VectorXd::Zero(6));
  const int bar = world.AddLinearBody(Bar2D(), AffineMaterial{200.0, 200.0, 0.0, 0.0});
  const int nail = world.AddNail(At(bar, Eigen::Vector2d(-0.5, 0.0)));
  world.ApplyPointForce(At(bar, Eigen::Vector2d(0.5, 0.0)), Eigen::Vector2d(0.0, 30.0));
  const WorldData start = world.data();
  ASSERT_TRUE(world.RunUntil(0.3)) << world.status().message;
  const WorldData end = world.data();
  EXPECT_FALSE(world.state<3>(box).contacts.empty());  // the box landed: contacts are data too
  world.SetData(start);
  EXPECT_EQ(world.time(), 0.0);
  EXPECT_EQ(world.steps(), 0);
  EXPECT_EQ(world.q(table), start.ffd_of<2>()[0].state.q);
  ASSERT_TRUE(world.RunUntil(0.3)) << world.status().message;
  EXPECT_EQ(world.steps(), end.steps);
  EXPECT_EQ(world.time(), end.time);
  EXPECT_EQ(world.q(table), end.ffd_of<2>()[0].state.q);
  EXPECT_EQ(world.qd(table), end.ffd_of<2>()[0].state.qd);
  EXPECT_EQ(world.q(box), end.ffd_of<3>()[0].state.q);
  EXPECT_EQ(world.qd(box), end.ffd_of<3>()[0].state.qd);
  EXPECT_EQ(world.state<3>(box).contacts.size(), end.ffd_of<3>()[0].state.contacts.size());
  EXPECT_EQ(world.linear_R(bar), end.linear[0].R);
  EXPECT_EQ(world.linear_R_dot(bar), end.linear[0].R_dot);
  EXPECT_EQ(world.Multiplier(nail), end.multipliers[size_t(nail)]);
  EXPECT_NE(end.multipliers[size_t(nail)], Eigen::VectorXd::Zero(2));

  World other(opt);
  other.AddLinearBody(Bar2D());
  EXPECT_THROW(world.SetData(other.data()), std::invalid_argument);  // other bodies
  WorldData bad = end;
  bad.ffd_of<3>()[0].state.qd.resize(3);
  EXPECT_THROW(world.SetData(bad), std::invalid_argument);  // a state that does not fit its model
  bad = end;
  bad.multipliers.pop_back();
  EXPECT_THROW(world.SetData(bad), std::invalid_argument);  // other constraints
  EXPECT_EQ(world.q(box), end.ffd_of<3>()[0].state.q);  // a refused SetData changes nothing
}

}  // namespace
}  // namespace wobble
