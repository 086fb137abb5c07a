// Conditioning analysis (§4.10.3) against independent computations: the per-point M of
// Eq. 4.10 with a symmetric eigensolver, the asymptotics of two nearly equal modes, rotation
// invariance, exact 1-norm condition numbers, and mode sets built to be dependent, nearly
// parallel, orthogonal or invisible to the mass points.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "support/test_bodies.h"
#include "wobble/analysis/conditioning.h"
#include "support/reference.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble::analysis {
namespace {

using testing::TableDef;

constexpr double kPi = 3.14159265358979323846;

double CondFromEigen(const Eigen::MatrixXd& M) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(M);
  return eig.eigenvalues().maxCoeff() / eig.eigenvalues().minCoeff();
}

TEST(Conditioning, SweepAtZeroEqualsEigenvaluesOfPerPointM) {
  const BodyDef def = TableDef();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(5);
  q << 10, 20, 0.3, 0.1, -0.05;
  const std::vector<SweepSample> s = AngleSweep(def, {0.0}, Squash(), q);
  ASSERT_EQ(s.size(), 1u);
  const Squash sq;
  const BodyModel body(def, {SquashMode(def.lattice, kPi / 2, sq, "v"), SquashMode(def.lattice, 0.0, sq, "h")});
  const double expected = CondFromEigen(reference::MassMatrix(body, q));
  EXPECT_FALSE(s[0].cond.singular);
  EXPECT_NEAR(s[0].cond.cond / expected, 1.0, 1e-9);
  EXPECT_NEAR(s[0].cond.singular_values.maxCoeff() / s[0].cond.singular_values.minCoeff(), s[0].cond.cond, 1e-6 * s[0].cond.cond);
}

// The squash at φ = 0 is a horizontal squash: squeezed along x, bulging along y.
TEST(Conditioning, SquashModeIsTheLinearFieldItNames) {
  const Lattice lat({0, 0}, {300, 0}, {0, 100});
  const DeformationMode h = SquashMode(lat, 0.0, Squash(), "h"), v = SquashMode(lat, kPi / 2, Squash(), "v");
  // control point (3, 3) is the top-right corner (300, 100); the anchor is (150, 0)
  EXPECT_NEAR(h.displacement[lat.Index(3, 3)].x(), -150.0, 1e-9);
  EXPECT_NEAR(h.displacement[lat.Index(3, 3)].y(), 50.0, 1e-9);
  EXPECT_NEAR(v.displacement[lat.Index(3, 3)].x(), 75.0, 1e-9);  // data/vsquash.def
  EXPECT_NEAR(v.displacement[lat.Index(3, 3)].y(), -100.0, 1e-9);
}

TEST(Conditioning, GrowsWithoutBoundTowardHalfPiAndIsSingularThere) {
  std::vector<double> phis;
  for (int i = 0; i <= 20; ++i) phis.push_back(kPi / 2 * i / 20);
  const std::vector<SweepSample> s = AngleSweep(TableDef(), phis, Squash(), Eigen::VectorXd::Zero(5));
  for (int i = 15; i < 20; ++i) EXPECT_GT(s[i].cond.cond, s[i - 1].cond.cond) << "phi " << s[i].phi;
  EXPECT_TRUE(s[20].cond.singular);
  EXPECT_TRUE(std::isinf(s[20].cond.cond));
  // Two unit fields at angle α have Gram eigenvalue 1 − cos α ≈ α²/2, and α ∝ δ = π/2 − φ:
  // cond ∝ 1/δ², so ten times closer is a hundred times worse.
  const std::vector<SweepSample> near =
      AngleSweep(TableDef(), {kPi / 2 - 1e-3, kPi / 2 - 1e-4}, Squash(), Eigen::VectorXd::Zero(5));
  const double ratio = near[1].cond.cond / near[0].cond.cond;
  EXPECT_GT(ratio, 90.0);
  EXPECT_LT(ratio, 110.0);
  EXPECT_FALSE(near[1].cond.singular);
}

// M(θ) = Tᵀ M(0) T with T = diag(R(θ), 1, I) orthogonal: the condition number cannot depend on θ.
TEST(Conditioning, IndependentOfRotation) {
  const BodyModel body(TableDef(), testing::TableModes());
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  q.tail(4) << 0.1, -0.2, 0.05, 0.1;
  const double c0 = MassMatrixCondition(body, q).cond;
  for (double theta : {0.4, 1.7, -2.9}) {
    q[2] = theta;
    EXPECT_NEAR(MassMatrixCondition(body, q).cond / c0, 1.0, 1e-9);
  }
}

