// Export round trips: .vtp/.pvd read back with VTK's readers (points and arrays), EXR read
// back with OpenEXR (named channels, displacement at known pixels against Eq. 4.2 evaluated
// independently, rendered colour and depth), and failed writes that leave the earlier file
// intact with a clear error.
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkDataArray.h>
#include <vtkCellArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkCamera.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkPointData.h>
#include <vtkPNGReader.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUtilities.h>
#include <vtkActor2DCollection.h>
#include <vtkCoordinate.h>
#include <vtkTextActor.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "pipelines/charts.h"
#include "pipelines/energy_charts.h"
#include "pipelines/exports.h"
#include "support/reference.h"
#include <Eigen/Eigenvalues>
#include "pipelines/exr_frame.h"
#include "pipelines/exr_io.h"
#include "pipelines/trajectory_render.h"
#include "wobble/record/trajectory.h"
#include "pipelines/scene_view.h"
#include "support/pipelines_test_util.h"
#include "support/test_bodies.h"
#include "wobble/dynamics/heightfield.h"
#include "wobble/formats/atomic_file.h"
#include "support/source_paths.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;
using testing::AirborneWorld;
using testing::IndependentWorldPoint;
using testing::TempDir;

// The sRGB transfer function's inverse (IEC 61966-2-1): what an 8-bit display value c is in
// linear light.
double SrgbToLinear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

vtkSmartPointer<vtkPolyData> ReadVtp(const std::string& path) {
  auto r = vtkSmartPointer<vtkXMLPolyDataReader>::New();
  r->SetFileName(path.c_str());
  r->Update();
  auto out = vtkSmartPointer<vtkPolyData>::New();
  out->DeepCopy(r->GetOutput());
  return out;
}

