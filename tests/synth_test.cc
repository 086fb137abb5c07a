// Motion synthesis (§5.1–5.2): annealing is reproducible from its seed whatever the number of
// threads, improves on the initial controller of the bounding-table scene, and the controller
// it finds makes the table travel forward in a stable periodic gait; the saved script replays it.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/scene/ffd_object.h"
#include "wobble/script/interpreter.h"
#include "wobble/core/interrupt.h"
#include "wobble/synth/anneal.h"
#ifdef WOBBLE_HAVE_PAGMO
#include "wobble/synth/cmaes.h"
#endif
#include "support/source_paths.h"

namespace wobble {
namespace {

const std::string kData = wobble::test_env::DataDir();

// data/bounding_table.wob's setup (table, modes, ground, the initial pose graph), without its
// optimisation: the tests add theirs.
const std::string kBoundingSetup =
    "load_obj table.obj\nload_def table_modes.def\nassign bend 4e7 4e6\nassign shear 4e7 4e6\n"
    "set integrator thesis\nset dt 0.01\nset grconst 45000\nset grdam 3000\nset frconst 3000\n"
    "set frsin 0.5\npose 0.1 0 0.4\npose 0 -0.1 0.4\npose -0.1 0 0.4\npose 0 0.1 0.4\n";

// Runs the scene file in a scratch folder (its outputs are relative to the working directory).
struct Scene {
  explicit Scene(const std::string& name) : interp(out) {
    dir = std::filesystem::temp_directory_path() / ("wobble_synth_" + name);
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    const auto cwd = std::filesystem::current_path();
    std::filesystem::current_path(dir);
    interp.SetRenderHook([this](const script::RenderRequest& r) { rendered.push_back(r); });  // no VTK here
    interp.RunFile(kData + "/" + name + ".wob");
    std::filesystem::current_path(cwd);
  }
  std::ostringstream out;
  script::Interpreter interp;
  std::filesystem::path dir;
  std::vector<script::RenderRequest> rendered;  // what the script's `render` lines asked for
};

TEST(Annealing, SameSeedSameResultWhateverTheThreadCount) {
  // the scene's setup, a short anneal, with 1 and 2 threads and twice with 2
  std::vector<synth::AnnealResult> results;
  for (int threads : {1, 2, 2}) {
    std::ostringstream out;
    script::Interpreter interp(out);
    std::istringstream in(kBoundingSetup + "set seed 11\nset batch 4\nset threads " + std::to_string(threads) + "\nanneal 6\n");
    interp.RunStream(in, "seeded.wob", kData);
    results.push_back(*interp.last_anneal());
  }
  for (size_t i = 1; i < results.size(); ++i) {
    EXPECT_EQ(results[i].best_outcome.cost, results[0].best_outcome.cost);
    ASSERT_EQ(results[i].best.poses.size(), results[0].best.poses.size());
    for (size_t p = 0; p < results[0].best.poses.size(); ++p) {
      EXPECT_EQ(results[i].best.poses[p], results[0].best.poses[p]);
      EXPECT_EQ(results[i].best.durations[p], results[0].best.durations[p]);
    }
    ASSERT_EQ(results[i].history.size(), results[0].history.size());
    for (size_t h = 0; h < results[0].history.size(); ++h) EXPECT_EQ(results[i].history[h].current, results[0].history[h].current);
  }
  EXPECT_EQ(results[0].trials, 1 + 6 * 4);
}

// A batch worker keeps one world and puts its start data back for every trial (TrialWorld):
// each trial of a sequence, whatever ran before it in that world (a graph the controller
// refuses, a graph that shakes the table apart, another gait), is the trial a fresh world gives,
// bit for bit.
TEST(Annealing, AWorkersWorldRepeatsAFreshWorldsTrials) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(kBoundingSetup);
  interp.RunStream(in, "setup.wob", kData);
  synth::Problem problem = interp.SynthesisProblem();
  problem.steps = 300;  // 3 s: a cycle and a half of the gait
  control::PoseGraph gait = interp.pose_graph();
  control::PoseGraph faster = gait, wrong = gait, violent = gait;
  for (double& d : faster.durations) d *= 0.7;
  wrong.poses[0].resize(wrong.poses[0].size() + 1);  // one target too many: refused
  for (Eigen::VectorXd& pose : violent.poses) pose *= 40.0;
  synth::TrialWorld worker(problem);
  int failed = 0;
  for (const control::PoseGraph* g : {&gait, &wrong, &violent, &faster, &gait, &violent, &faster}) {
    const synth::TrialOutcome reused = worker.Run(*g), fresh = synth::RunTrial(problem, *g);
    EXPECT_EQ(reused.ok, fresh.ok);
    EXPECT_EQ(reused.cost, fresh.cost);
    EXPECT_EQ(reused.distance, fresh.distance);
    EXPECT_EQ(reused.speed, fresh.speed);
    EXPECT_EQ(reused.energy, fresh.energy);
    EXPECT_EQ(reused.failure, fresh.failure);
    failed += !fresh.ok;
  }
  EXPECT_GE(failed, 1);  // the refused graph at least: a failed trial is among those repeated
}

TEST(Annealing, RestartsKeepTheBestOfIndependentSeeds) {
  // `set restarts 3` is the best of three anneals from seeds 11, 12, 13 run one by one
  const std::string setup = kBoundingSetup + "set trial_steps 400\nset batch 4\n";
  std::vector<synth::AnnealResult> alone;
  for (int seed : {11, 12, 13}) {
    std::ostringstream out;
    script::Interpreter interp(out);
    std::istringstream in(setup + "set seed " + std::to_string(seed) + "\nanneal 5\n");
    interp.RunStream(in, "alone.wob", kData);
    alone.push_back(*interp.last_anneal());
  }
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(setup + "set seed 11\nset restarts 3\nanneal 5\n");
  interp.RunStream(in, "restarts.wob", kData);
  const synth::AnnealResult& r = *interp.last_anneal();
  size_t best = 0;
  for (size_t k = 1; k < alone.size(); ++k)
    if (alone[k].best_outcome.cost < alone[best].best_outcome.cost) best = k;
  EXPECT_EQ(r.best_outcome.cost, alone[best].best_outcome.cost);
  EXPECT_EQ(r.trials, 3 * (1 + 5 * 4));
  ASSERT_EQ(r.history.size(), alone[best].history.size());
  for (size_t h = 0; h < r.history.size(); ++h) EXPECT_EQ(r.history[h].current, alone[best].history[h].current);
  for (size_t p = 0; p < r.best.poses.size(); ++p) EXPECT_EQ(r.best.poses[p], alone[best].best.poses[p]);
  // the script's pose graph is the best restart's
  EXPECT_EQ(interp.pose_graph().durations, alone[best].best.durations);
}

TEST(Annealing, TableCostFunctionsFollowTable51) {
  synth::TrialOutcome o;
  o.ok = true;
  o.distance = 4.0;
  o.speed = 9.0;
  o.energy = 6e7;
  synth::CostFunction c;
  c.kind = synth::CostKind::kEnergyPerSqrtDistanceSpeed;
  c.scale = 5e7;
  EXPECT_DOUBLE_EQ(synth::EvaluateCost(c, o), 6e7 / (5e7 * 6.0));
  c.kind = synth::CostKind::kEnergyPerSqrtDistance;
  EXPECT_DOUBLE_EQ(synth::EvaluateCost(c, o), 6e7 / (5e7 * 2.0));
  c.kind = synth::CostKind::kEnergyPerDistance;
  EXPECT_DOUBLE_EQ(synth::EvaluateCost(c, o), 6e7 / 4.0);
  c.kind = synth::CostKind::kInverseDistance;
  EXPECT_DOUBLE_EQ(synth::EvaluateCost(c, o), 0.25);
  // q_x q̇_x < 0: the high cost of the thesis
  c.kind = synth::CostKind::kEnergyPerSqrtDistanceSpeed;
  o.speed = -1.0;
  EXPECT_EQ(synth::EvaluateCost(c, o), c.high);
  o.speed = 9.0;
  o.distance = -4.0;
  EXPECT_EQ(synth::EvaluateCost(c, o), c.high);
  o.distance = 4.0;
  o.ok = false;  // the simulation stopped
  EXPECT_EQ(synth::EvaluateCost(c, o), c.high);
}

TEST(BoundingTable, AnnealingImprovesAndFindsAStableForwardGaitThatTheSavedScriptReplays) {
  Scene scene("bounding_table");
  const synth::AnnealResult& r = *scene.interp.last_anneal();
  EXPECT_EQ(r.trials, 1 + 60 * 8);
  EXPECT_LT(r.best_outcome.cost, 0.25 * r.initial_outcome.cost);
  EXPECT_GT(r.best_outcome.distance, 0.0);
  // Fig. 5.4/5.5: the best cost never rises
  for (size_t i = 1; i < r.history.size(); ++i) EXPECT_LE(r.history[i].best, r.history[i - 1].best);
  EXPECT_TRUE(std::filesystem::exists(scene.dir / "out/bounding_table/anneal.csv"));

  // the gait: centre-of-mass travel per cycle, positive in every cycle within the trial's
  // horizon, and settled into a periodic motion later on (cycle to cycle within 25%)
  const synth::Problem problem = scene.interp.SynthesisProblem();
  const std::vector<double> early = synth::DistancePerCycle(problem, r.best, 2, 5);
  for (double d : early) EXPECT_GT(d, 0.0) << "early cycle";
  const std::vector<double> late = synth::DistancePerCycle(problem, r.best, 40, 8);
  ASSERT_EQ(late.size(), 8u);
  double lo = late[0], hi = late[0], sum = 0;
  for (double d : late) {
    lo = std::min(lo, d);
    hi = std::max(hi, d);
    sum += d;
  }
  EXPECT_GT(lo, 0.0);
  EXPECT_LT(hi - lo, 0.25 * sum / late.size()) << "per cycle from " << lo << " to " << hi;

  // Fig. 5.3's filmstrip: cycle 40 of the best controller's pose graph, which the 90 s run
  // completes (a cycle starts each time the first pose comes back)
  ASSERT_EQ(scene.rendered.size(), 1u);
  const script::RenderRequest& strip = scene.rendered[0];
  EXPECT_EQ(strip.what, "filmstrip");
  EXPECT_NE(std::find(strip.options.begin(), strip.options.end(), std::make_pair(std::string("filmstrip-cycle"), std::string("40,6"))),
            strip.options.end());
  const record::Trajectory& played = *strip.trajectory;
  int first = -1, cycles = 0;
  for (int k = 0; k < played.size(); ++k) {
    if (first < 0) first = played.pose(k);
    else cycles += played.pose(k) == first && played.pose(k - 1) != first;
  }
  EXPECT_NEAR(played.time(played.size() - 1) - played.time(0), 90.0, 1e-9);
  EXPECT_GE(cycles, 41);

  // the saved controller replays the best trial exactly
  std::ostringstream out;
  script::Interpreter replay(out);
  replay.RunFile((scene.dir / "out/bounding_table/best.wob").string());
  double x0, v0, x1, v1;
  synth::CenterOfMassX(*replay.body(), problem.q0, problem.qd0, &x0, &v0);
  synth::CenterOfMassX(*replay.body(), replay.q(), replay.qd(), &x1, &v1);
  EXPECT_DOUBLE_EQ(x1 - x0, r.best_outcome.distance);
  EXPECT_DOUBLE_EQ(replay.control_energy(), r.best_outcome.energy);
}

#ifdef WOBBLE_HAVE_PAGMO
// CMA-ES on the same problem: reproducible from its seed, better than where it started, and it
// counts its simulations (the budget the comparison with annealing is made on).
TEST(Cmaes, ReproducibleFromItsSeedAndImprovesOnTheInitialController) {
  std::vector<synth::AnnealResult> results;
  for (int run = 0; run < 2; ++run) {
    std::ostringstream out;
    script::Interpreter interp(out);
    std::istringstream in(kBoundingSetup + "set seed 5\nset batch 6\ncmaes 8\n");
    interp.RunStream(in, "cmaes.wob", kData);
    results.push_back(*interp.last_anneal());
  }
  EXPECT_EQ(results[0].best_outcome.cost, results[1].best_outcome.cost);
  for (size_t p = 0; p < results[0].best.poses.size(); ++p) EXPECT_EQ(results[0].best.poses[p], results[1].best.poses[p]);
  EXPECT_EQ(results[0].trials, 6 + 8 * 6);
  EXPECT_LT(results[0].best_outcome.cost, results[0].initial_outcome.cost);
  for (size_t i = 1; i < results[0].history.size(); ++i) EXPECT_LE(results[0].history[i].best, results[0].history[i - 1].best);

  // Each generation simulated together (the rehearsal of cmaes.cc) is the same run as pagmo
  // asking for one trial after the other, bit for bit, on one thread or two.
  {
    std::ostringstream out;
    script::Interpreter interp(out);
    std::istringstream setup(kBoundingSetup + "set trial_steps 400\n");
    interp.RunStream(setup, "cmaes.wob", kData);
    synth::CmaesOptions o;
    o.seed = 9;
    o.generations = 6;
    o.population = 7;
    o.batch_generations = false;
    const synth::AnnealResult serial = synth::Cmaes(interp.SynthesisProblem(), interp.pose_graph(), o);
    o.batch_generations = true;
    const synth::AnnealResult batched = synth::Cmaes(interp.SynthesisProblem(), interp.pose_graph(), o);
    EXPECT_EQ(batched.trials, serial.trials);
    EXPECT_EQ(batched.trials, 7 + 6 * 7);
    EXPECT_EQ(batched.best_outcome.cost, serial.best_outcome.cost);
    ASSERT_EQ(batched.history.size(), serial.history.size());
    for (size_t g = 0; g < serial.history.size(); ++g) {
      EXPECT_EQ(batched.history[g].candidate, serial.history[g].candidate) << "generation " << g;
      EXPECT_EQ(batched.history[g].best, serial.history[g].best) << "generation " << g;
    }
    for (size_t p = 0; p < serial.best.poses.size(); ++p) {
      EXPECT_EQ(batched.best.poses[p], serial.best.poses[p]);
      EXPECT_EQ(batched.best.durations[p], serial.best.durations[p]);
    }
    EXPECT_LT(serial.best_outcome.cost, serial.initial_outcome.cost);  // a run that moved
  }

  // Ctrl-C before the first generation: the initial population only, marked interrupted
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream setup("load_obj table.obj\nload_def table_modes.def\npose 0.1 0 0.4\npose 0 -0.1 0.4\n");
  interp.RunStream(setup, "cmaes.wob", kData);
  synth::CmaesOptions o;
  o.generations = 5;
  o.population = 6;
  RequestInterrupt();
  const synth::AnnealResult stopped = synth::Cmaes(interp.SynthesisProblem(), interp.pose_graph(), o);
  ClearInterrupt();
  EXPECT_TRUE(stopped.interrupted);
  EXPECT_EQ(stopped.history.size(), 1u);
}
#endif

}  // namespace
}  // namespace wobble

