// The scene runtime (wobble/scene): the same script gives the same trajectory to 1e-12 through
// the interpreter's `simul`, through the scene stepped by hand one step at a time (as the
// viewer steps it), and through the CLI's `wobble run` writing its `output` CSV.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "wobble/scene/object_runs.h"
#include "wobble/scene/scene.h"
#include "wobble/script/interpreter.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

namespace fs = std::filesystem;
const std::string kData = wobble::test_env::DataDir();

// The table of data/ under a two-pose graph on the ground, recorded by `output`; its last line
// is the run (`simul 3`: 300 steps).
const std::string kTableScript = "load_obj " + kData + "/table.obj\nload_def " + kData +
                                 "/table_modes.def\nset integrator thesis\nset dt 0.01\nset grconst 45000\n"
                                 "assign 1 4e7 4e6\ntrans 0 0.1 0\npose 0.2 -0.1 0.3\npose -0.1 0.1 0.4\n"
                                 "output out.csv\nsimul 3\n";

// The lines of a script up to (not including) its first `simul`, run in an interpreter.
void RunUpToSimul(script::Interpreter* interp, const std::string& text, const std::string& dir) {
  std::istringstream in(text);
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.rfind("simul", 0) == 0) return;
    interp->RunLine(line, "<test>", n, dir);
  }
}

// What the viewer does: begin a run of the scene, step it, end it.
void StepByHand(scene::Scene* s, long steps) {
  s->BeginRun();
  for (long n = 0; n < steps; ++n) ASSERT_TRUE(s->Step()) << s->run_world()->status().message;
  s->EndRun();
}

double MaxDifference(const record::Trajectory& a, const record::Trajectory& b) {
  EXPECT_EQ(a.Columns(), b.Columns());
  EXPECT_EQ(a.size(), b.size());
  double d = 0.0;
  for (int k = 0; k < std::min(a.size(), b.size()); ++k)
    for (int c = 0; c < a.num_columns(); ++c) d = std::max(d, std::abs(a.Row(k)[c] - b.Row(k)[c]));
  return d;
}

std::vector<std::vector<double>> ReadCsv(const fs::path& path, std::string* header) {
  std::ifstream f(path);
  EXPECT_TRUE(f) << path;
  std::getline(f, *header);
  std::vector<std::vector<double>> rows;
  for (std::string line; std::getline(f, line);) {
    std::vector<double> row;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) row.push_back(std::stod(x));
    rows.push_back(row);
  }
  return rows;
}

struct ScratchFolder {
  explicit ScratchFolder(const std::string& name) : path(fs::temp_directory_path() / name), cwd(fs::current_path()) {
    fs::remove_all(path);
    fs::create_directories(path);
    fs::current_path(path);
  }
  ~ScratchFolder() { fs::current_path(cwd); }
  fs::path path, cwd;
};

// The scene runtime without the interpreter (scene.h's usage): kTableScript's setup through the
// API, run whole, is the interpreter's run.
TEST(Scene, HelloTable) {
  scene::Scene s;
  s.options().integrator = Integrator::kThesis;
  s.options().dt = 0.01;
  s.options().params.ground.stiffness = 45000;
  s.object().Load(kData + "/table.obj");
  s.object().LoadModes({kData + "/table_modes.def"});
  s.object().Assign(0, 4e7, 4e6);
  s.object().SetPlacement({0, 0.1, 0});
  control::PoseGraph& graph = s.control().graph;
  graph.poses = {Eigen::Vector2d(0.2, -0.1), Eigen::Vector2d(-0.1, 0.1)};
  graph.durations = {0.3, 0.4};
  const scene::RunReport r = s.Simulate(3.0);
  ASSERT_TRUE(r.ok()) << r.status.message;
  EXPECT_EQ(r.steps, 300);
  const record::Trajectory& run = *s.last_object_run();
  EXPECT_EQ(run.size(), 301);
  EXPECT_DOUBLE_EQ(s.time(), 3.0);

  ScratchFolder scratch("wobble_scene_test_hello");
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(kTableScript);
  interp.RunStream(in, "table.wob", kData);
  EXPECT_EQ(MaxDifference(run, *interp.scene().last_object_run()), 0.0);
}

