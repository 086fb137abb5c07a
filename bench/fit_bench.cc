// Fitting speed (issue 6; 3D bodies: issue 15, last in the file): the 11-point table pose fit with correspondences (goal < 1 ms), a
// 1,000-point polyline fit without correspondences, a 1,200-frame kinematic trajectory fit,
// and a dynamic fit through 100 simulated steps. Baselines in the same run: the Procrustes-
// only rigid fit of the same targets (a body without modes), and the pose fit without the
// conditioning analysis.
#include <benchmark/benchmark.h>

#include "support/test_bodies.h"
#include "wobble/world/world.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/core/rotation3.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble {
namespace {

Eigen::VectorXd KnownQ() {
  Eigen::VectorXd q(7);
  q << 40, -25, 0.3, 0.35, -0.2, 0.15, 0.25;
  return q;
}

std::vector<fit::Correspondence> MassTargets(const BodyModel& body, const Eigen::VectorXd& q) {
  std::vector<fit::Correspondence> t;
  for (int k = 0; k < body.num_points(); ++k) {
    fit::Correspondence p;
    p.mass_point = k;
    p.position = fit::PointPosition(fit::BasisOf(body, k, {}), q.data(), int(q.size()));
    t.push_back(p);
  }
  return t;
}

void BM_PoseFit_Table11(benchmark::State& state) {
  const BodyModel body(testing::TableDef(), testing::TableModes());
  const auto targets = MassTargets(body, KnownQ());
  fit::PoseFitOptions o;
  o.analyze_conditioning = state.range(0) != 0;
  int iterations = 0;
  for (auto _ : state) {
    const fit::PoseFitResult r = fit::FitPose(body, targets, o);
    iterations = r.report.iterations;
    benchmark::DoNotOptimize(r.q.data());
  }
  state.counters["ceres_iterations"] = iterations;
}
BENCHMARK(BM_PoseFit_Table11)->Arg(1)->Arg(0)->ArgName("conditioning")->Unit(benchmark::kMicrosecond);

// Baseline: the same 11 targets, rigid table (no modes).
void BM_PoseFit_Table11_Rigid(benchmark::State& state) {
  const BodyModel body(testing::TableDef(), {});
  Eigen::VectorXd q(3);
  q << 40, -25, 0.3;
  const auto targets = MassTargets(body, q);
  fit::PoseFitOptions o;
  o.analyze_conditioning = false;
  for (auto _ : state) benchmark::DoNotOptimize(fit::FitPose(body, targets, o).q.data());
}
BENCHMARK(BM_PoseFit_Table11_Rigid)->Unit(benchmark::kMicrosecond);

// 1,000 target points on three polylines (the table's drawing at KnownQ).
void BM_CurveFit_Polyline1000(benchmark::State& state) {
  const BodyModel body(testing::TableDef(), testing::TableModes());
  fit::CurveTarget target;
  const int counts[3] = {400, 300, 300};
  for (int l = 0; l < 3; ++l) {
    const Polyline& line = body.def().shapes[l];
    std::vector<Eigen::Vector2d> points;
    for (int i = 0; i < counts[l]; ++i) {
      const Eigen::Vector2d p = line.points[0] + (line.points[1] - line.points[0]) * (double(i) / (counts[l] - 1));
      points.push_back(fit::PointPosition(fit::BasisOf(body, -1, body.lattice().LocalCoords(p)), KnownQ().data(), 7));
    }
    target.AddPolyline(points, false);
  }
  fit::PoseFitOptions o;
  o.two_sided = state.range(0) != 0;
  o.joint_closest_points = state.range(1) != 0;
  int rounds = 0, iterations = 0;
  double rms = 0;
  for (auto _ : state) {
    const fit::PoseFitResult r = fit::FitPoseToCurve(body, target, o);
    rounds = r.rounds;
    iterations = r.report.iterations;
    rms = r.rms_residual;
  }
  state.counters["rounds"] = rounds;
  state.counters["ceres_iterations"] = iterations;
  state.counters["rms"] = rms;
}
BENCHMARK(BM_CurveFit_Polyline1000)
    ->Args({1, 1})
    ->Args({1, 0})
    ->Args({0, 1})
    ->Args({0, 0})
    ->ArgNames({"two_sided", "joint"})
    ->Unit(benchmark::kMillisecond);

// The table thrown without ground, 1,200 frames at dt 0.005, all 11 mass points observed.
std::vector<fit::ReferenceFrame> ThrownFrames(const std::shared_ptr<const BodyModel>& body, int frames, double dt) {
  WorldOptions wo;
  wo.params.ground.enabled = false;
  wo.dt = dt;
  World world(wo);
  world.AddBody(body);
  Eigen::VectorXd q0(7), qd0(7);
  q0 << 0, 100, 0.1, 0.2, -0.1, 0.1, 0.0;
  qd0 << 50, 80, 1.5, 0.3, 0.4, -0.2, 0.3;
  world.SetState(0, q0, qd0);
  std::vector<double> t = {0};
  std::vector<Eigen::VectorXd> q = {q0};
  for (int i = 1; i < frames; ++i) {
    world.Step();
    t.push_back(world.time());
    q.push_back(world.q(0));
  }
  return fit::FramesFromStates(*body, t, q, {});
}

void BM_KinematicTrajectory_1200Frames(benchmark::State& state) {
  const auto body = std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(4e6, 1e5));
  const std::vector<fit::ReferenceFrame> frames = ThrownFrames(body, 1200, 0.005);
  fit::TrajectoryFitOptions o;
  o.smoothness = 1.0;
  o.pose.gamma_lower = -3;
  o.pose.gamma_upper = 3;
  int iterations = 0;
  double rms = 0;
  for (auto _ : state) {
    const fit::TrajectoryFitResult r = fit::FitKinematicTrajectory(*body, frames, o);
    iterations = r.report.iterations;
    rms = r.rms_residual;
  }
  state.counters["ceres_iterations"] = iterations;
  state.counters["rms"] = rms;
}
BENCHMARK(BM_KinematicTrajectory_1200Frames)->Unit(benchmark::kMillisecond);

