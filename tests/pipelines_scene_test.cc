// The sources of world_sources.h on Witkin & Welch bodies against an independent evaluation of
// x = R p(u) written out by hand (affine: A u + t; quadratic 2D: the six terms), and the render
// driver's (RenderTrajectory) .pvd/.vtp read back with VTK's readers, for linear bodies and for
// a world of both kinds (frames and filmstrip only with an X display).
#include <gtest/gtest.h>
#include <vtkCellArray.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkPNGReader.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLPolyDataReader.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "pipelines/scene_view.h"
#include "pipelines/trajectory_render.h"
#include "pipelines/world_sources.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/record/trajectory.h"
#include "support/pipelines_test_util.h"
#include "support/test_bodies.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;
template <class T> using Ptr = vtkSmartPointer<T>;

Eigen::VectorXd V(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double a : v) x[i++] = a;
  return x;
}

Eigen::Vector3d PointOf(vtkPolyData* d, vtkIdType i) {
  double x[3];
  d->GetPoint(i, x);
  return {x[0], x[1], x[2]};
}

TEST(LinearSources, AffineMassPointsAreAuPlusT) {
  World w(testing::WitkinWelchOptions());
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("b", 3, LinearOrder::kAffine, V({0.5, 0.3, 0.2}), 3, 2.0));
  const int b = w.AddLinearBody(model);
  Eigen::Matrix3d A;
  A << 1.1, 0.2, 0.0, -0.1, 0.9, 0.3, 0.05, 0.0, 1.2;
  const Eigen::Vector3d t(1, 2, 3), t_dot(0.5, -1, 0);
  Eigen::Matrix3d A_dot = 0.1 * A;
  Eigen::MatrixXd R(3, 4), Rd(3, 4);
  R << A, t;  // columns [m | t] (basis [x y z 1])
  Rd << A_dot, t_dot;
  w.SetLinearState(b, R, Rd);
  auto src = Ptr<MassPointSource>::New();
  src->SetWorld(&w);
  src->SetBody(b);
  src->Update();
  vtkPolyData* out = src->GetOutput();
  ASSERT_EQ(out->GetNumberOfPoints(), 27);
  vtkDataArray* vel = out->GetPointData()->GetArray("velocity");
  vtkDataArray* mass = out->GetPointData()->GetArray("mass");
  ASSERT_TRUE(vel && mass);
  for (int k = 0; k < 27; ++k) {
    const Eigen::Vector3d u = model->def().points[k];
    EXPECT_LT((PointOf(out, k) - (A * u + t)).norm(), 1e-12);
    double v[3];
    vel->GetTuple(k, v);
    EXPECT_LT((Eigen::Vector3d(v[0], v[1], v[2]) - (A_dot * u + t_dot)).norm(), 1e-12);
    EXPECT_DOUBLE_EQ(mass->GetTuple1(k), 2.0 / 27);
  }
  EXPECT_EQ(out->GetNumberOfVerts(), 27);
}