TEST(Scene, TheInterpretersSimulAndTheSceneSteppedByHandGiveTheSameTrajectory) {
  ScratchFolder scratch("wobble_scene_test_by_hand");
  std::ostringstream out;
  script::Interpreter interp(out), by_hand(out);
  std::istringstream in(kTableScript);
  interp.RunStream(in, "table.wob", kData);
  RunUpToSimul(&by_hand, kTableScript, kData);
  StepByHand(&by_hand.scene(), 300);
  const record::Trajectory& a = *interp.scene().last_object_run();
  const record::Trajectory& b = *by_hand.scene().last_object_run();
  ASSERT_EQ(a.size(), 301);  // the start and every step
  EXPECT_LE(MaxDifference(a, b), 1e-12);
  EXPECT_GE(a.pose(a.size() - 1), 0);  // the pose graph drove it
  EXPECT_EQ(interp.q(), by_hand.q());
  EXPECT_EQ(interp.time(), by_hand.time());
  EXPECT_EQ(interp.control_energy(), by_hand.control_energy());
  EXPECT_GT(interp.control_energy(), 0.0);
}

TEST(Scene, Fig2SimulAndTheSceneSteppedByHandRecordTheSameFrames) {
  std::ostringstream out;
  script::Interpreter interp(out), by_hand(out);
  std::ifstream f(kData + "/fig2_triple_pendulum.wob");
  std::stringstream script;
  script << f.rdbuf();
  RunUpToSimul(&interp, script.str(), kData);
  RunUpToSimul(&by_hand, script.str(), kData);
  interp.RunLine("simul 1", "<test>", 1, kData);
  StepByHand(&by_hand.scene(), 1000);
  const record::Trajectory& a = *interp.scene().recorded();
  const record::Trajectory& b = *by_hand.scene().recorded();
  EXPECT_EQ(a.size(), 31);  // 1 s at 30 frames per second, both ends
  EXPECT_LE(MaxDifference(a, b), 1e-12);
  for (const char* name : {"elbow1", "elbow2", "tip"})
    EXPECT_LE((interp.scene().Point(name) - by_hand.scene().Point(name)).norm(), 1e-12) << name;
}

#ifdef WOBBLE_HAVE_CLI
TEST(Scene, TheCliWritesTheTrajectoryOfTheInterpreterAsItsOutputCsv) {
  ScratchFolder scratch("wobble_scene_test_cli");
  std::ofstream(scratch.path / "table.wob") << kTableScript;
  std::ostringstream out;
  script::Interpreter interp(out);
  fs::create_directories("interp");
  fs::current_path("interp");
  interp.RunFile((scratch.path / "table.wob").string());
  fs::current_path(scratch.path);
  fs::create_directories("cli");
  const std::string command = "cd cli && \"" + wobble::test_env::CliPath() + "\" run ../table.wob > run.log 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::string header_cli, header_interp;
  const auto cli = ReadCsv(scratch.path / "cli/out.csv", &header_cli);
  const auto mine = ReadCsv(scratch.path / "interp/out.csv", &header_interp);
  EXPECT_EQ(header_cli, header_interp);
  EXPECT_EQ(header_cli.rfind("t,tx,ty,theta,bend,shear,vsquash,hsquash,dtx,", 0), 0u) << header_cli;
  // the CSV is the run's trajectory: t, q, q̇ of every step
  const record::Trajectory& run = *interp.scene().last_object_run();
  ASSERT_EQ(cli.size(), size_t(run.size()));
  ASSERT_EQ(mine.size(), cli.size());
  double d = 0.0;
  for (int k = 0; k < run.size(); ++k) {
    ASSERT_EQ(cli[k].size(), mine[k].size());
    for (size_t c = 0; c < cli[k].size(); ++c) d = std::max(d, std::abs(cli[k][c] - mine[k][c]));
    d = std::max(d, std::abs(cli[k][0] - run.time(k)));
    for (int i = 0; i < 7; ++i) {
      d = std::max(d, std::abs(cli[k][1 + i] - run.q(k, 0)[i]));
      d = std::max(d, std::abs(cli[k][8 + i] - run.qd(k, 0)[i]));
    }
  }
  EXPECT_LE(d, 1e-12);
}
#endif

