// Render regression: small offscreen images of each layer (lattice, mass points, shape,
// ground), a full scene, a chart, a colour-mapped field and a filmstrip, compared with baseline PNGs committed in
// tests/baselines (made on the Xvfb + llvmpipe stack `make test` uses).
//
// Comparison (stated here, used by every case): a pixel matches when some pixel of the other
// image within ±1 pixel in x and y has every channel within kChannelTolerance (of 255); both
// directions are checked (new against baseline and baseline against new, so a missing line
// counts as well as an extra one), and an image passes when at most kMaxBadFraction of its
// pixels fail. On failure the new image and a diff image (|new − baseline| × 4) are written to
// tests/render_failures in the build folder (test_env::RenderFailureDir()).
//
// Without DISPLAY the tests skip with a message (VTK 9.1 aborts without X). To remake the
// baselines after an intended change: WOBBLE_UPDATE_BASELINES=1 xvfb-run -a -s "-screen 0
// 1280x1024x24" build/tests/pipelines_render_test, then look at every image before committing.
#include <gtest/gtest.h>
#include <vtkAxis.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkDoubleArray.h>
#include <vtkImageData.h>
#include <vtkActor2DCollection.h>
#include <vtkCoordinate.h>
#include <vtkPNGReader.h>
#include <vtkRenderer.h>
#include <vtkScalarBarActor.h>
#include <vtkTextActor.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "pipelines/condition_charts.h"
#include "pipelines/charts.h"
#include "pipelines/energy_charts.h"
#include "pipelines/exports.h"
#include "pipelines/mesh_io.h"
#include "wobble/formats/deformation_file.h"
#include "pipelines/scene_view.h"
#include "wobble/body/linear_shapes.h"
#include "support/pipelines_test_util.h"
#include "support/render_baseline.h"
#include "support/test_bodies.h"
#include "support/source_paths.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;
using testing::AirborneWorld;
using testing_render::CompareWithBaseline;

// One layer alone, 160 x 120, no overlay.
SceneOptions OnlyLayer(const std::string& layer) {
  SceneOptions o;
  o.width = 160;
  o.height = 120;
  o.overlay = false;
  o.show_ground = layer == "ground";
  o.show_lattice = layer == "lattice";
  o.show_points = layer == "points";
  o.show_shape = layer == "shape";
  o.show_springs = false;
  return o;
}

vtkSmartPointer<vtkImageData> RenderLayer(const SceneOptions& options) {
  auto world = AirborneWorld();
  SceneView view(world.get(), options);
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-100, 0), Eigen::Vector2d(400, 350)));
  view.Render();
  return view.Capture();
}

// Iterations and seeds: ticks on whole numbers only (1, 2 or 5 times a power of ten apart);
// a chart for a file keeps its legend beside the plot, where it cannot cover a curve.
TEST(Charts, WholeNumberTicksAndALegendBesideThePlot) {
  ChartSpec spec;
  ChartSeries s;
  for (int i = 0; i <= 60; ++i) s.x.push_back(i), s.y.push_back(1.0 / (1 + i));
  spec.series = {s};
  spec.integer_x = true;
  auto chart = vtkSmartPointer<vtkChartXY>::New();
  FillChart(chart, spec);
  vtkDoubleArray* ticks = chart->GetAxis(vtkAxis::BOTTOM)->GetTickPositions();
  ASSERT_NE(ticks, nullptr);
  ASSERT_EQ(ticks->GetNumberOfTuples(), 7);  // 0, 10, ..., 60
  for (vtkIdType k = 0; k < ticks->GetNumberOfTuples(); ++k) EXPECT_EQ(ticks->GetValue(k), 10.0 * double(k));
  EXPECT_TRUE(chart->GetLegend()->GetInline());  // FillChart's default, for the viewer's small panels
  spec.series[0].x = {1, 2, 3, 4, 5, 6};
  spec.series[0].y = {1, 2, 3, 4, 5, 6};
  spec.legend_beside = true;
  FillChart(chart, spec);
  ticks = chart->GetAxis(vtkAxis::BOTTOM)->GetTickPositions();
  ASSERT_EQ(ticks->GetNumberOfTuples(), 6);  // 1 ... 6, no 1.5
  for (vtkIdType k = 0; k < ticks->GetNumberOfTuples(); ++k) EXPECT_EQ(ticks->GetValue(k), double(k + 1));
  EXPECT_FALSE(chart->GetLegend()->GetInline());
}

