// The glTF export (pipelines/gltf_export.h, issue 48) read back through tinygltf's own loader:
// its structure (nodes, morph targets per mode with their names, LINEAR samplers keyed at the
// render's frame times), the vertices it gives at a state against the world's positions, and
// its failures (a clear error naming the file, no file half written). The vertex-exact check
// against wobble's drawing over a whole run, by a reader of its own, is
// tests/cli/check_gltf_export.py.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>
#include <tiny_gltf.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "pipelines/gltf_export.h"
#include "pipelines/mesh_io.h"
#include "pipelines/trajectory_render.h"
#include "pipelines/world_sources.h"
#include "support/pipelines_test_util.h"
#include "support/source_paths.h"
#include "support/test_bodies.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/dynamics/body_state.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/record/trajectory.h"

namespace wobble::pipelines {
namespace {

namespace fs = std::filesystem;

// The pot of the demo (data/pot3.obj, its three modes) in a world with the ground plane;
// `unnamed_mode` >= 0 clears that mode's name.
std::shared_ptr<const BodyModelN<3>> Pot(int unnamed_mode = -1) {
  const std::string data = wobble::test_env::DataDir();
  BodyDefN<3> def = ReadObject<3>(data + "/pot3.obj");
  std::vector<DeformationModeN<3>> modes = formats::ReadDeformationFile(data + "/pot3_modes.def3", def.lattice);
  if (unnamed_mode >= 0) modes.at(size_t(unnamed_mode)).name.clear();
  return std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes));
}

WorldOptions WithGroundPlane() {
  WorldOptions options;
  options.params.ground_plane.enabled = true;
  return options;
}

// The run from the world's state for `seconds`, every step recorded; the world is then put
// back where it started, as a render replays it from there.
std::shared_ptr<record::Trajectory> RecordFromStart(World& world, double seconds) {
  const WorldData start = world.data();
  auto run = std::make_shared<record::Trajectory>(world);
  auto recorder = std::make_shared<record::Recorder>(run);
  world.SetRecorder(recorder);
  recorder->Start(world);
  EXPECT_TRUE(world.RunUntil(seconds + 0.5 * world.options().dt));
  world.SetData(start);
  return run;
}

tinygltf::Model Load(const std::string& path) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &err, &warn, path)) << err;
  EXPECT_EQ(err, "");
  return model;
}

template <class T> const T* AccessorData(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors.at(size_t(accessor));
  const tinygltf::BufferView& v = m.bufferViews.at(size_t(a.bufferView));
  return reinterpret_cast<const T*>(m.buffers.at(size_t(v.buffer)).data.data() + v.byteOffset + a.byteOffset);
}

