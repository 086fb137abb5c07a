// VTK sources of Witkin & Welch bodies against an independent evaluation of x = R p(u) written
// out by hand (affine: A u + t; quadratic 2D: the six terms), and WriteSceneRun's .pvd/.vtp
// read back with VTK's readers (frames and filmstrip only with an X display).
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

#include "pipelines/constrained_sources.h"
#include "pipelines/scene_run.h"
#include "pipelines/scene_view.h"
#include "wobble/body/linear_shapes.h"
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
  auto src = Ptr<LinearMassPointSource>::New();
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

  auto box = Ptr<LinearBoxSource>::New();
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

  auto shape = Ptr<LinearShapeSource>::New();
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

// Three frames of a body moving at constant velocity.
std::vector<record::SceneFrame> MovingFrames(World* w, int b) {
  std::vector<record::SceneFrame> frames;
  Eigen::MatrixXd Rd = Eigen::MatrixXd::Zero(3, 4);
  Rd.col(3) << 1.0, 0.0, 0.0;
  w->SetLinearState(b, w->linear_R(b), Rd);
  for (int k = 0; k < 3; ++k) {
    frames.push_back(record::CaptureFrame(*w));
    w->RunUntil(w->time() + 0.1);
  }
  return frames;
}

TEST(SceneRun, WritesAPvdSeriesThatVtkReadsBack) {
  WorldOptions o = testing::WitkinWelchOptions();
  o.params.gravity_on = false;
  o.dt = 0.01;
  World w(o);
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("cube", 3, LinearOrder::kAffine, V({0.5, 0.5, 0.5}), 2, 1.0));
  const int b = w.AddLinearBody(model);
  const std::vector<record::SceneFrame> frames = MovingFrames(&w, b);
  ConstrainedSceneSpec spec;
  spec.drawings = {MakeBoxDrawing(V({0.5, 0.5, 0.5}), 2)};
  SceneRunOutputs out;
  out.folder = (fs::temp_directory_path() / "wobble_scene_run_vtp").string();
  fs::remove_all(out.folder);
  out.name = "cube_run";
  out.frames = out.filmstrip = false;  // no display needed
  const std::vector<std::string> written = WriteSceneRun(w, spec, frames, out);
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
  if (!HasDisplay()) GTEST_SKIP() << "no reachable X display: VTK 9.1 renders only through X";
  World w(testing::WitkinWelchOptions());
  auto model = std::make_shared<const LinearBodyModel>(MakeBoxBody("cube", 3, LinearOrder::kAffine, V({0.5, 0.5, 0.5}), 2, 1.0));
  const int b = w.AddLinearBody(model);
  const std::vector<record::SceneFrame> frames = MovingFrames(&w, b);
  SceneRunOutputs out;
  out.folder = (fs::temp_directory_path() / "wobble_scene_run_png").string();
  fs::remove_all(out.folder);
  out.width = 64;
  out.height = 48;
  out.filmstrip_width = 32;
  out.filmstrip_height = 24;
  out.filmstrip_columns = 3;
  out.filmstrip_times = {0.0, 0.1, 0.2};
  out.vtp = false;
  WriteSceneRun(w, ConstrainedSceneSpec{}, frames, out);
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

}  // namespace
}  // namespace wobble::pipelines
