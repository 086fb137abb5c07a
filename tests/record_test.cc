// The one recorder (record::Trajectory, record::Recorder) and its CSV schema.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <sstream>

#include "support/test_bodies.h"
#include "wobble/formats/parse_error.h"
#include "wobble/record/trajectory_csv.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

std::shared_ptr<const BodyModel> Table() {
  return std::make_shared<BodyModel>(testing::TableDef(), testing::TableModes(2e6, 5e4));
}

// A table dropped onto the ground, recorded every `every` steps.
struct DroppedTable {
  World world;
  std::shared_ptr<record::Trajectory> trajectory;
  std::shared_ptr<record::Recorder> recorder;
  explicit DroppedTable(int every) : world(WorldOptions{}) {
    world.AddBody(Table());
    Eigen::VectorXd q = Eigen::VectorXd::Zero(7), qd = Eigen::VectorXd::Zero(7);
    q[1] = 10.0;
    qd[0] = 3.0;
    world.SetState(0, q, qd);
    trajectory = std::make_shared<record::Trajectory>(world);
    recorder = std::make_shared<record::Recorder>(trajectory, every);
    recorder->Start(world);
    world.SetRecorder(recorder);
  }
};

TEST(Trajectory, ColumnsNameTheModes) {
  DroppedTable d(1);
  const std::vector<std::string>& c = d.trajectory->Columns();
  ASSERT_GE(c.size(), 12u);
  EXPECT_EQ(c[0], "t");
  EXPECT_EQ(c[1], "tx");
  EXPECT_EQ(c[4], "bend");  // mode names, not g1..gD
  EXPECT_EQ(c[8], "dtx");
  EXPECT_EQ(c[11], "dbend");
  EXPECT_GE(d.trajectory->Column("target_bend"), 0);
  EXPECT_GE(d.trajectory->Column("control_energy"), 0);
  EXPECT_EQ(c.back(), "violation");
}

// The recorder keeps the start, every Nth step and (Finish) the end; each sample is the
// world's state and energies at that step.
TEST(Recorder, KeepsEveryNthStepAndTheEnd) {
  DroppedTable d(7);
  World reference(WorldOptions{});
  reference.AddBody(d.world.shared_body<2>(0));
  reference.SetState(0, d.world.q(0), d.world.qd(0));
  for (int n = 1; n <= 100; ++n) {
    ASSERT_TRUE(d.world.Step()) << d.world.status().message;
    ASSERT_TRUE(reference.Step());
    if (n % 7 == 0) {
      const record::Trajectory& t = *d.trajectory;
      const int k = t.size() - 1;
      EXPECT_EQ(t.time(k), reference.time());
      EXPECT_EQ((t.q(k, 0) - reference.q(0)).norm(), 0.0);
      EXPECT_EQ((t.qd(k, 0) - reference.qd(0)).norm(), 0.0);
      EXPECT_EQ(t.energies(k, 0).total(), reference.ComputeEnergies(0).total());
      EXPECT_EQ(t.contacts(k, 0), int(reference.state<2>(0).contacts.size()));
    }
  }
  d.recorder->Finish(d.world);
  EXPECT_EQ(d.trajectory->size(), 1 + 100 / 7 + 1);
  EXPECT_EQ(d.trajectory->time(d.trajectory->size() - 1), d.world.time());
  d.recorder->Finish(d.world);  // twice: the end is not repeated
  EXPECT_EQ(d.trajectory->size(), 1 + 100 / 7 + 1);
}

