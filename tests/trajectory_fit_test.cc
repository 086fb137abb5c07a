// Kinematic trajectory fit: q(t) recovered from the mass points of a simulated reference
// (wobble's own World), with and without noise; the smoothness term reduces the error that
// noise causes; the simulation CSV reader is strict.
#include <gtest/gtest.h>

#include <random>
#include <sstream>

#include "support/test_bodies.h"
#include "wobble/world/world.h"
#include "wobble/fit/trajectory_fit.h"
#include "wobble/formats/parse_error.h"

namespace wobble {
namespace {

// The table thrown, spinning and wobbling, without ground: 1.5 s at dt 0.01.
struct Reference {
  std::vector<double> t;
  std::vector<Eigen::VectorXd> q;
};
Reference Simulated(const std::shared_ptr<const BodyModel>& body, int steps = 150) {
  WorldOptions options;
  options.params.ground.enabled = false;
  options.dt = 0.01;
  World world(options);
  world.AddBody(body);
  Eigen::VectorXd q0(7), qd0(7);
  q0 << 0, 100, 0.1, 0.2, -0.1, 0.1, 0.0;
  qd0 << 50, 80, 1.5, 0.3, 0.4, -0.2, 0.3;  // amplitudes stay inside [-1, 1]
  world.SetState(0, q0, qd0);
  Reference r;
  r.t.push_back(0);
  r.q.push_back(q0);
  for (int i = 0; i < steps; ++i) {
    EXPECT_TRUE(world.Step());
    r.t.push_back(world.time());
    r.q.push_back(world.q(0));
  }
  return r;
}

std::shared_ptr<const BodyModel> Table() {
  return std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(4e5, 1e4));
}

double MaxModeError(const fit::TrajectoryFitResult& r, const Reference& ref) {
  double e = 0;
  for (size_t f = 0; f < ref.q.size(); ++f)
    for (int d = 3; d < 7; ++d) e = std::max(e, std::abs(r.q[f][d] - ref.q[f][d]));
  return e;
}

TEST(TrajectoryFit, RecoversSimulatedQFromMassPoints) {
  const auto body = Table();
  const Reference ref = Simulated(body);
  const std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*body, ref.t, ref.q, {});
  fit::TrajectoryFitOptions o;
  o.smoothness = 0.0;  // exact data: nothing to smooth
  o.pose.gamma_lower = -3;  // the thrown table's amplitudes reach -1.3
  o.pose.gamma_upper = 3;
  const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(*body, frames, o);
  ASSERT_TRUE(r.report.usable) << r.report.brief_report;
  ASSERT_EQ(r.q.size(), ref.q.size());
  for (size_t f = 0; f < ref.q.size(); ++f)
    for (int i = 0; i < 7; ++i) ASSERT_NEAR(r.q[f][i], ref.q[f][i], 1e-6) << "frame " << f << " coordinate " << i;
  EXPECT_LT(r.rms_residual, 1e-6);
  EXPECT_EQ(r.linear_solver.rfind("SPARSE_NORMAL_CHOLESKY", 0), 0u);
}

TEST(TrajectoryFit, SmoothnessReducesTheErrorFromNoise) {
  const auto body = Table();
  const Reference ref = Simulated(body);
  // only 5 of the 11 points are observed (both feet, the top's ends and middle), with noise 2
  std::vector<fit::ReferenceFrame> frames = fit::FramesFromStates(*body, ref.t, ref.q, {0, 2, 4, 5, 8});
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 2.0);
  for (fit::ReferenceFrame& f : frames)
    for (fit::Correspondence& p : f.points) p.position += Eigen::Vector2d(noise(rng), noise(rng));
  fit::TrajectoryFitOptions rough, smooth;
  rough.smoothness = 0.0;
  smooth.smoothness = 30.0;
  for (fit::TrajectoryFitOptions* o : {&rough, &smooth}) {
    o->pose.gamma_lower = -3;
    o->pose.gamma_upper = 3;
  }
  const fit::TrajectoryFitResult a = fit::FitKinematicTrajectory(*body, frames, rough);
  const fit::TrajectoryFitResult b = fit::FitKinematicTrajectory(*body, frames, smooth);
  const double ea = MaxModeError(a, ref), eb = MaxModeError(b, ref);
  EXPECT_LT(eb, 0.5 * ea) << "rough " << ea << " smooth " << eb;
  // stated tolerance: amplitudes within 0.03 everywhere (a unit amplitude moves points by ~100)
  EXPECT_LT(eb, 0.03);
  for (size_t f = 0; f < ref.q.size(); ++f) EXPECT_NEAR(b.q[f][2], ref.q[f][2], 0.01) << f;
}

TEST(TrajectoryFit, UnevenKeyframesAndBounds) {
  const auto body = Table();
  const Reference ref = Simulated(body);
  // keyframes at uneven times, every mass point
  std::vector<Eigen::VectorXd> q;
  std::vector<double> t;
  for (size_t f : {0, 3, 10, 12, 30, 31, 60, 100, 150}) {
    q.push_back(ref.q[f]);
    t.push_back(ref.t[f]);
  }
  fit::TrajectoryFitOptions o;
  o.smoothness = 0.0;
  o.pose.gamma_lower = -0.1;
  o.pose.gamma_upper = 0.1;
  const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(*body, fit::FramesFromStates(*body, t, q, {}), o);
  ASSERT_TRUE(r.report.usable);
  for (const Eigen::VectorXd& qf : r.q)
    for (int d = 3; d < 7; ++d) {
      EXPECT_GE(qf[d], -0.1);
      EXPECT_LE(qf[d], 0.1);
    }
  EXPECT_GT(r.rms_residual, 1.0);  // the reference leaves the bounds: an honest residual
}

}  // namespace
}  // namespace wobble
