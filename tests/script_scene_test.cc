// The interpreter's Witkin & Welch commands: every command's errors name the line and what
// was expected (and suggest near names); a scene runs, its constraints hold, its behaviours
// chain, and `render` hands the recorded frames to the hook.
#include <gtest/gtest.h>


#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "wobble/formats/heightfield_file.h"
#include "wobble/script/interpreter.h"
#include "wobble/script/variables.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

const std::string kData = wobble::test_env::DataDir();

// Runs `text` as a script named "s.wob"; returns the error message ("" when it ran).
std::string RunScript(script::Interpreter& interp, const std::string& text) {
  std::istringstream in(text);
  try {
    interp.RunStream(in, "s.wob", "");
  } catch (const formats::ParseError& e) {
    return e.what();
  }
  return "";
}

std::string RunFresh(const std::string& text) {
  std::ostringstream out;
  script::Interpreter interp(out);
  return RunScript(interp, text);
}

const char* kTwoBlocks =
    "linear a 3d affine box 0.5 0.2 0.2 at 0 0 0\n"
    "linear b 3d affine box 0.5 0.2 0.2 at 2 0 0\n"
    "linear flat 2d affine box 0.5 0.2\n"
    "point pa a 0.5 0 0\n"
    "point pb b -0.5 0 0\n"
    "point pf flat 0.5 0\n"
    "place sky 0 3 0\n"
    "path swoop 3d 0 0 0 0  1 1 1 0\n";  // lines 1-8

struct ErrorCase {
  const char* line;      // appended as line 9 (after kTwoBlocks)
  const char* expected;  // in the message, after "s.wob:9: "
};
void PrintTo(const ErrorCase& c, std::ostream* os) { *os << '"' << c.line << '"'; }

class SceneErrors : public testing::TestWithParam<ErrorCase> {};

TEST_P(SceneErrors, NameTheLineAndWhatWasExpected) {
  const ErrorCase& c = GetParam();
  const std::string message = RunFresh(std::string(kTwoBlocks) + c.line + "\n");
  EXPECT_NE(message.find(std::string("s.wob:9: ") + c.expected), std::string::npos) << "got: " << message;
}

