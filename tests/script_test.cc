// The command interpreter: appendix C's script runs unchanged to a finite, settled end; every
// command's errors name the line and what was expected; keyframes hand over continuously to
// simulation; a saved script replays the same motion.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "wobble/dynamics/kinematics.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/script/interpreter.h"
#include "wobble/script/variables.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

const std::string kData = wobble::test_env::DataDir();

double KineticEnergy(const BodyModel& body, const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  MatQ<double> M;
  MassMatrix(body.moments(), VecQ<double>(q), &M);
  return 0.5 * qd.dot(Eigen::MatrixXd(M) * qd);
}

TEST(AppendixC, RunsUnchangedToAFiniteSettledEnd) {
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.LoadObject(kData + "/pot.obj");
  interp.RunFile(kData + "/appendix_c.wob");
  EXPECT_DOUBLE_EQ(interp.time(), 25.0);
  const BodyModel& pot = *interp.body();
  ASSERT_EQ(pot.num_modes(), 3);
  EXPECT_EQ(pot.modes()[0].stiffness, 400000);  // assign 1 400000 250000
  EXPECT_EQ(pot.modes()[2].damping, 7500000);   // assign 3 1200000 7500000
  ASSERT_TRUE(interp.q().allFinite() && interp.qd().allFinite());
  // dropped from 400: it fell, landed where it was dropped (no sideways push), and came to rest
  // on the ground y = 0 — its kinetic energy is below 1% of the m g h it gained by falling
  const double m = pot.moments().m;
  EXPECT_NEAR(interp.q()[0], 500.0, 1e-6);
  EXPECT_LT(std::abs(interp.q()[1]), 10.0);
  EXPECT_LT(KineticEnergy(pot, interp.q(), interp.qd()), 0.01 * m * 9.81 * 400);
  EXPECT_LT(std::abs(interp.q()[2]), 1e-9);
}

// load_def reads 2D files with the object's lattice, so generator modes load (issue 45): the
// table's generator file holds the typed bend and shear y x 150 = data/shear.def − (75, 0).
TEST(Interpreter, LoadDefReadsTwoDGeneratorsOverTheObjectsLattice) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream script("load_obj table.obj\nload_def table_generated.def\n");
  interp.RunStream(script, "generators.wob", kData);
  const BodyModel& table = *interp.body();
  ASSERT_EQ(table.num_modes(), 4);
  EXPECT_EQ(table.modes()[1].name, "lean");
  EXPECT_TRUE(table.modes()[1].active);
  const DeformationMode shear = formats::ReadDeformationFile(kData + "/shear.def")[0];
  for (int c = 0; c < 16; ++c)
    EXPECT_NEAR((table.modes()[1].displacement[c] - (shear.displacement[c] - Eigen::Vector2d(75, 0))).norm(), 0, 1e-12);
}

TEST(AppendixC, ExplicitSchemeAtItsTimeStepStopsWithAStatusNamingTheLine) {
  // the thesis' explicit scheme at dt 0.1 is beyond its stability limit for these dampings:
  // the run must stop with a status, not produce NaN
  std::ifstream f(kData + "/appendix_c.wob");
  std::stringstream script;
  script << "set integrator thesis\n" << f.rdbuf();
  const std::string text = script.str();
  // `simul` is the last line
  const int simul_line = int(std::count(text.begin(), text.end(), '\n'));
  std::ostringstream out;
  script::Interpreter interp(out);
  interp.LoadObject(kData + "/pot.obj");
  try {
    interp.RunStream(script, "thesis.wob", kData);
    FAIL() << "expected the run to stop";
  } catch (const script::SimulationStopped& e) {
    const std::string where = "thesis.wob:" + std::to_string(simul_line) + ": simulation stopped";
    EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
  }
  EXPECT_TRUE(interp.q().allFinite());
}

struct ErrorCase {
  std::string script;  // the last line is the bad one
  std::string expected;
};

