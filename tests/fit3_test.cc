// Fits of 3D FFD bodies (issue 15): pose fits with and without correspondences and kinematic
// trajectory fits. The targets are made by the direct per-point formula of the FFD (Eq. 4.1/
// 4.2: the deformed control points L + Σ γ_d d^d weighted at the point's lattice coordinates,
// then turned and moved), not by the fit's own kinematics, so a fit that recovers the q the
// targets were made with checks the whole chain.
#include <gtest/gtest.h>

#include <iostream>

#include <cmath>
#include <random>
#include <sstream>

#include "wobble/body/body_model.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"
#include "support/test_bodies.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/formats/parse_error.h"
#include "wobble/formats/target_file.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

using Vec3 = Eigen::Vector3d;

struct Character {
  BodyDefN<3> def;
  std::vector<DeformationModeN<3>> modes;
  BodyModelN<3> body;
};

Character MakeChair() {
  BodyModelN<3> body = testing::Chair3();
  return {body.def(), body.modes(), body};
}

// Eq. 4.1/4.2 directly: the world position of the body point at lattice coordinates u.
Vec3 Direct(const Character& c, const Eigen::VectorXd& q, const Vec3& u) {
  std::vector<Vec3> control = c.def.lattice.RestPoints();
  for (size_t k = 0; k < control.size(); ++k)
    for (size_t d = 0; d < c.modes.size(); ++d) control[k] += q[6 + int(d)] * c.modes[d].displacement[k];
  const Eigen::Matrix3d R = Eigen::AngleAxisd(q.segment<3>(3).norm(), q.segment<3>(3).normalized()).toRotationMatrix();
  return q.head<3>() + R * c.def.lattice.Evaluate(control, u);
}

Eigen::VectorXd Q(const Vec3& t, double angle, const Vec3& axis, const Vec3& gamma) {
  Eigen::VectorXd q(9);
  q << t, angle * axis.normalized(), gamma;
  return q;
}

Eigen::Matrix3d RotationOf(const Eigen::VectorXd& q) { return ExpRotation<double>(q.segment<3>(3)).toRotationMatrix(); }

// |t − t'|, the angle between the orientations, max |γ − γ'|.
struct QError {
  double translation, angle, gamma;
};
QError Compare(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::AngleAxisd turn(RotationOf(a).transpose() * RotationOf(b));
  return {(a.head<3>() - b.head<3>()).norm(), std::abs(turn.angle()), (a.tail(a.size() - 6) - b.tail(b.size() - 6)).cwiseAbs().maxCoeff()};
}

std::vector<fit::CorrespondenceN<3>> MassPointTargets(const Character& c, const Eigen::VectorXd& q) {
  std::vector<fit::CorrespondenceN<3>> targets;
  for (int k = 0; k < c.body.num_points(); k += 3) {
    fit::CorrespondenceN<3> t;
    t.mass_point = k;
    t.position = Direct(c, q, c.body.lattice_coords(k));
    targets.push_back(t);
  }
  return targets;
}

TEST(PoseFit3, CorrespondencesGiveBackTheQTheyWereMadeWith) {
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(30, -12, 250), 2.5, Vec3(1, 2, -0.7), Vec3(0.4, -0.3, 0.2));
  // mass points, and lattice points given by (s, t, u)
  std::vector<fit::CorrespondenceN<3>> targets = MassPointTargets(c, truth);
  for (const Vec3& u : {Vec3(0.1, 0.9, 0.5), Vec3(0.95, 0.05, 0.3), Vec3(0.5, 0.5, 0.99)}) {
    fit::CorrespondenceN<3> t;
    t.lattice_coords = u;
    t.position = Direct(c, truth, u);
    targets.push_back(t);
  }
  const fit::PoseFitResult r = fit::FitPose(c.body, targets, {});
  EXPECT_TRUE(r.report.usable) << r.report.brief_report;
  const QError e = Compare(r.q, truth);
  EXPECT_LT(e.translation, 1e-7);
  EXPECT_LT(e.angle, 1e-9);
  EXPECT_LT(e.gamma, 1e-9);
  EXPECT_LT(r.rms_residual, 1e-7);
  EXPECT_TRUE(r.at_bound.empty());
  // every coordinate is seen: nothing undetermined
  EXPECT_TRUE(r.conditioning.undetermined.empty());
  EXPECT_EQ(r.conditioning.column_norms.size(), 9u);
  EXPECT_TRUE(std::isfinite(r.conditioning.condition_number));
}