TEST(LinearSources, QuadraticControlBoxAndShapeFollowTheSecondOrderTerms) {
  // 2D quadratic: x = R [x, y, 1, xy, x², y²]: a bend y += c x² moves the box's and the
  // drawing's sampled points by exactly c x²
  World w(testing::WitkinWelchOptions());
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("q", 2, LinearOrder::kQuadratic, V({1.0, 0.25}), 3, 1.0));
  const int b = w.AddLinearBody(model);
  Eigen::MatrixXd R = model->RestState();
  const double c = -0.4, s = 0.15;
  R(1, 4) = c;  // y += c x²
  R(0, 3) = s;  // x += s xy
  w.SetLinearState(b, R, Eigen::MatrixXd::Zero(2, 6));
  auto bend = [&](const Eigen::Vector3d& u) { return Eigen::Vector3d(u.x() + s * u.x() * u.y(), u.y() + c * u.x() * u.x(), 0.0); };

  auto box = Ptr<LatticeSource>::New();
  box->SetWorld(&w);
  box->SetBody(b);
  box->SetPieces(8);
  box->Update();
  vtkPolyData* bo = box->GetOutput();
  vtkDataArray* rest = bo->GetPointData()->GetArray("rest_position");
  ASSERT_TRUE(rest);
  EXPECT_EQ(bo->GetNumberOfVerts(), 9);       // 3 × 3 grid nodes
  EXPECT_EQ(bo->GetNumberOfLines(), 6);       // 3 lines per direction
  EXPECT_EQ(bo->GetNumberOfPoints(), 9 + 6 * 9);
  for (vtkIdType i = 0; i < bo->GetNumberOfPoints(); ++i) {
    double u[3];
    rest->GetTuple(i, u);
    EXPECT_LT((PointOf(bo, i) - bend(Eigen::Vector3d(u[0], u[1], 0))).norm(), 1e-12);
  }
  // the grid spans the mass points' box: corners at (±1, ±0.25)
  double r0[3];
  rest->GetTuple(0, r0);
  EXPECT_DOUBLE_EQ(r0[0], -1.0);
  EXPECT_DOUBLE_EQ(r0[1], -0.25);

  auto shape = Ptr<ShapeSource>::New();
  shape->SetWorld(&w);
  shape->SetBody(b);
  const LinearDrawing d = MakeBoxDrawing(V({1.0, 0.25}), 4);
  shape->SetDrawing(d);
  shape->Update();
  vtkPolyData* so = shape->GetOutput();
  ASSERT_EQ(d.polylines.size(), 1u);
  ASSERT_EQ(so->GetNumberOfPoints(), vtkIdType(d.polylines[0].points.size()));
  for (size_t i = 0; i < d.polylines[0].points.size(); ++i) {
    const Eigen::VectorXd& u = d.polylines[0].points[i];
    EXPECT_LT((PointOf(so, vtkIdType(i)) - bend(Eigen::Vector3d(u[0], u[1], 0))).norm(), 1e-12);
  }
  // the outline is closed: one cell of n + 1 ids
  EXPECT_EQ(so->GetNumberOfLines(), 1);
}

TEST(LinearSources, PyramidDrawingAndBodyAreConsistent) {
  const LinearDrawing d = MakePyramidDrawing(3, 0.5, 1.0, 4);
  EXPECT_EQ(d.polylines.size(), 5u);                 // base outline + 4 slant edges
  EXPECT_EQ(d.triangles.size(), 4u * 16 + 2u * 16);  // 4 sides of 4² triangles + the base 4×4 quads
  for (const auto& t : d.triangles)
    for (int i : t) ASSERT_LT(i, int(d.vertices.size()));
  const LinearBodyDef body = MakePyramidBody("p", 3, LinearOrder::kQuadratic, 0.5, 1.0, 3, 3, 2.0);
  EXPECT_EQ(body.points.size(), 3u * 9 + 1);
  double total = 0;
  for (size_t k = 0; k < body.points.size(); ++k) {
    const Eigen::VectorXd& u = body.points[k];
    // inside the pyramid: |x|, |z| <= w (1 − y/h)
    EXPECT_LE(std::max(std::abs(u[0]), std::abs(u[2])), 0.5 * (1 - u[1]) + 1e-12);
    total += body.masses[k];
  }
  EXPECT_NEAR(total, 2.0, 1e-12);
  EXPECT_NO_THROW(LinearBodyModel{body});  // spans the quadratic basis
}

// Three samples of a body moving at constant velocity.
record::Trajectory MovingFrames(World* w, int b) {
  record::Trajectory frames(*w);
  Eigen::MatrixXd Rd = Eigen::MatrixXd::Zero(3, 4);
  Rd.col(3) << 1.0, 0.0, 0.0;
  w->SetLinearState(b, w->linear_R(b), Rd);
  for (int k = 0; k < 3; ++k) {
    frames.Append(*w);
    w->RunUntil(w->time() + 0.1);
  }
  return frames;
}

// The paths of the driver's report.
std::vector<std::string> Paths(const RenderReport& report) {
  std::vector<std::string> paths;
  for (const RenderReport::File& f : report.files) paths.push_back(f.path);
  return paths;
}