TEST(Conditioning, OneNormEstimateIsALowerBoundWithinAFactorOfThree) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int n : {1, 3, 7, 15, 40}) {
    for (int trial = 0; trial < 10; ++trial) {
      Eigen::MatrixXd A(n, n);
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) A(i, j) = u(rng);
      A = A * A.transpose() + 1e-3 * Eigen::MatrixXd::Identity(n, n);
      const Eigen::MatrixXd inv = A.inverse();
      const double exact = A.cwiseAbs().colwise().sum().maxCoeff() * inv.cwiseAbs().colwise().sum().maxCoeff();
      const double est = Cond1Estimate(A);
      EXPECT_LE(est, exact * (1 + 1e-9)) << n;
      EXPECT_GE(est, exact / 3.0) << n;
    }
  }
  EXPECT_TRUE(std::isinf(Cond1Estimate(Eigen::MatrixXd::Zero(3, 3))));
}

TEST(ModeCheck, DuplicatedModeIsAnErrorNamingBoth) {
  DeformationMode copy = testing::Bend();
  copy.name = "bend again";
  const BodyModel body(TableDef(), {testing::Bend(), testing::Shear(), copy});
  const ModeSetReport r = CheckModeSet(body);
  EXPECT_EQ(r.level, ModeSetReport::Level::kError);
  ASSERT_FALSE(r.messages.empty());
  EXPECT_NE(r.messages[0].find("'bend'"), std::string::npos) << r.messages[0];
  EXPECT_NE(r.messages[0].find("'bend again'"), std::string::npos) << r.messages[0];
  EXPECT_EQ(r.smallest_angle_deg, 0.0);
  EXPECT_TRUE(r.condition.singular);
}

TEST(ModeCheck, NearlyParallelModesWarnWithTheAngle) {
  const BodyDef def = TableDef();
  const double delta = 0.02;  // rad between the squash axes
  const BodyModel body(def, {SquashMode(def.lattice, kPi / 2, Squash(), "vsquash"),
                             SquashMode(def.lattice, kPi / 2 - delta, Squash(), "tilted squash")});
  const ModeSetReport r = CheckModeSet(body);
  EXPECT_EQ(r.level, ModeSetReport::Level::kWarning);
  ASSERT_EQ(r.messages.size(), 1u);
  EXPECT_NE(r.messages[0].find("within"), std::string::npos) << r.messages[0];
  EXPECT_NE(r.messages[0].find("°"), std::string::npos) << r.messages[0];
  EXPECT_GT(r.smallest_angle_deg, 0.0);
  EXPECT_LT(r.smallest_angle_deg, 5.0);
  // the angle to the others can only be smaller than the angle to the one partner
  EXPECT_LE(r.smallest_angle_deg, r.pair_angle_deg(0, 1) + 1e-9);
  // and the partner is named first in the combination
  EXPECT_TRUE(r.modes[0].closest_combination[0].dof == "tilted squash" ||
              r.modes[1].closest_combination[0].dof == "vsquash");
}

// Under the mass inner product, a mode even about the table's vertical mid-line (the squash)
// and one odd about it (a vertical shear, d_y ∝ (x − 150)) are exactly orthogonal.
TEST(ModeCheck, OrthogonalModesGiveNoWarning) {
  const BodyDef def = TableDef();
  DeformationMode vshear;
  vshear.name = "vshear";
  for (const Eigen::Vector2d& p : def.lattice.RestPoints()) vshear.displacement.push_back({0.0, 0.3 * (p.x() - 150.0)});
  const BodyModel body(def, {SquashMode(def.lattice, kPi / 2, Squash(), "vsquash"), vshear});
  const ModeSetReport r = CheckModeSet(body);
  EXPECT_NEAR(r.pair_angle_deg(0, 1), 90.0, 1e-9);
  EXPECT_EQ(r.level, ModeSetReport::Level::kOk) << (r.messages.empty() ? "" : r.messages[0]);
  EXPECT_TRUE(r.messages.empty());
}

// A mode that moves only the right column of the lattice, on a body whose mass sits in the
// left third: the Bernstein weight of that column there is at most (1/3)³.
TEST(ModeCheck, ModeOverALatticeRegionWithoutMassIsFlagged) {
  BodyDef def;
  def.name = "left-heavy";
  def.lattice = Lattice({0, 0}, {300, 0}, {0, 100});
  for (double x : {0.0, 50.0, 100.0})
    for (double y : {0.0, 50.0, 100.0}) def.mass_positions.push_back({x, y});
  def.masses.assign(def.mass_positions.size(), 10.0);
  DeformationMode right;
  right.name = "right column";
  right.displacement.assign(16, Eigen::Vector2d::Zero());
  for (int j = 0; j < 4; ++j) right.displacement[def.lattice.Index(3, j)] = {0.0, 50.0 * j};
  const ModeSetReport r = CheckModeSet(BodyModel(def, {right}));
  EXPECT_LT(r.modes[0].visibility, 0.05);
  EXPECT_GT(r.modes[0].visibility, 0.0);
  EXPECT_EQ(r.level, ModeSetReport::Level::kWarning);
  ASSERT_FALSE(r.messages.empty());
  EXPECT_NE(r.messages[0].find("right column"), std::string::npos) << r.messages[0];
}

