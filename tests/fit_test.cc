// Pose fits (lib/wobble/fit): synthetic targets made from a known q are recovered; bounds
// hold; unreachable targets end with an honest residual; a mode the data cannot see is
// reported as undetermined; target files are parsed strictly; bad input is refused by name
// by the same code in both dimensions (typed over the dimension).
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <sstream>

#include "support/test_bodies.h"
#include "wobble/core/errors.h"
#include "wobble/core/interrupt.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"
#include "wobble/formats/parse_error.h"
#include "wobble/formats/target_file.h"

namespace wobble {
namespace {

using fit::PoseFitOptions;
using fit::PoseFitResult;
using fit::Correspondence;

BodyModel Table() { return BodyModel(testing::TableDef(), testing::TableModes()); }

Eigen::VectorXd KnownQ() {
  Eigen::VectorXd q(7);
  q << 40, -25, 0.3, 0.35, -0.2, 0.15, 0.25;
  return q;
}

Eigen::Vector2d Place(const BodyModel& body, int k, const Eigen::Vector2d& st, const Eigen::VectorXd& q) {
  return fit::PointPosition(fit::BasisOf(body, k, st), q.data(), int(q.size()));
}

// Targets for every mass point and 5 samples along each drawn segment of the table.
std::vector<Correspondence> TargetsFrom(const BodyModel& body, const Eigen::VectorXd& q) {
  std::vector<Correspondence> t;
  for (int k = 0; k < body.num_points(); ++k) {
    Correspondence p;
    p.mass_point = k;
    p.position = Place(body, k, {}, q);
    t.push_back(p);
  }
  for (double u : {0.1, 0.3, 0.5, 0.7, 0.9})
    for (Eigen::Vector2d st : {Eigen::Vector2d(u, 1.0), Eigen::Vector2d(0.0, u), Eigen::Vector2d(1.0, u)}) {
      Correspondence p;
      p.lattice_coords = st;
      p.position = Place(body, -1, st, q);
      t.push_back(p);
    }
  return t;
}

TEST(PoseFit, ExactTargetsRecoverQ) {
  const BodyModel body = Table();
  const PoseFitResult r = fit::FitPose(body, TargetsFrom(body, KnownQ()), PoseFitOptions());
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(r.q[i], KnownQ()[i], 1e-7) << i;
  EXPECT_LT(r.rms_residual, 1e-6);
  EXPECT_TRUE(r.conditioning.undetermined.empty());
  EXPECT_TRUE(std::isfinite(r.conditioning.condition_number));
  // the cost history starts at the initial cost and ends at the final one
  EXPECT_DOUBLE_EQ(r.report.cost_per_iteration.front(), r.report.initial_cost);
  EXPECT_LE(r.report.cost_per_iteration.back(), r.report.initial_cost);
}

// Gaussian noise of 0.5 (lattice 300 x 100) and three outliers moved by 60-90 units.
std::vector<Correspondence> NoisyTargets(const BodyModel& body, unsigned seed) {
  std::vector<Correspondence> t = TargetsFrom(body, KnownQ());
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.5);
  for (Correspondence& p : t) p.position += Eigen::Vector2d(noise(rng), noise(rng));
  t[2].position += Eigen::Vector2d(80, -30);
  t[7].position += Eigen::Vector2d(-60, 40);
  t[15].position += Eigen::Vector2d(0, 90);
  return t;
}

// Ctrl-C (the flag of core/interrupt.h the CLI's SIGINT handler raises) aborts the Ceres solve
// at its next iteration and the fit ends with Interrupted, not with a half-done result.
TEST(PoseFit, CtrlCStopsTheSolveWithInterrupted) {
  const BodyModel body = Table();
  RequestInterrupt();
  EXPECT_THROW(fit::FitPose(body, TargetsFrom(body, KnownQ()), PoseFitOptions()), Interrupted);
  ClearInterrupt();
  EXPECT_TRUE(fit::FitPose(body, TargetsFrom(body, KnownQ()), PoseFitOptions()).report.usable);
}

TEST(PoseFit, RobustLossRecoversQDespiteNoiseAndOutliers) {
  const BodyModel body = Table();
  for (unsigned seed : {1u, 2u, 3u}) {
    PoseFitOptions o;
    o.loss = fit::Loss::kCauchy;
    o.loss_scale = 2.0;  // four times the noise
    const PoseFitResult r = fit::FitPose(body, NoisyTargets(body, seed), o);
    ASSERT_TRUE(r.report.usable);
    // stated tolerances: translation 0.5, angle 2e-3 rad, amplitudes 0.01 (a unit amplitude
    // moves the points by 50-150)
    EXPECT_NEAR(r.q[0], KnownQ()[0], 0.5);
    EXPECT_NEAR(r.q[1], KnownQ()[1], 0.5);
    EXPECT_NEAR(r.q[2], KnownQ()[2], 2e-3);
    for (int d = 3; d < 7; ++d) EXPECT_NEAR(r.q[d], KnownQ()[d], 0.01) << "mode " << d - 3 << " seed " << seed;
    // the outliers keep their large residuals instead of dragging the fit
    EXPECT_GT(r.point_residuals[2], 50);
    EXPECT_GT(r.point_residuals[15], 50);
  }
  // the squared loss is dragged by the same outliers: the check above is not vacuous
  const PoseFitResult plain = fit::FitPose(body, NoisyTargets(body, 1), PoseFitOptions());
  double worst = 0;
  for (int d = 3; d < 7; ++d) worst = std::max(worst, std::abs(plain.q[d] - KnownQ()[d]));
  EXPECT_GT(worst, 0.02);
}

TEST(PoseFit, BoundsHoldAndUnreachableTargetsEndWithHonestResidual) {
  const BodyModel body = Table();
  Eigen::VectorXd far = KnownQ();
  far[3] = 1.8;  // bend beyond the bound 1
  far[5] = -1.5;
  const std::vector<Correspondence> t = TargetsFrom(body, far);
  const PoseFitResult r = fit::FitPose(body, t, PoseFitOptions());
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  for (int d = 3; d < 7; ++d) {
    EXPECT_GE(r.q[d], -1.0);
    EXPECT_LE(r.q[d], 1.0);
  }
  EXPECT_DOUBLE_EQ(r.q[3], 1.0);
  EXPECT_DOUBLE_EQ(r.q[5], -1.0);
  EXPECT_EQ(r.at_bound, (std::vector<std::string>{"bend", "vsquash"}));
  EXPECT_GT(r.rms_residual, 5.0);
  // the reported cost is the residuals': ½ Σ |r|² with unit weights
  double half_sum = 0;
  for (double d : r.point_residuals) half_sum += 0.5 * d * d;
  EXPECT_NEAR(r.report.final_cost, half_sum, 1e-9 * half_sum);
  // per-mode bounds override the scalars
  PoseFitOptions wide;
  wide.mode_lower = {-2, -2, -2, -2};
  wide.mode_upper = {2, 2, 2, 2};
  const PoseFitResult w = fit::FitPose(body, t, wide);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(w.q[i], far[i], 1e-7);

  // a shape the table cannot take (a circle): no failure, the residual says how far it is
  std::vector<Correspondence> circle;
  for (int k = 0; k < body.num_points(); ++k) {
    Correspondence p;
    p.mass_point = k;
    p.position = 100.0 * Eigen::Vector2d(std::cos(k * 2 * M_PI / 11), std::sin(k * 2 * M_PI / 11));
    circle.push_back(p);
  }
  const PoseFitResult c = fit::FitPose(body, circle, PoseFitOptions());
  EXPECT_TRUE(c.report.usable);
  EXPECT_GT(c.rms_residual, 20.0);
  EXPECT_EQ(c.point_residuals.size(), 11u);
}

TEST(PoseFit, PriorPullsTowardRest) {
  const BodyModel body = Table();
  const std::vector<Correspondence> t = TargetsFrom(body, KnownQ());
  PoseFitOptions o;
  o.prior_weight = 1e5;
  const PoseFitResult r = fit::FitPose(body, t, o);
  for (int d = 3; d < 7; ++d) EXPECT_LT(std::abs(r.q[d]), std::abs(KnownQ()[d]) - 1e-3) << d;
}

// A mode that moves only the interior control points (i = 1, 2; j = 0, 1, 2) of the 4 x 4
// Bernstein lattice: every table mass point lies on an edge (s = 0, s = 1 or t = 1), where
// those control points have zero weight, so the mass points cannot see the mode.
DeformationMode HiddenMode() {
  DeformationMode m;
  m.name = "hidden";
  m.displacement.assign(16, Eigen::Vector2d::Zero());
  for (int i = 1; i <= 2; ++i)
    for (int j = 0; j <= 2; ++j) m.displacement[i * 4 + j] = {0, -40};
  return m;
}

TEST(PoseFit, ModeTheMassPointsCannotSeeIsReportedUndetermined) {
  std::vector<DeformationMode> modes = testing::TableModes();
  modes.push_back(HiddenMode());
  const BodyModel body(testing::TableDef(), modes);
  Eigen::VectorXd q(8);
  q << 40, -25, 0.3, 0.35, -0.2, 0.15, 0.25, 0.0;
  std::vector<Correspondence> t;
  for (int k = 0; k < body.num_points(); ++k) {
    Correspondence p;
    p.mass_point = k;
    p.position = Place(body, k, {}, q);
    t.push_back(p);
  }
  const PoseFitResult r = fit::FitPose(body, t, PoseFitOptions());
  ASSERT_TRUE(r.report.usable);
  EXPECT_EQ(r.conditioning.undetermined, std::vector<std::string>{"hidden"});
  EXPECT_TRUE(std::isinf(r.conditioning.condition_number));
  EXPECT_EQ(r.conditioning.column_norms[7], 0.0);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(r.q[i], q[i], 1e-7) << i;

  // a target inside the lattice (under the table top) makes it visible
  Correspondence inside;
  inside.lattice_coords = {0.5, 0.3};
  q[7] = 0.4;
  inside.position = Place(body, -1, inside.lattice_coords, q);
  t.push_back(inside);
  for (Correspondence& p : t)
    if (p.mass_point >= 0) p.position = Place(body, p.mass_point, {}, q);
  const PoseFitResult seen = fit::FitPose(body, t, PoseFitOptions());
  EXPECT_TRUE(seen.conditioning.undetermined.empty());
  EXPECT_TRUE(std::isfinite(seen.conditioning.condition_number));
  EXPECT_NEAR(seen.q[7], 0.4, 1e-6);
}

TEST(PoseFit, NearlyDependentModesArePoorlyDetermined) {
  // a second copy of the bend, changed a little at one corner: the targets can hardly tell
  // the two apart
  std::vector<DeformationMode> modes = testing::TableModes();
  DeformationMode twin = modes[0];
  twin.name = "bend_twin";
  twin.displacement[0] += Eigen::Vector2d(0.01, 0);
  modes.push_back(twin);
  const BodyModel body(testing::TableDef(), modes);
  Eigen::VectorXd q = Eigen::VectorXd::Zero(8);
  q.head(7) = KnownQ();
  std::vector<Correspondence> t = TargetsFrom(body, q);
  const PoseFitResult r = fit::FitPose(body, t, PoseFitOptions());
  EXPECT_EQ(r.conditioning.poorly_determined, (std::vector<std::string>{"bend", "bend_twin"}));
  ASSERT_FALSE(r.conditioning.weak.empty());
  EXPECT_LT(r.conditioning.weak[0].relative_singular_value, 1e-3);
}

// ---- without correspondences ----

// The table's drawing deformed by q, as polylines of `n` points each.
fit::CurveTarget DrawnTarget(const BodyModel& body, const Eigen::VectorXd& q, int n, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  fit::CurveTarget f;
  for (const Polyline& line : body.def().shapes) {
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d p = line.points[0] + (line.points[1] - line.points[0]) * (double(i) / (n - 1));
      points.push_back(Place(body, -1, body.lattice().LocalCoords(p), q) +
                       (noise > 0 ? Eigen::Vector2d(g(rng), g(rng)) : Eigen::Vector2d::Zero()));
    }
    f.AddPolyline(points, false);
  }
  return f;
}