INSTANTIATE_TEST_SUITE_P(
    EveryCommand, SceneErrors,
    testing::Values(
        // linear
        ErrorCase{"linear c 3d affine box 1 1", "expected 3 numbers for a half extent"},
        ErrorCase{"linear c 4d affine box 1 1 1", "expected 2d or 3d, got '4d'"},
        ErrorCase{"linear c 3d cubic box 1 1 1", "expected affine or quadratic, got 'cubic'"},
        ErrorCase{"linear c 3d affine sphere 1 1 1", "expected box or pyramid, got 'sphere'"},
        ErrorCase{"linear c 3d affine box 1 0 1", "expected positive sizes"},
        ErrorCase{"linear c 3d affine box 1 1 1 mas 2", "unknown option 'mas' of linear; did you mean 'mass'?"},
        ErrorCase{"linear c 3d affine box 1 1 1 grid 1", "expected grid as a whole number >= 2, got '1'"},
        ErrorCase{"linear c 3d affine box 1 1 1 ke -1", "expected a non-negative ke, got -1"},
        ErrorCase{"linear c 3d affine box 1 1 1 at 1 2", "expected 3 numbers for the position after 'at'"},
        ErrorCase{"linear a 3d affine box 1 1 1", "a body named 'a' exists already"},
        ErrorCase{"linear c 3d quadratic box 1 1 1 grid 2", "linear body 'c': the 8 mass points do not span"},
        ErrorCase{"linear c 2d", "expected 'linear NAME 2d|3d"},
        // the 3D ground
        ErrorCase{"heightfield", "expected 'heightfield FILE' or 'heightfield off'"},
        ErrorCase{"heightfield /nonexistent/hills.heightfield", "/nonexistent/hills.heightfield:0: "},
        // point, place
        ErrorCase{"point q aa 0 0 0", "no body named 'aa'; did you mean 'a'?"},
        ErrorCase{"point q a 0 0", "expected 3 undeformed coordinates for a point of the 3D body 'a'"},
        ErrorCase{"point pa a 0 0 0", "a point or place named 'pa' exists already"},
        ErrorCase{"place here 1", "expected 'place NAME X Y [Z]'"},
        ErrorCase{"place here 1 x", "expected a coordinate (a finite number), got 'x'"},
        // nail, attach
        ErrorCase{"nail n pz", "no point or place named 'pz'; did you mean 'pa'?"},
        ErrorCase{"nail n sky", "nail 'sky' is a fixed place; expected a point of a body ('point')"},
        ErrorCase{"nail n pa 1 2", "expected 3 coordinates for where to nail, or none"},
        ErrorCase{"attach j pa pf", "cannot attach a 2D point to a 3D one"},
        ErrorCase{"attach j pa", "expected 'attach NAME POINT_A POINT_B'"},
        // path, trajectory
        ErrorCase{"path p 2d 0 1 1", "expected at least two keys of 3 numbers"},
        ErrorCase{"path p 2d 0 1 1  0 2 2", "path p: key times must strictly increase"},
        ErrorCase{"trajectory t pa swop", "no path named 'swop'; did you mean 'swoop'?"},
        ErrorCase{"trajectory t pf swoop", "path 'swoop' and point 'pf' differ in dimension"},
        ErrorCase{"trajectory t pa swoop prerol 1", "expected 'preroll DT' after the path, got 'prerol'"},
        ErrorCase{"trajectory t pa swoop preroll -1", "expected a non-negative preroll time, got -1"},
        // impulse, chase, grab, connect
        ErrorCase{"impulse pa 1 2", "expected 3 velocity components after 'impulse pa'"},
        ErrorCase{"chase sky pa 1", "chase 'sky' is a fixed place; expected a point of a body"},
        ErrorCase{"chase pa pb 0", "expected a positive DURATION, got 0"},
        ErrorCase{"chase pa pb 1 1 2", "expected 'chase POINT TARGET DURATION [VX VY [VZ]]' with 3 velocity components or none"},
        ErrorCase{"grab pa pf 1", "'pa' and 'pf' differ in dimension"},
        ErrorCase{"connect pa pb j1 extra", "expected 'connect POINT TARGET [NAME]'"},
        // release, on, off, wait, wait_for
        ErrorCase{"release pivot", "no constraint named 'pivot' (known: none)"},
        ErrorCase{"off swoop", "no constraint named 'swoop'"},
        ErrorCase{"on", "expected 'on NAME'"},
        ErrorCase{"wait -1", "expected a non-negative DURATION, got -1"},
        ErrorCase{"wait_for soon 1", "expected 'time', 'near', 'below' or 'above' after wait_for, got 'soon'"},
        ErrorCase{"wait_for near pa pb 0", "expected a positive distance R, got 0"},
        ErrorCase{"wait_for below pq 1", "no point or place named 'pq'"},
        // record, render, set
        ErrorCase{"record 0", "expected a positive FPS, got 0"},
        ErrorCase{"render out", "nothing was recorded: 'record FPS' before 'simul'"},
        ErrorCase{"render out frames,pictures", "expected a comma list of frames, filmstrip, vtp, mp4, webp, gltf, web after 'render DIR' for a scene, got 'pictures'"},
        ErrorCase{"set feedback_rate -1", "expected a positive feedback_rate, got -1"},
        ErrorCase{"set view_elevation 95", "expected an elevation between -90 and 90 degrees, got 95"},
        ErrorCase{"grap pa pb 1", "unknown command 'grap'; did you mean 'grab'?"},
        ErrorCase{"simul -1", "expected a non-negative DURATION, got -1"}),
    // test names from the command word and the case's index: "render_37"
    [](const testing::TestParamInfo<ErrorCase>& info) {
      std::string word = info.param.line;
      word = word.substr(0, word.find(' '));
      return word + "_" + std::to_string(info.index);
    });