// Shapes on a chart: with equal_aspect a circle is drawn round (its red pixels' box is
// square to 2 %) although the data span three times as much in y as in x; without it, the
// same circle is not round (so the check can fail). Segments draw pairs, not a polyline.
TEST(Charts, EqualAspectDrawsACircleRound) {
  REQUIRE_DISPLAY();
  ChartSpec spec;
  spec.width = 700;
  spec.height = 500;
  ChartSeries circle, far;
  circle.name = "circle";
  circle.rgb[0] = 255, circle.rgb[1] = 0, circle.rgb[2] = 0;
  for (int i = 0; i <= 200; ++i) circle.x.push_back(10 * std::cos(i * M_PI / 100)), circle.y.push_back(10 * std::sin(i * M_PI / 100));
  far.name = "far";
  far.points = true;
  far.x = {0.0};
  far.y = {50.0};
  far.rgb[0] = 0, far.rgb[1] = 0, far.rgb[2] = 255;
  spec.series = {circle, far};
  auto red_box = [](vtkImageData* image) {
    int dims[3];
    image->GetDimensions(dims);
    int x0 = dims[0], x1 = -1, y0 = dims[1], y1 = -1;
    for (int y = 0; y < dims[1]; ++y)
      for (int x = 0; x < dims[0] * 7 / 10; ++x) {  // left of the legend (beside the plot, with a red sample)
        const auto* p = static_cast<unsigned char*>(image->GetScalarPointer(x, y, 0));
        if (p[0] > 200 && p[1] < 80 && p[2] < 80) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
      }
    return std::pair<double, double>(x1 - x0, y1 - y0);
  };
  const auto [w_plain, h_plain] = red_box(RenderChart(spec));
  EXPECT_GT(std::abs(w_plain / h_plain - 1.0), 0.1) << w_plain << " x " << h_plain;
  spec.equal_aspect = true;
  const auto [w, h] = red_box(RenderChart(spec));
  EXPECT_GT(w, 50.0);
  EXPECT_NEAR(w / h, 1.0, 0.02) << w << " x " << h;
}

// One spike does not flatten the rest: the axis shows the bulk, the title names the peak, and
// without a spike the range is the data's.
TEST(Charts, OneSpikeLeavesTheBulkReadable) {
  ChartSeries s;
  for (int i = 0; i < 200; ++i) s.x.push_back(0.01 * i), s.y.push_back(std::sin(0.1 * i));
  s.y[41] = 1000;  // one sample, 500 spans above the rest
  const RobustRange r = RobustYRange({s});
  EXPECT_EQ(r.cut_y, 1000.0);
  EXPECT_DOUBLE_EQ(r.cut_x, 0.41);
  EXPECT_GT(r.hi, 0.99);  // the sine's top is in view ...
  EXPECT_LT(r.hi, 1.6);   // ... the spike is not
  EXPECT_EQ(r.lo, -1.0 * std::abs(*std::min_element(s.y.begin(), s.y.end())));  // no dip: the data's low end
  ChartSpec spec;
  spec.title = "energy";
  spec.series = {s};
  auto chart = vtkSmartPointer<vtkChartXY>::New();
  FillChart(chart, spec);
  EXPECT_EQ(chart->GetAxis(vtkAxis::LEFT)->GetMaximum(), r.hi);
  EXPECT_NE(std::string(chart->GetTitle()).find("peak 1e+03 at x = 0.41 off the scale"), std::string::npos)
      << chart->GetTitle();
  s.y[41] = std::sin(4.1);
  const RobustRange plain = RobustYRange({s});
  EXPECT_TRUE(std::isnan(plain.cut_y));
  EXPECT_EQ(plain.hi, *std::max_element(s.y.begin(), s.y.end()));
  spec.series = {s};
  FillChart(chart, spec);
  EXPECT_EQ(std::string(chart->GetTitle()), "energy");
}