TEST(CurveFit, RecoversQFromTheDrawnShape) {
  const BodyModel body = Table();
  for (double noise : {0.0, 0.3})
  for (bool joint : {true, false}) {
    const fit::CurveTarget target = DrawnTarget(body, KnownQ(), 60, noise, 5);
    PoseFitOptions o;
    o.joint_closest_points = joint;
    const PoseFitResult r = fit::FitPoseToCurve(body, target, o);
    ASSERT_TRUE(r.report.usable);
    // stated tolerances: translation 1, angle 5e-3 rad, amplitudes 0.02 (the polyline is a
    // chord approximation of the deformed curve, and points may slide along it)
    EXPECT_NEAR(r.q[0], KnownQ()[0], 1.0) << noise;
    EXPECT_NEAR(r.q[1], KnownQ()[1], 1.0) << noise;
    EXPECT_NEAR(r.q[2], KnownQ()[2], 5e-3) << noise;
    for (int d = 3; d < 7; ++d) EXPECT_NEAR(r.q[d], KnownQ()[d], 0.02) << "mode " << d - 3 << " noise " << noise;
    EXPECT_LT(r.rms_residual, 0.5 + noise);
    EXPECT_EQ(r.rounds >= 2, !joint);  // alternated fits take several closest-point rounds
  }
}