// Every point and every point array of a and b are bit-identical (raw binary doubles).
void ExpectSamePolyData(vtkPolyData* a, vtkPolyData* b) {
  ASSERT_EQ(a->GetNumberOfPoints(), b->GetNumberOfPoints());
  ASSERT_GT(a->GetNumberOfPoints(), 0);
  EXPECT_EQ(a->GetNumberOfCells(), b->GetNumberOfCells());
  for (vtkIdType i = 0; i < a->GetNumberOfPoints(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(a->GetPoint(i)[c], b->GetPoint(i)[c]);
  ASSERT_EQ(a->GetPointData()->GetNumberOfArrays(), b->GetPointData()->GetNumberOfArrays());
  for (int k = 0; k < a->GetPointData()->GetNumberOfArrays(); ++k) {
    vtkDataArray* x = a->GetPointData()->GetArray(k);
    vtkDataArray* y = b->GetPointData()->GetArray(x->GetName());
    ASSERT_NE(y, nullptr) << x->GetName();
    ASSERT_EQ(x->GetNumberOfValues(), y->GetNumberOfValues());
    for (vtkIdType v = 0; v < x->GetNumberOfValues(); ++v)
      EXPECT_EQ(x->GetComponent(v / x->GetNumberOfComponents(), int(v % x->GetNumberOfComponents())),
                y->GetComponent(v / y->GetNumberOfComponents(), int(v % y->GetNumberOfComponents())))
          << x->GetName();
  }
  vtkDataArray* ta = a->GetFieldData()->GetArray("TimeValue");
  vtkDataArray* tb = b->GetFieldData()->GetArray("TimeValue");
  ASSERT_TRUE(ta && tb);
  EXPECT_EQ(ta->GetTuple1(0), tb->GetTuple1(0));
}

TEST(VtpExport, SeriesReadsBackThroughThePvdWithEveryPointAndArray) {
  const std::string dir = TempDir("vtp");
  auto world = AirborneWorld();
  VtpSeriesWriter series(world.get(), dir, "table");
  std::vector<std::vector<vtkSmartPointer<vtkPolyData>>> expected;  // [frame][part]
  std::vector<double> times;
  for (int frame = 0; frame < 3; ++frame) {
    for (int k = 0; k < 5; ++k) world->Step();
    series.WriteFrame(frame);
    // what the sources give now, built independently of the writer
    std::vector<vtkSmartPointer<vtkPolyData>> parts;
    auto lattice = vtkSmartPointer<LatticeSource>::New();
    auto points = vtkSmartPointer<MassPointSource>::New();
    auto shape = vtkSmartPointer<ShapeSource>::New();
    for (WorldSourceBase* s : {(WorldSourceBase*)lattice, (WorldSourceBase*)points, (WorldSourceBase*)shape}) {
      s->SetWorld(world.get());
      s->Update();
      auto copy = vtkSmartPointer<vtkPolyData>::New();
      copy->DeepCopy(s->GetOutput());
      parts.push_back(copy);
    }
    expected.push_back(parts);
    times.push_back(world->time());
  }
  const std::string pvd = series.WriteCollection();

  // the collection, parsed by VTK's XML parser: 3 time steps x 3 parts, relative file names
  vtkXMLDataElement* root = vtkXMLUtilities::ReadElementFromFile(pvd.c_str());
  ASSERT_NE(root, nullptr);
  EXPECT_STREQ(root->GetAttribute("type"), "Collection");
  vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
  ASSERT_NE(collection, nullptr);
  ASSERT_EQ(collection->GetNumberOfNestedElements(), 9);
  for (int e = 0; e < 9; ++e) {
    vtkXMLDataElement* ds = collection->GetNestedElement(e);
    double t = 0;
    int part = -1;
    ASSERT_TRUE(ds->GetScalarAttribute("timestep", t));
    ASSERT_TRUE(ds->GetScalarAttribute("part", part));
    const std::string file = ds->GetAttribute("file");
    EXPECT_FALSE(fs::path(file).is_absolute()) << file;
    const int frame = e / 3;
    EXPECT_EQ(part, e % 3);
    EXPECT_NEAR(t, times[frame], 1e-15);
    // each file read back equals what the sources gave, bit for bit, TimeValue included
    vtkSmartPointer<vtkPolyData> back = ReadVtp(dir + "/" + file);
    ExpectSamePolyData(expected[frame][part], back);
    EXPECT_EQ(back->GetFieldData()->GetArray("TimeValue")->GetTuple1(0), times[frame]);
  }
  root->Delete();
  // the mass points part carries the named arrays
  vtkSmartPointer<vtkPolyData> points = ReadVtp(dir + "/table_points_0002.vtp");
  for (const char* name : {"mass", "velocity", "applied_force", "in_contact"})
    EXPECT_NE(points->GetPointData()->GetArray(name), nullptr) << name;
  fs::remove_all(dir);
}

// A world with a terrain: the .pvd lists it as the last part at every time, one file (it does
// not move) whose surface polyline passes through every vertex of the profile.
TEST(VtpExport, TerrainIsItsOwnPartAtEveryTime) {
  const std::string dir = TempDir("vtp_terrain");
  WorldOptions o;
  o.params.ground.terrain = Terrain::Make({{0, 100}, {0, 0}, {300, 0}, {400, 50}});
  World world(o);
  world.AddBody(testing::Table());
  world.SetState(0, testing::Vec({-250, 140, 0, 0, 0, 0, 0}), testing::Vec({0, 0, 0, 0, 0, 0, 0}));
  VtpSeriesWriter series(&world, dir, "cliff");
  for (int frame = 0; frame < 3; ++frame) {
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(world.Step());
    series.WriteFrame(frame);
  }
  vtkXMLDataElement* root = vtkXMLUtilities::ReadElementFromFile(series.WriteCollection().c_str());
  ASSERT_NE(root, nullptr);
  vtkXMLDataElement* collection = root->FindNestedElementWithName("Collection");
  ASSERT_EQ(collection->GetNumberOfNestedElements(), 3 * 4);  // 3 times x (lattice, points, shape, terrain)
  for (int e = 3; e < 12; e += 4) {
    vtkXMLDataElement* ds = collection->GetNestedElement(e);
    int part = -1;
    ASSERT_TRUE(ds->GetScalarAttribute("part", part));
    EXPECT_EQ(part, 3);
    EXPECT_STREQ(ds->GetAttribute("file"), "terrain.vtp");
    EXPECT_STREQ(ds->GetAttribute("name"), "terrain");
  }
  root->Delete();
  vtkSmartPointer<vtkPolyData> terrain = ReadVtp(dir + "/terrain.vtp");
  ASSERT_EQ(terrain->GetLines()->GetNumberOfCells(), 1);
  vtkNew<vtkIdList> line;
  terrain->GetLines()->GetCellAtId(0, line);
  std::vector<Eigen::Vector2d> surface;
  for (vtkIdType k = 0; k < line->GetNumberOfIds(); ++k) {
    const double* p = terrain->GetPoint(line->GetId(k));
    surface.emplace_back(p[0], p[1]);
  }
  for (const Eigen::Vector2d& v : o.params.ground.terrain->vertices())
    EXPECT_NE(std::find(surface.begin(), surface.end(), v), surface.end()) << v.transpose();
  // filled below: the level left of the cliff, the floor, the slope and the level beyond it
  EXPECT_EQ(terrain->GetPolys()->GetNumberOfCells(), 4);
  EXPECT_NE(terrain->GetPointData()->GetArray("height"), nullptr);
  fs::remove_all(dir);
}

TEST(ExrIo, NamedChannelsRoundTripExactly) {
  const std::string dir = TempDir("exr");
  const int w = 7, h = 5;
  std::vector<ExrChannel> ch = {{"cond", {}}, {"angle.X", {}}, {"zeta", {}}};
  for (size_t c = 0; c < ch.size(); ++c)
    for (int i = 0; i < w * h; ++i) ch[c].data.push_back(float(1e-3 * i * i - 0.25 * c + (i % 3 ? 1e6 : -2.5)));
  for (ExrCompression comp : {ExrCompression::kNone, ExrCompression::kZip}) {
    WriteExrChannels(dir + "/c.exr", w, h, ch, comp);
    const ExrImage back = ReadExrChannels(dir + "/c.exr");
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    ASSERT_EQ(back.channels.size(), 3u);
    for (const ExrChannel& c : ch) EXPECT_EQ(back.channels.at(c.name), c.data) << c.name;  // lossless floats
    // row 0 is the top: pixel (x, y) is data[y * w + x]
    EXPECT_EQ(back.At("zeta", 3, 2), ch[2].data[2 * w + 3]);
  }
  EXPECT_THROW(WriteExrChannels(dir + "/bad.exr", w, h, {{"a", std::vector<float>(3)}}), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir + "/bad.exr"));
  fs::remove_all(dir);
}

TEST(DisplacementExr, ValuesAtKnownPixelsMatchTheFfdEvaluatedIndependently) {
  const std::string dir = TempDir("disp");
  auto world = AirborneWorld();
  const BodyModel& body = world->body<2>(0);
  const Eigen::VectorXd q = world->q(0);
  const int w = 64, h = 24;
  WriteDisplacementExr(dir + "/disp.exr", *world, 0, w, h);
  const ExrImage img = ReadExrChannels(dir + "/disp.exr");
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  ASSERT_TRUE(img.channels.count("disp.X") && img.channels.count("disp.Y"));
  // corners, centre and a few inner pixels: pixel (px, py) stands for s = (px + ½)/w and
  // t = 1 − (py + ½)/h, whose rest point on the 300 x 100 table lattice is (300 s, 100 t)
  for (auto [px, py] : std::vector<std::pair<int, int>>{{0, 0}, {w - 1, 0}, {0, h - 1}, {w - 1, h - 1}, {32, 12}, {5, 17}, {50, 3}}) {
    const Eigen::Vector2d st((px + 0.5) / w, 1.0 - (py + 0.5) / h);
    const Eigen::Vector2d rest(300 * st.x(), 100 * st.y());
    const Eigen::Vector2d disp = IndependentWorldPoint(body, q, st) - rest;
    // float channels: relative 1e-6 of the world coordinates (a few hundred)
    EXPECT_NEAR(img.At("disp.X", px, py), disp.x(), 1e-3) << px << "," << py;
    EXPECT_NEAR(img.At("disp.Y", px, py), disp.y(), 1e-3) << px << "," << py;
  }
  // at rest nothing moves
  World rest_world;
  rest_world.AddBody(testing::Table());
  WriteDisplacementExr(dir + "/rest.exr", rest_world, 0, 16, 8);
  const ExrImage rest = ReadExrChannels(dir + "/rest.exr");
  for (float v : rest.channels.at("disp.X")) EXPECT_NEAR(v, 0.0, 1e-4);
  for (float v : rest.channels.at("disp.Y")) EXPECT_NEAR(v, 0.0, 1e-4);
  fs::remove_all(dir);
}

// The header carries OpenEXR's standard camera and time attributes: a mass point's world
// position through worldToNDC lands on the pixel where that point is drawn (red, opaque), its
// worldToCamera z is its depth.Z, and the frame number comes back from the timeCode at 30 fps.
TEST(RenderedExr, CameraAndTimeInTheHeaderAtKnownPixels) {
  REQUIRE_DISPLAY();
  const std::string dir = TempDir("frame_exr_meta");
  auto world = AirborneWorld();  // deformed and turned: the camera is not the identity on it
  SceneOptions opt;
  opt.width = 200;
  opt.height = 150;
  opt.overlay = false;
  SceneView view(world.get(), opt);
  view.Render();
  view.WriteExr(dir + "/f.exr", nullptr, 30.0, 3725);  // 2 min 4 s and 5 frames at 30 fps
  const ExrImage img = ReadExrChannels(dir + "/f.exr");
  ASSERT_TRUE(img.metadata.world_to_ndc && img.metadata.world_to_camera);
  EXPECT_EQ(img.metadata.frames_per_second, 30.0);
  EXPECT_EQ(img.metadata.frame, 3725);
  auto times = [](const Eigen::Vector3d& p, const std::array<float, 16>& m) {  // p M, row vector
    Eigen::Vector4d r = Eigen::Vector4d::Zero();
    for (int j = 0; j < 4; ++j)
      r[j] = p.x() * m[size_t(j)] + p.y() * m[size_t(4 + j)] + p.z() * m[size_t(8 + j)] + m[size_t(12 + j)];
    return Eigen::Vector3d(r[0] / r[3], r[1] / r[3], r[2] / r[3]);
  };
  const std::vector<Eigen::Vector2d> points = world->PointPositions<2>(0);
  int checked = 0;
  for (const Eigen::Vector2d& x : points) {
    // (drawn 3 above the plane, their layer's z offset: the parallel camera looks down z, so
    // neither their pixel nor, within 1 %, their depth moves)
    const Eigen::Vector3d at(x.x(), x.y(), 0.0);
    const Eigen::Vector3d ndc = times(at, *img.metadata.world_to_ndc);
    const int px = int(ndc.x() * img.width), py = int(ndc.y() * img.height);
    if (px < 2 || py < 2 || px >= img.width - 2 || py >= img.height - 2) continue;
    SCOPED_TRACE(std::to_string(px) + ", " + std::to_string(py));
    EXPECT_EQ(img.At("A", px, py), 1.0f);
    EXPECT_NEAR(img.At("R", px, py), SrgbToLinear(0.85), 5e-3);  // the mass points' red
    EXPECT_NEAR(img.At("G", px, py), SrgbToLinear(0.2), 2e-3);
    // the camera looks along +z of its space: the depth of a point drawn in front of it
    const double z = times(at, *img.metadata.world_to_camera).z();
    EXPECT_GT(z, 0.0);
    EXPECT_NEAR(img.At("depth.Z", px, py), z, 0.01 * z);
    ++checked;
  }
  EXPECT_GE(checked, 8);
  fs::remove_all(dir);
}

TEST(RenderedExr, ColourAlphaAndDepthAtKnownPixels) {
  REQUIRE_DISPLAY();
  const std::string dir = TempDir("frame_exr");
  World world;  // flat ground through the origin, the table at rest standing on it
  world.AddBody(testing::Table());
  SceneOptions opt;
  opt.width = 160;
  opt.height = 120;
  opt.overlay = false;
  opt.exr_terrain_layer = true;  // the ground in its own layer
  SceneView view(&world, opt);
  // 400 x 300 world units around (150, 50): 2.5 units per pixel
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-50, -100), Eigen::Vector2d(350, 200)), 0.0);
  view.Render();
  view.WriteExr(dir + "/f.exr");
  const ExrImage img = ReadExrChannels(dir + "/f.exr");
  ASSERT_EQ(img.width, 160);
  ASSERT_EQ(img.height, 120);
  for (const char* c : {"R", "G", "B", "A", "terrain.R", "terrain.G", "terrain.B", "terrain.A", "depth.Z", "forward.u",
                        "forward.v"})
    ASSERT_TRUE(img.channels.count(c)) << c;
  EXPECT_EQ(img.channels.count("ViewLayer.Vector.X"), 0u) << "Blender's pass only when asked for (exr-motion)";
  // pixel (10, 110) is at world (−50 + 10.5·2.5, 200 − 110.5·2.5) = (−23.75, −76.25): the
  // ground band, drawn at z = 0, so its depth is the camera's height above z = 0
  double cam[3];
  vtkRenderer* renderer = view.window()->GetRenderers()->GetFirstRenderer();
  renderer->GetActiveCamera()->GetPosition(cam);
  EXPECT_NEAR(img.At("depth.Z", 10, 110), cam[2], 1e-3 * cam[2]);
  // the ground is not a character: it is in the terrain layer, and the characters' alpha is 0
  EXPECT_EQ(img.At("A", 10, 110), 0.0f);
  EXPECT_EQ(img.At("R", 10, 110), 0.0f);
  EXPECT_EQ(img.At("terrain.A", 10, 110), 1.0f);
  // the ground's colour (0.55, 0.47, 0.38), 8-bit sRGB in the frame buffer, in linear light
  // in the EXR (IEC 61966-2-1), stored as half floats (11 significant bits)
  EXPECT_NEAR(img.At("terrain.R", 10, 110), SrgbToLinear(0.55), 2.5e-3);
  EXPECT_NEAR(img.At("terrain.G", 10, 110), SrgbToLinear(0.47), 2.5e-3);
  EXPECT_NEAR(img.At("terrain.B", 10, 110), SrgbToLinear(0.38), 2.5e-3);
  // pixel (80, 10) is at world y = 200 − 10.5·2.5 = 173.75, above the table: nothing drawn
  EXPECT_TRUE(std::isinf(img.At("depth.Z", 80, 10)));
  for (const char* c : {"A", "R", "terrain.A", "terrain.R"}) EXPECT_EQ(img.At(c, 80, 10), 0.0f) << c;
  // the table's top at world (150, 100) is pixel (80, 40): a character, in front of nothing
  EXPECT_EQ(img.At("A", 80, 40), 1.0f);
  EXPECT_EQ(img.At("terrain.A", 80, 40), 0.0f);
  // a single frame has no next one: nothing moves
  for (const char* c : {"forward.u", "forward.v"})
    for (float v : img.channels.at(c)) ASSERT_EQ(v, 0.0f) << c;
  fs::remove_all(dir);
}