// Written and read back, a trajectory is the same to the last bit (shortest round-trip numbers).
TEST(TrajectoryCsv, RoundTripsExactly) {
  DroppedTable d(3);
  for (int n = 0; n < 60; ++n) ASSERT_TRUE(d.world.Step());
  const std::string path = (std::filesystem::temp_directory_path() / "wobble_record_test.csv").string();
  record::WriteTrajectoryCsv(path, *d.trajectory);
  const record::ReadTrajectory back = record::ReadTrajectoryCsv(path, {record::DescribeFfdBody(d.world.shared_body<2>(0))});
  std::remove(path.c_str());
  ASSERT_TRUE(back.has_velocities);
  ASSERT_EQ(back.trajectory.size(), d.trajectory->size());
  ASSERT_EQ(back.trajectory.Columns(), d.trajectory->Columns());
  for (int k = 0; k < d.trajectory->size(); ++k)
    for (int c = 0; c < d.trajectory->num_columns(); ++c) EXPECT_EQ(back.trajectory.Row(k)[c], d.trajectory->Row(k)[c]);
}

// Restore puts a sample back: stepping on from it repeats the recorded run exactly.
TEST(Trajectory, RestoreReplaysTheRun) {
  DroppedTable d(1);
  for (int n = 0; n < 80; ++n) ASSERT_TRUE(d.world.Step());
  World again(WorldOptions{});
  again.AddBody(d.world.shared_body<2>(0));
  d.trajectory->Restore(30, again);
  EXPECT_EQ(again.time(), d.trajectory->time(30));
  for (int n = 31; n <= 80; ++n) {
    ASSERT_TRUE(again.Step());
    EXPECT_EQ((again.q(0) - d.trajectory->q(n, 0)).norm(), 0.0) << "step " << n;
  }
}

// RestoreAt: at a sample's time it is Restore; between two samples every coordinate is the
// linear blend (a 3D body's quaternion normalised), the clock at t; past the last sample, the
// last sample.
TEST(Trajectory, RestoreAtInterpolatesBetweenSamples) {
  DroppedTable d(4);
  for (int n = 0; n < 80; ++n) ASSERT_TRUE(d.world.Step());
  const record::Trajectory& run = *d.trajectory;
  World at(WorldOptions{}), exact(WorldOptions{});
  at.AddBody(d.world.shared_body<2>(0));
  exact.AddBody(d.world.shared_body<2>(0));
  run.RestoreAt(run.time(7), at);
  run.Restore(7, exact);
  EXPECT_EQ(at.q(0), exact.q(0));
  EXPECT_EQ(at.qd(0), exact.qd(0));
  const double t = run.time(7) + 0.3 * (run.time(8) - run.time(7));
  run.RestoreAt(t, at);
  EXPECT_EQ(at.time(), t);
  const Eigen::VectorXd q = 0.7 * run.q(7, 0) + 0.3 * run.q(8, 0), qd = 0.7 * run.qd(7, 0) + 0.3 * run.qd(8, 0);
  EXPECT_LT((at.q(0) - q).norm(), 1e-12 * (1 + q.norm()));
  EXPECT_LT((at.qd(0) - qd).norm(), 1e-12 * (1 + qd.norm()));
  run.RestoreAt(run.time(run.size() - 1) + 1.0, at);
  EXPECT_EQ(at.q(0), run.q(run.size() - 1, 0));

  // a 3D body turning: the orientation between two samples is the normalised blend
  World w3(WorldOptions{});
  w3.mutable_options().params.ground_plane.enabled = false;
  const int b = w3.AddBody(std::make_shared<const BodyModelN<3>>(testing::Chair3()));
  const Eigen::VectorXd g0 = Eigen::VectorXd::Zero(w3.body<3>(b).num_modes());
  w3.SetState(b, PositionsOf(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), g0), (Eigen::VectorXd(6 + g0.size()) << Eigen::VectorXd::Zero(3), 0.5, 2.0, -1.0, g0).finished());
  auto run3 = std::make_shared<record::Trajectory>(w3);
  auto rec3 = std::make_shared<record::Recorder>(run3, 10);
  rec3->Start(w3);
  w3.SetRecorder(rec3);
  for (int n = 0; n < 40; ++n) ASSERT_TRUE(w3.Step()) << w3.status().message;
  World at3(WorldOptions{});
  at3.mutable_options().params.ground_plane.enabled = false;
  at3.AddBody(w3.shared_body<3>(b));
  const double t3 = 0.5 * (run3->time(2) + run3->time(3));
  run3->RestoreAt(t3, at3);
  const Eigen::Map<const Eigen::VectorXd> qa = run3->q(2, b), qb = run3->q(3, b);
  const Eigen::Vector4d wxyz = 0.5 * (qa.segment<4>(3) + qb.segment<4>(3));  // recorded as qw qx qy qz
  const Eigen::Quaterniond mid = Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized();
  EXPECT_LT(std::abs(std::abs(at3.state<3>(b).orientation().dot(mid)) - 1.0), 1e-12);
  EXPECT_LT((at3.state<3>(b).translation() - 0.5 * (qa.head<3>() + qb.head<3>())).norm(), 1e-12);
  EXPECT_EQ(at3.time(), t3);
}