// Every command's errors: the line is named and the message says what was expected.
TEST(Interpreter, EveryCommandsErrorsNameTheLineAndWhatWasExpected) {
  const std::string pot = "load_obj " + kData + "/pot.obj\nload_def " + kData + "/def_pot\n";
  const std::string active = pot + "mode bend active\nmode vsquash active\n";
  // a mode for a 2x2 lattice, which the pot's 4x4 lattice cannot take
  const auto small = std::filesystem::temp_directory_path() / "wobble_small_mode.def";
  std::ofstream(small) << "mode small\nx: 0 1\n   0 1\ny: 0 0\n   1 1\n";
  const std::vector<ErrorCase> cases = {
      {"simull", "unknown command 'simull'; did you mean 'simul'?"},
      {"lod_def x", "did you mean 'load_def'?"},
      {"frobnicate", "unknown command 'frobnicate'"},
      {"load_obj", "expected 'load_obj FILE'"},
      {"load_obj /no/such/file.obj", "cannot open file"},
      {"load_def def_pot", "load_def needs an object"},
      {"load_obj POT\nload_def", "expected 'load_def FILE [FILE...]'"},
      {"load_obj POT\nload_def SMALL", "the modes do not fit the object"},
      {"trans 1 2", "expected 'trans X Y THETA'"},
      {"trans 1 2 x", "expected THETA (a finite number), got 'x'"},
      {"set grconst", "expected 'set NAME VALUE'"},
      {"set grconts 4500", "unknown parameter 'grconts'; did you mean 'grconst'?"},
      {"set grconst abc", "expected grconst (a finite number), got 'abc'"},
      {"set grdam -1", "expected a non-negative value for grdam"},
      {"set gravity X", "expected T or F for gravity, got 'X'"},
      {"set dt 0", "expected a positive value for dt"},
      {"set ground_slope 95", "between -90 and 90 degrees"},
      {"set integrator euler", "expected an integrator"},
      {"set interp cubic", "expected 'linear' or 'smooth'"},
      {"set optimize all", "expected poses, times or both"},
      {"set cost fast", "expected a cost"},
      {"set seed -1", "expected a whole non-negative seed"},
      {"set batch 0", "expected a whole number >= 1 for batch"},
      {"set cooling 2", "expected cooling in (0, 1]"},
      {"assign 1 1 1", "assign needs an object"},
      {"DEFS\nassign 9 1 1", "expected a mode number from 1 to 3, got 9"},
      {"DEFS\nassign bnd 1 1", "no mode 'bnd'"},
      {"DEFS\nassign 1 -1 0", "expected a non-negative stiffness and damping"},
      {"DEFS\nassign 1 1", "expected 'assign MODE STIFFNESS DAMPING'"},
      {"DEFS\nmode 1 sleepy", "expected 'active' or 'passive', got 'sleepy'"},
      {"DEFS\nset_vec q 1 2", "expected 6 numbers after 'set_vec q'"},
      {"DEFS\nset_vec x 1", "expected 'set_vec q V1 .. Vn'"},
      {"DEFS\nset_vec dq 0 0 0 0 0 nan", "expected a coordinate (a finite number)"},
      {"DEFS\nsimul -1", "expected a non-negative DURATION"},
      {"DEFS\nset time 5\nset end 1\nsimul", "end (1) is before time (5)"},
      {"DEFS\npose 0.1 1", "pose needs active modes"},
      {"ACTIVE\npose 0.1 1", "expected 'pose' with 2 targets"},
      {"ACTIVE\npose 0.1 0.2 0", "expected a positive DURATION"},
      {"DEFS\nkey 1 bend=0.1", "the first key must be at time 0"},
      {"DEFS\nkey 0 bend", "expected MODE=VALUE, got 'bend'"},
      {"DEFS\nkey 0 bend=x", "expected an amplitude after '='"},
      {"DEFS\nkey 0 bend=0.1\nkey 0 bend=0.2", "expected a key time after 0"},
      {"DEFS\nkey 0 bend=0.1\nkeyframe", "keyframing needs at least two keys"},
      {"hold 2 0", "expected lattice coordinates S and T in [0, 1]"},
      {"hold 0.5", "expected 'hold S T | hold off'"},
      {"DEFS\nspring 0.5 0.5 1", "expected 'spring S T X Y [K [C [REST]]]'"},
      {"DEFS\nspring 0.5 0.5 1 1 -5", "expected non-negative K, C and REST"},
      {"clear stuff", "expected poses, keys, springs, output, energy or track"},
      {"DEFS\nrender", "expected 'render DIR [WHAT] [NAME=VALUE ...]'"},
      {"DEFS\nrender out frames sizes=3x3", "unknown render option 'sizes' (azimuth, camera, chart-size,"},
      {"DEFS\nrender out frames fps=2 frames", "expected NAME=VALUE after the outputs, got 'frames'"},
      {"terrain 0 0", "expected 'terrain X1 Y1 X2 Y2 ...'"},
      {"terrain 0 0 -1 5", "vertex 2 (x -1) is left of vertex 1"},
      {"terrain 0 0 1 x", "expected Y2 (a finite number), got 'x'"},
      {"terrain 0 0 0 5 0 9", "one vertical line"},
      {"terrain_face 1 frsin 0.1", "no terrain yet"},
      {"terrain 0 0 1 0\nterrain_face 2 frsin 0.1", "expected a segment from 1 to 1, got 2"},
      {"terrain 0 0 1 0\nterrain_face 1 fric 0.1", "expected grconst, grdam, frconst or frsin, got 'fric'"},
      {"terrain 0 0 1 0\nterrain_face 1 frsin -1", "expected a non-negative frsin"},
      {"heightfield_region 0 0 1 1 frsin 0.1", "no heightfield yet"},
      {"heightfield_region 0 0 1 frsin", "expected 'heightfield_region X0 Z0 X1 Z1 NAME VALUE"},
      {"terrain 0 0 1 0\nset ground_slope 5", "the ground is a terrain"},
      {"set g -1", "expected a non-negative"},
      {"output out.csv 0", "expected EVERY as a whole number >= 1"},
      {"DEFS\nanneal x", "expected ITERATIONS as a whole number >= 0"},
      {"DEFS\nanneal 5", "anneal needs an initial pose graph"},
      {"DEFS\ncmaes x", "expected GENERATIONS as a whole number >= 0"},
      {"DEFS\ncmaes 5", "cmaes needs an initial pose graph"},
      {"set sigma0 2", "expected sigma0 in (0, 1]"},
      {"DEFS\ngait 1", "expected 'gait SKIP CYCLES'"},
      {"DEFS\ngait 1 2", "gait needs a cyclic pose graph"},
      {"save", "expected 'save FILE'"},
      {"print now", "expected 'print'"},
  };
  for (const ErrorCase& c : cases) {
    std::string script = c.script;
    // placeholders keep the table short
    for (auto [key, value] : {std::pair<std::string, std::string>{"ACTIVE\n", active}, {"DEFS\n", pot},
                              {"load_obj POT", "load_obj " + kData + "/pot.obj"},
                              {"SMALL", small.string()}}) {
      const size_t at = script.find(key);
      if (at != std::string::npos) script.replace(at, key.size(), value);
    }
    const int bad_line = int(std::count(script.begin(), script.end(), '\n')) + 1;
    std::istringstream in(script);
    std::ostringstream out;
    script::Interpreter interp(out);
    try {
      interp.RunStream(in, "case.wob", kData);
      ADD_FAILURE() << "no error for:\n" << script << "\n(wanted " << c.expected << ")";
    } catch (const formats::ParseError& e) {
      const std::string what = e.what();
      if (c.expected.find("cannot open") == std::string::npos) {
        EXPECT_EQ(e.file(), "case.wob") << what;
        EXPECT_EQ(e.line(), bad_line) << what;
      }
      EXPECT_NE(what.find(c.expected), std::string::npos) << "got: " << what << "\nwanted: " << c.expected;
    }
  }
}