// A gait's filmstrip samples one cycle of the recorded pose graph: the cycle runs from where
// the first pose comes back to where it comes back again, the first row before the controller
// (pose −1) is not a cycle's start, and a run too short for the cycle asked for is refused.
TEST(SceneRun, GaitFilmstripSamplesOneCycleOfThePoseGraph) {
  World w;
  w.AddLinearBody(std::make_shared<LinearBodyModel>(
      MakeBoxBody("box", 2, LinearOrder::kAffine, Eigen::Vector2d(1, 1), 2, 1.0)));
  record::Trajectory run(w);
  // samples every 0.1 s: no pose, then poses 0 0 1 2 2 | 0 1 1 2 | 0 0 1 2 | 0 (cycles of 0.5, 0.4, 0.4 s)
  const int poses[] = {-1, 0, 0, 1, 2, 2, 0, 1, 1, 2, 0, 0, 1, 2, 0};
  for (int i = 0; i < 15; ++i) {
    w.SetTime(0.1 * i);
    run.Append(w, 0.0, poses[i]);
  }
  auto near = [](const std::vector<double>& got, const std::vector<double>& want) {
    ASSERT_EQ(got.size(), want.size());
    for (size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << i;
  };
  near(FilmstripCycleTimes(run, 0, 5), {0.1, 0.2, 0.3, 0.4, 0.5, 0.6});
  near(FilmstripCycleTimes(run, 1, 4), {0.6, 0.7, 0.8, 0.9, 1.0});
  near(FilmstripCycleTimes(run, 2, 2), {1.0, 1.2, 1.4});
  EXPECT_THROW(FilmstripCycleTimes(run, 3, 2), std::invalid_argument);  // the fourth never ends
  record::Trajectory no_graph(w);
  no_graph.Append(w);
  EXPECT_THROW(FilmstripCycleTimes(no_graph, 0, 2), std::invalid_argument);
}

TEST(SceneRun, WritesAPvdSeriesThatVtkReadsBack) {
  WorldOptions o = testing::WitkinWelchOptions();
  o.params.gravity_on = false;
  o.dt = 0.01;
  World w(o);
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("cube", 3, LinearOrder::kAffine, V({0.5, 0.5, 0.5}), 2, 1.0));
  const int b = w.AddLinearBody(model);
  const record::Trajectory frames = MovingFrames(&w, b);
  SceneSpec spec;
  spec.drawings = {MakeBoxDrawing(V({0.5, 0.5, 0.5}), 2)};
  RenderOutputs out;
  out.folder = (fs::temp_directory_path() / "wobble_scene_run_vtp").string();
  fs::remove_all(out.folder);
  out.name = "cube_run";
  out.frames = out.filmstrip = false;  // no display needed
  const std::vector<std::string> written = Paths(RenderTrajectory(w, frames, spec, out));
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0], out.folder + "/vtp/cube_run.pvd");
  std::ifstream pvd(written[0]);
  std::stringstream text;
  text << pvd.rdbuf();
  const std::string xml = text.str();
  // 3 frames × 3 parts
  size_t n = 0;
  for (size_t at = xml.find("<DataSet"); at != std::string::npos; at = xml.find("<DataSet", at + 1)) ++n;
  EXPECT_EQ(n, 9u);
  EXPECT_NE(xml.find("part=\"2\""), std::string::npos);
  // the mass points of the last frame: the cube's corners moved 0.2 along x
  auto reader = Ptr<vtkXMLPolyDataReader>::New();
  reader->SetFileName((out.folder + "/vtp/cube_points_0002.vtp").c_str());
  reader->Update();
  vtkPolyData* pts = reader->GetOutput();
  ASSERT_EQ(pts->GetNumberOfPoints(), 8);
  for (int k = 0; k < 8; ++k)
    EXPECT_LT((PointOf(pts, k) - (Eigen::Vector3d(model->def().points[k]) + Eigen::Vector3d(0.2, 0, 0))).norm(), 1e-9);
  vtkDataArray* tv = pts->GetFieldData()->GetArray("TimeValue");
  ASSERT_TRUE(tv);
  EXPECT_NEAR(tv->GetTuple1(0), 0.2, 1e-12);
  // the world is left at the last frame
  EXPECT_NEAR(w.time(), 0.2, 1e-12);
}