TEST(RenderRegression, LatticeView) {
  REQUIRE_DISPLAY();
  CompareWithBaseline("lattice", RenderLayer(OnlyLayer("lattice")));
}

TEST(RenderRegression, MassPointsColouredByVelocity) {
  REQUIRE_DISPLAY();
  SceneOptions o = OnlyLayer("points");
  o.color_by = "velocity";
  o.color_range[0] = 0;
  o.color_range[1] = 200;
  o.show_color_bar = false;
  CompareWithBaseline("mass_points", RenderLayer(o));
}

TEST(RenderRegression, ShapeResampled) {
  REQUIRE_DISPLAY();
  CompareWithBaseline("shape", RenderLayer(OnlyLayer("shape")));
}

TEST(RenderRegression, SlopedGround) {
  REQUIRE_DISPLAY();
  CompareWithBaseline("ground", RenderLayer(OnlyLayer("ground")));
}

TEST(RenderRegression, FullSceneWithOverlayAndColourBar) {
  REQUIRE_DISPLAY();
  SceneOptions o;
  o.width = 240;
  o.height = 180;
  o.color_by = "applied_force";
  o.color_range[0] = 0;
  o.color_range[1] = 2000;
  auto world = testing::TouchingWorld();
  SceneView view(world.get(), o);
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-50, -150), Eigen::Vector2d(350, 150)));
  view.Render();
  CompareWithBaseline("full_scene", view.Capture());
}

// The overlay lists every term of the energy it shows that is not zero (here the ground's
// penalty energy too, the table resting in contact), each as the world computes it, and the
// colour bar never covers the text: both at the baseline's size and at the render's default.
TEST(RenderOverlay, EnergyIsTheSumOfTheTermsListedAndTheColourBarClearsTheText) {
  REQUIRE_DISPLAY();
  auto world = testing::TouchingWorld();
  const Energies e = world->ComputeEnergies(0);
  ASSERT_GT(e.ground, 0.0);
  ASSERT_EQ(e.springs, 0.0);
  for (const auto& [w, h] : {std::pair{240, 180}, std::pair{640, 480}}) {
    SCOPED_TRACE(w);
    SceneOptions o;
    o.width = w;
    o.height = h;
    o.color_by = "applied_force";
    SceneView view(world.get(), o);
    view.Render();
    vtkTextActor* text = nullptr;
    vtkScalarBarActor* bar = nullptr;
    vtkActor2DCollection* actors = view.renderer()->GetActors2D();
    actors->InitTraversal();
    while (vtkActor2D* a = actors->GetNextActor2D()) {
      if (auto* t = vtkTextActor::SafeDownCast(a)) text = t;
      if (auto* b = vtkScalarBarActor::SafeDownCast(a)) bar = b;
    }
    ASSERT_TRUE(text && bar);
    const std::string overlay = text->GetInput();
    auto value_after = [&](const std::string& label) {
      const size_t at = overlay.find(label);
      if (at == std::string::npos) return std::nan("");
      return std::strtod(overlay.c_str() + at + label.size(), nullptr);
    };
    EXPECT_NEAR(value_after("E = "), e.total(), 5e-4 * std::abs(e.total())) << overlay;  // %.4g
    EXPECT_NEAR(value_after("kin "), e.kinetic, 5e-3 * std::abs(e.kinetic) + 1e-12) << overlay;  // %.3g
    EXPECT_NEAR(value_after("grav "), e.gravity, 5e-3 * std::abs(e.gravity)) << overlay;
    EXPECT_NEAR(value_after("modes "), e.modes, 5e-3 * std::abs(e.modes) + 1e-12) << overlay;
    EXPECT_NEAR(value_after("ground "), e.ground, 5e-3 * e.ground) << overlay;
    EXPECT_EQ(overlay.find("springs"), std::string::npos) << overlay;  // zero: not listed
    // the two boxes in display pixels do not meet
    double t[4];  // VTK gives it relative to the text's position
    text->GetBoundingBox(view.renderer(), t);
    const int* at = text->GetPositionCoordinate()->GetComputedDisplayValue(view.renderer());
    for (int k = 0; k < 4; ++k) t[k] += at[k / 2];
    EXPECT_GT(t[3], 0.8 * h);  // the text is at the top
    double* p = bar->GetPositionCoordinate()->GetComputedDoubleDisplayValue(view.renderer());
    const double b[4] = {p[0], p[0] + bar->GetWidth() * w, p[1], p[1] + bar->GetHeight() * h};
    EXPECT_TRUE(t[1] <= b[0] || b[1] <= t[0] || t[3] <= b[2] || b[3] <= t[2])
        << "text " << t[0] << ".." << t[1] << " x " << t[2] << ".." << t[3] << ", bar " << b[0] << ".." << b[1] << " x "
        << b[2] << ".." << b[3];
  }
}