TEST(CurveFit, StartsFromThePrincipalAxisEvenUpsideDown) {
  const BodyModel body = Table();
  Eigen::VectorXd q = KnownQ();
  q[2] = 3.0;  // nearly upside down: the other orientation of the axis must win
  const PoseFitResult r = fit::FitPoseToCurve(body, DrawnTarget(body, q, 60, 0.0, 1), PoseFitOptions());
  EXPECT_NEAR(r.q[2], 3.0, 5e-3);
  EXPECT_LT(r.rms_residual, 0.5);
}

TEST(CurveFit, CloudTargetAndUnreachableShape) {
  const BodyModel body = Table();
  // a point cloud: points of the drawing at the known pose, shuffled (no order, no segments)
  std::vector<Eigen::Vector2d> points = DrawnTarget(body, KnownQ(), 20, 0.0, 1).vertices;
  std::shuffle(points.begin(), points.end(), std::mt19937(3));
  fit::CurveTarget cloud;
  for (const Eigen::Vector2d& p : points) cloud.AddPoint(p);
  const PoseFitResult r = fit::FitPoseToCurve(body, cloud, PoseFitOptions());
  for (int d = 3; d < 7; ++d) EXPECT_NEAR(r.q[d], KnownQ()[d], 0.05) << d;
  // a body sample is as far as the nearest cloud point: at most half the spacing (300 / 19)
  EXPECT_LT(r.rms_residual, 0.5 * 300.0 / 19.0);
  // a short dash the 300-wide table cannot shrink to (|γ| <= 1): an honest residual, not a failure
  fit::CurveTarget dash;
  dash.AddPolyline({{0, 0}, {10, 0}}, false);
  const PoseFitResult rc = fit::FitPoseToCurve(body, dash, PoseFitOptions());
  EXPECT_TRUE(rc.report.usable);
  EXPECT_GT(rc.rms_residual, 20.0);
  for (int d = 3; d < 7; ++d) EXPECT_LE(std::abs(rc.q[d]), 1.0);
}