// Dynamic fit of q0, q̇0, K, c to 100 steps (51 frames) from a start 40% off.
void BM_DynamicFit_100Steps(benchmark::State& state) {
  const auto body = std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(3e6, 2e5));
  const std::vector<fit::ReferenceFrame> all = ThrownFrames(body, 101, 0.01);
  std::vector<fit::ReferenceFrame> frames;
  for (size_t i = 0; i < all.size(); i += 2) frames.push_back(all[i]);
  fit::DynamicParameters start;
  start.stiffness = Eigen::VectorXd::Constant(4, 3e6 * 1.4);
  start.damping = Eigen::VectorXd::Constant(4, 2e5 * 0.6);
  fit::DynamicFitOptions o;
  o.world.ground.enabled = false;
  if (state.range(0)) {
    o.gradient = fit::FitGradient::kAdjoint;
    o.max_iterations = 2000;
  }
  fit::DynamicFitResult r;
  for (auto _ : state) r = fit::FitDynamicTrajectory(*body, frames, start, o);
  state.counters["simulations"] = double(r.simulations);
  state.counters["iterations"] = r.report.iterations;
  state.counters["cost"] = r.report.final_cost;
}
// adjoint 0: Jets and Levenberg–Marquardt; 1: the adjoint gradient and BFGS (issue 18)
BENCHMARK(BM_DynamicFit_100Steps)->Arg(0)->Arg(1)->ArgName("adjoint")->Unit(benchmark::kMillisecond);

// Baseline on the same problem: simulated annealing with a budget of simulations (the
// argument; Ceres used 24, each a Jet simulation). Counter "cost": the best cost found;
// compare with the Ceres fit's final cost, printed by tests/dynamic_fit_test (~1e-21).
void BM_DynamicFit_Annealing(benchmark::State& state) {
  const auto body = std::make_shared<const BodyModel>(testing::TableDef(), testing::TableModes(3e6, 2e5));
  const std::vector<fit::ReferenceFrame> all = ThrownFrames(body, 101, 0.01);
  std::vector<fit::ReferenceFrame> frames;
  for (size_t i = 0; i < all.size(); i += 2) frames.push_back(all[i]);
  fit::DynamicParameters start;
  start.stiffness = Eigen::VectorXd::Constant(4, 3e6 * 1.4);
  start.damping = Eigen::VectorXd::Constant(4, 2e5 * 0.6);
  fit::DynamicFitOptions o;
  o.world.ground.enabled = false;
  double cost = 0, ceres_cost = 0;
  for (auto _ : state) cost = fit::AnnealDynamicTrajectory(*body, frames, start, o, state.range(0), 1).cost;
  ceres_cost = fit::FitDynamicTrajectory(*body, frames, start, o).report.final_cost;
  state.counters["cost"] = cost;
  state.counters["ceres_cost"] = ceres_cost;
}
BENCHMARK(BM_DynamicFit_Annealing)->Arg(24)->Arg(240)->Arg(2400)->ArgName("simulations")->Unit(benchmark::kMillisecond);