TEST(PoseFit3, FarStartTurnsOnTheGroupToTheAnswer) {
  // from the identity to a turn of 2.5 rad: more than one chart (kRecentreAngle)
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(30, -12, 20), 2.5, Vec3(-0.3, 1, 0.2), Vec3(0.2, 0.1, -0.2));
  fit::PoseFitOptions o;
  o.initial_q = Eigen::VectorXd::Zero(9);
  o.initial_q.head<3>() = truth.head<3>();
  const fit::PoseFitResult r = fit::FitPose(c.body, MassPointTargets(c, truth), o);
  const QError e = Compare(r.q, truth);
  EXPECT_LT(e.angle, 1e-8) << r.report.brief_report;
  EXPECT_LT(e.gamma, 1e-8);
  EXPECT_LT(e.translation, 1e-6);
}

TEST(PoseFit3, RobustLossShrugsOffOutliers) {
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(5, 40, -3), 0.8, Vec3(0, 1, 1), Vec3(-0.3, 0.35, 0.1));
  std::vector<fit::CorrespondenceN<3>> targets = MassPointTargets(c, truth);
  for (size_t i = 0; i < targets.size(); i += 10) targets[i].position += Vec3(60, -40, 30);  // 10% outliers
  fit::PoseFitOptions squared, cauchy;
  cauchy.loss = fit::Loss::kCauchy;
  cauchy.loss_scale = 1.0;
  const QError bad = Compare(fit::FitPose(c.body, targets, squared).q, truth);
  const QError good = Compare(fit::FitPose(c.body, targets, cauchy).q, truth);
  EXPECT_GT(bad.translation, 1.0);  // the outliers drag a least-squares fit
  EXPECT_LT(good.translation, 1e-2);
  EXPECT_LT(good.angle, 1e-4);
  EXPECT_LT(good.gamma, 1e-4);
}

TEST(PoseFit3, BoundsHoldAndAreReported) {
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(0, 0, 0), 0.3, Vec3(1, 0, 0), Vec3(0.9, 0, 0));
  fit::PoseFitOptions o;
  o.gamma_lower = -0.5;
  o.gamma_upper = 0.5;
  const fit::PoseFitResult r = fit::FitPose(c.body, MassPointTargets(c, truth), o);
  EXPECT_NEAR(r.q[6], 0.5, 1e-12);
  EXPECT_EQ(r.at_bound, std::vector<std::string>{"bend"});
}

TEST(PoseFit3, SurfaceFitRefusesAnEmptyTarget) {
  const Character c = MakeChair();
  EXPECT_THROW(fit::FitPoseToSurface(c.body, fit::SurfaceTarget{}, {}), std::invalid_argument);
}

// The deformed mesh of the character at q, vertex by vertex from the direct formula.
SurfaceMesh DeformedMesh(const Character& c, const Eigen::VectorXd& q) {
  SurfaceMesh m = c.def.mesh;
  for (Vec3& p : m.points) p = Direct(c, q, c.def.lattice.LocalCoords(p));
  return m;
}