TEST(SceneScript, ConstraintNamesAreCheckedWhenQueuedAndKnownOnceMade) {
  // a name a queued behaviour will make can be released later; a second one of the same name
  // is refused at once
  EXPECT_EQ(RunFresh(std::string(kTwoBlocks) + "connect pa pb held\nrelease held\n"), "");
  EXPECT_NE(RunFresh(std::string(kTwoBlocks) + "nail held pa\nconnect pb pa held\n")
                .find("s.wob:10: a constraint named 'held' exists already"),
            std::string::npos);
  EXPECT_NE(RunFresh(std::string(kTwoBlocks) + "grab pa pb 1\ngrab pa pb 1\n")
                .find("s.wob:10: a queued behaviour will make a constraint named 'connect:pa' already"),
            std::string::npos);
}

TEST(SceneScript, RenderWithoutAHookSaysItCannotDraw) {
  const std::string m = RunFresh(std::string(kTwoBlocks) + "record 10\nsimul 0.1\nrender out\n");
  EXPECT_NE(m.find("s.wob:11: render: this program cannot draw"), std::string::npos) << m;
}

TEST(SceneScript, Fig2PendulumKeepsItsNailJointsAndEnergyAndRendersEveryFrame) {
  // Fig. 2's triple pendulum: the nail and the attachments hold, and since nothing damps the
  // motion and constraint forces do no work, the total energy stays what it was: 0 (at rest,
  // at y = 0, undeformed). The scene's `render` reaches the hook with every recorded frame.
  std::ostringstream out;
  script::Interpreter interp(out);
  int hook_calls = 0;
  size_t frames = 0;
  std::string folder;
  interp.SetSceneRenderHook([&](const script::SceneRenderRequest& r) {
    ++hook_calls;
    frames = r.recorded->size();
    folder = r.folder;
    EXPECT_EQ(r.what, (std::vector<std::string>{"frames", "filmstrip", "vtp"}));
    EXPECT_EQ(r.fps, 30.0);  // `record 30`
    EXPECT_EQ(r.drawing.drawings.size(), 3u);
    EXPECT_EQ(r.drawing.anchors.size(), 6u);
    return std::vector<std::string>{};
  });
  interp.RunFile(kData + "/fig2_triple_pendulum.wob");
  EXPECT_EQ(hook_calls, 1);
  EXPECT_EQ(frames, 121u);  // 4 s at 30 per second, both ends
  EXPECT_EQ(folder, "out/fig2");
  const World& w = interp.scene().world();
  EXPECT_NEAR(w.time(), 4.0, 1e-9);
  EXPECT_LT(interp.scene().Point("top").norm(), 1e-6);
  EXPECT_LT((interp.scene().Point("elbow1") - interp.scene().Point("elbow1b")).norm(), 1e-6);
  EXPECT_LT((interp.scene().Point("elbow2") - interp.scene().Point("elbow2b")).norm(), 1e-6);
  std::cout << "energy after 4 s: " << w.TotalEnergy() << " (m g L = " << 3 * 9.81 * 1.5 << ")\n";
  EXPECT_LT(std::abs(w.TotalEnergy()), 0.01 * 3 * 9.81 * 1.5);
  // it swung: the tip is well below where it started
  EXPECT_LT(interp.scene().Point("tip")[1], -0.5);
}