namespace wobble {
namespace {

// A synthesis trial of a 3D body (issue 15) measures the travel of its centre of mass: a free
// body's centre moves uniformly whatever it does about it (momentum), here spinning about an
// axis away from the centre and with its modes free to ring.
TEST(Synthesis3d, ATrialMeasuresTheUniformTravelOfAFreeBodysCentre) {
  const std::string data = wobble::test_env::DataDir();
  const BodyDefN<3> def = formats::ReadObjectFile<3>(data + "/table3.obj");
  synth::Problem p;
  p.set_body(std::make_shared<const BodyModelN<3>>(def, formats::ReadDeformationFile(data + "/table3_modes.def3", def.lattice)));
  p.world.params.gravity_on = false;
  p.world.integrator = Integrator::kRK4;
  p.world.dt = 1e-3;
  p.steps = 1000;
  p.q0 = Eigen::VectorXd::Zero(10);
  p.q0 << 0, 20, 0, 0.1, 0.3, 0, 0.05, 0, 0, 0;
  p.qd0 = Eigen::VectorXd::Zero(10);
  p.qd0 << 3, 1, 0, 0, 0.8, 0.2, 0, 0, 0, 0;
  // the centre's x velocity at the start, from the same state in a world
  World w(p.world);
  w.AddBody(p.body<3>());
  w.SetCoordinates(0, p.q0, p.qd0);
  double x0, v0;
  synth::CenterOfMassX(w, &x0, &v0);
  const synth::TrialOutcome o = synth::RunTrial(p, {});
  ASSERT_TRUE(o.ok) << o.failure;
  const double T = 1.0;
  EXPECT_NEAR(o.distance, v0 * T, 1e-8 * std::abs(v0 * T));
  EXPECT_NEAR(o.speed, v0, 1e-8 * std::abs(v0));
  EXPECT_GT(std::abs(v0 - 3.0), 1.0);  // the spin about a point off the centre moves it too
}

// The bounding table in 3D (data/bounding_table3.wob without its outputs): annealing lowers
// the cost, the gait travels forward every cycle, and the motion stays in its plane (the body
// and its in-plane modes are symmetric about z = 100: no force leaves the x-y plane).
TEST(Synthesis3d, TheBoundingTableIn3dLearnsToTravelForwardInItsPlane) {
  std::ifstream file(wobble::test_env::DataDir() + "/bounding_table3.wob");
  std::string script, line;
  while (std::getline(file, line))
    if (line.rfind("output", 0) != 0 && line.rfind("render", 0) != 0 && line.rfind("set anneal_csv", 0) != 0 &&
        line.rfind("gait", 0) != 0 && line.rfind("simul", 0) != 0)
      script += line + "\n";
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(script);
  interp.RunStream(in, "bounding_table3.wob", wobble::test_env::DataDir());
  const synth::AnnealResult& result = *interp.last_anneal();
  EXPECT_LT(result.best_outcome.cost, result.initial_outcome.cost);
  const std::vector<double> d = synth::DistancePerCycle(interp.SynthesisProblem(), interp.pose_graph(), 2, 6);
  ASSERT_EQ(d.size(), 6u);
  for (double x : d) EXPECT_GT(x, 5.0);
  std::istringstream run("simul 12\n");
  interp.RunStream(run, "bounding_table3.wob", wobble::test_env::DataDir());
  const Eigen::VectorXd q = interp.q();
  EXPECT_GT(q[0], 100.0);                                  // travelled forward
  EXPECT_LT(std::abs(q[2]) + std::abs(q[3]) + std::abs(q[4]), 1e-6);  // tz, rx, ry: still in the plane
}

}  // namespace
}  // namespace wobble