// A 3D character with its own mesh (issue 15): the pot deformed (squash, sway, twist) and
// turned above the ground plane, with its lattice and mass points, in perspective.
TEST(RenderRegression, MeshCharacter3d) {
  REQUIRE_DISPLAY();
  BodyDefN<3> def = ReadObject<3>(wobble::test_env::DataDir() + "/pot3.obj");
  std::vector<DeformationModeN<3>> modes = formats::ReadDeformationFile(wobble::test_env::DataDir() + "/pot3_modes.def3", def.lattice);
  WorldOptions options;
  options.params.ground_plane.enabled = true;
  World world(options);
  world.AddBody(std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes)));
  world.SetState(0, PositionsOf(Eigen::Vector3d(0, 40, 0), Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 0, 0.5).normalized())), Eigen::Vector3d(-0.3, 0.4, 0.5)), Eigen::VectorXd::Zero(9));
  SceneOptions o;
  o.width = 240;
  o.height = 180;
  o.overlay = false;
  o.elevation = 25;
  SceneView view(&world, o);
  view.FrameBounds(SceneBounds(world));
  view.Render();
  CompareWithBaseline("mesh_character_3d", view.Capture());
}

TEST(RenderRegression, EnergyChart) {
  REQUIRE_DISPLAY();
  auto world = testing::AirborneWorld();
  auto run = std::make_shared<record::Trajectory>(*world);
  auto recorder = std::make_shared<record::Recorder>(run);
  world->SetRecorder(recorder);
  recorder->Start(*world);
  world->RunUntil(1.0);
  ChartSpec spec = EnergyChart(*run, 0, "energy");
  spec.width = 320;
  spec.height = 200;
  CompareWithBaseline("energy_chart", RenderChart(spec));
}

TEST(RenderRegression, Filmstrip) {
  REQUIRE_DISPLAY();
  auto world = testing::AirborneWorld();
  SceneOptions o;
  o.width = 96;
  o.height = 72;
  o.overlay = false;
  SceneView view(world.get(), o);
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-100, -100), Eigen::Vector2d(500, 350)));
  std::vector<vtkSmartPointer<vtkImageData>> panels;
  for (double t : {0.0, 1.5, 3.0, 4.5}) {
    world->RunUntil(t, [](const World&) {});
    view.Render();
    panels.push_back(view.Capture());
  }
  vtkSmartPointer<vtkImageData> strip = TileImages(panels, 2);
  int dims[3];
  strip->GetDimensions(dims);
  EXPECT_EQ(dims[0], 2 * 96 + 4);  // two columns, a 4-pixel gap
  EXPECT_EQ(dims[1], 2 * 72 + 4);
  CompareWithBaseline("filmstrip", strip);
}

// Issue 4's pictures: the Fig. 4.7 sweep chart and the cond map over the angle and the
// vertical squash amplitude, for the table of data/table.obj.
TEST(RenderRegression, ConditionSweepChart) {
  REQUIRE_DISPLAY();
  std::vector<double> phis;
  for (int i = 0; i <= 18; ++i) phis.push_back(3.14159265358979323846 / 2 * i / 18);
  const auto samples = analysis::AngleSweep(testing::Table()->def(), phis, analysis::Squash(), Eigen::VectorXd::Zero(5));
  ChartSpec spec = SweepChart(samples);
  spec.width = 320;
  spec.height = 200;
  CompareWithBaseline("condition_sweep", RenderChart(spec));
}