// Fig. 3 with every integrator that takes constraints: behaviours (a chase along a path, a
// velocity-matching impulse, attachments) are stages of thesis, symplectic, rk4 and implicit
// alike. Each run must end as the paper's frames do (tests/cli/check_scenes.py's checks), its
// joints at round-off; against a fine RK4 run (dt/4) RK4 at the scene's dt is closer than the
// Euler forms.
TEST(SceneScript, Fig3SkyHookWithEachIntegrator) {
  std::ifstream file(kData + "/fig3_sky_hook.wob");
  std::stringstream text;
  text << file.rdbuf();
  const std::string original = text.str();
  auto run = [&](const std::string& integrator, const std::string& dt) {
    std::string script = original;
    const auto replace = [&](const std::string& from, const std::string& to) {
      const size_t at = script.find(from);
      EXPECT_NE(at, std::string::npos) << from;
      if (at != std::string::npos) script.replace(at, from.size(), to);
    };
    replace("set dt 0.001", "set dt " + dt + "\nset integrator " + integrator);
    std::ostringstream out;
    auto interp = std::make_unique<script::Interpreter>(out);
    interp->SetSceneRenderHook([](const script::SceneRenderRequest&) { return std::vector<std::string>{}; });
    std::istringstream in(script);
    interp->RunStream(in, "fig3_sky_hook.wob", kData);
    return interp;
  };
  const auto reference = run("rk4", "0.00025");
  const Eigen::VectorXd ref_tip = reference->scene().Point("pyr_tip");
  std::map<std::string, double> off;
  for (const std::string integrator : {"thesis", "symplectic", "rk4", "implicit"}) {
    SCOPED_TRACE(integrator);
    const auto interp = run(integrator, "0.001");
    scene::Scene& scene = interp->scene();
    const World& w = scene.world();
    ASSERT_TRUE(w.status().ok()) << w.status().message;
    EXPECT_NEAR(w.time(), 6.0, 1e-9);
    const auto p = [&](const char* name) { return Eigen::VectorXd(scene.Point(name)); };
    EXPECT_LT((p("hook_eye") - p("sky_point")).norm(), 1e-3);
    EXPECT_LT((p("hook_tip") - p("pyr_tip")).norm(), 1e-3);
    // the soft hook (k_e 30) stretches and springs under the swinging 2 kg pyramid: its length
    // at t = 6 is a phase of that oscillation (the converged run: 0.837), not an invariant
    EXPECT_NEAR((p("hook_eye") - p("hook_tip")).norm(), 0.8, 0.15);
    EXPECT_LT(p("pyr_tip")[1], p("hook_eye")[1] - 0.3);
    EXPECT_GT(std::min({p("pyr_a")[1], p("pyr_b")[1], p("pyr_c")[1]}), 1.0);
    off[integrator] = (p("pyr_tip") - ref_tip).norm();
    std::printf("Fig. 3, %-10s dt 0.001: max |c| now %.2g, the pyramid's tip %.3g from rk4 at dt 0.00025, hook length %.3f (reference %.3f)\n",
                integrator.c_str(), w.MaxViolation(), off[integrator], (p("hook_eye") - p("hook_tip")).norm(),
                (reference->scene().Point("hook_eye") - reference->scene().Point("hook_tip")).norm());
    EXPECT_LT(w.MaxViolation(), 1e-6);
  }
  // the Euler forms at dt 0.001 are a quarter to three quarters of a metre off after 6 s of
  // swinging (first order); RK4 is within millimetres of the converged run
  EXPECT_LT(off["rk4"], 0.01);
  for (const char* euler : {"thesis", "symplectic", "implicit"}) EXPECT_LT(20 * off["rk4"], off[euler]) << euler;
}

// Witkin & Welch Fig. 4 over a range of the humanoid's starting positions: `wait_for near` fires
// when the heart comes within 0.8 of the skewer's tip, at t = X0 − 3.5 − √(0.8² − 0.2²) (it walks
// at 1 along y = 0.5, the tip at (3.5, 0.3)); then the skewer grabs the heart and the heart ends
// in the jaws, the tip with it.
TEST(SceneScript, Fig4MonsterWaitsForTheHumanoidWhereverItStarts) {
  std::ifstream file(kData + "/ww_fig4_monster.wob");
  std::stringstream text;
  text << file.rdbuf();
  for (double x0 : {5.0, 7.0, 9.0, 12.0}) {
    SCOPED_TRACE(x0);
    std::ostringstream out;
    script::Interpreter interp(out);
    interp.SetSceneRenderHook([](const script::SceneRenderRequest&) { return std::vector<std::string>{}; });
    char value[32];
    std::snprintf(value, sizeof value, "%g", x0);
    std::istringstream in(script::ExpandVariables(text.str(), {{"X0", value}, {"END", "10"}}, "ww_fig4_monster.wob"));
    interp.RunStream(in, "ww_fig4_monster.wob", kData);
    // "  t = 2.726: chase tip -> heart in 0.3" in the scene's log
    const std::string log = out.str();
    const size_t at = log.find(": chase tip -> heart");
    ASSERT_NE(at, std::string::npos) << log;
    const size_t t_at = log.rfind("t = ", at);
    const double fired = std::stod(log.substr(t_at + 4, at - t_at - 4));
    EXPECT_NEAR(fired, x0 - 3.5 - std::sqrt(0.8 * 0.8 - 0.2 * 0.2), 2e-3);
    const scene::Scene& scene = interp.scene();
    EXPECT_LT((scene.Point("heart") - scene.Point("jaws")).norm(), 1e-6);
    EXPECT_LT((scene.Point("tip") - scene.Point("heart")).norm(), 1e-6);
    EXPECT_LT((scene.Point("base_l") - (Eigen::VectorXd(2) << -1.5, -1).finished()).norm(), 1e-6);  // still nailed
  }
}

