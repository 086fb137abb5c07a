// The VTK sources of pipelines/world_sources.h on FFD bodies against independent evaluations
// (linear bodies: pipelines_scene_test.cc): Eq. 4.2
// through Lattice::Evaluate on deformed control points, finite differences of positions for
// velocities, and the generalized force's translation rows for the applied forces.
#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "pipelines/world_sources.h"
#include "support/pipelines_test_util.h"
#include "wobble/body/linear_body.h"

namespace wobble::pipelines {
namespace {

using testing::AirborneWorld;
using testing::Source;
using testing::IndependentWorldPoint;
using testing::TouchingWorld;

Eigen::Vector2d Point(vtkPolyData* pd, vtkIdType i) {
  double p[3];
  pd->GetPoint(i, p);
  EXPECT_EQ(p[2], 0.0);
  return {p[0], p[1]};
}

Eigen::Vector2d Tuple2(vtkPolyData* pd, const char* name, vtkIdType i) {
  vtkDataArray* a = pd->GetPointData()->GetArray(name);
  EXPECT_NE(a, nullptr) << name;
  if (!a) return {NAN, NAN};
  return {a->GetComponent(i, 0), a->GetComponent(i, 1)};
}

double TimeValue(vtkPolyData* pd) {
  vtkDataArray* t = pd->GetFieldData()->GetArray("TimeValue");
  return t ? t->GetTuple1(0) : NAN;
}

TEST(LatticeSource, ControlPointsAreTheDeformedLatticeMovedIntoTheWorld) {
  auto world = AirborneWorld();
  const BodyModel& body = world->body<2>(0);
  const Eigen::VectorXd q = world->q(0);
  auto src = Source<LatticeSource>(*world);
  vtkPolyData* out = src->GetOutput();
  const Lattice& lat = body.lattice();
  ASSERT_EQ(out->GetNumberOfPoints(), lat.size());
  for (int i = 0; i < lat.num_s(); ++i)
    for (int j = 0; j < lat.num_t(); ++j) {
      const int c = lat.Index(i, j);
      // a Bernstein lattice interpolates its corner control points; inner ones are checked
      // through the displacement array against the mode matrices directly
      Eigen::Vector2d d = Eigen::Vector2d::Zero();
      for (int m = 0; m < body.num_modes(); ++m) d += q[3 + m] * body.modes()[m].displacement[c];
      EXPECT_NEAR((Tuple2(out, "rest_position", c) - lat.RestPoint(i, j)).norm(), 0.0, 1e-12);
      EXPECT_NEAR((Tuple2(out, "displacement", c) - d).norm(), 0.0, 1e-12);
      const bool corner = (i == 0 || i == lat.num_s() - 1) && (j == 0 || j == lat.num_t() - 1);
      if (corner) {
        const Eigen::Vector2d st(double(i) / (lat.num_s() - 1), double(j) / (lat.num_t() - 1));
        EXPECT_NEAR((Point(out, c) - IndependentWorldPoint(body, q, st)).norm(), 0.0, 1e-9) << i << "," << j;
      }
    }
  // a vertex per control point, a line per row and column
  EXPECT_EQ(out->GetNumberOfVerts(), lat.size());
  EXPECT_EQ(out->GetNumberOfLines(), lat.num_s() + lat.num_t());
  EXPECT_DOUBLE_EQ(TimeValue(out), world->time());
}

TEST(MassPointSource, PositionsVelocitiesAndMassesMatchIndependentEvaluation) {
  auto world = AirborneWorld();
  const BodyModel& body = world->body<2>(0);
  const Eigen::VectorXd q = world->q(0), qd = world->qd(0);
  auto src = Source<MassPointSource>(*world);
  vtkPolyData* out = src->GetOutput();
  ASSERT_EQ(out->GetNumberOfPoints(), body.num_points());
  EXPECT_EQ(out->GetNumberOfVerts(), body.num_points());
  const double h = 1e-6;
  for (int k = 0; k < body.num_points(); ++k) {
    const Eigen::Vector2d st = body.lattice_coords(k);
    EXPECT_NEAR((Point(out, k) - IndependentWorldPoint(body, q, st)).norm(), 0.0, 1e-9);
    // velocity: central difference of the position along q̇
    const Eigen::Vector2d v_fd =
        (IndependentWorldPoint(body, q + h * qd, st) - IndependentWorldPoint(body, q - h * qd, st)) / (2 * h);
    EXPECT_NEAR((Tuple2(out, "velocity", k) - v_fd).norm(), 0.0, 1e-5 * (1 + v_fd.norm()));
    EXPECT_EQ(out->GetPointData()->GetArray("mass")->GetTuple1(k), body.mass(k));
    EXPECT_EQ(out->GetPointData()->GetArray("in_contact")->GetTuple1(k), 0.0);
    // in the air only gravity acts: m g
    EXPECT_NEAR((Tuple2(out, "applied_force", k) - body.mass(k) * Eigen::Vector2d(0, -9.81)).norm(), 0.0, 1e-9);
  }
}

TEST(MassPointSource, ContactFlagsAndForcesAgreeWithTheGeneralizedForce) {
  auto world = TouchingWorld();
  const BodyModel& body = world->body<2>(0);
  ASSERT_GE(world->state<2>(0).contacts.size(), 2u);
  auto src = Source<MassPointSource>(*world);
  vtkPolyData* out = src->GetOutput();
  std::vector<bool> touching(body.num_points(), false);
  for (const auto& c : world->state<2>(0).contacts) touching[c.point] = true;
  // the translation rows of Q = Σ Jᵀ f are Σ f (J's translation block is the identity), so
  // the point forces must add up to Q_t of gravity plus ground (Eq. 4.20)
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int k = 0; k < body.num_points(); ++k) {
    EXPECT_EQ(out->GetPointData()->GetArray("in_contact")->GetTuple1(k), touching[k] ? 1.0 : 0.0) << k;
    sum += Tuple2(out, "applied_force", k);
  }
  const ForceBreakdown<2, double> f = world->Forces<2>(0);
  const Eigen::Vector2d expected(f.gravity[0] + f.ground[0], f.gravity[1] + f.ground[1]);
  EXPECT_GT((expected - f.gravity.head<2>()).norm(), 1.0);  // the ground does push
  EXPECT_NEAR((sum - expected).norm(), 0.0, 1e-9 * expected.norm());
  // and the θ row: Σ (x_k − t) × f_k equals Q_θ
  double torque = 0;
  const Eigen::Vector2d t = world->q(0).head<2>();
  for (int k = 0; k < body.num_points(); ++k) {
    const Eigen::Vector2d r = Point(out, k) - t, fk = Tuple2(out, "applied_force", k);
    torque += r.x() * fk.y() - r.y() * fk.x();
  }
  EXPECT_NEAR(torque, f.gravity[2] + f.ground[2], 1e-9 * (1 + std::abs(f.gravity[2] + f.ground[2])));
}

TEST(ShapeSource, SamplesAreTheFfdOfTheDrawingResampledFiner) {
  auto world = AirborneWorld();
  const BodyModel& body = world->body<2>(0);
  const Eigen::VectorXd q = world->q(0);
  auto src = vtkSmartPointer<ShapeSource>::New();
  src->SetWorld(world.get());
  src->SetSamplesPerSegment(10);
  src->Update();
  vtkPolyData* out = src->GetOutput();
  // three open one-segment polylines: 11 samples each, far more than the 11 mass points
  ASSERT_EQ(body.def().shapes.size(), 3u);
  ASSERT_EQ(out->GetNumberOfPoints(), 33);
  ASSERT_EQ(out->GetNumberOfLines(), 3);
  vtkIdType id = 0;
  for (const Polyline& pl : body.def().shapes) {
    const Eigen::Vector2d a = pl.points[0], b = pl.points[1];
    for (int k = 0; k <= 10; ++k, ++id) {
      const Eigen::Vector2d rest = a + (b - a) * (k / 10.0);
      // the table's lattice is the axis-aligned 300 x 100 box at the origin: st = rest / size
      const Eigen::Vector2d st(rest.x() / 300.0, rest.y() / 100.0);
      EXPECT_NEAR((Point(out, id) - IndependentWorldPoint(body, q, st)).norm(), 0.0, 1e-9) << id;
    }
  }
  // at rest the FFD is the identity: the drawing comes out where the file put it
  World rest_world;
  rest_world.AddBody(testing::Table());
  src->SetWorld(&rest_world);
  src->Update();
  EXPECT_NEAR((Point(src->GetOutput(), 0) - Eigen::Vector2d(0, 100)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((Point(src->GetOutput(), 10) - Eigen::Vector2d(300, 100)).norm(), 0.0, 1e-12);
}

TEST(GroundSource, SurfaceLiesOnTheSlopedGround) {
  auto world = AirborneWorld();
  auto src = vtkSmartPointer<GroundSource>::New();
  src->SetWorld(world.get());
  src->SetCenter(100, 500);
  src->SetLength(1000);
  src->SetDepth(50);
  src->Update();
  vtkPolyData* out = src->GetOutput();
  ASSERT_EQ(out->GetNumberOfPoints(), 4);
  const double slope = -10.0 * M_PI / 180.0;
  const Eigen::Vector2d a = Point(out, 0), b = Point(out, 1);
  // on the line y = x tan(slope) through the origin, 1000 long, centred below (100, 500)
  EXPECT_NEAR(a.y(), a.x() * std::tan(slope), 1e-9);
  EXPECT_NEAR(b.y(), b.x() * std::tan(slope), 1e-9);
  EXPECT_NEAR((b - a).norm(), 1000.0, 1e-9);
  const Eigen::Vector2d mid = 0.5 * (a + b), tangent(std::cos(slope), std::sin(slope));
  EXPECT_NEAR((mid - Eigen::Vector2d(100, 500)).dot(tangent), 0.0, 1e-9);
  // the band reaches 50 below the surface
  const Eigen::Vector2d normal(-std::sin(slope), std::cos(slope));
  EXPECT_NEAR((Point(out, 3) - a).dot(normal), -50.0, 1e-9);
}

TEST(SpringSource, LinesRunFromAnchorToTheHeldPoint) {
  auto world = AirborneWorld();
  Spring sp;
  sp.lattice_coords = {0.25, 0.75, 0.0};  // a 2D spring: z is 0
  sp.anchor = {40, 400, 0.0};
  sp.stiffness = 100;
  sp.rest_length = 10;
  world->AddSpring(sp);
  auto src = Source<SpringSource>(*world);
  vtkPolyData* out = src->GetOutput();
  ASSERT_EQ(out->GetNumberOfLines(), 1);
  const Eigen::Vector2d held = IndependentWorldPoint(world->body<2>(0), world->q(0), sp.LatticeCoords<2>());
  EXPECT_NEAR((Point(out, 0) - sp.Anchor<2>()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((Point(out, 1) - held).norm(), 0.0, 1e-9);
  EXPECT_NEAR(out->GetCellData()->GetArray("stretch")->GetTuple1(0), (held - sp.Anchor<2>()).norm() - 10, 1e-9);
}

TEST(TrailSource, RecordsTheTrackedPointsEachFrame) {
  auto world = AirborneWorld();
  auto src = vtkSmartPointer<TrailSource>::New();
  src->SetWorld(world.get());
  src->SetTrackedPoints({{0, 0}, {1, 1}});
  std::vector<Eigen::Vector2d> expected;
  for (int k = 0; k < 5; ++k) {
    if (k) world->Step();
    src->Record();
    expected.push_back(IndependentWorldPoint(world->body<2>(0), world->q(0), {0, 0}));
  }
  src->Update();
  vtkPolyData* out = src->GetOutput();
  ASSERT_EQ(out->GetNumberOfLines(), 2);
  ASSERT_EQ(out->GetNumberOfPoints(), 10);
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR((Point(out, k) - expected[k]).norm(), 0.0, 1e-9);
    EXPECT_NEAR(out->GetPointData()->GetArray("time")->GetTuple1(k), k * world->options().dt, 1e-12);
  }
}

TEST(WorldSources, WithoutAWorldTheyFailInsteadOfCrashing) {
  auto src = vtkSmartPointer<LatticeSource>::New();
  src->GetExecutive();  // errors go to VTK's output window; the update must just fail
  src->SetBody(0);
  src->Update();
  EXPECT_EQ(src->GetOutput()->GetNumberOfPoints(), 0);
}

TEST(WorldSources, OneSourceDrawsEitherKindAndRefusesWhatItCannotDraw) {
  auto world = AirborneWorld();
  const int box = world->AddLinearBody(std::make_shared<const LinearBodyModel>(
      MakeBoxBody("box", 2, LinearOrder::kAffine, testing::Vec({50, 30}), 3, 9.0)));
  // the same MassPointSource draws the FFD table (with its force arrays) and the linear box
  auto ffd = Source<MassPointSource>(*world);
  EXPECT_EQ(ffd->GetOutput()->GetNumberOfPoints(), world->body<2>(0).num_points());
  EXPECT_NE(ffd->GetOutput()->GetPointData()->GetArray("applied_force"), nullptr);
  auto linear = vtkSmartPointer<MassPointSource>::New();
  linear->SetWorld(world.get());
  linear->SetBody(box);
  linear->Update();
  EXPECT_EQ(linear->GetOutput()->GetNumberOfPoints(), 9);
  EXPECT_NE(linear->GetOutput()->GetPointData()->GetArray("velocity"), nullptr);
  EXPECT_EQ(linear->GetOutput()->GetPointData()->GetArray("in_contact"), nullptr);
  // trails follow lattice coordinates of an FFD body: asked for the linear box, they report
  // (vtkErrorMacro) and record nothing; a body the world does not have draws nothing
  auto trail = vtkSmartPointer<TrailSource>::New();
  trail->GetExecutive();
  trail->SetWorld(world.get());
  trail->SetBody(box);
  trail->SetTrackedPoints({{0.5, 0.5}});
  trail->Record();
  EXPECT_EQ(trail->GetNumberOfSamples(), 0);
  auto missing = vtkSmartPointer<LatticeSource>::New();
  missing->GetExecutive();
  missing->SetWorld(world.get());
  missing->SetBody(7);
  missing->Update();
  EXPECT_EQ(missing->GetOutput()->GetNumberOfPoints(), 0);
}

}  // namespace
}  // namespace wobble::pipelines