// The characters' alpha and motion vectors of a rendered frame: the pot turned and moved
// rigidly between two frames (its modes unchanged), so that every point of it goes where
// x_B = c_B + R(θ_B) R(θ_A)ᵀ (x_A − c_A) takes it (Eq. 4.2: x = c + R(θ) l(γ)). At every pixel
// the rasteriser says the table covers by a filled surface, forward.u/v is that map applied to
// the pixel's centre, in pixels (lines and dots: see below); the alpha agrees with what VTK
// drew away from the edges, in both styles.
TEST(RenderedExr, CharactersAlphaAndMotionOfARigidMotionAtEveryPixel) {
  REQUIRE_DISPLAY();
  WorldOptions o;
  o.params.ground.enabled = false;
  World world(o);
  // the pot: its closed outline is filled in the clean style
  const std::string data = wobble::test_env::DataDir();
  world.AddBody(std::make_shared<const BodyModel>(formats::ReadObjectFile(data + "/pot.obj"),
                                                  formats::ReadDeformationFile(data + "/def_pot")));
  const int dofs = world.body<2>(0).num_q();
  Eigen::VectorXd qa = Eigen::VectorXd::Zero(dofs), qb = qa;
  qa.head(3) << 12, 140, 0.3;
  qb.head(3) << 31, 128, 0.42;
  for (int m = 3; m < dofs; ++m) qa[m] = qb[m] = 0.05 * (m - 1);  // deformed alike in both
  for (RenderStyle style : {RenderStyle::kDiagnostic, RenderStyle::kClean}) {
    SCOPED_TRACE(style == RenderStyle::kClean ? "clean" : "diagnostic");
    SceneOptions opt;
    opt.width = 240;
    opt.height = 180;
    opt.overlay = false;
    opt.style = style;
    opt.exr_terrain_layer = true;
    SceneView view(&world, opt);
    view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-200, 0), Eigen::Vector2d(400, 450)), 0.0);
    world.SetState(0, qa, Eigen::VectorXd::Zero(dofs));
    view.Render();
    const ExrFrame frame = view.CaptureExrFrame();
    world.SetState(0, qb, Eigen::VectorXd::Zero(dofs));
    view.Render();
    const ScreenGeometry next = view.CharacterGeometry();
    std::map<std::string, std::vector<float>> ch;
    for (ExrChannel& c : ExrFrameChannels(frame, &next)) ch[c.name] = std::move(c.data);
    const Eigen::AlignedBox2d box = view.framed_box();
    const double scale = opt.width / box.sizes().x();  // pixels per world unit, both axes
    ASSERT_NEAR(scale, opt.height / box.sizes().y(), 1e-9);
    const Eigen::Matrix2d rotate = Eigen::Rotation2Dd(qb[2]).toRotationMatrix() * Eigen::Rotation2Dd(qa[2]).toRotationMatrix().transpose();
    const Eigen::Vector2d ca(qa[0], qa[1]), cb(qb[0], qb[1]);
    auto at = [&](const char* name, int x, int y_up) { return ch.at(name)[size_t(opt.height - 1 - y_up) * opt.width + x]; };
    auto drawn = [&](int x, int y_up) { return std::isfinite(frame.depth[size_t(opt.height - 1 - y_up) * opt.width + x]); };
    int covered = 0, exact = 0, interior_checked = 0;
    for (int y = 0; y < opt.height; ++y)
      for (int x = 0; x < opt.width; ++x) {
        if (at("A", x, y) == 0.0f) {
          EXPECT_EQ(at("forward.u", x, y), 0.0f);
          continue;
        }
        ++covered;
        const Eigen::Vector2d pixel(x + 0.5, y + 0.5);
        const Eigen::Vector2d xa = box.min() + pixel / scale;
        const Eigen::Vector2d xb = cb + rotate * (xa - ca);
        const Eigen::Vector2d motion = (xb - xa) * scale;
        const Eigen::Vector2d got(at("forward.u", x, y), at("forward.v", x, y));
        // a filled surface's pixel moves as its own point; a line's pixel as the point of the
        // line's centre beside it, and a dot's as its centre, up to r pixels away: those differ
        // from the pixel's own motion by at most |R − I| r = 2 sin(Δθ / 2) r
        double r = 0;
        for (const ScreenGeometry::Segment& sg : frame.characters.segments) {
          const Eigen::Vector2d a = frame.characters.vertices[size_t(sg.a)].head<2>(), d = frame.characters.vertices[size_t(sg.b)].head<2>() - a;
          const double t = std::clamp((pixel - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
          if ((pixel - a - t * d).norm() <= 0.5 * sg.width + 1) r = std::max(r, 0.5 * sg.width);
        }
        for (const ScreenGeometry::Dot& dot : frame.characters.dots)
          if ((pixel - frame.characters.vertices[size_t(dot.v)].head<2>()).cwiseAbs().maxCoeff() <= 0.5 * dot.size + 1)
            r = std::max(r, std::sqrt(0.5) * dot.size);
        const double bound = 1e-3 + 2 * std::sin(0.5 * (qb[2] - qa[2])) * r;
        ASSERT_LE((got - motion).norm(), bound) << x << "," << y;
        exact += r == 0;
        EXPECT_EQ(at("terrain.A", x, y), 0.0f);
      }
    // where the rasterised characters and VTK's drawing both fill a 3 x 3 neighbourhood they
    // agree; they may differ only along edges
    for (int y = 1; y + 1 < opt.height; ++y)
      for (int x = 1; x + 1 < opt.width; ++x) {
        bool all_a = true, all_drawn = true;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            all_a = all_a && at("A", x + dx, y + dy) == 1.0f;
            all_drawn = all_drawn && drawn(x + dx, y + dy);
          }
        if (all_a) {
          EXPECT_TRUE(drawn(x, y)) << x << "," << y;
        }
        if (all_drawn) {
          EXPECT_EQ(at("A", x, y), 1.0f) << x << "," << y;
        }
        interior_checked += all_a || all_drawn;
      }
    EXPECT_GT(covered, style == RenderStyle::kClean ? 2000 : 400);
    if (style == RenderStyle::kClean) {
      EXPECT_GT(exact, 1000);  // the fill inside the outline
    }
    EXPECT_GT(interior_checked, 100);
  }
}