TEST(SceneRun, FramesAndFilmstripWithADisplay) {
  REQUIRE_DISPLAY();
  World w(testing::WitkinWelchOptions());
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("cube", 3, LinearOrder::kAffine, V({0.5, 0.5, 0.5}), 2, 1.0));
  const int b = w.AddLinearBody(model);
  const record::Trajectory frames = MovingFrames(&w, b);
  RenderOutputs out;
  out.folder = (fs::temp_directory_path() / "wobble_scene_run_png").string();
  fs::remove_all(out.folder);
  out.view.width = 64;
  out.view.height = 48;
  out.filmstrip_width = 32;
  out.filmstrip_height = 24;
  out.filmstrip_columns = 3;
  out.filmstrip_times = {0.0, 0.1, 0.2};
  out.vtp = false;
  RenderTrajectory(w, frames, SceneSpec{}, out);
  for (int k = 0; k < 3; ++k) EXPECT_TRUE(fs::exists(out.folder + "/frames/frame_000" + std::to_string(k) + ".png"));
  EXPECT_FALSE(fs::exists(out.folder + "/frames/frame_0003.png"));
  auto reader = Ptr<vtkPNGReader>::New();
  reader->SetFileName((out.folder + "/filmstrip.png").c_str());
  reader->Update();
  int dims[3];
  reader->GetOutput()->GetDimensions(dims);
  EXPECT_EQ(dims[0], 3 * 32 + 2 * 4);
  EXPECT_EQ(dims[1], 24);
}

// A constraint scene of both kinds: the FFD table falling with a linear box attached below the
// middle of its bottom edge (the multiplier step, A rebuilt per step), recorded every 25 steps
// (0.05 s) and exported. Issue 13: an FFD body in a scene was exported with TimeValue 0 in every
// .vtp while the .pvd had the right time; with one world and one clock every part of every
// frame carries its sample's time.
struct MixedRun {
  WorldOptions options = testing::WitkinWelchOptions();
  std::shared_ptr<record::Trajectory> run;
  SceneSpec spec;
  MixedRun() {
    World w(options);
    const int table = w.AddBody(testing::Table());
    w.SetState(table, testing::Vec({0, 50, 0, 0, 0, 0, 0}), Eigen::VectorXd::Zero(7));
    const int box = w.AddLinearBody(
        std::make_shared<const LinearBodyModel>(MakeBoxBody("box", 2, LinearOrder::kAffine, V({50, 30}), 3, 10.0)));
    Eigen::MatrixXd R = w.linear_R(box);
    R.col(2) << 150, 20;  // the box's top middle (0, 30) at the table's bottom middle (150, 50)
    w.SetLinearState(box, R, Eigen::MatrixXd::Zero(2, 3));
    w.AddAttachment(At(table, V({0.5, 0.0})), At(box, V({0.0, 30.0})));
    spec.drawings.resize(2);
    spec.drawings[box] = MakeBoxDrawing(V({50, 30}), 2);
    run = std::make_shared<record::Trajectory>(w);
    auto recorder = std::make_shared<record::Recorder>(run, 25);
    w.SetRecorder(recorder);
    recorder->Start(w);
    EXPECT_TRUE(w.RunUntil(0.5)) << w.status().message;
    EXPECT_LT(w.MaxViolation(), 1e-6);
    EXPECT_GT(w.per_step_factorizations(), 0);  // the constrained step moved the FFD body
  }
};

double TimeValueOf(const std::string& vtp) {
  auto reader = Ptr<vtkXMLPolyDataReader>::New();
  reader->SetFileName(vtp.c_str());
  reader->Update();
  vtkDataArray* tv = reader->GetOutput()->GetFieldData()->GetArray("TimeValue");
  return tv ? tv->GetTuple1(0) : NAN;
}