TEST(RenderRegression, ConditionMap) {
  REQUIRE_DISPLAY();
  ConditionGrid grid;
  grid.nx = grid.ny = 12;
  grid.x0 = 0.0;
  grid.dx = 90.0 / 11;
  grid.y0 = -0.5;
  grid.dy = 1.0 / 11;
  for (int j = 0; j < grid.ny; ++j) {
    std::vector<double> phis;
    for (int i = 0; i < grid.nx; ++i) phis.push_back((grid.x0 + grid.dx * i) * 3.14159265358979323846 / 180);
    Eigen::VectorXd q = Eigen::VectorXd::Zero(5);
    q[3] = grid.y0 + grid.dy * j;
    for (const auto& s : analysis::AngleSweep(testing::Table()->def(), phis, analysis::Squash(), q))
      grid.cond.push_back(s.cond.cond);
  }
  ScalarFieldSpec spec = ConditionMapField(grid, "phi (degrees)", "gamma1");
  spec.width = 320;
  spec.height = 240;
  CompareWithBaseline("condition_map", RenderScalarField(spec));
}

TEST(RenderRegression, ScalarFieldWithColourLegend) {
  REQUIRE_DISPLAY();
  ScalarFieldSpec s;
  s.title = "field";
  s.x_title = "x";
  s.y_title = "y";
  s.value_title = "v";
  s.nx = 12;
  s.ny = 8;
  s.x_min = 0;
  s.x_max = 1.1;
  s.y_min = -1;
  s.y_max = 0.4;
  for (int j = 0; j < s.ny; ++j)
    for (int i = 0; i < s.nx; ++i) s.values.push_back(1.0 + i * i + 3.0 * j);
  s.width = 240;
  s.height = 180;
  CompareWithBaseline("scalar_field", RenderScalarField(s));
}

// Issue 7: a 3D frame of Witkin & Welch bodies in perspective: a quadratic block bent by its
// second-order terms (control box, mass points, lit surface and outline), a pyramid sheared
// and lifted, and two named points.
TEST(RenderRegression, ConstrainedScene3d) {
  REQUIRE_DISPLAY();
  World world(testing::WitkinWelchOptions());
  Eigen::VectorXd half(3);
  half << 1.0, 0.5, 0.5;
  auto block = std::make_shared<const LinearBodyModel>(MakeBoxBody("block", 3, LinearOrder::kQuadratic, half, 3, 1.0));
  auto pyramid = std::make_shared<const LinearBodyModel>(MakePyramidBody("pyramid", 3, LinearOrder::kAffine, 0.5, 1.0, 3, 3, 1.0));
  const int b = world.AddLinearBody(block), p = world.AddLinearBody(pyramid);
  Eigen::MatrixXd R = block->RestState();
  R(1, 7) = -0.3;  // y −= 0.3 x²: the block bends down at both ends (basis [x y z 1 xy xz yz x² y² z²])
  R(0, 4) = 0.2;   // x += 0.2 xy: and shears with height
  world.SetLinearState(b, R, Eigen::MatrixXd::Zero(3, 10));
  Eigen::MatrixXd Rp = pyramid->RestState();
  Rp(0, 1) = 0.3;  // x += 0.3 y: leaning
  Rp.col(3) << 2.2, -0.5, 0.3;
  world.SetLinearState(p, Rp, Eigen::MatrixXd::Zero(3, 4));
  SceneSpec spec;
  spec.drawings = {MakeBoxDrawing(half, 6), MakePyramidDrawing(3, 0.5, 1.0, 6)};
  AnchorSource::Anchor corner, sky;
  corner.point = At(b, (Eigen::VectorXd(3) << 1, 0.5, 0.5).finished());
  sky.place = Eigen::Vector3d(0.0, 1.5, 0.0);
  spec.anchors = {corner, sky};
  SceneOptions o;
  o.width = 200;
  o.height = 150;
  o.overlay = false;
  o.azimuth = 30;
  o.elevation = 20;
  SceneView view(&world, o, spec);
  view.Render();
  CompareWithBaseline("constrained_scene_3d", view.Capture());
}

}  // namespace
}  // namespace wobble::pipelines