TEST(Interpreter, NearestUsesEditDistanceAndKnowsWhenNothingIsClose) {
  EXPECT_EQ(script::Interpreter::Nearest("simu", {"simul", "set", "save"}), "simul");
  EXPECT_EQ(script::Interpreter::Nearest("asign", {"assign", "anneal"}), "assign");
  EXPECT_EQ(script::Interpreter::Nearest("xyzzyqwerty", {"assign", "anneal"}), "");
  // every documented command and parameter is known to the interpreter: none is "unknown"
  for (const script::CommandInfo& c : script::Interpreter::Commands())
    EXPECT_EQ(script::Interpreter::Nearest(c.name, {c.name}), c.name);
}

// `help` is a command like any other, so a script, piped stdin and the prompt all print the
// command table: every command's usage and help once, and the parameters of set.
TEST(Interpreter, HelpPrintsTheCommandTable) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in("help\n");
  interp.RunStream(in, "h.wob", "");
  EXPECT_EQ(out.str(), script::Interpreter::Help());
  for (const script::CommandInfo& c : script::Interpreter::Commands()) {
    EXPECT_NE(out.str().find("  " + c.usage + "\n      " + c.summary + "\n"), std::string::npos) << c.name;
    EXPECT_EQ(std::count_if(script::Interpreter::Commands().begin(), script::Interpreter::Commands().end(),
                            [&](const script::CommandInfo& d) { return d.name == c.name; }),
              1)
        << c.name << " is listed twice";
  }
  EXPECT_NE(out.str().find("parameters of set: gravity ground"), std::string::npos) << out.str();
}

// §4.10.1: a keyframed run hands over to simulation with the q and q̇ it had.
TEST(Interpreter, KeyframesHandOverContinuouslyInQAndQdot) {
  const std::string setup = "load_obj " + kData + "/table.obj\nload_def " + kData +
                            "/table_modes.def\nset gravity F\nset ground F\nset integrator rk4\nset dt 1e-4\n"
                            "trans 10 20 0\nhold 0 0\nkey 0\nkey 0.3 bend=0.1 shear=-0.05\nkey 0.5 bend=0.15 shear=0.1\n"
                            "keyframe\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(setup);
  interp.RunStream(in, "keys.wob", kData);
  const Eigen::VectorXd q0 = interp.q(), qd0 = interp.qd();
  EXPECT_NEAR(interp.time(), 0.5, 1e-12);
  EXPECT_NEAR(q0[kRigidDofs], 0.15, 1e-12);
  EXPECT_NEAR(qd0[kRigidDofs], 0.05 / 0.2, 1e-12);      // slope of the last bend segment
  EXPECT_NEAR(qd0[kRigidDofs + 1], 0.15 / 0.2, 1e-12);  // and of the shear
  // the left foot was held at its start position (10, 20)
  EXPECT_NEAR((control::PointAt(*interp.body(), {0, 0}, q0) - Eigen::Vector2d(10, 20)).norm(), 0.0, 1e-9);
  // one simulation step later: q moved by q̇ Δt to first order and q̇ changed by O(Δt)
  std::istringstream step("simul 1e-4\n");
  interp.RunStream(step, "keys.wob", kData);
  const double dt = 1e-4;
  EXPECT_LT((interp.q() - q0 - dt * qd0).norm(), 1e-3 * dt * qd0.norm());
  EXPECT_LT((interp.qd() - qd0).norm(), 1e-2 * qd0.norm());
}