TEST(SceneScript, AThinStiffBodyWarnsAboutTheTimeStep) {
  std::ostringstream out;
  script::Interpreter interp(out);
  EXPECT_EQ(RunScript(interp, "set gravity F\nset dt 0.01\nlinear thin 2d affine box 1 0.01 ke 1000 kc 1000\nsimul 0.01\n"), "");
  EXPECT_NE(out.str().find("warning: dt 0.01 is above the stable step"), std::string::npos) << out.str();
  EXPECT_NE(out.str().find("of body 'thin'"), std::string::npos);
}

TEST(SceneScript, AnFfdTableJoinsTheSceneNailedAtACornerAndAttachedToALinearBlock) {
  // the same world holds both kinds: the table of data/ (lattice 300 x 100) hangs from its
  // top-left corner and carries an affine block attached at its top-right corner
  std::ostringstream out;
  script::Interpreter interp(out);
  const std::string script = "load_obj " + kData + "/table.obj\nload_def " + kData + "/table_modes.def\n" +
                             "set dt 0.0005\nset ground F\n"
                             "ffd table\n"
                             "linear block 2d affine box 20 10 at 320 100 mass 100 ke 1 kc 1\n"
                             "point corner table 0 1\n"
                             "point right table 1 1\n"
                             "point block_end block -20 0\n"
                             "nail hold corner\n"
                             "attach joint right block_end\n"
                             "simul 1\n";
  ASSERT_EQ(RunScript(interp, script), "");
  const World& w = interp.scene().world();
  ASSERT_EQ(w.num_bodies(), 2);
  EXPECT_EQ(w.kind(0), BodyKind::kFfd);
  EXPECT_LT((interp.scene().Point("corner") - (Eigen::VectorXd(2) << 0, 100).finished()).norm(), 1e-3);
  EXPECT_LT((interp.scene().Point("right") - interp.scene().Point("block_end")).norm(), 1e-3);
  // it swings down about the nail: the far corner fell
  EXPECT_LT(interp.scene().Point("right")[1], 100 - 1.0);
  EXPECT_NE(RunFresh("load_obj " + kData + "/table.obj\nffd t\npoint p t 1.5 0\n").find("s.wob:3: point p:"),
            std::string::npos);
}

// Synthesis trials simulate the FFD object alone: while a constraint holds it in the scene,
// annealing is refused by name, not run without the constraint; released, it runs.
TEST(SceneScript, SynthesisRefusesAnObjectTheSceneHolds) {
  std::ostringstream out;
  script::Interpreter interp(out);
  const std::string setup = "load_obj " + kData + "/table.obj\nload_def " + kData + "/table_modes.def\n" +
                            "set integrator thesis\nset ground F\nset trial_steps 20\n" +
                            "pose 0.1 0 0.4\npose 0 -0.1 0.4\n" + "ffd table\npoint corner table 0 1\nnail hold corner\n";
  const std::string message = RunScript(interp, setup + "anneal 1\n");
  EXPECT_NE(message.find("s.wob:11: "), std::string::npos) << message;
  EXPECT_NE(message.find("'hold' holds it in the scene: release it first (release hold)"), std::string::npos) << message;
  EXPECT_EQ(RunScript(interp, "release hold\nsimul 0.01\nanneal 1\n"), "");
}