// A 3D heightfield is terrain: with the terrain layer asked for, every interior grid node in view
// (a point of the drawn surface, found through the header's worldToNDC) is in terrain.R,G,B,A and
// not in the characters' A, its depth.Z is the node's worldToCamera z, and the chair floating
// above it is in A. No pixel is in both layers.
TEST(RenderedExr, A3dHeightfieldIsTheTerrainLayer) {
  REQUIRE_DISPLAY();
  const int nx = 13, nz = 13;
  const Eigen::Vector2d origin(-300.0, -300.0), spacing(50.0, 50.0);
  std::vector<double> heights;
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nx; ++i) heights.push_back(60.0 + 0.15 * (origin.x() + spacing.x() * i));  // a slope in x
  WorldOptions o;
  o.params.ground_plane.enabled = true;
  o.params.ground_plane.heightfield = Heightfield::Make(origin, spacing, nx, nz, heights);
  World world(o);
  world.AddBody(std::make_shared<const BodyModelN<3>>(testing::Chair3()));
  world.SetState(0, PositionsOf(Eigen::Vector3d(-50, 200, -30), Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())), Eigen::VectorXd::Zero(3)), Eigen::VectorXd::Zero(9));
  SceneOptions opt;
  opt.width = 320;
  opt.height = 240;
  opt.overlay = false;
  opt.elevation = 30;
  opt.exr_terrain_layer = true;
  SceneView view(&world, opt);
  view.FrameBounds(Eigen::AlignedBox3d(Eigen::Vector3d(-250, 0, -250), Eigen::Vector3d(250, 320, 250)));
  view.Render();
  const ExrFrame frame = view.CaptureExrFrame();
  ASSERT_TRUE(frame.metadata.world_to_ndc && frame.metadata.world_to_camera);
  std::map<std::string, std::vector<float>> ch;
  for (ExrChannel& c : ExrFrameChannels(frame, nullptr)) ch[c.name] = std::move(c.data);
  auto times = [](const Eigen::Vector3d& p, const std::array<float, 16>& m) {  // p M, row vector
    Eigen::Vector4d r = Eigen::Vector4d::Zero();
    for (int j = 0; j < 4; ++j)
      r[j] = p.x() * m[size_t(j)] + p.y() * m[size_t(4 + j)] + p.z() * m[size_t(8 + j)] + m[size_t(12 + j)];
    return Eigen::Vector3d(r[0] / r[3], r[1] / r[3], r[2] / r[3]);
  };
  int nodes = 0;
  for (int j = 1; j + 1 < nz; ++j)  // the interior nodes: a border node's pixel is half off the surface
    for (int i = 1; i + 1 < nx; ++i) {
      const Eigen::Vector3d node(origin.x() + spacing.x() * i, heights[size_t(i + nx * j)], origin.y() + spacing.y() * j);
      const Eigen::Vector3d ndc = times(node, *frame.metadata.world_to_ndc);
      const int px = int(ndc.x() * opt.width), py = int(ndc.y() * opt.height);
      if (px < 2 || py < 2 || px >= opt.width - 2 || py >= opt.height - 2) continue;
      const size_t at = size_t(py) * opt.width + px;
      if (ch.at("A")[at] > 0.0f) continue;  // behind the chair
      SCOPED_TRACE(std::to_string(i) + ", " + std::to_string(j));
      EXPECT_EQ(ch.at("terrain.A")[at], 1.0f);
      EXPECT_GT(ch.at("terrain.R")[at] + ch.at("terrain.G")[at] + ch.at("terrain.B")[at], 0.0f);
      const double z = times(node, *frame.metadata.world_to_camera).z();
      EXPECT_NEAR(ch.at("depth.Z")[at], z, 0.01 * z);
      ++nodes;
    }
  EXPECT_GE(nodes, 40);
  int chair = 0;
  for (size_t k = 0; k < ch.at("A").size(); ++k) {
    EXPECT_LE(ch.at("A")[k] + ch.at("terrain.A")[k], 1.0f) << k;
    chair += ch.at("A")[k] == 1.0f;
  }
  EXPECT_GT(chair, 500);
}