// `save` writes a script that rebuilds the setup; running it gives the same motion.
TEST(Interpreter, SavedScriptReplaysTheSameMotion) {
  const auto dir = std::filesystem::temp_directory_path() / "wobble_script_test";
  std::filesystem::create_directories(dir);
  const std::string saved = (dir / "replay.wob").string();
  const std::string setup = "load_obj " + kData + "/table.obj\nload_def " + kData +
                            "/table_modes.def\nset integrator thesis\nset dt 0.01\nset grconst 45000\nassign 1 4e7 4e6\n"
                            "set g 12\nterrain -500 30 -200 -10 -200 -40 600 -40\nterrain_face 1 frsin 0.5 grdam 700\n"
                            "terrain_face 3 grconst 60000\n"
                            "trans 0 0.1 0\npose 0.2 -0.1 0.3\npose -0.1 0.1 0.4\nset end 3\nsave " + saved + "\nsimul\n";
  std::ostringstream out1, out2;
  script::Interpreter a(out1), b(out2);
  std::istringstream in(setup);
  a.RunStream(in, "a.wob", kData);
  b.RunFile(saved);
  ASSERT_TRUE(b.world_options().params.ground.terrain);  // the terrain and its faces' own parameters
  EXPECT_TRUE(a.world_options().params.ground == b.world_options().params.ground);
  EXPECT_EQ(b.world_options().params.gravity, Eigen::Vector3d(0, -12, 0));
  EXPECT_EQ(a.q(), b.q());
  EXPECT_EQ(a.qd(), b.qd());
  EXPECT_EQ(a.control_energy(), b.control_energy());
  EXPECT_GT(a.control_energy(), 0.0);
}

TEST(Interpreter, OutputWritesOneRowPerRecordedStep) {
  const auto dir = std::filesystem::temp_directory_path() / "wobble_script_test";
  const std::string csv = (dir / "out.csv").string();
  std::filesystem::remove(csv);
  const std::string setup = "load_obj " + kData + "/table.obj\nload_def " + kData +
                            "/table_modes.def\nset dt 0.01\ntrans 0 50 0\noutput " + csv + " 10\nsimul 1\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(setup);
  interp.RunStream(in, "o.wob", kData);
  std::ifstream f(csv);
  std::string header, line;
  std::getline(f, header);
  EXPECT_EQ(header.rfind("t,tx,ty,theta,bend,shear,vsquash,hsquash,dtx,", 0), 0u) << header;  // the one schema: modes by name
  int rows = 0;
  while (std::getline(f, line)) ++rows;
  EXPECT_EQ(rows, 11);  // the start and every 10th of 100 steps
  EXPECT_FALSE(std::filesystem::exists(csv + ".tmp"));
}

}  // namespace
}  // namespace wobble

