// scene::SessionScript without VTK (so it also runs in the ASan build, which has no display): a
// World stepped by hand with PD targets changed at chosen steps, written as a script and run
// by the interpreter, ends in the same state; a change on every step and a change on the
// first step replay too; bad records are refused; the pull note is written.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <sstream>

#include "wobble/control/control.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/script/interpreter.h"
#include "wobble/scene/script_writer.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

const std::string kData = wobble::test_env::DataDir();

struct Session {
  std::shared_ptr<const BodyModel> body;
  scene::SessionRecord record;
  Eigen::VectorXd q;  // the state at the end
};

// Steps the table `steps` times from q0, setting the targets given for some steps before them.
Session RunByHand(const WorldOptions& options, const Eigen::VectorXd& q0, long steps,
                  const std::map<long, Eigen::VectorXd>& changes) {
  Session s;
  s.body = std::make_shared<const BodyModel>(formats::ReadObjectFile(kData + "/table.obj"),
                                             formats::ReadDeformationFile(kData + "/table_modes.def"));
  World world(options);
  world.AddBody(s.body);
  world.SetState(0, q0, Eigen::VectorXd::Zero(q0.size()));
  for (long n = 0; n < steps; ++n) {
    if (auto it = changes.find(n); it != changes.end()) {
      world.SetModeTargets(0, it->second);
      s.record.segments.push_back({n, it->second});
    }
    EXPECT_TRUE(world.Step());
  }
  s.q = world.q(0);
  s.record.object_path = kData + "/table.obj";
  s.record.mode_paths = {kData + "/table_modes.def"};
  s.record.body = s.body.get();
  s.record.world = options;
  s.record.q0 = q0;
  s.record.qd0 = Eigen::VectorXd::Zero(q0.size());
  s.record.steps = steps;
  return s;
}

Eigen::VectorXd Replay(const std::string& script) {
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(script);
  interp.RunStream(in, "<session>", "");
  return interp.q();
}

Eigen::VectorXd V(std::initializer_list<double> v) {
  Eigen::VectorXd out(int(v.size()));
  int i = 0;
  for (double x : v) out[i++] = x;
  return out;
}

TEST(SessionScript, TargetChangesReplayToTheSameState) {
  WorldOptions o;  // thesis integrator, dt 0.01, default ground
  o.params.ground.slope = -0.05;
  const Session s = RunByHand(o, V({0, 40, 0, 0, 0, 0, 0}), 400,
                              {{0, V({0, 0, 0, 0})}, {37, V({0.2, 0, 0, 0})}, {151, V({0.2, -0.1, 0.05, 0})},
                               {152, V({-0.1, -0.1, 0.05, 0.02})}, {390, V({0, 0, 0, 0})}});
  const Eigen::VectorXd q = Replay(scene::SessionScript(s.record));
  ASSERT_EQ(q.size(), s.q.size());
  EXPECT_LT((q - s.q).cwiseAbs().maxCoeff(), 1e-12) << q.transpose() << "\n" << s.q.transpose();
}

TEST(SessionScript, ChangesOnEveryStepAndSpringsAndAnotherIntegrator) {
  WorldOptions o;
  o.integrator = Integrator::kImplicitEuler;
  o.dt = 0.005;
  Spring sp;
  sp.lattice_coords = {0.5, 1.0, 0.0};  // a 2D spring: z is 0
  sp.anchor = {150, 160, 0};
  sp.stiffness = 300;
  sp.damping = 5;
  std::map<long, Eigen::VectorXd> every;
  for (long n = 0; n < 120; ++n) every[n] = V({0.1 * std::sin(0.1 * n), 0, 0, 0.05 * std::cos(0.07 * n)});
  WorldOptions with_spring = o;
  {
    // the World wants the spring's basis filled in: AddSpring does it, so build it that way
    World w(o);
    w.AddBody(std::make_shared<const BodyModel>(formats::ReadObjectFile(kData + "/table.obj"),
                                                formats::ReadDeformationFile(kData + "/table_modes.def")));
    w.AddSpring(sp);
    with_spring = w.options();
  }
  const Session s = RunByHand(with_spring, V({0, 20, 0.05, 0, 0, 0, 0}), 120, every);
  const Eigen::VectorXd q = Replay(scene::SessionScript(s.record));
  EXPECT_LT((q - s.q).cwiseAbs().maxCoeff(), 1e-12) << q.transpose() << "\n" << s.q.transpose();
}

// A session that began with keys and a held point: its script holds the same point (every
// lattice coordinate, to the last bit) when the interpreter reads it back.
TEST(SessionScript, AKeyedSessionKeepsItsHeldPoint) {
  Session s = RunByHand(WorldOptions{}, V({0, 40, 0, 0, 0, 0, 0}), 10, {});
  s.record.keys.times = {0.0, 0.05};
  s.record.keys.amplitudes = {V({0, 0, 0, 0}), V({0.1, 0, 0, 0})};
  s.record.key_steps = 5;
  s.record.hold.enabled = true;
  s.record.hold.lattice_coords = {1.0 / 3.0, 0.7, 0.0};  // a 2D body's point: u is 0
  const std::string text = scene::SessionScript(s.record);
  std::ostringstream out;
  script::Interpreter interp(out);
  std::istringstream in(text);
  interp.RunStream(in, "<session>", "");
  const control::HeldPoint& hold = interp.scene().control().hold;
  EXPECT_TRUE(hold.enabled) << text;
  EXPECT_EQ(hold.lattice_coords, s.record.hold.lattice_coords) << text;
}

TEST(SessionScript, RefusesBadRecordsAndNotesPulls) {
  Session s = RunByHand(WorldOptions{}, V({0, 0, 0, 0, 0, 0, 0}), 10, {{0, V({0.1, 0, 0, 0})}, {5, V({0, 0, 0, 0})}});
  s.record.drags = 2;
  s.record.first_drag_step = 4;
  EXPECT_NE(scene::SessionScript(s.record).find("2 pull(s) by the mouse"), std::string::npos);
  scene::SessionRecord bad = s.record;
  bad.segments[1].step = 0;  // out of order
  EXPECT_THROW(scene::SessionScript(bad), std::invalid_argument);
  bad = s.record;
  bad.segments[0].targets = V({1, 2});  // wrong size
  EXPECT_THROW(scene::SessionScript(bad), std::invalid_argument);
  bad = s.record;
  bad.object_path.clear();
  EXPECT_THROW(scene::SessionScript(bad), std::invalid_argument);
  EXPECT_THROW(scene::PoseGraphScript(s.record, {V({0.1, 0, 0, 0})}, {0.0}), std::invalid_argument);
}

}  // namespace
}  // namespace wobble