// One clock for every body: an FFD body nailed to a linear block in one world moves with the
// world's time (the old constrained world kept its FFD bodies on a clock that never moved).
TEST(Trajectory, FfdBodyInAConstraintSceneHasTheWorldsTime) {
  World w(testing::WitkinWelchOptions());
  const int table = w.AddBody(Table());
  Eigen::VectorXd half(2);
  half << 0.5, 0.5;
  const int block = w.AddLinearBody(std::make_shared<LinearBodyModel>(MakeBoxBody("block", 2, LinearOrder::kAffine, half, 2, 1.0)));
  w.AddNail(At(table, Eigen::Vector2d(0.0, 1.0)));
  // the block's material point at (300, 100) is where the table's top right corner is
  w.AddAttachment(At(table, Eigen::Vector2d(1.0, 1.0)), At(block, Eigen::Vector2d(300.0, 100.0)));
  record::Trajectory t(w);
  EXPECT_EQ(t.Column("table.tx"), 1);  // two bodies: columns carry the body name
  EXPECT_GE(t.Column("block.r0_0"), 0);
  t.Append(w);
  for (int n = 1; n <= 50; ++n) {
    ASSERT_TRUE(w.Step()) << w.status().message;
    t.Append(w);
    EXPECT_NEAR(t.time(n), n * 0.002, 1e-15);
  }
  EXPECT_LT(t.violation(50), 1e-6);
}

std::string CsvMessage(const std::string& text) {
  std::istringstream in(text);
  record::BodyInfo one_mode;
  one_mode.name = "body";
  one_mode.coordinate_names = {"tx", "ty", "theta", "g1"};
  one_mode.num_q = 4;
  try {
    record::ParseTrajectoryCsv(in, "ref.csv", {one_mode});
  } catch (const formats::ParseError& e) {
    return e.what();
  }
  return "no error";
}

// (moved from trajectory_fit_test: the reader of what `wobble simulate` writes)
TEST(TrajectoryCsv, ReadsWobbleSimulateOutputAndRejectsBadRows) {
  std::istringstream good("t,tx,ty,theta,g1,dtx,dty,dtheta,dg1,kinetic\n0,1,2,3,4,5,6,7,8,9\n0.5,1,2,3,4.5,5,6,7,8,9\n");
  record::BodyInfo one_mode;
  one_mode.coordinate_names = {"tx", "ty", "theta", "g1"};
  one_mode.num_q = 4;
  const record::ReadTrajectory s = record::ParseTrajectoryCsv(good, "ref.csv", {one_mode});
  ASSERT_EQ(s.trajectory.size(), 2);
  ASSERT_TRUE(s.has_velocities);
  EXPECT_EQ(s.trajectory.q(1, 0)[3], 4.5);
  EXPECT_EQ(s.trajectory.qd(0, 0)[0], 5.0);
  EXPECT_EQ(s.trajectory.energies(0, 0).kinetic, 9.0);
  EXPECT_EQ(CsvMessage(""), "ref.csv:0: file is empty: expected the header of `wobble simulate`");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g2\n"),
            "ref.csv:1: expected the header to start with t,tx,ty,theta,g1 (a body with 1 modes), got 't,tx,ty,theta,g2'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta\n"),
            "ref.csv:1: expected the header to start with t,tx,ty,theta,g1 (a body with 1 modes), got 't,tx,ty,theta'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1\n0,1,2,3,4\n1,1,2,x,4\n"),
            "ref.csv:3: expected a number in column 4 (theta), got 'x'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1\n0,1,2,3\n"), "ref.csv:2: expected 5 values like the header, got 4");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1\n1,1,2,3,4\n1,1,2,3,4\n"),
            "ref.csv:3: times must strictly increase (previous row: t = 1)");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1\n"), "ref.csv:0: no rows after the header");
}