TEST(SceneScript, GravitySetAfterTheBodiesAppliesToTheNextSimul) {
  std::ostringstream out;
  script::Interpreter interp(out);
  ASSERT_EQ(RunScript(interp, "linear b 3d affine box 0.5 0.5 0.5\npoint c b 0 0 0\nset gravity F\nsimul 1\n"), "");
  EXPECT_LT(interp.scene().Point("c").norm(), 1e-12) << "no gravity: at rest where it was";
  ASSERT_EQ(RunScript(interp, "set gravity T\nsimul 1\n"), "");
  // free fall for 1 s from rest: y = −g/2 (the semi-implicit step falls g Δt t further at most)
  EXPECT_NEAR(interp.scene().Point("c")[1], -0.5 * 9.81, 9.81 * 0.01 * 1.0 + 1e-9);
}

// `heightfield FILE`: a 3D block rests on the level heightfield 2 high as it rests on the plane
// at 0, 2 higher; `heightfield off` puts the plane back. `save` writes the heightfield beside its script and
// names it, and the file reads back the same field.
TEST(SceneScript, HeightfieldIsTheGroundOf3DBodiesAndSaveKeepsIt) {
  const std::string dir = ::testing::TempDir();
  const std::string field_path = dir + "/level.heightfield";
  {
    std::ofstream f(field_path);
    f << "# level at 2\norigin -5 -5\nspacing 2.5 2.5\n";
    for (int j = 0; j < 5; ++j) f << "2, 2, 2, 2, 2\n";
  }
  // the same block dropped with and without the heightfield (the plane y = 0 then)
  auto rest_height = [&](const std::string& ground) {
    std::ostringstream out;
    script::Interpreter interp(out);
    EXPECT_EQ(RunScript(interp, ground + "set dt 0.001\nset grdam 10\nlinear b 3d affine box 0.5 0.5 0.5 at 0 3 0 ground\n"
                                         "point c b 0 0 0\nsimul 4\n"),
              "");
    return interp.scene().Point("c")[1];
  };
  const double on_field = rest_height("heightfield " + field_path + "\n");
  const double on_plane = rest_height("heightfield " + field_path + "\nheightfield off\n");
  EXPECT_LT(on_plane, 0.0) << "sunk into the plane a little";
  EXPECT_GT(on_plane, -1e-3);
  EXPECT_NEAR(on_field, on_plane + 2.0, 1e-9) << "the same rest, 2 higher";

  std::ostringstream out;
  script::Interpreter interp(out);
  const std::string saved = dir + "/hills_saved.wob";
  ASSERT_EQ(RunScript(interp, "load_obj " + kData + "/table3.obj\nheightfield " + kData + "/hills.heightfield\nsave " +
                                  saved + "\n"),
            "");
  std::ifstream in(saved);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string written = dir + "/hills_saved.heightfield";
  EXPECT_NE(text.find("heightfield off\nheightfield " + written + "\n"), std::string::npos) << text;
  EXPECT_TRUE(*formats::ReadHeightfieldFile(written) == *formats::ReadHeightfieldFile(kData + "/hills.heightfield"));

  // a region's own constants go into the saved heightfield: an icy valley floor
  script::Interpreter with_region(out);
  ASSERT_EQ(RunScript(with_region, "load_obj " + kData + "/table3.obj\nheightfield " + kData +
                                       "/hills.heightfield\nheightfield_region -200 -400 200 400 frsin 0.05 grdam 900\nsave " +
                                       saved + "\n"),
            "");
  const std::shared_ptr<const Heightfield> icy = formats::ReadHeightfieldFile(written);
  EXPECT_TRUE(*icy == *formats::ReadHeightfieldFile(kData + "/hills.heightfield")->WithRegion(
                          {-200, -400}, {200, 400}, [] {
                            SurfaceOverrides o;
                            o.friction_cap = 0.05;
                            o.normal_damping = 900;
                            return o;
                          }()));
  int icy_cells = 0;
  for (int c = 0; c < icy->num_cells(); ++c) icy_cells += icy->CellOverrides(c).friction_cap == 0.05;
  EXPECT_EQ(icy_cells, 10 * 20) << "cells 40 wide with centres from -180 to 180 in x, all 20 in z";
}

}  // namespace
}  // namespace wobble