fs::path TestDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("wobble_gltf_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// A pot falling and spinning for 0.5 s beside a 2D table, rendered with gltf only at 30 fps:
// nodes pot3, table and ground (static), a target per mode, three LINEAR samplers per body
// sharing the 16 frame times t0 + k/30.
TEST(GltfExport, StructureThroughTinygltfsLoader) {
  World world(WithGroundPlane());
  world.AddBody(Pot());
  world.AddBody(testing::Table());
  world.SetState(0, PositionsOf(Eigen::Vector3d(0, 30, 0), Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())),
                                Eigen::Vector3d::Zero()),
                 (Eigen::VectorXd(9) << 0, -60, 0, 0, 1.2, 0, 0, 0, 0).finished());
  world.SetState(1, testing::Vec({0, 50, 0, 0, 0, 0, 0}), Eigen::VectorXd::Zero(7));
  const std::shared_ptr<record::Trajectory> run = RecordFromStart(world, 0.5);

  const fs::path dir = TestDir("structure");
  RenderOutputs out;
  out.folder = dir.string();
  out.name = "pot3";
  ASSERT_EQ(SetOutputs({"gltf"}, &out), "");
  out.fps = 30;
  out.t_end = 0.5;
  const RenderReport report = RenderTrajectory(world, *run, SceneSpec{}, out);
  ASSERT_EQ(report.frames, 16);
  ASSERT_EQ(report.files.size(), 1u);
  EXPECT_EQ(report.files[0].path, (dir / "pot3.glb").string());
  EXPECT_NE(report.files[0].note.find("2 bodies with morph targets (FFD: one per mode), 16 keys"), std::string::npos)
      << report.files[0].note;
  EXPECT_FALSE(fs::exists(dir / "pot3.glb.tmp"));

  const tinygltf::Model m = Load((dir / "pot3.glb").string());
  EXPECT_EQ(m.asset.version, "2.0");
  ASSERT_EQ(m.scenes.size(), 1u);
  EXPECT_EQ(m.scenes[0].nodes, (std::vector<int>{0, 1, 2}));
  ASSERT_EQ(m.nodes.size(), 3u);
  ASSERT_EQ(m.meshes.size(), 3u);
  EXPECT_EQ(m.nodes[1].name, "table");
  EXPECT_EQ(m.nodes[2].name, "ground");
  ASSERT_EQ(m.materials.size(), 1u);
  EXPECT_TRUE(m.materials[0].doubleSided);
  {  // the table: its three open polylines as LINES (nothing to fill), a target per mode
    const tinygltf::Mesh& table = m.meshes.at(size_t(m.nodes[1].mesh));
    ASSERT_EQ(table.primitives.size(), 1u);
    EXPECT_EQ(table.primitives[0].mode, TINYGLTF_MODE_LINE);
    EXPECT_EQ(int(table.primitives[0].targets.size()), world.body<2>(1).num_modes());
    const size_t samples = 3 * (16 + 1);  // 3 segments at shape_samples 16, and their ends
    EXPECT_EQ(m.accessors.at(size_t(table.primitives[0].attributes.at("POSITION"))).count, samples);
    EXPECT_EQ(m.accessors.at(size_t(table.primitives[0].indices)).count, 2 * 3 * 16);
  }
  {  // the ground: the 3D plane under the pot (GroundSource), two triangles, no targets
    const tinygltf::Mesh& ground = m.meshes.at(size_t(m.nodes[2].mesh));
    ASSERT_EQ(ground.primitives.size(), 1u);
    EXPECT_EQ(ground.primitives[0].mode, TINYGLTF_MODE_TRIANGLES);
    EXPECT_EQ(m.accessors.at(size_t(ground.primitives[0].indices)).count, 6u);
    EXPECT_TRUE(ground.primitives[0].targets.empty());
  }
  const tinygltf::Node& node = m.nodes[0];
  EXPECT_EQ(node.name, "pot3");
  EXPECT_EQ(node.mesh, 0);
  const tinygltf::Mesh& mesh = m.meshes[0];
  ASSERT_EQ(mesh.primitives.size(), 1u);
  const tinygltf::Primitive& p = mesh.primitives[0];  // the pot has no polylines: its mesh only
  EXPECT_EQ(p.mode, TINYGLTF_MODE_TRIANGLES);
  const TriangleMeshN<3>& pot_mesh = world.body<3>(0).def().mesh;
  EXPECT_EQ(m.accessors.at(size_t(p.attributes.at("POSITION"))).count, pot_mesh.points.size());
  EXPECT_EQ(m.accessors.at(size_t(p.indices)).count, 3 * pot_mesh.triangles.size());
  ASSERT_EQ(p.targets.size(), 3u);  // = the modes
  for (const auto& target : p.targets) {
    const tinygltf::Accessor& a = m.accessors.at(size_t(target.at("POSITION")));
    EXPECT_EQ(a.count, pot_mesh.points.size());
    EXPECT_EQ(a.minValues.size(), 3u);  // glTF requires POSITION's bounds, of targets too
  }
  ASSERT_TRUE(mesh.extras.Has("targetNames"));
  const tinygltf::Value& names = mesh.extras.Get("targetNames");
  ASSERT_EQ(names.ArrayLen(), 3u);
  EXPECT_EQ(names.Get(0).Get<std::string>(), "squash");
  EXPECT_EQ(names.Get(1).Get<std::string>(), "sway");
  EXPECT_EQ(names.Get(2).Get<std::string>(), "twist");

  ASSERT_EQ(m.animations.size(), 1u);
  const tinygltf::Animation& anim = m.animations[0];
  ASSERT_EQ(anim.samplers.size(), 6u);  // the pot's and the table's; the ground stands still
  ASSERT_EQ(anim.channels.size(), 6u);
  std::vector<std::string> paths;
  for (const tinygltf::AnimationChannel& c : anim.channels) {
    EXPECT_EQ(c.target_node, int(&c - anim.channels.data()) / 3);
    paths.push_back(c.target_path);
    const tinygltf::AnimationSampler& s = anim.samplers.at(size_t(c.sampler));
    EXPECT_EQ(s.interpolation, "LINEAR");
    const size_t per_key = c.target_path != "weights" ? 1 : c.target_node == 0 ? 3 : size_t(world.body<2>(1).num_modes());
    EXPECT_EQ(m.accessors.at(size_t(s.output)).count, 16 * per_key) << c.target_path;
    const tinygltf::Accessor& input = m.accessors.at(size_t(s.input));
    ASSERT_EQ(input.count, 16u);
    const float* times = AccessorData<float>(m, s.input);
    for (int k = 0; k < 16; ++k) EXPECT_EQ(times[k], float(run->time(0) + k / 30.0)) << k;
    EXPECT_EQ(input.minValues, std::vector<double>{double(times[0])});
    EXPECT_EQ(input.maxValues, std::vector<double>{double(times[15])});
  }
  EXPECT_EQ(paths, (std::vector<std::string>{"translation", "rotation", "weights", "translation", "rotation", "weights"}));
  // the node's own TRS is the first frame's, for a viewer that does not play the animation
  ASSERT_EQ(node.translation.size(), 3u);
  EXPECT_NEAR(node.translation[1], 30.0, 1e-5);
  ASSERT_EQ(node.rotation.size(), 4u);
  EXPECT_NEAR(node.rotation[0], std::sin(0.15), 1e-6);
  EXPECT_NEAR(node.rotation[3], std::cos(0.15), 1e-6);
  fs::remove_all(dir);
}