TEST(PoseFit3, SurfaceWithoutCorrespondencesFindsThePoseAndTheShape) {
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(-20, 35, 10), 0.6, Vec3(0.2, 1, -0.4), Vec3(0.3, -0.25, 0.15));
  const SurfaceMesh target_mesh = DeformedMesh(c, truth);
  fit::SurfaceTarget target;
  target.AddMesh(target_mesh);
  const fit::PoseFitResult r = fit::FitPoseToSurface(c.body, target, {});  // samples: the mesh's vertices
  const QError e = Compare(r.q, truth);
  EXPECT_LT(e.translation, 1e-5) << r.report.brief_report;
  EXPECT_LT(e.angle, 1e-7);
  EXPECT_LT(e.gamma, 1e-7);
  EXPECT_LT(r.rms_residual, 1e-6);
  EXPECT_EQ(r.point_residuals.size(), target_mesh.points.size());
}

TEST(PoseFit3, PointCloudWithoutCorrespondences) {
  // a scan-like cloud: the mass points at the truth, shuffled, no triangles
  const Character c = MakeChair();
  const Eigen::VectorXd truth = Q(Vec3(10, 0, -30), 0.4, Vec3(1, 1, 1), Vec3(-0.2, 0.2, 0.1));
  std::vector<Vec3> cloud;
  for (int k = 0; k < c.body.num_points(); ++k) cloud.push_back(Direct(c, truth, c.body.lattice_coords(k)));
  std::shuffle(cloud.begin(), cloud.end(), std::mt19937(7));
  fit::SurfaceTarget target;
  for (const Vec3& p : cloud) target.AddPoint(p);
  fit::PoseFitOptions o;
  o.max_mesh_samples = 0;  // the samples are the mass points
  const fit::PoseFitResult r = fit::FitPoseToSurface(c.body, target, o);
  const QError e = Compare(r.q, truth);
  EXPECT_LT(e.translation, 1e-6) << r.report.brief_report;
  EXPECT_LT(e.angle, 1e-8);
  EXPECT_LT(e.gamma, 1e-8);
}

// A tumbling, squashing motion whose turn passes through π (where rotation vectors wrap).
Eigen::VectorXd Motion(double t) {
  return Q(Vec3(40 * t, 80 * t - 30 * t * t, -20 * t), 0.2 + 2.2 * t, Vec3(1, 2, 0.5),
           Vec3(0.3 * std::sin(3 * t), 0.2 * std::cos(2 * t), 0.1 * t));
}

std::vector<fit::ReferenceFrameN<3>> Frames(const Character& c, int count, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, noise);
  std::vector<fit::ReferenceFrameN<3>> frames;
  for (int f = 0; f < count; ++f) {
    fit::ReferenceFrameN<3> frame;
    frame.time = 2.0 * f / (count - 1);
    for (fit::CorrespondenceN<3> p : MassPointTargets(c, Motion(frame.time))) {
      if (noise > 0) p.position += Vec3(n(rng), n(rng), n(rng));
      frame.points.push_back(p);
    }
    frames.push_back(frame);
  }
  return frames;
}

TEST(TrajectoryFit3, ExactFramesGiveBackTheMotion) {
  const Character c = MakeChair();
  fit::TrajectoryFitOptions o;
  o.smoothness = 0;
  const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(c.body, Frames(c, 21, 0, 1), o);
  ASSERT_EQ(r.q.size(), 21u);
  for (size_t f = 0; f < r.q.size(); ++f) {
    const QError e = Compare(r.q[f], Motion(r.times[f]));
    EXPECT_LT(e.translation, 1e-7) << "frame " << f;
    EXPECT_LT(e.angle, 1e-9) << "frame " << f;
    EXPECT_LT(e.gamma, 1e-9) << "frame " << f;
  }
  EXPECT_LT(r.rms_residual, 1e-7);
}