// Found by fuzz_trajectory_csv: Trajectory::pose() reads the pose column as an int, so a pose
// that is not a whole number an int holds was undefined behaviour; it is refused on its line.
TEST(TrajectoryCsv, RefusesAPoseThatIsNoIndex) {
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1,pose\n0,1,2,3,4,2\n1,1,2,3,4,21474836483\n"),
            "ref.csv:3: expected a whole number >= -1 in column 6 (pose), got '21474836483'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1,pose\n0,1,2,3,4,0.5\n"),
            "ref.csv:2: expected a whole number >= -1 in column 6 (pose), got '0.5'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1,pose\n0,1,2,3,4,-2\n"),
            "ref.csv:2: expected a whole number >= -1 in column 6 (pose), got '-2'");
  EXPECT_EQ(CsvMessage("t,tx,ty,theta,g1,pose\n0,1,2,3,4,-1\n1,1,2,3,4,3\n"), "no error");
}

// A body read from a file without its model takes its mode count from its coordinates: 0 there
// dropped the target columns from the schema and a 3D body's γ from Restore.
TEST(BodyInfo, CountsTheModesOfABodyReadWithoutItsModel) {
  World w;
  w.AddBody(Table());
  w.AddBody(std::make_shared<const BodyModelN<3>>(testing::Chair3()));
  Eigen::VectorXd q3(9), qd3 = Eigen::VectorXd::Zero(9);
  q3 << 1, 2, 3, 0.1, -0.2, 0.3, 0.05, -0.04, 0.03;
  w.SetCoordinates(1, q3, qd3);
  record::Trajectory recorded(w);
  ASSERT_EQ(recorded.Append(w), -1);
  std::vector<record::BodyInfo> read;  // what a caller knows of a file: names and dimension
  for (const record::BodyInfo& b : recorded.bodies()) {
    record::BodyInfo r;
    r.name = b.name;
    r.dim = b.dim;
    r.num_q = b.num_q;
    r.coordinate_names = b.coordinate_names;
    r.velocity_names = b.velocity_names;
    read.push_back(r);
  }
  EXPECT_EQ(read[0].num_modes(), 4);
  EXPECT_EQ(read[1].num_modes(), 3);
  record::Trajectory file(read);
  EXPECT_EQ(file.Columns(), recorded.Columns());
  file.AppendRow(std::vector<double>(recorded.Row(0), recorded.Row(0) + recorded.num_columns()));
  World back;
  back.AddBody(w.shared_body<2>(0));
  back.AddBody(w.shared_body<3>(1));
  file.Restore(0, back);
  EXPECT_NEAR((back.coordinates(1) - q3).norm(), 0.0, 1e-12);

  // an FFD body with neither model nor coordinates says so instead of "no modes"
  record::BodyInfo unknown;
  unknown.name = "ghost";
  try {
    (void)unknown.num_modes();
    ADD_FAILURE() << "no error";
  } catch (const std::logic_error& e) {
    EXPECT_NE(std::string(e.what()).find("'ghost' has neither a model nor its coordinates"), std::string::npos) << e.what();
  }
  record::BodyInfo linear;
  linear.kind = BodyKind::kLinear;
  EXPECT_EQ(linear.num_modes(), 0);
}

}  // namespace
}  // namespace wobble