// Pose-graph controller (bounding table's modes: bend and shear active, K 4e7, c 4e6) standing
// on the synthesis scenes' ground, 3 s (300 steps), every 2nd step observed: poses and times
// fitted from a start 0.03-0.05 off in every target and 8-12% off in every time (as
// tests/pose_graph_fit_test.cc). Counter "cost": the final cost; "simulations".
struct PoseGraphProblem {
  std::shared_ptr<const BodyModel> body;
  fit::DynamicFitOptions o;
  fit::DynamicParameters truth, start;
  std::vector<fit::ReferenceFrame> frames;
  PoseGraphProblem() {
    std::vector<DeformationMode> modes = testing::TableModes(4e7, 4e6);
    modes[0].active = modes[1].active = true;
    body = std::make_shared<const BodyModel>(testing::TableDef(), modes);
    o.world.ground.stiffness = 45000;
    o.world.ground.normal_damping = 3000;
    o.world.ground.friction_damping = 3000;
    o.world.ground.friction_cap = 0.5;
    o.fit_q0 = o.fit_qd0 = o.fit_stiffness = o.fit_damping = false;
    o.fit_poses = o.fit_times = true;
    truth.q0 = truth.qd0 = Eigen::VectorXd::Zero(7);
    truth.stiffness = Eigen::VectorXd::Constant(4, 4e7);
    truth.damping = Eigen::VectorXd::Constant(4, 4e6);
    truth.graph.poses = {(Eigen::VectorXd(2) << 0.2, -0.1).finished(), (Eigen::VectorXd(2) << -0.1, 0.15).finished(),
                         (Eigen::VectorXd(2) << 0.05, 0.1).finished()};
    truth.graph.durations = {0.4, 0.3, 0.5};
    WorldOptions wo;
    wo.params = o.world;
    World world(wo);
    world.AddBody(body);
    world.SetState(0, truth.q0, truth.qd0);
    std::vector<double> t = {0};
    std::vector<Eigen::VectorXd> q = {truth.q0};
    for (int n = 0; n < 300; ++n) {
      world.SetModeTargets(0, control::SmoothPoseTargets(*body, truth.graph, n * o.dt, o.switch_width));
      world.Step();
      t.push_back(world.time());
      q.push_back(world.q(0));
    }
    frames = fit::FramesFromStates(*body, t, q, {}, 2);
    start = truth;
    const double dp[3][2] = {{0.05, -0.04}, {-0.03, 0.05}, {0.04, 0.03}};
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 2; ++k) start.graph.poses[i][k] += dp[i][k];
    start.graph.durations = {0.44, 0.27, 0.56};
  }
};

void BM_PoseGraphFit_Ground(benchmark::State& state) {
  PoseGraphProblem p;
  if (state.range(0)) {
    p.o.gradient = fit::FitGradient::kAdjoint;
    p.o.max_iterations = 2000;
  }
  fit::DynamicFitResult r;
  for (auto _ : state) r = fit::FitDynamicTrajectory(*p.body, p.frames, p.start, p.o);
  state.counters["simulations"] = double(r.simulations);
  state.counters["iterations"] = r.report.iterations;
  state.counters["cost"] = r.report.final_cost;
  state.counters["start_cost"] = fit::DynamicCost(*p.body, p.frames, p.start, p.o);
}
// adjoint 0: Jets and Levenberg–Marquardt; 1: the adjoint gradient and BFGS (issue 18)
BENCHMARK(BM_PoseGraphFit_Ground)->Arg(0)->Arg(1)->ArgName("adjoint")->Unit(benchmark::kMillisecond);

// The same problem by lib/wobble/synth's simulated annealing (Fig. 5.2, batch 1) with a budget
// of simulations (the argument; Ceres used about 24).
void BM_PoseGraphFit_Annealing(benchmark::State& state) {
  const PoseGraphProblem p;
  fit::AnnealingResult r;
  for (auto _ : state) r = fit::AnnealPoseGraph(*p.body, p.frames, p.start, p.o, state.range(0), 1);
  state.counters["cost"] = r.cost;
}
BENCHMARK(BM_PoseGraphFit_Annealing)->Arg(24)->Arg(240)->Arg(2400)->ArgName("simulations")->Unit(benchmark::kMillisecond)->Iterations(1);

// ---- 3D bodies (issue 15): the chair of tests/support (3 modes, ~300 mass points, 24-vertex mesh) ----

Eigen::VectorXd KnownQChair() {
  Eigen::VectorXd q(9);
  q << 30, -12, 20, 0.9, -0.6, 1.2, 0.3, -0.2, 0.15;
  return q;
}