TEST(TrajectoryFit3, SmoothnessOnTheGroupFiltersNoise) {
  // noisy markers: the smoothed fit lies nearer the true motion than frame-by-frame fits
  const Character c = MakeChair();
  const std::vector<fit::ReferenceFrameN<3>> frames = Frames(c, 41, 2.0, 5);
  auto error = [&](double smoothness) {
    fit::TrajectoryFitOptions o;
    o.smoothness = smoothness;
    const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(c.body, frames, o);
    double sum = 0;
    int count = 0;
    for (size_t f = 0; f < r.q.size(); ++f)
      for (int k = 0; k < c.body.num_points(); k += 5, ++count)
        sum += (fit::PointPosition(fit::BasisOf(c.body, k, {}), r.q[f]) -
                Direct(c, Motion(r.times[f]), c.body.lattice_coords(k))).squaredNorm();
    return std::sqrt(sum / count);
  };
  // the data term sums about 100 markers a frame: a weight of that order balances it (measured:
  // rms 0.58 raw, 0.31 at 100, 0.49 at 10⁴ where the smoothing starts to flatten the motion)
  const double raw = error(0.0), smoothed = error(100.0), oversmoothed = error(1e4);
  EXPECT_LT(smoothed, 0.6 * raw) << "raw " << raw << ", smoothed " << smoothed;
  EXPECT_GT(oversmoothed, smoothed);  // the term is real: too much of it bends the motion
}

// ---- 3D target files ----

std::string TargetError(const std::string& text) {
  std::istringstream in(text);
  try {
    formats::ParseTargets<3>(in, "dir/t.tgt", [](const std::string& path) {
      if (path != "dir/scan.ply") throw std::runtime_error("cannot read " + path);
      return testing::ChairMesh();
    });
  } catch (const formats::ParseError& e) {
    return e.what();
  }
  return "no error";
}

TEST(TargetFile3, ParsesEveryStatement) {
  std::istringstream in("dimension 3\npoint 3 10 20 30\nsample 0.5 1 0.25 1.5 -2 7 weight 4\n");
  const formats::TargetFileN<3> f = formats::ParseTargets<3>(in, "t.tgt");
  ASSERT_EQ(f.points.size(), 2u);
  EXPECT_EQ(f.points[0].position, Vec3(10, 20, 30));
  EXPECT_EQ(f.points[1].lattice_coords, Vec3(0.5, 1, 0.25));
  EXPECT_EQ(f.points[1].weight, 4.0);
  std::istringstream surface("dimension 3\nmesh scan.ply   # beside the target file\ncloud 1 2 3\n");
  const formats::TargetFileN<3> s = formats::ParseTargets<3>(surface, "dir/t.tgt", [](const std::string&) { return testing::ChairMesh(); });
  EXPECT_EQ(s.mesh.triangles.size(), 36u);
  EXPECT_EQ(s.cloud.size(), 1u);
  EXPECT_TRUE(s.has_curve());
  std::istringstream traj("dimension 3\nframe 0\npoint 0 1 2 3\nframe 0.5\npoint 0 1 3 4\n");
  EXPECT_EQ(formats::ParseTargets<3>(traj, "k.tgt").frames.size(), 2u);
}