// The 2D overlay (title, time, energy) is drawn at window depth 0, which no geometry reaches:
// the EXR frame leaves those pixels out of every layer. Every pixel so marked lies inside the
// text's box, and the ground band behind the text is in the terrain layer only around it.
TEST(RenderedExr, TheTextOverlayIsInNoLayer) {
  REQUIRE_DISPLAY();
  auto world = AirborneWorld();
  SceneOptions opt;
  opt.width = 320;
  opt.height = 240;
  opt.title = "a title over the ground";
  opt.exr_terrain_layer = true;
  SceneView view(world.get(), opt);
  // the ground band fills the top of the picture, behind the text
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-100, -300), Eigen::Vector2d(300, 0)), 0.0);
  view.Render();
  const ExrFrame frame = view.CaptureExrFrame();
  vtkTextActor* text = nullptr;
  vtkActor2DCollection* actors = view.renderer()->GetActors2D();
  actors->InitTraversal();
  while (vtkActor2D* a = actors->GetNextActor2D())
    if (auto* t = vtkTextActor::SafeDownCast(a)) text = t;
  ASSERT_TRUE(text);
  double box[4];  // display pixels, y up (VTK gives it relative to the text's position)
  text->GetBoundingBox(view.renderer(), box);
  const int* at = text->GetPositionCoordinate()->GetComputedDisplayValue(view.renderer());
  for (int k = 0; k < 4; ++k) box[k] += at[k / 2];
  std::map<std::string, std::vector<float>> ch;
  for (ExrChannel& c : ExrFrameChannels(frame, nullptr)) ch[c.name] = std::move(c.data);
  int marked = 0, terrain_beside = 0;
  for (int row = 0; row < opt.height; ++row)
    for (int x = 0; x < opt.width; ++x) {
      const size_t i = size_t(row) * opt.width + x;
      const double y_up = opt.height - 1 - row;
      if (frame.overlay[i]) {
        ++marked;
        EXPECT_TRUE(x >= box[0] - 1 && x <= box[1] + 1 && y_up >= box[2] - 1 && y_up <= box[3] + 1) << x << "," << row;
        EXPECT_EQ(ch.at("A")[i], 0.0f);
        EXPECT_EQ(ch.at("terrain.A")[i], 0.0f);
        EXPECT_TRUE(std::isinf(ch.at("depth.Z")[i]));
      } else if (x <= box[1] && y_up >= box[2] && ch.at("terrain.A")[i] == 1.0f) {
        ++terrain_beside;  // the ground between the letters
      }
    }
  EXPECT_GT(marked, 100);
  EXPECT_GT(terrain_beside, 100);
}