// Pose with correspondences: every 10th mass point (~30). Baseline: the 2D table's 11-point fit.
void BM_PoseFit3_Chair(benchmark::State& state) {
  const BodyModelN<3> body = testing::Chair3();
  std::vector<fit::CorrespondenceN<3>> targets;
  for (int k = 0; k < body.num_points(); k += 10) {
    fit::CorrespondenceN<3> t;
    t.mass_point = k;
    t.position = fit::PointPosition(fit::BasisOf(body, k, {}), KnownQChair());
    targets.push_back(t);
  }
  int iterations = 0;
  for (auto _ : state) iterations = fit::FitPose(body, targets, {}).report.iterations;
  state.counters["iterations"] = iterations;
  state.counters["points"] = double(targets.size());
}
BENCHMARK(BM_PoseFit3_Chair)->Unit(benchmark::kMicrosecond);

// Surface without correspondences: the chair's mesh deformed and placed at KnownQChair (36
// triangles); samples: the body mesh's 24 vertices; 24 axis matchings ranked, 4 solved.
void BM_SurfaceFit3_Chair(benchmark::State& state) {
  const BodyModelN<3> body = testing::Chair3();
  SurfaceMesh target_mesh = body.def().mesh;
  const Eigen::VectorXd q = KnownQChair();
  for (size_t v = 0; v < target_mesh.points.size(); ++v)
    target_mesh.points[v] = fit::PointPosition(fit::PointBasisN<3>{body.mesh_rest_local(int(v)), body.mesh_mode_matrix(int(v))}, q);
  fit::SurfaceTarget target;
  target.AddMesh(target_mesh);
  double rms = 0;
  for (auto _ : state) rms = fit::FitPoseToSurface(body, target, {}).rms_residual;
  state.counters["rms"] = rms;
}
BENCHMARK(BM_SurfaceFit3_Chair)->Unit(benchmark::kMillisecond);

// Dynamic fit of q0, q̇0, K, c: 100 steps of the chair tumbling in the air (51 frames of ~30
// points), from K×1.4 and c×0.6. Baseline: BM_DynamicFit_100Steps (the 2D table).
void BM_DynamicFit3_100Steps(benchmark::State& state) {
  BodyModelN<3> passive = testing::Chair3();
  std::vector<DeformationModeN<3>> modes = passive.modes();
  for (DeformationModeN<3>& m : modes) m.stiffness = 3e5, m.damping = 2e3;
  const BodyModelN<3> body(passive.def(), modes);
  fit::DynamicFitOptionsN<3> o;
  o.dt = 0.005;
  fit::DynamicParameters truth;
  truth.q0 = KnownQChair();
  truth.qd0.resize(9);
  truth.qd0 << 20, 40, -10, 1.5, -2, 3, 0, 1, -0.5;
  truth.stiffness = Eigen::VectorXd::Constant(3, 3e5);
  truth.damping = Eigen::VectorXd::Constant(3, 2e3);
  std::vector<fit::ReferenceFrameN<3>> frames;
  std::vector<int> steps;
  for (int f = 0; f <= 50; ++f) steps.push_back(2 * f);
  fit::SimulateWithParameters(body, o, truth, steps, [&](int f, const Eigen::VectorXd& q) {
    fit::ReferenceFrameN<3> frame;
    frame.time = steps[size_t(f)] * o.dt;
    for (int k = 0; k < body.num_points(); k += 10) {
      fit::CorrespondenceN<3> p;
      p.mass_point = k;
      p.position = fit::PointPosition(fit::BasisOf(body, k, {}), q);
      frame.points.push_back(p);
    }
    frames.push_back(frame);
  });
  fit::DynamicParameters start;
  start.stiffness = truth.stiffness * 1.4;
  start.damping = truth.damping * 0.6;
  if (state.range(0)) {
    o.gradient = fit::FitGradient::kAdjoint;
    o.max_iterations = 2000;
  }
  long sims = 0;
  double cost = 0;
  int iterations = 0;
  for (auto _ : state) {
    const fit::DynamicFitResult r = fit::FitDynamicTrajectory(body, frames, start, o);
    sims = r.simulations;
    cost = r.report.final_cost;
    iterations = r.report.iterations;
  }
  state.counters["simulations"] = double(sims);
  state.counters["iterations"] = iterations;
  state.counters["final_cost"] = cost;
}
// adjoint 0: Jets and Levenberg–Marquardt; 1: the 3D adjoint and BFGS (issue 18)
BENCHMARK(BM_DynamicFit3_100Steps)->Arg(0)->Arg(1)->ArgName("adjoint")->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