TEST(TargetFile3, RejectsMalformedInputWithFileAndLine) {
  EXPECT_EQ(TargetError(""), "dir/t.tgt:0: file is empty: expected 'dimension 3' and point, sample, cloud, mesh or frame lines");
  EXPECT_EQ(TargetError("point 0 1 2 3\n"),
            "dir/t.tgt:1: the object is 3D: its target file starts with 'dimension 3' (got 'point')");
  EXPECT_EQ(TargetError("dimension 2\npoint 0 1 2\n"), "dir/t.tgt:1: a 2D target file for a 3D object");
  EXPECT_EQ(TargetError("dimension 3\npoint 0 1 2\n"), "dir/t.tgt:2: expected 4 numbers (point <k> <x> <y> <z> [weight <w>])");
  EXPECT_EQ(TargetError("dimension 3\nsample 0 0 2 1 1 1\n"), "dir/t.tgt:2: lattice coordinate u must be in [0, 1], got 2");
  EXPECT_EQ(TargetError("dimension 3\ncloud 1 2\n"), "dir/t.tgt:2: expected 3 numbers (cloud <x> <y> <z>)");
  EXPECT_EQ(TargetError("dimension 3\nmesh other.ply\n"), "dir/t.tgt:2: mesh dir/other.ply: cannot read dir/other.ply");
  EXPECT_EQ(TargetError("dimension 3\nmesh scan.ply\nmesh scan.ply\n"), "dir/t.tgt:3: mesh given twice (first on line 2)");
  EXPECT_EQ(TargetError("dimension 3\npoint 0 1 2 3\nmesh scan.ply\n"),
            "dir/t.tgt:3: a file holds correspondences (point/sample) or a surface (mesh/cloud), not both");
  EXPECT_EQ(TargetError("dimension 3\nframe 0\npoint 0 1 2 3\ncloud 1 2 3\n"),
            "dir/t.tgt:4: mesh/cloud lines are not allowed in a trajectory (frame) file");
  EXPECT_EQ(TargetError("dimension 3\npolyline 0 0 1 1\n"),
            "dir/t.tgt:2: 'polyline' is for 2D target files (expected point, sample, cloud, mesh or frame)");
  EXPECT_EQ(TargetError("dimension 3\npoint 0 1 2 3\ndimension 3\n"), "dir/t.tgt:3: 'dimension' must be the first statement of the file");
  std::istringstream no_reader("dimension 3\nmesh scan.ply\n");
  EXPECT_THROW(formats::ParseTargets<3>(no_reader, "t.tgt"), formats::ParseError);
}

// ---- dynamic fits: through the simulation (StepBody3 with Jets) ----

// The chair with stiff, lightly damped modes, as the World steps it: vibrating and tumbling
// in the air. K_d from a mode frequency f_d (γ̈ G_dd = −2K γ: ω² = 2K/G_dd), c_d = 2ζ sqrt(2K G_dd).
struct Vibrating {
  Character chair = MakeChair();
  std::shared_ptr<const BodyModelN<3>> body;
  Eigen::VectorXd K, c;
  Vibrating() {
    const double f[] = {2.0, 3.0, 2.5}, zeta[] = {0.05, 0.1, 0.02};
    std::vector<DeformationModeN<3>> modes = chair.modes;
    K.resize(3);
    c.resize(3);
    for (int d = 0; d < 3; ++d) {
      const double G = chair.body.moments().G(d, d), w = 2 * M_PI * f[d];
      K[d] = 0.5 * G * w * w;
      c[d] = 2 * zeta[d] * std::sqrt(2 * K[d] * G);
      modes[size_t(d)].stiffness = K[d];
      modes[size_t(d)].damping = c[d];
    }
    body = std::make_shared<const BodyModelN<3>>(chair.def, modes);
  }
};

// Frames of a World run (the world's own mode forces, not the fit's), every `every` steps.
std::vector<fit::ReferenceFrameN<3>> WorldFrames(const std::shared_ptr<const BodyModelN<3>>& body, const Eigen::VectorXd& q0,
                                              const Eigen::VectorXd& v0, double dt, int steps, int every) {
  WorldOptions o;
  o.dt = dt;
  o.integrator = Integrator::kThesis;
  World world(o);
  const int b = world.AddBody(body);
  world.SetState(b, PositionsOf(q0.head<3>(), ExpRotation<double>(q0.segment<3>(3)), q0.tail(3)), v0);
  std::vector<fit::ReferenceFrameN<3>> frames;
  for (int k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      const BodyState<3, double>& s = world.state<3>(b);
      Eigen::VectorXd q(9);
      q << s.translation(), LogRotation<double>(s.orientation()), s.gamma();
      fit::ReferenceFrameN<3> f;
      f.time = k * dt;
      for (int i = 0; i < body->num_points(); i += 4) {
        fit::CorrespondenceN<3> p;
        p.mass_point = i;
        p.position = fit::PointPosition(fit::BasisOf(*body, i, {}), q);
        f.points.push_back(p);
      }
      frames.push_back(f);
    }
    if (k < steps && !world.Step()) throw std::runtime_error("the world stopped at step " + std::to_string(k));
  }
  return frames;
}