// The render driver writes each EXR frame once the next is drawn: a table in free flight
// (no gravity, no ground) translates at constant velocity v, so every character pixel of
// every frame but the last moves v / fps world units (scaled to pixels), and the last, which
// has no next frame, does not move. Blender's Vector pass holds the same: X, Y the motion to
// the previous frame (−v / fps; zero on the first) and Z, W minus the motion to the next.
TEST(RenderedExr, SeriesMotionPointsToTheNextFrameAndTheLastStandsStill) {
  REQUIRE_DISPLAY();
  WorldOptions o;
  o.params.ground.enabled = false;
  o.params.gravity_on = false;
  World w(o);
  w.AddBody(testing::Table());
  const Eigen::Vector2d v(120.0, -45.0);
  w.SetState(0, testing::Vec({0, 100, 0.2, 0, 0, 0, 0}), testing::Vec({v.x(), v.y(), 0, 0, 0, 0, 0}));  // modes at rest: no mode forces
  auto run = std::make_shared<record::Trajectory>(w);
  auto recorder = std::make_shared<record::Recorder>(run, 5);
  w.SetRecorder(recorder);
  recorder->Start(w);
  ASSERT_TRUE(w.RunUntil(0.3)) << w.status().message;
  RenderOutputs out;
  out.folder = TempDir("exr_series");
  out.frames = out.filmstrip = out.vtp = false;
  out.exr = true;
  out.fps = 10;  // frames at 0, 0.1, 0.2, 0.3
  out.view.width = 160;
  out.view.height = 120;
  out.view.overlay = false;
  ApplyRenderSettings(scene::ParseRenderOptions({{"exr-motion", "both"}}), &out);  // Nuke's layer and Blender's pass
  out.fps = 10;
  out.view.width = 160;
  out.view.height = 120;
  World world = WorldFor(*run, o);
  const RenderReport report = RenderTrajectory(world, *run, SceneSpec(), out);
  ASSERT_EQ(report.frames, 4);
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    char name[32];
    std::snprintf(name, sizeof(name), "/exr/frame_%04d.exr", k);
    const ExrImage img = ReadExrChannels(out.folder + name);
    EXPECT_EQ(img.channels.count("terrain.A"), 0u);  // the terrain layer is asked for (--exr-terrain)
    // pixels per world unit from the header's worldToNDC (row vectors: x_ndc = x M00 + ...)
    const double sx = (*img.metadata.world_to_ndc)[0] * img.width, sy = -(*img.metadata.world_to_ndc)[5] * img.height;
    const Eigen::Vector2d step(v.x() / out.fps * sx, v.y() / out.fps * sy);
    const Eigen::Vector2d expected = k < 3 ? step : Eigen::Vector2d::Zero();
    const Eigen::Vector2d back = k > 0 ? Eigen::Vector2d(-step) : Eigen::Vector2d::Zero();
    int covered = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        if (img.At("A", x, y) == 0.0f) continue;
        ++covered;
        // stored as half floats: to 2^-11 of their size
        ASSERT_NEAR(img.At("forward.u", x, y), expected.x(), 1e-3 + std::abs(expected.x()) / 2048) << x << "," << y;
        ASSERT_NEAR(img.At("forward.v", x, y), expected.y(), 1e-3 + std::abs(expected.y()) / 2048) << x << "," << y;
        ASSERT_EQ(img.At("ViewLayer.Vector.Z", x, y), -img.At("forward.u", x, y)) << x << "," << y;
        ASSERT_EQ(img.At("ViewLayer.Vector.W", x, y), -img.At("forward.v", x, y)) << x << "," << y;
        ASSERT_NEAR(img.At("ViewLayer.Vector.X", x, y), back.x(), 1e-3 + std::abs(back.x()) / 2048) << x << "," << y;
        ASSERT_NEAR(img.At("ViewLayer.Vector.Y", x, y), back.y(), 1e-3 + std::abs(back.y()) / 2048) << x << "," << y;
      }
    EXPECT_GT(covered, 100);
  }
  fs::remove_all(out.folder);
}

