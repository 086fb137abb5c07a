// The Witkin & Welch step against MuJoCo 2.2.2 (issue 18), on one machine in one run.
//
// The problem is Fig. 2's triple pendulum as data/fig2_triple_pendulum.wob sets it up: three
// links 1 long and 0.2 thick, 1 kg each as a 3 × 3 grid of mass points, joined end to end,
// nailed at the top, let go from the horizontal under g = 9.81, dt = 0.001, no damping.
//  - wobble: three affine bodies (6 coordinates each, k_e = k_c = 100), a nail and two
//    attachments through the pre-inverted A of Eq. 10, semi-implicit Euler (velocity first);
//  - MuJoCo: the same chain in reduced coordinates, three hinges, each link's mass and
//    rotational inertia those of the same nine points (I = 0.17333 about the link's centre),
//    integrator "Euler" (MuJoCo's semi-implicit Euler), no contacts, no geoms.
// Both run 10 s from the same start; the energy drift counter is max |E(t) − E(0)| over that
// run divided by the chain's potential drop scale m g L = 3 · 9.81 · 1.5 (J).
// Run: build/bench/mujoco_bench --benchmark_min_time=1
#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>

#include "wobble/world/world.h"

namespace wobble {
namespace {

constexpr double kDt = 0.001;
constexpr int kRunSteps = 10000;                       // 10 s
constexpr double kEnergyScale = 3.0 * 9.81 * 1.5;      // m g L of the chain (J)
constexpr double kLinkInertia = (3 * 2 * 0.25 + 3 * 2 * 0.01) / 9.0;  // Σ m (x² + y²), 9 points of 1/9 kg

// ---------------------------------------------------------------- wobble

std::shared_ptr<const LinearBodyModel> Link() {
  static const auto model = std::make_shared<LinearBodyModel>(
      MakeBoxBody("link", 2, LinearOrder::kAffine, Eigen::Vector2d(0.5, 0.1), 3, 1.0));
  return model;
}

std::unique_ptr<World> WobbleChain() {
  WorldOptions opt;
  opt.dt = kDt;
  auto world = std::make_unique<World>(opt);
  const AffineMaterial mat{100.0, 100.0, 0.0, 0.0};
  for (int i = 0; i < 3; ++i) {
    const int b = world->AddLinearBody(Link(), mat);
    world->SetLinearState(b, Link()->PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(0.5 + i, 0.0)),
                          Eigen::MatrixXd::Zero(2, 3));
  }
  world->AddNail(At(0, Eigen::Vector2d(-0.5, 0.0)));
  world->AddAttachment(At(0, Eigen::Vector2d(0.5, 0.0)), At(1, Eigen::Vector2d(-0.5, 0.0)));
  world->AddAttachment(At(1, Eigen::Vector2d(0.5, 0.0)), At(2, Eigen::Vector2d(-0.5, 0.0)));
  return world;
}

double WobbleDrift() {
  auto world = WobbleChain();
  const double e0 = world->TotalEnergy();
  double worst = 0.0;
  for (int i = 0; i < kRunSteps; ++i) {
    if (!world->Step()) throw std::runtime_error(world->status().message);
    worst = std::max(worst, std::abs(world->TotalEnergy() - e0));
  }
  return worst / kEnergyScale;
}

void BM_WobbleTriplePendulum(benchmark::State& state) {
  auto world = WobbleChain();
  for (auto _ : state) {
    if (!world->Step()) state.SkipWithError(world->status().message.c_str());
    if (world->steps() == kRunSteps) {  // restarted every 10 s, as the MuJoCo run is
      state.PauseTiming();
      world = WobbleChain();
      state.ResumeTiming();
    }
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["drift/mgL"] = WobbleDrift();
}
BENCHMARK(BM_WobbleTriplePendulum);

// ---------------------------------------------------------------- MuJoCo

// Links along +x, hinges about y, gravity −z: the chain starts horizontal as wobble's does.
// The energy flag only for the drift run: it makes mj_step evaluate the energies, which the
// timed wobble step does not do either.
std::string ChainXml(bool energy) {
  char inertial[160];
  std::snprintf(inertial, sizeof inertial,
                "<inertial pos='0.5 0 0' mass='1' diaginertia='0.01 %.17g %.17g'/>", kLinkInertia, kLinkInertia);
  std::string link = std::string("<joint type='hinge' axis='0 1 0'/>") + inertial;
  return "<mujoco model='fig2'>"
         "<option timestep='0.001' integrator='Euler' gravity='0 0 -9.81'>"
         "<flag contact='disable' energy='" + std::string(energy ? "enable" : "disable") + "'/></option>"
         "<worldbody><body pos='0 0 0'>" + link +
         "<body pos='1 0 0'>" + link + "<body pos='1 0 0'>" + link +
         "</body></body></body></worldbody></mujoco>";
}

struct MuJoCo {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  explicit MuJoCo(bool energy) {
    auto vfs = std::make_unique<mjVFS>();  // 2 MB: not on the stack
    mj_defaultVFS(vfs.get());
    const std::string xml = ChainXml(energy);
    if (mj_makeEmptyFileVFS(vfs.get(), "fig2.xml", int(xml.size())) != 0)
      throw std::runtime_error("MuJoCo: no room in the VFS");
    const int f = mj_findFileVFS(vfs.get(), "fig2.xml");
    std::copy(xml.begin(), xml.end(), static_cast<char*>(vfs->filedata[f]));
    char error[1000] = "";
    m = mj_loadXML("fig2.xml", vfs.get(), error, sizeof error);
    mj_deleteVFS(vfs.get());
    if (!m) throw std::runtime_error(std::string("MuJoCo: ") + error);
    d = mj_makeData(m);
  }
  ~MuJoCo() {
    mj_deleteData(d);
    mj_deleteModel(m);
  }
  double Energy() const { return d->energy[0] + d->energy[1]; }  // filled by mj_step (flag energy)
};

double MuJoCoDrift() {
  MuJoCo mj(true);
  mj_forward(mj.m, mj.d);
  const double e0 = mj.Energy();
  double worst = 0.0;
  for (int i = 0; i < kRunSteps; ++i) {
    mj_step(mj.m, mj.d);
    worst = std::max(worst, std::abs(mj.Energy() - e0));  // energy of the state before the step
  }
  return worst / kEnergyScale;
}

void BM_MuJoCoTriplePendulum(benchmark::State& state) {
  MuJoCo mj(false);
  int steps = 0;
  for (auto _ : state) {
    mj_step(mj.m, mj.d);
    if (++steps == kRunSteps) {
      state.PauseTiming();
      mj_resetData(mj.m, mj.d);
      steps = 0;
      state.ResumeTiming();
    }
  }
  state.counters["steps/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["drift/mgL"] = MuJoCoDrift();
}
BENCHMARK(BM_MuJoCoTriplePendulum);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