TEST(SceneRun, AWorldOfBothKindsExportsEachSamplesTimeValue) {
  const MixedRun mixed;
  const record::Trajectory& run = *mixed.run;
  ASSERT_EQ(run.size(), 11);
  RenderOutputs out;
  out.folder = testing::TempDir("scene_mixed_vtp");
  out.name = "mixed";
  out.frames = out.filmstrip = false;  // no display needed
  World world = WorldFor(run, mixed.options);
  const std::vector<std::string> written = Paths(RenderTrajectory(world, run, mixed.spec, out));
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0], out.folder + "/vtp/mixed.pvd");
  const char* parts[] = {"table_lattice", "table_points", "table_shape", "box_box", "box_points", "box_shape"};
  for (int k = 0; k < run.size(); ++k) {
    if (k > 0) {
      EXPECT_GT(run.time(k), 0.0);
    }
    char number[16];
    std::snprintf(number, sizeof(number), "_%04d.vtp", k);
    for (const char* part : parts)
      EXPECT_NEAR(TimeValueOf(out.folder + "/vtp/" + part + number), run.time(k), 1e-12) << part << " frame " << k;
  }
  // the .pvd says the same times, six parts a frame
  std::ifstream pvd(written[0]);
  std::stringstream text;
  text << pvd.rdbuf();
  std::vector<double> times;
  const std::string xml = text.str();
  for (size_t at = xml.find("timestep=\""); at != std::string::npos; at = xml.find("timestep=\"", at + 1))
    times.push_back(std::stod(xml.substr(at + 10)));
  ASSERT_EQ(times.size(), 6u * run.size());
  for (size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], run.time(int(i / 6)), 1e-12) << i;
  // the world is left at the last sample
  EXPECT_EQ(world.time(), run.time(run.size() - 1));
  fs::remove_all(out.folder);
}

// Frames at their exact times: between two samples every coordinate is blended linearly, so
// the table's points in a frame's .vtp are those of the blended state, and its TimeValue is k/7.
TEST(SceneRun, FramesAtAnFpsAreAtTheirExactTimes) {
  const MixedRun mixed;
  const record::Trajectory& run = *mixed.run;
  RenderOutputs out;
  out.folder = testing::TempDir("scene_mixed_fps");
  out.name = "mixed";
  out.frames = out.filmstrip = false;
  out.fps = 7;  // frames at k/7 s up to 0.5; samples every 0.05 s
  World world = WorldFor(run, mixed.options);
  const RenderReport report = RenderTrajectory(world, run, mixed.spec, out);
  EXPECT_EQ(report.frames, 4);
  World blended = WorldFor(run, mixed.options);
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    char number[16];
    std::snprintf(number, sizeof(number), "_%04d.vtp", k);
    const std::string vtp = out.folder + "/vtp/table_points" + number;
    const double t = k / 7.0;
    EXPECT_NEAR(TimeValueOf(vtp), t, 1e-12);
    int a = 0;
    while (a + 1 < run.size() && run.time(a + 1) <= t) ++a;
    const double alpha = a + 1 < run.size() ? (t - run.time(a)) / (run.time(a + 1) - run.time(a)) : 0.0;
    const int b = std::min(a + 1, run.size() - 1);
    blended.SetState(0, (1 - alpha) * run.q(a, 0) + alpha * run.q(b, 0), (1 - alpha) * run.qd(a, 0) + alpha * run.qd(b, 0));
    const std::vector<Eigen::Vector2d> expected = blended.PointPositions<2>(0);
    auto reader = Ptr<vtkXMLPolyDataReader>::New();
    reader->SetFileName(vtp.c_str());
    reader->Update();
    vtkPolyData* points = reader->GetOutput();
    ASSERT_EQ(points->GetNumberOfPoints(), vtkIdType(expected.size()));
    for (vtkIdType i = 0; i < points->GetNumberOfPoints(); ++i) {
      double x[3];
      points->GetPoint(i, x);
      EXPECT_LT((Eigen::Vector2d(x[0], x[1]) - expected[size_t(i)]).norm(), 1e-9);
    }
  }
  EXPECT_FALSE(fs::exists(out.folder + "/vtp/table_points_0004.vtp"));
  fs::remove_all(out.folder);
}

}  // namespace
}  // namespace wobble::pipelines