// exr-compression (wobble render --exr-compression, a script's render line) reaches the frames'
// writer under each of its names.
TEST(RenderedExr, EveryCompressionNameReachesTheWriter) {
  for (const char* name : {"zip", "zips", "piz", "dwaa", "none"}) {
    RenderOutputs out;
    ApplyRenderSettings(scene::ParseRenderOptions({{"exr-compression", name}}), &out);
    EXPECT_STREQ(ExrCompressionName(out.view.exr_compression), name);
  }
  RenderOutputs plain;
  ApplyRenderSettings(scene::ParseRenderOptions({}), &plain);
  EXPECT_EQ(plain.view.exr_compression, ExrCompression::kZip);
}

TEST(VtiExport, ImageReadsBackWithItsGeometryAndValues) {
  const std::string dir = TempDir("vti");
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(5, 4, 1);
  image->SetOrigin(0.5, -2, 0);
  image->SetSpacing(0.25, 0.5, 1);
  image->AllocateScalars(VTK_DOUBLE, 1);
  auto* v = static_cast<double*>(image->GetScalarPointer());
  for (int i = 0; i < 20; ++i) v[i] = 1e5 / (1 + i) + 0.125;
  image->GetPointData()->GetScalars()->SetName("cond");
  WriteVti(dir + "/c.vti", image);
  auto r = vtkSmartPointer<vtkXMLImageDataReader>::New();
  r->SetFileName((dir + "/c.vti").c_str());
  r->Update();
  vtkImageData* back = r->GetOutput();
  int dims[3];
  back->GetDimensions(dims);
  EXPECT_EQ(dims[0], 5);
  EXPECT_EQ(dims[1], 4);
  EXPECT_EQ(back->GetOrigin()[0], 0.5);
  EXPECT_EQ(back->GetSpacing()[1], 0.5);
  vtkDataArray* a = back->GetPointData()->GetArray("cond");
  ASSERT_NE(a, nullptr);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(a->GetTuple1(i), v[i]);
  fs::remove_all(dir);
}

TEST(TrajectoryCharts, EnergiesConditionAndContactEventsAgreeWithIndependentSums) {
  WorldOptions o;
  o.params.ground.slope = -5.0 * M_PI / 180.0;
  World world(o);
  world.AddBody(testing::Table());
  world.SetState(0, testing::Vec({0, 50, 0, 0, 0, 0, 0}), Eigen::VectorXd::Zero(7));
  auto run = std::make_shared<record::Trajectory>(world);
  auto recorder = std::make_shared<record::Recorder>(run);
  world.SetRecorder(recorder);
  recorder->Start(world);
  double first_contact = -1;
  std::vector<double> reference_cond = {NAN};  // after every step (the start is not checked)
  world.RunUntil(4.0, [&](const World& w) {
    if (first_contact < 0 && !w.state<2>(0).contacts.empty()) first_contact = w.time();
    // cond₂ of the per-point reference M (Eq. 4.10), by eigenvalues: M is symmetric positive definite
    const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(
        reference::MassMatrix(w.body<2>(0), w.q(0))).eigenvalues();
    reference_cond.push_back(ev.maxCoeff() / ev.minCoeff());
  });
  const std::vector<double> cond = ConditionNumbers(*run, 0);
  ASSERT_EQ(cond.size(), reference_cond.size());
  for (size_t k = 1; k < cond.size(); ++k) EXPECT_NEAR(cond[k], reference_cond[k], 1e-8 * cond[k]);
  const std::vector<double> events = ContactEvents(*run, 0);
  // a fall from 50 lands after about sqrt(2 * 50 / g) = 3.19 s; the first event is that step
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.front(), first_contact);
  EXPECT_NEAR(first_contact, std::sqrt(2 * 50 / 9.81), 0.05);

  const ChartSpec spec = EnergyChart(*run, 0, "e");
  auto series = [&](const std::string& name) -> const std::vector<double>& {
    for (const ChartSeries& s : spec.series)
      if (s.name == name) return s.y;
    throw std::runtime_error("no series " + name);
  };
  const std::vector<double>& total = series("total");
  for (size_t i = 0; i < total.size(); ++i) {
    double modes = 0;
    for (const char* m : {"mode bend", "mode shear", "mode vsquash", "mode hsquash"}) modes += series(m)[i];
    const double sum = series("kinetic")[i] + series("gravity")[i] + modes + series("ground")[i];
    EXPECT_NEAR(total[i], sum, 1e-9 * std::abs(total[i]));
  }
  // at the start: at rest, 50 up: gravity m g h = 550 · 9.81 · (50 + 50) (centre of mass 50 above the lattice's foot)
  EXPECT_NEAR(series("gravity")[0], world.body<2>(0).moments().m * 9.81 * (50 + world.body<2>(0).moments().c0.y() / world.body<2>(0).moments().m), 1e-6);

  // the CSV beside the chart holds the same numbers
  const std::string dir = TempDir("chart_csv");
  WriteChartCsv(spec, dir + "/e.csv");
  std::ifstream in(dir + "/e.csv");
  std::string header, line;
  std::getline(in, header);
  EXPECT_EQ(header.rfind("time (s),kinetic,gravity", 0), 0u) << header;
  size_t rows = 0;
  while (std::getline(in, line)) {
    std::stringstream ss(line);
    std::string cell;
    std::vector<double> cells;
    while (std::getline(ss, cell, ',')) cells.push_back(std::stod(cell));
    ASSERT_EQ(cells.size(), spec.series.size() + 1);
    EXPECT_EQ(cells[0], spec.series[0].x[rows]);
    EXPECT_EQ(cells.back(), total[rows]);
    ++rows;
  }
  EXPECT_EQ(rows, total.size());
  EXPECT_TRUE(fs::exists(dir + "/e_markers.csv"));
  fs::remove_all(dir);
}