// ---- target files ----

std::string ParseMessage(const std::string& text) {
  std::istringstream in(text);
  try {
    formats::ParseTargets(in, "t.tgt");
  } catch (const formats::ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(TargetFile, ParsesEveryStatement) {
  std::istringstream in(
      "# a comment\n"
      "point 3 10 20\n"
      "sample 0.5 1 1.5 -2 weight 4   # the top's middle\n");
  const formats::TargetFile f = formats::ParseTargets(in, "t.tgt");
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_EQ(f.points[0].mass_point, 3);
  EXPECT_EQ(f.points[0].position, Eigen::Vector2d(10, 20));
  EXPECT_EQ(f.points[1].mass_point, -1);
  EXPECT_EQ(f.points[1].lattice_coords, Eigen::Vector2d(0.5, 1));
  EXPECT_EQ(f.points[1].weight, 4.0);
  EXPECT_EQ(f.points[1].line, 3);
  std::istringstream curve("polyline 0 0 1 0 1 1 closed\ncloud 5 5\n");
  const formats::TargetFile c = formats::ParseTargets(curve, "c.tgt");
  fit::CurveTarget target;  // as `wobble fit pose` makes it
  for (const formats::TargetCurve& line : c.polylines) target.AddPolyline(line.points, line.closed);
  for (const Eigen::Vector2d& p : c.cloud) target.AddPoint(p);
  EXPECT_EQ(target.a.size(), 4u);  // 3 closed segments + 1 cloud point
  std::istringstream traj("frame 0\npoint 0 1 2\nframe 0.5\npoint 0 1 3\nsample 0 0 1 1\n");
  const formats::TargetFile t = formats::ParseTargets(traj, "k.tgt");
  ASSERT_EQ(t.frames.size(), 2u);
  EXPECT_EQ(t.frames[1].points.size(), 2u);
}

TEST(TargetFile, RejectsMalformedInputWithFileAndLine) {
  EXPECT_EQ(ParseMessage(""), "t.tgt:0: file is empty: expected point, sample, polyline, cloud or frame lines");
  EXPECT_EQ(ParseMessage("point 1 2 x\n"), "t.tgt:1: expected a number for y, got 'x' (point <k> <x> <y> [weight <w>])");
  EXPECT_EQ(ParseMessage("\npoint -1 2 3\n"), "t.tgt:2: expected a mass point index >= 0, got '-1' (point <k> <x> <y> [weight <w>])");
  EXPECT_EQ(ParseMessage("sample 1.5 0 1 1\n"), "t.tgt:1: lattice coordinate s must be in [0, 1], got 1.5");
  EXPECT_EQ(ParseMessage("point 0 1 2 weight 0\n"), "t.tgt:1: the weight must be > 0, got 0");
  EXPECT_EQ(ParseMessage("point 0 1 2 3\n"), "t.tgt:1: unexpected '3' (point <k> <x> <y> [weight <w>])");
  EXPECT_EQ(ParseMessage("polyline 0 0 1\n"), "t.tgt:1: expected pairs of numbers (polyline <x1> <y1> <x2> <y2> ... [closed])");
  EXPECT_EQ(ParseMessage("point 0 1 2\npolyline 0 0 1 1\n"),
            "t.tgt:2: a file holds correspondences (point/sample) or a curve (polyline/cloud), not both");
  EXPECT_EQ(ParseMessage("frame 1\npoint 0 1 2\nframe 1\n"), "t.tgt:3: frame times must strictly increase (previous frame: 1)");
  EXPECT_EQ(ParseMessage("frame 1\nframe 2\npoint 0 0 0\n"), "t.tgt:1: frame has no point or sample lines");
  EXPECT_EQ(ParseMessage("wobble 1\n"), "t.tgt:1: unknown keyword 'wobble' (expected point, sample, polyline, cloud or frame)");
  std::istringstream in("point 0 1 2\n\npoint 11 1 2\n");
  const formats::TargetFile f = formats::ParseTargets(in, "t.tgt");
  try {
    formats::CheckMassPointIndices(f, 11);
    FAIL() << "index 11 accepted";
  } catch (const formats::ParseError& e) {
    EXPECT_STREQ(e.what(), "t.tgt:3: mass point 11 does not exist: the body has 11 (numbered from 0)");
  }
}

// ---- both dimensions: one fit, one set of checks (the 2D table, fit3_test's 3D chair) ----

template <class Body> class FitOverDimension : public ::testing::Test {};
using Bodies = ::testing::Types<BodyModel, BodyModelN<3>>;
TYPED_TEST_SUITE(FitOverDimension, Bodies);

BodyModel MakeBody(BodyModel*) { return Table(); }
BodyModelN<3> MakeBody(BodyModelN<3>*) { return testing::Chair3(); }

// Every third mass point where the rest pose (q = 0) has it.
template <int Dim> std::vector<fit::CorrespondenceN<Dim>> RestTargets(const BodyModelN<Dim>& body) {
  std::vector<fit::CorrespondenceN<Dim>> targets;
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  for (int k = 0; k < body.num_points(); k += 3) {
    fit::CorrespondenceN<Dim> t;
    t.mass_point = k;
    t.position = fit::PointPosition(fit::BasisOf(body, k, {}), q);
    targets.push_back(t);
  }
  return targets;
}

TYPED_TEST(FitOverDimension, BadInputIsRefusedByName) {
  const TypeParam body = MakeBody(static_cast<TypeParam*>(nullptr));
  constexpr int Dim = TypeParam::dim();
  EXPECT_THROW(fit::FitPose(body, {}, {}), std::invalid_argument);
  fit::CorrespondenceN<Dim> missing;
  missing.mass_point = body.num_points();
  EXPECT_THROW(fit::FitPose(body, {missing}, {}), std::invalid_argument);
  PoseFitOptions o;
  o.initial_q = Eigen::VectorXd::Zero(body.num_q() - 3);  // too short by 3
  try {
    fit::FitPose(body, RestTargets(body), o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    const std::string expected = "the body has " + std::to_string(body.num_q()) + " coordinates";
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
  // a weight that is not > 0, in a pose and in a trajectory; a frame without points
  std::vector<fit::CorrespondenceN<Dim>> weightless = RestTargets(body);
  weightless[1].weight = 0.0;
  try {
    fit::FitPose(body, weightless, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "pose fit: weights must be > 0");
  }
  fit::ReferenceFrameN<Dim> a{0.0, RestTargets(body)}, b{0.1, weightless}, empty{0.2, {}};
  try {
    fit::FitKinematicTrajectory(body, {a, b}, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "trajectory fit: weights must be > 0");
  }
  try {
    fit::FitKinematicTrajectory(body, {a, empty}, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "trajectory fit: a frame has no points");
  }
  // the names of q: the rigid coordinates, then the modes
  const std::vector<std::string> names = fit::CoordinateNames(body);
  ASSERT_EQ(int(names.size()), body.num_q());
  EXPECT_EQ(names[Dim == 2 ? 2 : 5], Dim == 2 ? "theta" : "rz");
  EXPECT_EQ(names.back(), body.modes().back().name);
}

// The rest pose's own points are met exactly at q = 0, from the rigid start, in both dimensions.
TYPED_TEST(FitOverDimension, RestTargetsGiveBackTheRestPose) {
  const TypeParam body = MakeBody(static_cast<TypeParam*>(nullptr));
  const PoseFitResult r = fit::FitPose(body, RestTargets(body), {});
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  EXPECT_LT(r.q.cwiseAbs().maxCoeff(), 1e-7) << r.q.transpose();
  EXPECT_LT(r.rms_residual, 1e-7);
}

}  // namespace
}  // namespace wobble