// §4.10.3: a bend along x on a vertical rod at s = 1/2 has nothing to bend: there the §4.10.1
// bend moves every point straight up by 75 γ, the same motion as a translation in y.
TEST(ModeCheck, BendOnAVerticalRodIsATranslation) {
  BodyDef def;
  def.name = "vertical rod";
  def.lattice = Lattice({0, 0}, {300, 0}, {0, 100});
  for (double y : {0.0, 25.0, 50.0, 75.0, 100.0}) def.mass_positions.push_back({150.0, y});
  def.masses.assign(def.mass_positions.size(), 20.0);
  const ModeSetReport r = CheckModeSet(BodyModel(def, {testing::Bend()}));
  EXPECT_EQ(r.level, ModeSetReport::Level::kError);
  ASSERT_FALSE(r.messages.empty());
  EXPECT_NE(r.messages[0].find("'bend'"), std::string::npos) << r.messages[0];
  EXPECT_NE(r.messages[0].find("translation y"), std::string::npos) << r.messages[0];
}

TEST(ModeCheck, ZeroAndMasslessModesAreErrors) {
  BodyDef def = TableDef();
  DeformationMode zero;
  zero.name = "nothing";
  zero.displacement.assign(16, Eigen::Vector2d::Zero());
  const ModeSetReport r = CheckModeSet(BodyModel(def, {testing::Bend(), zero}));
  EXPECT_EQ(r.level, ModeSetReport::Level::kError);
  EXPECT_NE(r.messages[0].find("'nothing' is zero"), std::string::npos) << r.messages[0];
}


// ---- 3D bodies ----

TEST(conditioning3D, TheTableModesAreIndependent) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  const BodyModelN<3> body(def, formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table3_modes.def3", def.lattice));
  const ModeSetReport r = CheckModeSet(body);
  EXPECT_EQ(r.level, ModeSetReport::Level::kOk) << (r.messages.empty() ? "" : r.messages[0]);
  ASSERT_EQ(r.dofs.size(), 10u);
  EXPECT_EQ(r.dofs[4], "rotation y");
  EXPECT_FALSE(r.condition.singular);
  EXPECT_GT(r.smallest_angle_deg, 20.0);
}

// A "mode" that is a rigid turn about the vertical: dependent on the rotation dof, and named so.
TEST(conditioning3D, ARigidTurnAsAModeIsFoundWithTheRotation) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  std::vector<DeformationModeN<3>> modes =
      formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table3_modes.def3", def.lattice);
  DeformationModeN<3> turn;
  turn.name = "turn";
  turn.lattice_size = def.lattice.sizes();
  for (const Eigen::Vector3d& p : def.lattice.RestPoints())
    turn.displacement.push_back(Eigen::Vector3d::UnitY().cross(p - Eigen::Vector3d(150, 50, 100)));
  modes.push_back(turn);
  const ModeSetReport r = CheckModeSet(BodyModelN<3>(def, modes));
  EXPECT_EQ(r.level, ModeSetReport::Level::kError);
  EXPECT_EQ(r.smallest_angle_deg, 0.0);
  const ModeFinding& f = r.modes.back();
  bool names_rotation = false;
  for (const Participant& p : f.closest_combination) names_rotation |= p.dof == "rotation y";
  EXPECT_TRUE(names_rotation) << r.messages[0];
}


// Fig. 4.7 in 3D: the squash whose axis turns from x to y meets the vertical squash at 90°.
TEST(conditioning3D, AngleSweepIsSingularOnlyWhereTheSquashesMeet) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  std::vector<double> phis;
  for (int deg = 30; deg <= 90; deg += 5) phis.push_back(deg * M_PI / 180.0);
  const std::vector<SweepSample> sweep = AngleSweep(def, phis, Squash());
  for (size_t i = 0; i + 1 < sweep.size(); ++i) {
    EXPECT_FALSE(sweep[i].cond.singular) << sweep[i].phi;
    EXPECT_GT(sweep[i + 1].cond.cond, sweep[i].cond.cond) << "cond grows toward 90°, at " << sweep[i].phi;
  }
  EXPECT_TRUE(sweep.back().cond.singular);
  // near 90° the two fields differ by an angle δ ∝ (90° − φ), the smallest eigenvalue of the
  // unit-free (Jacobi-scaled) M goes as δ², so halving δ quadruples cond_scaled
  const std::vector<SweepSample> close = AngleSweep(def, {89.0 * M_PI / 180.0, 89.5 * M_PI / 180.0}, Squash());
  EXPECT_NEAR(close[1].cond.cond_scaled / close[0].cond.cond_scaled, 4.0, 0.2);
}

}  // namespace
}  // namespace wobble::analysis