// ---- failed writes: the earlier file stays, the error says which file and why ------------

class FailedWrite : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = TempDir("fail"); }
  void TearDown() override { fs::remove_all(dir_); }
  // Writes `path` once successfully, then makes the next write to it fail by turning its
  // temporary file into `kind`: a folder (cannot be opened) or a link to /dev/full (every
  // write fails with "no space left", as on a full disk).
  template <class Write> void ExpectFailureKeepsEarlierFile(const std::string& path, Write write, bool disk_full) {
    ASSERT_NO_THROW(write());
    const std::string before = ReadAll(path);
    ASSERT_FALSE(before.empty());
    const std::string tmp = formats::TempPathFor(path);
    if (disk_full) {
      fs::create_symlink("/dev/full", tmp);
    } else {
      fs::create_directory(tmp);
    }
    try {
      write();
      ADD_FAILURE() << path << ": the write should have failed";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
      // the system's reason, not "Success" (errno read after fclose) or a writer's guess
      if (disk_full) {
        EXPECT_NE(std::string(e.what()).find(std::strerror(ENOSPC)), std::string::npos) << e.what();
      }
    }
    EXPECT_EQ(ReadAll(path), before) << "the earlier file changed";
    EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(path))) << "the earlier file was replaced";
    if (disk_full) {
      EXPECT_FALSE(fs::exists(fs::symlink_status(tmp))) << "the temporary file was left";
    }
    fs::remove_all(tmp);
  }
  std::string dir_;
};

TEST_F(FailedWrite, VtpOnAFullDiskOrAnUnopenableTemporaryFile) {
  auto world = AirborneWorld();
  auto src = vtkSmartPointer<MassPointSource>::New();
  src->SetWorld(world.get());
  src->Update();
  const std::string path = dir_ + "/p.vtp";
  ExpectFailureKeepsEarlierFile(path, [&] { WriteVtp(path, src->GetOutput()); }, true);
  ExpectFailureKeepsEarlierFile(path, [&] { WriteVtp(path, src->GetOutput()); }, false);
}

TEST_F(FailedWrite, ExrOnAFullDiskOrAnUnopenableTemporaryFile) {
  auto world = AirborneWorld();
  const std::string path = dir_ + "/d.exr";
  ExpectFailureKeepsEarlierFile(path, [&] { WriteDisplacementExr(path, *world, 0, 32, 16); }, true);
  ExpectFailureKeepsEarlierFile(path, [&] { WriteDisplacementExr(path, *world, 0, 32, 16); }, false);
}

TEST_F(FailedWrite, PvdAndChartCsvOnAFullDisk) {
  PvdCollection pvd;
  pvd.Add(0.5, 0, dir_ + "/a.vtp");
  const std::string path = dir_ + "/s.pvd";
  ExpectFailureKeepsEarlierFile(path, [&] { pvd.Write(path); }, true);
  ChartSpec spec;
  spec.series.push_back({"e", {0, 1}, {2, 3}});
  const std::string csv = dir_ + "/c.csv";
  ExpectFailureKeepsEarlierFile(csv, [&] { WriteChartCsv(spec, csv); }, true);
}

TEST_F(FailedWrite, PngOnAFullDiskOrAnUnopenableTemporaryFile) {
  auto image = vtkSmartPointer<vtkImageData>::New();
  image->SetDimensions(4, 3, 1);
  image->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  std::fill_n(static_cast<unsigned char*>(image->GetScalarPointer()), 36, 200);
  const std::string path = dir_ + "/i.png";
  ExpectFailureKeepsEarlierFile(path, [&] { WritePng(path, image); }, true);
  ExpectFailureKeepsEarlierFile(path, [&] { WritePng(path, image); }, false);
}

// wobble's PNG encoder (libpng) read back by VTK's reader: every pixel of a gradient with
// noise, RGB and RGBA, at every compression level the tools use.
TEST(Png, EveryPixelReadsBackThroughVtk) {
  const std::string dir = TempDir("png_round_trip");
  for (int channels : {3, 4}) {
    auto image = vtkSmartPointer<vtkImageData>::New();
    image->SetDimensions(37, 23, 1);
    image->AllocateScalars(VTK_UNSIGNED_CHAR, channels);
    auto* px = static_cast<unsigned char*>(image->GetScalarPointer());
    for (int i = 0; i < 37 * 23 * channels; ++i) px[i] = static_cast<unsigned char>((i * 7 + (i * i) % 13) & 0xff);
    for (int level : {0, 1, 9}) {
      const std::string path = dir + "/c" + std::to_string(channels) + "_l" + std::to_string(level) + ".png";
      WritePng(path, image, level);
      auto reader = vtkSmartPointer<vtkPNGReader>::New();
      reader->SetFileName(path.c_str());
      reader->Update();
      vtkImageData* back = reader->GetOutput();
      int dims[3];
      back->GetDimensions(dims);
      ASSERT_EQ(dims[0], 37);
      ASSERT_EQ(dims[1], 23);
      ASSERT_EQ(back->GetNumberOfScalarComponents(), channels);
      const auto* got = static_cast<const unsigned char*>(back->GetScalarPointer());
      int differing = 0;
      for (int i = 0; i < 37 * 23 * channels; ++i) differing += got[i] != px[i];
      EXPECT_EQ(differing, 0) << path;
    }
  }
}

TEST_F(FailedWrite, AFolderThatCannotBeCreatedIsNamed) {
  // a path under a regular file: its folder can never exist, even for root
  std::ofstream(dir_ + "/plain") << "x";
  const std::string path = dir_ + "/plain/sub/d.exr";
  auto world = AirborneWorld();
  try {
    WriteDisplacementExr(path, *world, 0, 8, 8);
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("folder"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace wobble::pipelines