// At one deformed, turned state the .glb's vertices, evaluated as a viewer does
// (base + Σ w_j target_j, then R and t of the node), are the world positions of the mesh's
// vertices (Eq. 4.2 through WorldPosition, in double) to float precision; a mode without a
// name is mode_<j+1>.
TEST(GltfExport, VerticesAtAStateAreTheWorldPositions) {
  World world(WithGroundPlane());
  world.AddBody(Pot(/*unnamed_mode=*/1));
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 0.4, -0.2).normalized()));
  world.SetState(0, PositionsOf(Eigen::Vector3d(5, 40, -3), turn, Eigen::Vector3d(-0.3, 0.4, 0.5)), Eigen::VectorXd::Zero(9));
  GltfRecorder gltf(&world);
  gltf.AddFrame();
  const fs::path dir = TestDir("state");
  gltf.Write((dir / "pot.glb").string());
  const tinygltf::Model m = Load((dir / "pot.glb").string());
  ASSERT_EQ(m.meshes.size(), 2u);  // the pot and the ground
  EXPECT_EQ(m.meshes[0].extras.Get("targetNames").Get(1).Get<std::string>(), "mode_2");
  const tinygltf::Primitive& p = m.meshes[0].primitives[0];
  const tinygltf::Node& node = m.nodes[0];
  const float* base = AccessorData<float>(m, p.attributes.at("POSITION"));
  std::vector<const float*> targets;
  for (const auto& t : p.targets) targets.push_back(AccessorData<float>(m, t.at("POSITION")));
  const Eigen::Quaterniond r(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
  const Eigen::Vector3d t(node.translation[0], node.translation[1], node.translation[2]);
  const BodyModelN<3>& pot = world.body<3>(0);
  double worst = 0, size = (pot.lattice().axes()[0] + pot.lattice().axes()[1] + pot.lattice().axes()[2]).norm();
  for (int v = 0; v < int(pot.def().mesh.points.size()); ++v) {
    Eigen::Vector3d local(base[3 * v], base[3 * v + 1], base[3 * v + 2]);
    for (size_t j = 0; j < targets.size(); ++j)
      local += node.weights[j] * Eigen::Vector3d(targets[j][3 * v], targets[j][3 * v + 1], targets[j][3 * v + 2]);
    const Eigen::Vector3d expected = WorldPosition<3>(world, 0, pot.mesh_rest_local(v), pot.mesh_mode_matrix(v));
    worst = std::max(worst, (t + r * local - expected).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, 1e-6 * size) << "size " << size;
  fs::remove_all(dir);
}

// A Witkin & Welch quadratic block (x = R p(u)) at two states: targets R_i_j hold p_j(u) along
// axis i, the weights of frame k are R's entries, and base + Σ w target is LinearWorldPoint at
// every vertex of its drawing (polylines, then the surface) to float precision.
TEST(GltfExport, LinearBodyWeightsAreItsCoordinates) {
  World world(testing::WitkinWelchOptions());
  Eigen::VectorXd half(3);
  half << 1.0, 0.5, 0.5;
  auto block = std::make_shared<const LinearBodyModel>(MakeBoxBody("block", 3, LinearOrder::kQuadratic, half, 3, 1.0));
  world.AddLinearBody(block);
  const LinearDrawing drawing = MakeBoxDrawing(half, 4);
  GltfRecorder gltf(&world, {drawing}, 16);
  EXPECT_TRUE(gltf.SkippedBodies().empty());
  std::vector<std::vector<Eigen::Vector3d>> expected;
  for (int k = 0; k < 2; ++k) {
    Eigen::MatrixXd R = block->RestState();
    R(1, 7) = -0.3 * (k + 1);  // y -= 0.3 x²: bent (basis [x y z 1 xy xz yz x² y² z²])
    R(0, 4) = 0.2 * k;         // x += 0.2 xy: sheared
    R.col(3) << 0.5 * k, 1.0, -0.25 * k;
    world.SetLinearState(0, R, Eigen::MatrixXd::Zero(3, 10));
    world.SetTime(0.1 * k);
    gltf.AddFrame();
    std::vector<Eigen::Vector3d> points;
    for (const auto& line : drawing.polylines)
      for (const Eigen::VectorXd& u : line.points) points.push_back(LinearWorldPoint(world, 0, u));
    for (const Eigen::VectorXd& u : drawing.vertices) points.push_back(LinearWorldPoint(world, 0, u));
    expected.push_back(points);
  }
  const fs::path dir = TestDir("linear");
  gltf.Write((dir / "block.glb").string());
  const tinygltf::Model m = Load((dir / "block.glb").string());
  ASSERT_EQ(m.nodes.size(), 1u);  // no ground: the block does not touch it
  const tinygltf::Mesh& mesh = m.meshes.at(size_t(m.nodes[0].mesh));
  ASSERT_EQ(mesh.primitives.size(), 2u);  // the surface and the outline
  EXPECT_EQ(mesh.primitives[0].mode, TINYGLTF_MODE_TRIANGLES);
  EXPECT_EQ(mesh.primitives[1].mode, TINYGLTF_MODE_LINE);
  const tinygltf::Primitive& p = mesh.primitives[0];
  ASSERT_EQ(p.targets.size(), 30u);  // 3 × 10
  EXPECT_EQ(mesh.extras.Get("targetNames").Get(7).Get<std::string>(), "R_0_7");
  ASSERT_EQ(m.animations.size(), 1u);
  ASSERT_EQ(m.animations[0].channels.size(), 1u);  // weights only: the node stays put
  EXPECT_EQ(m.animations[0].channels[0].target_path, "weights");
  const float* weights = AccessorData<float>(m, m.animations[0].samplers[0].output);
  const float* base = AccessorData<float>(m, p.attributes.at("POSITION"));
  const size_t vertices = m.accessors.at(size_t(p.attributes.at("POSITION"))).count;
  ASSERT_EQ(vertices, expected[0].size());
  double worst = 0;
  for (int k = 0; k < 2; ++k)
    for (size_t v = 0; v < vertices; ++v) {
      Eigen::Vector3d x(base[3 * v], base[3 * v + 1], base[3 * v + 2]);
      for (size_t j = 0; j < 30; ++j) {
        const float* target = AccessorData<float>(m, p.targets[j].at("POSITION"));
        x += weights[30 * k + j] * Eigen::Vector3d(target[3 * v], target[3 * v + 1], target[3 * v + 2]);
      }
      worst = std::max(worst, (x - expected[size_t(k)][v]).cwiseAbs().maxCoeff());
    }
  EXPECT_LT(worst, 1e-5);  // the block is 2 × 1 × 1
  fs::remove_all(dir);
}

// With frames rendered the .glb has the render's camera: a perspective camera node keyed per
// frame. The 3D view orbits at 30°/s from azimuth 20° at elevation 25° (FrameBox3d: the camera
// sits along (cos el sin az, sin el, cos el cos az) from what it looks at), so the node's +z
// (glTF's camera looks down −z) must have that elevation and turn by 30° per second.
TEST(GltfExport, RenderedFramesAddTheOrbitingCamera) {
  REQUIRE_DISPLAY();
  World world(WithGroundPlane());
  world.AddBody(Pot());
  world.SetState(0, PositionsOf(Eigen::Vector3d(0, 30, 0), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()),
                 Eigen::VectorXd::Zero(9));
  const std::shared_ptr<record::Trajectory> run = RecordFromStart(world, 0.3);
  const fs::path dir = TestDir("camera");
  RenderOutputs out;
  out.folder = dir.string();
  out.name = "pot3";
  ASSERT_EQ(SetOutputs({"frames", "gltf"}, &out), "");
  out.fps = 10;
  out.view.width = 160;
  out.view.height = 120;
  out.view.azimuth = 20;
  out.view.elevation = 25;
  out.orbit_deg_per_s = 30;
  const RenderReport report = RenderTrajectory(world, *run, SceneSpec{}, out);
  ASSERT_EQ(report.frames, 4);
  const tinygltf::Model m = Load((dir / "pot3.glb").string());
  ASSERT_EQ(m.cameras.size(), 1u);
  EXPECT_EQ(m.cameras[0].type, "perspective");
  EXPECT_NEAR(m.cameras[0].perspective.yfov, out.view.view_angle * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(m.cameras[0].perspective.aspectRatio, 160.0 / 120.0, 1e-6);
  int node = -1;
  for (size_t n = 0; n < m.nodes.size(); ++n)
    if (m.nodes[n].camera == 0) node = int(n);
  ASSERT_GE(node, 0);
  EXPECT_EQ(m.nodes[size_t(node)].name, "camera");
  const float* rotations = nullptr;
  const float* times = nullptr;
  for (const tinygltf::AnimationChannel& c : m.animations.at(0).channels)
    if (c.target_node == node && c.target_path == "rotation") {
      rotations = AccessorData<float>(m, m.animations[0].samplers.at(size_t(c.sampler)).output);
      times = AccessorData<float>(m, m.animations[0].samplers.at(size_t(c.sampler)).input);
    }
  ASSERT_NE(rotations, nullptr);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Quaterniond r(rotations[4 * k + 3], rotations[4 * k], rotations[4 * k + 1], rotations[4 * k + 2]);
    const Eigen::Vector3d back = r * Eigen::Vector3d::UnitZ(), up = r * Eigen::Vector3d::UnitY();
    EXPECT_NEAR(std::asin(back.y()) * 180.0 / M_PI, 25.0, 1e-3) << k;
    EXPECT_NEAR(std::atan2(back.x(), back.z()) * 180.0 / M_PI, 20.0 + 30.0 * times[k], 1e-3) << k;
    EXPECT_GT(up.y(), 0.5) << k;  // upright
  }
  fs::remove_all(dir);
}

// A path that cannot be written: std::runtime_error naming it, and nothing left behind; an
// earlier file of the name stays as it was when the write fails.
TEST(GltfExport, BadPathThrowsNamingTheFileAndLeavesNoFile) {
  World world(WithGroundPlane());
  world.AddBody(Pot());
  GltfRecorder gltf(&world);
  EXPECT_THROW(gltf.Write("/nonexistent_dir_never/x.glb"), std::logic_error);  // no frame yet
  gltf.AddFrame();
  const fs::path dir = TestDir("bad");
  {  // the folder is a regular file
    std::ofstream(dir / "file") << "x";
    const std::string path = (dir / "file" / "run.glb").string();
    try {
      gltf.Write(path);
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    }
  }
  {  // the path is a folder
    fs::create_directories(dir / "run.glb");
    EXPECT_THROW(gltf.Write((dir / "run.glb").string()), std::runtime_error);
    EXPECT_TRUE(fs::is_directory(dir / "run.glb"));
    EXPECT_FALSE(fs::exists(dir / "run.glb.tmp"));
  }
  {  // its temporary file is a FIFO (writing would block): refused, the earlier file kept
    const fs::path path = dir / "old.glb";
    std::ofstream(path) << "earlier";
    ASSERT_EQ(::mkfifo((path.string() + ".tmp").c_str(), 0600), 0);
    try {
      gltf.Write(path.string());
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
    std::ifstream in(path);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(text, "earlier");
  }
  fs::remove_all(dir);
}

TEST(GltfExport, IsAnOutputWrittenWithoutADisplay) {
  RenderOutputs out;
  EXPECT_EQ(SetOutputs({"frames", "gltf"}, &out), "");
  EXPECT_TRUE(out.gltf);
  EXPECT_EQ(KeepWithoutDisplay(&out), std::vector<std::string>{"frames"});
  EXPECT_TRUE(out.gltf);
  EXPECT_NE(SetOutputs({"glb"}, &out).find("gltf"), std::string::npos);  // the message lists it
}

}  // namespace
}  // namespace wobble::pipelines
