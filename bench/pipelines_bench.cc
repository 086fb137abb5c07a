// Benchmarks of pipelines/: frames rendered offscreen per second at 640x480, and .png, .exr
// (R,G,B,A,depth.Z), displacement .exr and .vtp frames written per second, each for the
// table of data/ falling onto a sloped ground; a rendered frame's EXR channels written with
// each of OpenEXR's compressions wobble offers; and the goal of issue 3 in one number: 300
// frames (10 s at 30 fps) simulated, rendered and exported (PNG + EXR + VTP + displacement).
// `wobble view`'s frame (issue 8): one frame of the interactive viewer (1280x720 window: scene,
// two live charts, sliders) for the thesis' table and pot, each frame advancing 1/30 s.
// Rendering needs an X display: `make bench` runs this under xvfb-run; without DISPLAY the
// rendering benchmarks are skipped with a message.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <vtkImageData.h>
#include <vtkPNGWriter.h>

#include "pipelines/exports.h"
#include "pipelines/exr_frame.h"
#include "pipelines/exr_io.h"
#include "pipelines/interactive_view.h"
#include "pipelines/scene_view.h"
#include "pipelines/mesh_io.h"
#include "pipelines/trajectory_render.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble::pipelines {
namespace {

const std::string kData = wobble::test_env::DataDir();

std::shared_ptr<const BodyModel> Table() {
  static auto body = std::make_shared<const BodyModel>(formats::ReadObjectFile(kData + "/table.obj"),
                                                       formats::ReadDeformationFile(kData + "/table_modes.def"));
  return body;
}

// The demo scene: the table dropped from 50 onto a ground sloped by -10 degrees.
std::unique_ptr<World> DemoWorld() {
  WorldOptions o;
  o.params.ground.slope = -10.0 * M_PI / 180.0;
  auto world = std::make_unique<World>(o);
  world->AddBody(Table());
  Eigen::VectorXd q = Eigen::VectorXd::Zero(Table()->num_q());
  q[1] = 50;
  world->SetState(0, q, Eigen::VectorXd::Zero(q.size()));
  return world;
}

// Steps to the next frame at 30 fps (dt 0.01: 3 or 4 steps), starting over after 10 s.
void Advance(std::unique_ptr<World>* world, long* frame) {
  ++*frame;
  if (*frame > 300) {
    **world = std::move(*DemoWorld());  // in place: the views and writers keep pointing at it
    *frame = 0;
  }
  (*world)->RunUntil(*frame / 30.0, [](const World&) {});
}

std::string OutDir() {
  const std::string dir = (std::filesystem::temp_directory_path() / "wobble_pipelines_bench").string();
  std::filesystem::create_directories(dir);
  return dir;
}

bool NeedDisplay(benchmark::State& state) {
  if (HasDisplay()) return true;
  state.SkipWithError("no DISPLAY: rendering needs X (run under xvfb-run)");
  return false;
}

void BM_RenderFrame640x480(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  auto world = DemoWorld();
  SceneView view(world.get());
  view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-50, -80), Eigen::Vector2d(350, 160)));
  long frame = 0;
  for (auto _ : state) {
    Advance(&world, &frame);
    view.Render();
    benchmark::DoNotOptimize(view.Capture());  // the pixels must come back to count
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_WritePngFrame640x480(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  auto world = DemoWorld();
  SceneView view(world.get());
  long frame = 0;
  const std::string path = OutDir() + "/frame.png";
  for (auto _ : state) {
    Advance(&world, &frame);
    view.Render();
    view.WritePng(path);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WritePngFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

// Encoding one rendered 640x480 frame as PNG at the frames' level (1): wobble's libpng encoder
// (pipelines/png_io.h, which runs on the writer threads) against vtkPNGWriter, the baseline
// it replaced (VTK objects may not be used off the main thread).
void BM_EncodePng640x480(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  auto world = DemoWorld();
  SceneView view(world.get());
  view.Render();
  vtkSmartPointer<vtkImageData> image = view.Capture();
  const PngPixels pixels = PixelsOf(image);
  const std::string path = OutDir() + "/encode.png";
  const bool vtk = state.range(0) == 1;
  for (auto _ : state) {
    if (vtk) {
      auto w = vtkSmartPointer<vtkPNGWriter>::New();
      w->SetInputData(image);
      w->SetCompressionLevel(1);
      w->SetFileName(path.c_str());
      w->Write();
    } else {
      WritePngPixels(path, pixels, 1);
    }
  }
  state.SetLabel(vtk ? "vtkPNGWriter (baseline)" : "wobble WritePngPixels");
  state.SetBytesProcessed(state.iterations() * int64_t(pixels.bytes.size()));
}
BENCHMARK(BM_EncodePng640x480)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// Writing one rendered 640x480 EXR frame's channels (R, G, B, A, forward.u/v halves, depth.Z
// float) with each of OpenEXR's compressions wobble offers (arg: ExrCompression): time per
// frame, and the file's mean size as the `bytes` counter. The frames: 30 consecutive frames of
// the demo, cycled.
void BM_WriteExrChannels640x480(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  auto world = DemoWorld();
  SceneView view(world.get());
  std::vector<std::vector<ExrChannel>> frames;
  long frame = 0;
  for (int k = 0; k < 30; ++k) {
    Advance(&world, &frame);
    view.Render();
    frames.push_back(ExrFrameChannels(view.CaptureExrFrame(), nullptr, nullptr));
  }
  const std::string path = OutDir() + "/channels.exr";
  const auto compression = ExrCompression(state.range(0));
  size_t k = 0;
  double bytes = 0;
  for (auto _ : state) {
    WriteExrChannels(path, 640, 480, frames[k++ % frames.size()], compression);
    state.PauseTiming();
    bytes += double(std::filesystem::file_size(path));
    state.ResumeTiming();
  }
  state.counters["bytes"] = bytes / double(state.iterations());
  state.SetLabel(ExrCompressionName(compression));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WriteExrChannels640x480)
    ->DenseRange(int(ExrCompression::kNone), int(ExrCompression::kDwaa))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_WriteExrFrame640x480(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  auto world = DemoWorld();
  SceneView view(world.get());
  long frame = 0;
  const std::string path = OutDir() + "/frame.exr";
  for (auto _ : state) {
    Advance(&world, &frame);
    view.Render();
    view.WriteExr(path);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WriteExrFrame640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_WriteVtpFrame(benchmark::State& state) {
  auto world = DemoWorld();
  VtpSeriesWriter writer(world.get(), OutDir() + "/vtp", "table");
  long frame = 0;
  for (auto _ : state) {
    Advance(&world, &frame);
    writer.WriteFrame(int(frame));  // three .vtp files: lattice, points, shape
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WriteVtpFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

// Arg 0: ZIP level 1 (how displacement EXRs were written, the baseline); arg 1: as
// WriteDisplacementExr writes them now, uncompressed. The file's size is the `bytes` counter.
void BM_WriteDisplacementExr256x85(benchmark::State& state) {
  auto world = DemoWorld();
  long frame = 0;
  const std::string path = OutDir() + "/disp.exr";
  const bool zip = state.range(0) == 0;
  for (auto _ : state) {
    Advance(&world, &frame);
    if (zip)
      WriteExrChannels(path, 256, 85, DisplacementImage(*world, 0, 256, 85), ExrCompression::kZip);
    else
      WriteDisplacementExr(path, *world, 0, 256, 85);
  }
  state.counters["bytes"] = double(std::filesystem::file_size(path));
  state.SetLabel(zip ? "ZIP (baseline)" : "WriteDisplacementExr");
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_WriteDisplacementExr256x85)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

// The goal: 300 frames of the demo, simulated, rendered at 640x480 and written as PNG, EXR,
// VTP and displacement EXR, in under 10 s of wall time.
void BM_Demo300FramesAllOutputs(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  const std::string dir = OutDir() + "/demo";
  for (auto _ : state) {
    auto world = DemoWorld();
    SceneView view(world.get());
    view.FrameBox(Eigen::AlignedBox2d(Eigen::Vector2d(-50, -80), Eigen::Vector2d(350, 160)));
    VtpSeriesWriter vtp(world.get(), dir + "/vtp", "table");
    BackgroundWriter writer;  // as `wobble render`/`export` do: write while the next frame renders
    for (int k = 0; k < 300; ++k) {
      world->RunUntil(k / 30.0, [](const World&) {});
      view.Render();
      char name[32];
      std::snprintf(name, sizeof(name), "%04d", k);
      view.WritePng(dir + "/frame_" + name + ".png", &writer);
      view.WriteExr(dir + "/frame_" + name + ".exr", &writer);
      WriteDisplacementExr(dir + "/disp_" + name + ".exr", *world, 0, 256, 85, &writer);
      vtp.WriteFrame(k, &writer);
    }
    writer.Wait();
    vtp.WriteCollection();
  }
  state.SetItemsProcessed(300 * state.iterations());
}
BENCHMARK(BM_Demo300FramesAllOutputs)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace wobble::pipelines

namespace wobble::pipelines {
namespace {

// One viewer frame: 1/30 s simulated (3 or 4 steps of 0.01), the recorders sampled, the
// window drawn (charts redrawn every 10th frame as in `wobble view`). Arguments: 0 table,
// 1 pot; 1 with the charts, 0 without. Restarts after 300 frames (10 s).
void BM_ViewerFrame1280x720(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  const bool pot = state.range(0) == 1;
  scene::Scene scene;  // as `wobble view OBJECT --modes DEF --q "0 50 0 .."` loads it
  scene.options() = WorldOptions();  // the World's defaults, as before the scene runtime
  scene.object().Load(kData + (pot ? "/pot.obj" : "/table.obj"));
  scene.object().LoadModes({kData + (pot ? "/def_pot" : "/table_modes.def")});
  Eigen::VectorXd q0 = Eigen::VectorXd::Zero(scene.object().Body<2>()->num_q());
  q0[1] = 50;
  scene.object().SetState(q0, Eigen::VectorXd::Zero(q0.size()));
  ViewerOptions o;
  o.fixed_frame_time = true;
  o.charts = state.range(1) == 1;
  InteractiveView view(scene, o);
  view.Initialize();
  long frames = 0, steps = 0;
  for (auto _ : state) {
    const long before = view.session_steps();
    view.Frame();
    steps += view.session_steps() - before;
    ++frames;
    if (view.num_recorded_frames() > 300) view.Restart();
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["steps_per_frame"] = double(steps) / double(std::max(1L, frames));
  state.SetLabel(pot ? "pot" : "table");
}
BENCHMARK(BM_ViewerFrame1280x720)->Args({0, 1})->Args({1, 1})->Args({0, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

// The video's cost on the render (issue 48: at most 20% on the critical path): the demo's
// 10 s table run, recorded once, rendered to 301 frames at 640x480 as `wobble render --what`
// does. Arguments: 0 frames (PNG) alone, the baseline; 1 frames and mp4; 2 mp4 alone.
void BM_RenderTable300Frames(benchmark::State& state) {
  if (!NeedDisplay(state)) return;
  static const std::shared_ptr<const record::Trajectory> run = [] {
    auto world = DemoWorld();
    auto recorded = std::make_shared<record::Trajectory>(*world);
    auto recorder = std::make_shared<record::Recorder>(recorded);
    world->SetRecorder(recorder);
    recorder->Start(*world);
    world->RunUntil(10.0 + 0.005, [](const World&) {});
    return recorded;
  }();
  RenderOutputs out;
  out.folder = OutDir() + "/render_video";
  out.name = "table";
  out.fps = 30;
  out.filmstrip = out.vtp = false;
  out.frames = state.range(0) != 2;
  out.mp4 = state.range(0) != 0;
  long frames = 0;
  for (auto _ : state) {
    auto world = DemoWorld();
    frames += RenderTrajectory(*world, *run, SceneSpec{}, out).frames;
  }
  state.SetItemsProcessed(frames);
  state.SetLabel(state.range(0) == 0 ? "frames (baseline)" : state.range(0) == 1 ? "frames + mp4" : "mp4");
}
BENCHMARK(BM_RenderTable300Frames)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(2);

// The glTF export's size and time (issue 48: < 2 MB for a 10,000-vertex character with 6 modes
// over 300 frames): a ball of 100 x 100 vertices (a UV sphere, radius 50) in a fitted 4x4x4
// lattice with six modes, dropped for 10 s and exported at 30 fps with nothing else. Counters:
// the .glb's bytes, and a per-frame vertex cache of the same frames (float32 x, y, z).
void BM_GltfExport10kVertices300Frames(benchmark::State& state) {
  const std::string dir = OutDir() + "/gltf10k";
  std::filesystem::create_directories(dir);
  constexpr int kRings = 100, kAround = 100;
  {
    std::ofstream mesh(dir + "/ball.obj");
    for (int i = 0; i < kRings; ++i) {
      const double polar = M_PI * (i + 0.5) / kRings;
      for (int j = 0; j < kAround; ++j) {
        const double azimuth = 2 * M_PI * j / kAround;
        mesh << "v " << 50 * std::sin(polar) * std::cos(azimuth) << " " << 50 + 50 * std::cos(polar) << " "
             << 50 * std::sin(polar) * std::sin(azimuth) << "\n";
      }
    }
    for (int i = 0; i + 1 < kRings; ++i)
      for (int j = 0; j < kAround; ++j) {
        const int a = i * kAround + j + 1, b = i * kAround + (j + 1) % kAround + 1;
        mesh << "f " << a << " " << a + kAround << " " << b + kAround << "\nf " << a << " " << b + kAround << " " << b << "\n";
      }
    std::ofstream(dir + "/ball3.obj") << "dimension 3\nname ball\nmesh ball.obj\nlattice fit 4 4 4 margin 0.05\n"
                                         "sample volume 400 600\nsample surface 240 150\n";
    std::ofstream(dir + "/ball.def3") << "dimension 3\n"
                                         "mode squash stiffness 2000000 damping 20000\n  squash y 0.4\n"
                                         "mode squash_x stiffness 2000000 damping 20000\n  squash x 0.4\n"
                                         "mode sway stiffness 2000000 damping 20000\n  shear y x 30\n"
                                         "mode sway_z stiffness 2000000 damping 20000\n  shear y z 30\n"
                                         "mode twist stiffness 2000000 damping 20000\n  twist y 30\n"
                                         "mode bend stiffness 2000000 damping 20000\n  bend x y 30\n";
  }
  BodyDefN<3> def = ReadObject<3>(dir + "/ball3.obj");
  auto modes = formats::ReadDeformationFile(dir + "/ball.def3", def.lattice);
  auto body = std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes));
  WorldOptions options;
  options.dt = 0.001;
  options.params.ground_plane.enabled = true;
  World world(options);
  world.AddBody(body);
  // tilted by 0.3 rad about x, spinning at 1.2 rad/s about y (q: t, quaternion x y z w, γ)
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body->num_positions()), qdot = Eigen::VectorXd::Zero(body->num_q());
  q[1] = 60;
  q[3] = std::sin(0.15);
  q[6] = std::cos(0.15);
  qdot[4] = 1.2;
  world.SetState(0, q, qdot);
  auto run = std::make_shared<record::Trajectory>(world);
  auto recorder = std::make_shared<record::Recorder>(run);
  world.SetRecorder(recorder);
  recorder->Start(world);
  world.RunUntil(10.0 + 0.0005, [](const World&) {});
  RenderOutputs out;
  out.folder = dir;
  out.name = "ball";
  out.fps = 30;
  out.frames = out.filmstrip = out.vtp = false;
  out.gltf = true;
  long frames = 0;
  for (auto _ : state) {
    World replay(options);
    replay.AddBody(body);
    frames = RenderTrajectory(replay, *run, SceneSpec{}, out).frames;
  }
  const size_t vertices = body->def().mesh.points.size();
  state.counters["vertices"] = double(vertices);
  state.counters["frames"] = double(frames);
  state.counters["glb_bytes"] = double(std::filesystem::file_size(dir + "/ball.glb"));
  state.counters["vertex_cache_bytes"] = double(vertices * 3 * 4 * size_t(frames));
}
BENCHMARK(BM_GltfExport10kVertices300Frames)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
}  // namespace wobble::pipelines

BENCHMARK_MAIN();