// `output` and `render` see the runs as one motion: modes by name across mode sets, the
// hand-over sample once.
TEST(ObjectRuns, ModesAreMatchedByNameAndTheHandOverIsCountedOnce) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in("load_obj " + kData + "/table.obj\nload_def " + kData + "/bend.def " + kData +
                        "/shear.def\nset dt 0.01\ntrans 0 60 0\nsimul 0.1\nload_def " + kData + "/shear.def " + kData +
                        "/vsquash.def\nsimul 0.05\n");
  scene::ObjectRuns runs;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    interp.RunLine(line, "<test>", ++n, kData);
    if (line.rfind("simul", 0) == 0) runs.push_back(interp.scene().last_object_run());
  }
  const record::Trajectory merged = scene::MergeRuns(runs);
  ASSERT_EQ(merged.size(), 11 + 5);  // 0 .. 0.1, then 0.11 .. 0.15
  const std::vector<std::string>& names = merged.bodies()[0].coordinate_names;
  EXPECT_EQ(names, (std::vector<std::string>{"tx", "ty", "theta", "bend", "shear", "vsquash"}));
  // the shear keeps its column across the load_def; bend reads 0 in the second run, vsquash in the first
  EXPECT_EQ(merged.q(10, 0)[kRigidDofs + 1], runs[1]->q(0, 0)[kRigidDofs + 0]);
  EXPECT_EQ(merged.q(12, 0)[kRigidDofs + 0], 0.0);
  EXPECT_EQ(merged.q(5, 0)[kRigidDofs + 2], 0.0);
  const record::Trajectory table = scene::OutputTrajectory(runs, 5);
  EXPECT_EQ(table.Columns(), merged.Columns());  // the one schema, modes by name
  ASSERT_EQ(table.size(), 4);  // samples 0, 5, 10, 15
  EXPECT_DOUBLE_EQ(table.time(3), 0.15);
  EXPECT_EQ(table.q(3, 0)[kRigidDofs + 1], merged.q(15, 0)[kRigidDofs + 1]);
}

// The viewer's live runs keep no record (keep_steps false) and end in the state of a recorded
// run; StopPoseGraph freezes the targets where the graph left them.
TEST(Scene, RunsWithoutARecordAndAStoppedPoseGraph) {
  std::ostringstream log;
  script::Interpreter recorded(log), live(log);
  RunUpToSimul(&recorded, kTableScript, kData);
  RunUpToSimul(&live, kTableScript, kData);
  StepByHand(&recorded.scene(), 150);
  scene::Scene& s = live.scene();
  s.BeginRun(scene::RunKind::kSimulate, /*keep_steps=*/false);
  for (int n = 0; n < 150; ++n) ASSERT_TRUE(s.Step());
  s.EndRun();
  EXPECT_FALSE(s.last_object_run()) << "a run without a record kept one";
  EXPECT_EQ((s.object().q() - recorded.scene().object().q()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_DOUBLE_EQ(s.time(), recorded.scene().time());

  // pose 1 holds 0.3 s (30 steps): stopped at step 10, the targets stay those of pose 1
  s.BeginRun(scene::RunKind::kSimulate, false);
  for (int n = 0; n < 10; ++n) ASSERT_TRUE(s.Step());
  const Eigen::VectorXd held = s.run_world()->mode_targets(0);
  ASSERT_GT(held.cwiseAbs().maxCoeff(), 0.0);
  s.StopPoseGraph();
  for (int n = 0; n < 60; ++n) ASSERT_TRUE(s.Step());  // past the switch to pose 2 at step 30
  EXPECT_EQ(s.run_world()->mode_targets(0), held);
  s.EndRun();
}

}  // namespace
}  // namespace wobble