// From K×1.4, c×0.5 and q0, q̇0 from pose fits of the first two frames to the World run's own
// numbers, with either gradient: Jets and Levenberg–Marquardt, or the 3D adjoint and BFGS.
void ExpectTheVibratingChairRecovered(fit::FitGradient gradient) {
  const Vibrating v;
  Eigen::VectorXd q0(9), v0(9);
  q0 << 10, 50, -5, 0.3, -0.2, 0.5, 0.2, -0.15, 0.1;
  v0 << 20, 40, -10, 1.5, -2.0, 3.0, 0, 1.0, -0.5;  // body ω of a few rad/s
  const double dt = 0.004;
  const std::vector<fit::ReferenceFrameN<3>> frames = WorldFrames(v.body, q0, v0, dt, 150, 5);
  fit::DynamicFitOptionsN<3> o;
  o.dt = dt;
  o.world.gravity_on = true;
  fit::DynamicParameters start;  // q0 and q̇0 from pose fits of the first two frames
  start.stiffness = v.K * 1.4;
  start.damping = v.c * 0.5;
  o.gradient = gradient;
  if (gradient == fit::FitGradient::kAdjoint) o.max_iterations = 2000;  // line-search iterations are cheaper
  const fit::DynamicFitResult r = fit::FitDynamicTrajectory(*v.body, frames, start, o);
  EXPECT_TRUE(r.report.usable) << r.report.brief_report;
  std::cout << r.report.brief_report << "\n" << r.simulations << " simulations, rms " << r.rms_residual << std::endl;
  for (int d = 0; d < 3; ++d) {
    EXPECT_NEAR(r.params.stiffness[d] / v.K[d], 1.0, 1e-6) << "mode " << d;
    EXPECT_NEAR(r.params.damping[d] / v.c[d], 1.0, 1e-5) << "mode " << d;
  }
  EXPECT_LT(Compare(r.params.q0, q0).angle, 1e-8);
  EXPECT_LT(Compare(r.params.q0, q0).translation, 1e-6);
  EXPECT_LT((r.params.qd0 - v0).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT(r.rms_residual, 1e-6);
  // the fitted parameters replay the reference through the fit's own simulation
  EXPECT_LT(fit::DynamicCost(*v.body, frames, r.params, o), 1e-9);
}

TEST(DynamicFit3, RecoversStiffnessDampingAndTheStartOfATumblingVibratingBody) {
  ExpectTheVibratingChairRecovered(fit::FitGradient::kJets);
}

TEST(DynamicFit3, TheAdjointGradientRecoversTheSameParameters) {
  ExpectTheVibratingChairRecovered(fit::FitGradient::kAdjoint);
}

TEST(DynamicFit3, CostIsTheWorldsRunAtTheTrueParameters) {
  // the fit's simulation (passive body + Jet-ready mode force) against the World's (the body's
  // own mode forces): the same motion, so the cost at the truth is zero to rounding
  const Vibrating v;
  Eigen::VectorXd q0(9), v0(9);
  q0 << 0, 0, 0, 2.0, 1.0, -0.5, 0.3, 0.2, -0.1;
  v0 << 1, 2, 3, -4, 2, 1, 0.5, 0, 0;
  const std::vector<fit::ReferenceFrameN<3>> frames = WorldFrames(v.body, q0, v0, 0.005, 200, 10);
  fit::DynamicFitOptionsN<3> o;
  o.dt = 0.005;
  fit::DynamicParameters truth{q0, v0, v.K, v.c, {}};
  EXPECT_LT(fit::DynamicCost(*v.body, frames, truth, o), 1e-16);
  truth.stiffness[1] *= 1.01;
  EXPECT_GT(fit::DynamicCost(*v.body, frames, truth, o), 1e-6);
}

}  // namespace
}  // namespace wobble