namespace wobble {
namespace {

// A data/ script with its ${NAME}s filled, run in a fresh temporary working folder (where its
// outputs land) with a render hook that keeps what `render` asked for.
struct DataScriptRun {
  std::ostringstream out;
  script::Interpreter interp{out};
  script::RenderRequest drawn;
  std::filesystem::path dir;
};
std::unique_ptr<DataScriptRun> RunDataScript(const std::string& name, const std::map<std::string, std::string>& values = {}) {
  auto run = std::make_unique<DataScriptRun>();
  run->dir = std::filesystem::temp_directory_path() / ("wobble_" + name);
  std::filesystem::remove_all(run->dir);
  std::filesystem::create_directories(run->dir);
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(run->dir);
  DataScriptRun* r = run.get();
  r->interp.SetRenderHook([r](const script::RenderRequest& request) { r->drawn = request; });
  std::ifstream file(kData + "/" + name);
  std::stringstream text;
  text << file.rdbuf();
  std::istringstream in(script::ExpandVariables(text.str(), values, name));
  r->interp.RunStream(in, name, kData);
  std::filesystem::current_path(cwd);
  return run;
}

// Fig. 4.12: the keyframed jump hands over to the simulation; the table leaves the cliff top
// (y = 300 up to x = 340, a terrain face, as is the cliff and the valley floor y = 0: no mass
// point goes below the top while over it after the hand-over), lands on the valley floor on its
// feet and comes to rest. Criteria: upright throughout (|θ| < 0.01 rad after the hand-over),
// and at t = 3: |θ| < 1e-3, |ṫ| < 0.1 cm/s, |θ̇| < 1e-3, kinetic energy below 1e-4 of m g h
// (h = 300, the cliff; g = 981 cm/s²), both feet on the floor (within 1) past the cliff.
TEST(CliffJump, LeavesTheCliffLandsUprightOnTheFloorAndSettles) {
  const std::unique_ptr<DataScriptRun> cliff = RunDataScript("table_cliff.wob");
  script::Interpreter& interp = cliff->interp;
  const script::RenderRequest& drawn = cliff->drawn;
  const std::filesystem::path& dir = cliff->dir;
  ASSERT_TRUE(drawn.trajectory);
  const record::Trajectory& states = *drawn.trajectory;
  const BodyModel& table = *states.bodies()[0].ffd<2>();  // bend, shear, vsquash: every mode of the two runs
  ASSERT_EQ(table.num_modes(), 3);
  EXPECT_EQ(drawn.dir, "out/demo");
  ASSERT_TRUE(interp.world_options().params.ground.terrain);  // the scene's terrain reaches the renderer
  EXPECT_TRUE(drawn.world.params.ground == interp.world_options().params.ground);
  const double hand_over = 0.46;  // the last key
  // the CSV and the render request carry the same states (one column per mode, by name)
  std::ifstream f(dir / "out/demo/table_cliff.csv");
  std::string line;
  std::getline(f, line);
  double lowest_over_cliff = 1e9, landed_at = -1, max_tilt = 0;
  size_t rows = 0;
  while (std::getline(f, line)) {
    std::stringstream ss(line);
    std::vector<double> v;
    for (std::string x; std::getline(ss, x, ',');) v.push_back(std::stod(x));
    ASSERT_EQ(v.size(), size_t(states.num_columns()));  // the trajectory schema: the CSV is the render request's trajectory
    const Eigen::VectorXd q = Eigen::Map<const Eigen::VectorXd>(v.data() + 1, table.num_q());
    ASSERT_TRUE(q.allFinite());
    ASSERT_LT(rows, size_t(states.size()));
    EXPECT_NEAR(states.time(int(rows)), v[0], 1e-12);
    EXPECT_LT((states.q(int(rows), 0) - q).norm(), 1e-9 * (1 + q.norm()));
    ++rows;
    if (v[0] <= hand_over + 1e-9) continue;
    EXPECT_EQ(q[kRigidDofs + 1], 0.0);  // the shear left at the hand-over, at 0
    max_tilt = std::max(max_tilt, std::abs(q[2]));
    for (int k = 0; k < table.num_points(); ++k) {
      const Eigen::Vector2d p = control::PointAt(table, table.lattice_coords(k), q);
      if (p.x() <= 340) lowest_over_cliff = std::min(lowest_over_cliff, p.y() - 300);
      if (p.y() < 1 && landed_at < 0) landed_at = v[0];
    }
  }
  EXPECT_EQ(rows, size_t(461 + 2540));  // keyframes at t = 0 .. 0.46, then 2.54 s of simulation
  EXPECT_EQ(size_t(states.size()), rows);
  EXPECT_GT(lowest_over_cliff, 0.0);
  EXPECT_GT(landed_at, hand_over + 0.5);  // about a second in the air
  EXPECT_LT(landed_at, 2.5);
  EXPECT_LT(max_tilt, 0.01);
  EXPECT_DOUBLE_EQ(interp.time(), 3.0);
  // at rest on its feet
  const Eigen::VectorXd& q = interp.q();
  const Eigen::VectorXd& qd = interp.qd();
  EXPECT_LT(std::abs(q[2]), 1e-3);
  EXPECT_LT(qd.head<2>().norm(), 0.1);
  EXPECT_LT(std::abs(qd[2]), 1e-3);
  World w(interp.world_options());
  w.AddBody(std::make_shared<BodyModel>(*interp.body()));
  w.SetState(0, q, qd);
  const double mgh = table.moments().m * 981 * 300.0;
  EXPECT_LT(w.ComputeEnergies(0).kinetic, 1e-4 * mgh);
  const Eigen::VectorXd q3 = states.q(states.size() - 1, 0);
  for (int foot : {5, 8}) {
    const Eigen::Vector2d p = control::PointAt(table, table.lattice_coords(foot), q3);
    EXPECT_NEAR(p.y(), 0.0, 1.0);
    EXPECT_GT(p.x(), 340.0);
  }
}

// Figs. 4.10/4.11: a rigid pot (no modes) thrown onto a level floor. Friction off: the floor
// pushes only along its normal, so from the moment it lands the centre of mass keeps its
// horizontal speed (the thesis scheme integrates (t, θ), not the centre of mass, so while the
// pot rocks it keeps it to O(Δt): halving Δt must shrink the drift at least 1.6-fold). Friction
// on: the slide stops and the pot rests upright.
TEST(PotFriction, FrictionOffKeepsTheHorizontalSpeedOnSlidesStopsUpright) {
  struct Slide {
    double drift, end_speed, end_tilt;
  };
  auto slide = [](const std::map<std::string, std::string>& values, const std::string& expected_dir) {
    const std::unique_ptr<DataScriptRun> script = RunDataScript("fig4_10_11_pot.wob", values);
    EXPECT_EQ(script->drawn.dir, expected_dir);
    if (!script->drawn.trajectory) throw std::runtime_error("the pot script rendered nothing");
    const record::Trajectory& run = *script->drawn.trajectory;
    const BodyModel& pot = *run.bodies()[0].ffd<2>();
    EXPECT_EQ(pot.num_modes(), 0);
    const Eigen::Vector2d c = pot.moments().c0 / pot.moments().m;
    auto com_vx = [&](int k) {  // ṫ + θ̇ R S c̄, its x
      const Eigen::VectorXd q = run.q(k, 0), qd = run.qd(k, 0);
      return qd[0] - qd[2] * (std::sin(q[2]) * c.x() + std::cos(q[2]) * c.y());
    };
    int landed = -1;
    for (int k = 0; k < run.size() && landed < 0; ++k)
      if (run.contacts(k, 0) > 0) landed = k;
    EXPECT_GT(landed, 0);
    Slide s{0, 0, 0};
    for (int k = std::max(landed, 0); k < run.size(); ++k) s.drift = std::max(s.drift, std::abs(com_vx(k) / com_vx(landed) - 1));
    s.end_speed = com_vx(run.size() - 1);
    s.end_tilt = run.q(run.size() - 1, 0)[2];
    return s;
  };
  const Slide off = slide({}, "out/fig4_10");
  const Slide off_fine = slide({{"DT", "0.0005"}}, "out/fig4_10");
  EXPECT_LT(off.drift, 2e-3);
  EXPECT_LT(off_fine.drift, off.drift / 1.6);
  EXPECT_GT(off.end_speed, 100.0);  // still sliding at the end
  const Slide on = slide({{"FRSIN", "0.8"}, {"FIG", "fig4_11"}}, "out/fig4_11");
  EXPECT_LT(std::abs(on.end_speed), 0.1);
  EXPECT_LT(std::abs(on.end_tilt), 1e-3);  // upright
}

// A script's runs are drawn only through the hook the CLI installs; a script with nothing run,
// or a program without a renderer, is told so with the line.
TEST(ScriptRender, ErrorsNameTheLine) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream none("load_obj table.obj\nload_def bend.def\nrender out\n");
  try {
    interp.RunStream(none, "r.wob", kData);
    FAIL() << "expected an error";
  } catch (const formats::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("r.wob:3: render: nothing to draw yet"), std::string::npos) << e.what();
  }
  std::istringstream no_hook("simul 0.1\nrender out\n");
  try {
    interp.RunStream(no_hook, "r.wob", kData);
    FAIL() << "expected an error";
  } catch (const formats::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("r.wob:2: render: this program has no renderer"), std::string::npos) << e.what();
  }
  interp.SetRenderHook([](const script::RenderRequest&) { throw std::runtime_error("disk full"); });
  std::istringstream failing("render out vtp\n");
  try {
    interp.RunStream(failing, "r.wob", kData);
    FAIL() << "expected an error";
  } catch (const formats::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("r.wob:1: render: disk full"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace wobble

namespace wobble {
namespace {

// A 3D object in a script (issue 15): the table of data/table3.obj (no mesh: lib reads it).
void Run3d(script::Interpreter& interp, const std::string& lines, bool with_modes = true) {
  std::istringstream in("load_obj " + kData + "/table3.obj\n" +
                        (with_modes ? "load_def " + kData + "/table3_modes.def3\n" : std::string()) + lines);
  interp.RunStream(in, "three.wob", kData);
}

TEST(Script3d, FreeFallAndSpinFollowTheClosedForms) {
  // no ground: the centre of mass falls as y0 − g t²/2 while the body spins about it at a
  // constant ω about the vertical (a principal axis of the symmetric table): the body origin is
  // a lattice corner, so ṫ = −ω × c keeps the centre still but for gravity
  std::ostringstream out;
  script::Interpreter interp(out);
  const double g = 9.81, t = 0.8, w = 0.5;
  Run3d(interp, "set ground F\nset integrator rk4\nset dt 1e-3\n", false);  // rigid: no modes to excite
  const BodyModelN<3> body(formats::ReadObjectFile<3>(kData + "/table3.obj"), {});
  const Eigen::Vector3d c = body.moments().c0 / body.moments().m;
  const Eigen::Vector3d v = -Eigen::Vector3d(0, w, 0).cross(c);  // ṫ = −ω × c: the centre at rest
  std::ostringstream lines;
  lines << "set ground F\nset integrator rk4\nset dt 1e-3\nset_vec q 0 50 0 0 0 0\nset_vec dq " << v.x() << " "
        << v.y() << " " << v.z() << " 0 " << w << " 0\nsimul " << t << "\n";
  Run3d(interp, lines.str(), false);
  const Eigen::VectorXd q = interp.q();
  ASSERT_EQ(q.size(), 6);
  // the orientation turned by w t about y; the centre (t + R c) on the parabola
  const Eigen::Vector3d r = q.segment<3>(3);
  EXPECT_NEAR(r.y(), w * t, 1e-9);
  EXPECT_NEAR(r.x(), 0.0, 1e-9);
  const Eigen::Quaterniond R(Eigen::AngleAxisd(r.norm(), r.normalized()));
  const Eigen::Vector3d centre = q.head<3>() + R * c;
  EXPECT_LT((centre - (Eigen::Vector3d(0, 50, 0) + c - Eigen::Vector3d(0, 0.5 * g * t * t, 0))).norm(), 1e-6);
  EXPECT_NEAR(interp.time(), t, 1e-12);
}

TEST(Script3d, PlacementTurnsAboutZAndPoseGraphsKeepTheMomentum) {
  std::ostringstream out;
  script::Interpreter interp(out);
  Run3d(interp, "set ground F\nset gravity F\ntrans 10 20 0.3\nset_vec q 1 0 0 0 0 0 0 0 0 0\n");
  // trans x y θ: t = (x, y, 0) + Rz(θ) t_q, the orientation Rz(θ) (rotation vector (0, 0, θ))
  Eigen::VectorXd q = interp.q();
  EXPECT_LT((q.head<3>() - Eigen::Vector3d(10 + std::cos(0.3), 20 + std::sin(0.3), 0)).norm(), 1e-14);
  EXPECT_LT((q.segment<3>(3) - Eigen::Vector3d(0, 0, 0.3)).norm(), 1e-14);
  // a pose graph on the bend: internal forces only, so the centre of mass stays where it was
  const BodyDefN<3> def = formats::ReadObjectFile<3>(kData + "/table3.obj");
  const BodyModelN<3> body(def, formats::ReadDeformationFile(kData + "/table3_modes.def3", def.lattice));
  auto centre = [&](const Eigen::VectorXd& x) {
    const Eigen::Vector3d r = x.segment<3>(3);
    const Eigen::Quaterniond R(Eigen::AngleAxisd(r.norm(), r.normalized()));
    const MassMomentsN<3>& mm = body.moments();
    return Eigen::Vector3d(x.head<3>() + R * ((mm.c0 + mm.C * x.tail(4)) / mm.m));
  };
  const Eigen::Vector3d c0 = centre(q);
  Run3d(interp, "trans 10 20 0.3\nset_vec q 1 0 0 0 0 0 0 0 0 0\nmode bend active\nmode shear passive\npose 0.2 0.5\npose -0.1 0.5\n"
                "set integrator rk4\nset dt 1e-4\nsimul 0.4\n");
  q = interp.q();
  EXPECT_GT(q[6], 1e-3);  // the bend moved towards the first pose's 0.2
  EXPECT_GT(interp.control_energy(), 0.0);  // the PD forces' work is counted in 3D too
  EXPECT_LT((centre(q) - c0).norm(), 1e-9 * c0.norm());
}

TEST(Script3d, A3dObjectJoinsAWitkinWelchSceneNailedAndAttached) {
  // the 3D table hung by the centre of its top, a linear box attached to one foot: the nail
  // holds (the multiplier step with feedback), and both fall only as the constraints allow
  std::ostringstream out;
  script::Interpreter interp(out);
  Run3d(interp, "set dt 1e-3\nffd t\npoint p t 0.5 1 0.5\npoint foot t 0 0 0\nnail n1 p\n"
                "linear b 3d affine box 20 20 20 at 0 -40 0\npoint bc b 0 0 0\nattach a1 foot bc\nsimul 0.5\n", false);
  const Eigen::VectorXd p = interp.scene().Point("p");
  EXPECT_LT((p - Eigen::Vector3d(150, 100, 100)).norm(), 1e-3);
  EXPECT_LT((interp.scene().Point("foot") - interp.scene().Point("bc")).norm(), 0.5);  // pulled together from 40 apart
  EXPECT_LT(interp.scene().Point("bc")[1], 0.0);  // the box hangs below the table's foot
}

TEST(Script3d, ASpringAtTheCentreOfMassOscillatesWithItsPeriod) {
  // no gravity, no ground, no modes: a spring from the centre of mass to the world point where
  // the centre rests pulls it back as x(t) = A cos(√(k/m) t), and never turns the body
  const BodyModelN<3> body(formats::ReadObjectFile<3>(kData + "/table3.obj"), {});
  const double m = body.moments().m, k = 5e4, A = 12.0;
  const Eigen::Vector3d c = body.moments().c0 / m, u = body.lattice().LocalCoords(c);
  const double omega = std::sqrt(k / m), period = 2 * M_PI / omega, t = 0.75 * period;
  std::ostringstream lines;
  lines.precision(17);
  lines << "set gravity F\nset ground F\nset integrator rk4\nset dt 1e-4\nset_vec q " << A << " 0 0 0 0 0\n"
        << "spring " << u.x() << " " << u.y() << " " << u.z() << " " << c.x() << " " << c.y() << " " << c.z() << " " << k
        << "\nsimul " << t << "\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  Run3d(interp, lines.str(), false);
  const Eigen::VectorXd q = interp.q();
  EXPECT_NEAR(q[0], A * std::cos(omega * interp.time()), 1e-7 * A);
  EXPECT_LT(q.segment<3>(1).norm() + q.segment<3>(3).norm(), 1e-9);
  // the script's 3D spring has the 2D form's errors
  std::istringstream bad("spring 0.5 0.5 2 0 0 0\n");
  EXPECT_THROW(interp.RunStream(bad, "three.wob", kData), formats::ParseError);
}

TEST(Script3d, KeyframesHoldAPointAndHandOverContinuously) {
  // the 3D table keyframed from rest with its foot (0, 0, 0) held: the foot stays where it was,
  // the amplitudes reach the last key, and the hand-over carries the last segment's slope
  std::ostringstream out;
  script::Interpreter interp(out);
  Run3d(interp, "set gravity F\nset ground F\nset dt 1e-3\nset_vec q 10 20 30 0.1 0.4 -0.2 0 0 0 0\nhold 0 0 0\n"
                "key 0\nkey 0.3 bend=0.2 twist=-0.1\nkey 0.5 bend=0.3 twist=0.1\n");
  const BodyDefN<3> def = formats::ReadObjectFile<3>(kData + "/table3.obj");
  const BodyModelN<3> body(def, formats::ReadDeformationFile(kData + "/table3_modes.def3", def.lattice));
  auto foot = [&](const Eigen::VectorXd& q) {
    const Eigen::Vector3d r = q.segment<3>(3);
    const Eigen::Quaterniond R(Eigen::AngleAxisd(r.norm(), r.normalized()));
    Eigen::Vector3d b0;
    Mat3D<double> B;
    body.LocalBasis(Eigen::Vector3d::Zero(), &b0, &B);
    return Eigen::Vector3d(q.head<3>() + R * (b0 + B * q.tail(4)));
  };
  const Eigen::Vector3d foot0 = foot(interp.q());
  std::istringstream run("keyframe\n");
  interp.RunStream(run, "three.wob", kData);
  const Eigen::VectorXd q = interp.q(), qd = interp.qd();
  EXPECT_NEAR(interp.time(), 0.5, 1e-12);
  EXPECT_LT((foot(q) - foot0).norm(), 1e-9 * foot0.norm());
  EXPECT_NEAR(q[6 + 0], 0.3, 1e-12);   // bend
  EXPECT_NEAR(q[6 + 3], 0.1, 1e-12);   // twist
  EXPECT_NEAR(qd[6 + 0], 0.1 / 0.2, 1e-12);  // the slopes of the last segment
  EXPECT_NEAR(qd[6 + 3], 0.2 / 0.2, 1e-12);
  EXPECT_LT((q.segment<3>(3) - Eigen::Vector3d(0.1, 0.4, -0.2)).norm(), 1e-12);  // the orientation kept
}

TEST(Script3d, SavedScriptReplaysTheSameMotion) {
  // `save` of a 3D object with a spring, a pose graph and a turned state: its script rebuilds
  // the setup, and running it gives the same motion to the last bit
  const auto dir = std::filesystem::temp_directory_path() / "wobble_script_test";
  std::filesystem::create_directories(dir);
  const std::string saved = (dir / "replay3.wob").string();
  std::ostringstream out1, out2;
  script::Interpreter a(out1), b(out2);
  Run3d(a, "set dt 0.005\nset codamA 1000\nassign twist 5e6 2e5\nmode shear passive\nspring 0.5 1 0.5 150 300 100 2e4 100 50\n"
           "set_vec q 5 60 -3 0.1 0.2 0.05 0.01 0 0 0\nset_vec dq 1 0 0 0 0.3 0 0 0 0 0\npose 0.1 0.3\npose -0.05 0.3\n"
           "set end 2\nsave " + saved + "\nsimul\n");
  b.RunFile(saved);
  EXPECT_EQ(a.q(), b.q());
  EXPECT_EQ(a.qd(), b.qd());
  EXPECT_EQ(a.control_energy(), b.control_energy());
  EXPECT_GT(a.control_energy(), 0.0);
}

}  // namespace
}  // namespace wobble
