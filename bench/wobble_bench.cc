// Benchmarks of the solver core.
//
// The table of Fig. 1.2 (11 mass points, 4 modes; data/table.obj and data/table_modes.def when
// present, else the same table built here) resting on the ground and falling freely, the same
// table resampled to 10,000 mass points (the step must not care: O(D²), not O(N), out of
// contact), and the moment-based mass matrix against the per-point reference of Eq. 4.10.
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <numeric>
#include <memory>
#include <string>
#include <vector>

#include "support/reference.h"
#include "wobble/dynamics/step.h"
#include "wobble/world/world.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

// ---- the table -------------------------------------------------------------------------

// The table of Fig. 1.2 / Fig. 4.3 on a 300 x 100 lattice: a top and two legs, 11 points of 50.
BodyDef TableInCode() {
  BodyDef def;
  def.name = "table";
  def.lattice = Lattice({0, 0}, {300, 0}, {0, 100});
  for (int i = 0; i < 5; ++i) def.mass_positions.push_back({75.0 * i, 100.0});
  for (double x : {0.0, 300.0})
    for (int j = 0; j < 3; ++j) def.mass_positions.push_back({x, 100.0 * j / 3});
  def.masses.assign(def.mass_positions.size(), 50.0);
  def.shapes = {{{{0, 100}, {300, 100}}, false}, {{{0, 0}, {0, 100}}, false}, {{{300, 0}, {300, 100}}, false}};
  return def;
}

// A 4 x 4 mode from rows of x and y displacements (row j at t = j/3, column i at s = i/3).
DeformationMode ModeFromRows(const std::string& name, const double (&x)[4][4], const double (&y)[4][4]) {
  DeformationMode m;
  m.name = name;
  m.displacement.resize(16);
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) m.displacement[i * 4 + j] = {x[j][i], y[j][i]};
  m.stiffness = 4e5;  // as in data/table_modes.def
  m.damping = 2.5e4;
  return m;
}

// The four modes of data/table_modes.def: the §4.10.1 bend, a shear, vertical and horizontal squash.
std::vector<DeformationMode> TableModesInCode() {
  const double zero[4][4] = {};
  const double bend_x[4][4] = {
      {150, 150, -150, -150}, {50, 50, -50, -50}, {-50, -50, 50, 50}, {-150, -150, 150, 150}};
  const double bend_y[4][4] = {{0, 100, 100, 0}, {0, 100, 100, 0}, {0, 100, 100, 0}, {0, 100, 100, 0}};
  const double shear_x[4][4] = {{0, 0, 0, 0}, {50, 50, 50, 50}, {100, 100, 100, 100}, {150, 150, 150, 150}};
  const double vsq_x[4][4] = {{-75, -25, 25, 75}, {-75, -25, 25, 75}, {-75, -25, 25, 75}, {-75, -25, 25, 75}};
  const double vsq_y[4][4] = {
      {0, 0, 0, 0}, {-100. / 3, -100. / 3, -100. / 3, -100. / 3}, {-200. / 3, -200. / 3, -200. / 3, -200. / 3},
      {-100, -100, -100, -100}};
  const double hsq_x[4][4] = {{75, 25, -25, -75}, {75, 25, -25, -75}, {75, 25, -25, -75}, {75, 25, -25, -75}};
  const double hsq_y[4][4] = {{0, 0, 0, 0}, {50. / 3, 50. / 3, 50. / 3, 50. / 3}, {100. / 3, 100. / 3, 100. / 3, 100. / 3},
                              {50, 50, 50, 50}};
  return {ModeFromRows("bend", bend_x, bend_y), ModeFromRows("shear", shear_x, zero),
          ModeFromRows("vsquash", vsq_x, vsq_y), ModeFromRows("hsquash", hsq_x, hsq_y)};
}

const std::string kDataDir = wobble::test_env::DataDir();

BodyDef TableDef() {
  const std::string path = kDataDir + "/table.obj";
  return std::filesystem::exists(path) ? formats::ReadObjectFile(path) : TableInCode();
}

std::vector<DeformationMode> TableModes() {
  const std::string path = kDataDir + "/table_modes.def";
  return std::filesystem::exists(path) ? formats::ReadDeformationFile(path) : TableModesInCode();
}

// The same body with `n` mass points spread evenly (by length) along its drawing's segments,
// with the same total mass.
BodyDef Resampled(const BodyDef& def, int n) {
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segments;
  for (const Polyline& p : def.shapes) {
    for (size_t i = 0; i + 1 < p.points.size(); ++i) segments.push_back({p.points[i], p.points[i + 1]});
    if (p.closed && p.points.size() > 2) segments.push_back({p.points.back(), p.points.front()});
  }
  if (segments.empty()) return Resampled(TableInCode(), n);
  double length = 0.0, mass = 0.0;
  for (const auto& s : segments) length += (s.second - s.first).norm();
  for (double m : def.masses) mass += m;
  BodyDef out = def;
  out.mass_positions.clear();
  for (int k = 0; k < n; ++k) {
    // the point at arc length (k + 1/2) / n of the whole drawing
    double a = (k + 0.5) / n * length;
    for (const auto& s : segments) {
      const double l = (s.second - s.first).norm();
      if (a <= l || &s == &segments.back()) {
        out.mass_positions.push_back(s.first + (s.second - s.first) * std::min(1.0, a / l));
        break;
      }
      a -= l;
    }
  }
  out.masses.assign(n, mass / n);
  return out;
}

std::shared_ptr<const BodyModel> Table11() {
  static const auto body = std::make_shared<const BodyModel>(TableDef(), TableModes());
  return body;
}

std::shared_ptr<const BodyModel> Table10k() {
  static const auto body = std::make_shared<const BodyModel>(Resampled(TableDef(), 10000), TableModes());
  return body;
}

Eigen::VectorXd TableQ(const BodyModel& body, double ty) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  q[1] = ty;
  return q;
}

// Times World::Step(); items are steps.
void TimeSteps(benchmark::State& state, World& world) {
  for (auto _ : state) {
    if (!world.Step()) {
      state.SkipWithError(world.status().message.c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["contacts"] = double(world.state<2>(0).contacts.size());
}

// ---- benchmarks --------------------------------------------------------------------------

// The table standing on the ground after a small drop: the steady state of most animations.
void BM_TableRestingOnGround(benchmark::State& state) {
  World world;  // thesis integrator, dt 0.01, gravity, ground y = 0
  world.AddBody(Table11());
  world.SetState(0, TableQ(*Table11(), 10.0), Eigen::VectorXd::Zero(Table11()->num_q()));
  for (int i = 0; i < 2000; ++i)
    if (!world.Step()) {
      state.SkipWithError(world.status().message.c_str());
      return;
    }
  TimeSteps(state, world);
}
BENCHMARK(BM_TableRestingOnGround);

// The same resting table resampled to 10,000 points: the ground scan visits only the point
// groups whose bounding box reaches the ground (the feet), not all 10,000, and at rest the
// contact update reuses its last walk of the point tree (PlaneScanMemo).
void BM_Table10kRestingOnGround(benchmark::State& state) {
  World world;
  world.AddBody(Table10k());
  world.SetState(0, TableQ(*Table10k(), 10.0), Eigen::VectorXd::Zero(Table10k()->num_q()));
  for (int i = 0; i < 2000; ++i)
    if (!world.Step()) {
      state.SkipWithError(world.status().message.c_str());
      return;
    }
  TimeSteps(state, world);
}
BENCHMARK(BM_Table10kRestingOnGround);

// Falling freely far above the ground (convex-hull test only), or with no ground at all.
void OutOfContact(benchmark::State& state, std::shared_ptr<const BodyModel> body) {
  WorldOptions options;
  options.params.ground.enabled = state.range(0) != 0;
  options.params.ground.point = Eigen::Vector2d(0.0, -1e12);
  World world(options);
  world.AddBody(body);
  world.SetState(0, TableQ(*body, 0.0), Eigen::VectorXd::Zero(body->num_q()));
  TimeSteps(state, world);
}
void BM_Table11OutOfContact(benchmark::State& state) { OutOfContact(state, Table11()); }
void BM_Table10kOutOfContact(benchmark::State& state) { OutOfContact(state, Table10k()); }
BENCHMARK(BM_Table11OutOfContact)->ArgName("ground")->Arg(1)->Arg(0);
BENCHMARK(BM_Table10kOutOfContact)->ArgName("ground")->Arg(1)->Arg(0);

// M(q) of the 11-point table: from the mass moments, and point by point (Eq. 4.10).
Eigen::VectorXd SomeQ(const BodyModel& body) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(body.num_q());
  q.head<3>() << 12.0, 34.0, 0.3;
  for (int d = 0; d < body.num_modes(); ++d) q[kRigidDofs + d] = 0.1 * (d + 1) * (d % 2 ? -1 : 1);
  return q;
}

void BM_MassMatrixMoments(benchmark::State& state) {
  const BodyModel& body = *Table11();
  const VecQ<double> q = SomeQ(body);
  MatQ<double> M;
  for (auto _ : state) {
    MassMatrix(body.moments(), q, &M);
    benchmark::DoNotOptimize(M.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MassMatrixMoments);

void BM_MassMatrixReference(benchmark::State& state) {
  const BodyModel& body = *Table11();
  const Eigen::VectorXd q = SomeQ(body);
  for (auto _ : state) {
    Eigen::MatrixXd M = reference::MassMatrix(body, q);
    benchmark::DoNotOptimize(M.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_MassMatrixReference);


// ---- the 3D table (data/table3.obj, data/table3_modes.def3) ----------------------------

// The 3D table with its four modes; `points` > 0 redistributes its mass over that many points:
// 20 keeps the legs' 12 and 8 of the top's 15; more repeat the file's 27 with small offsets
// (same total mass, same lattice), to show that a step out of contact does not depend on N.
// An ellipsoid of about `vertices` vertices inside the table's box: a user's mesh is drawing
// geometry, so it must not change what a step costs (issue 15's 10,000-vertex table).
SurfaceMesh EllipsoidInTable(int vertices) {
  const int rings = std::max(3, int(std::sqrt(double(vertices)))), segments = rings;
  SurfaceMesh m;
  const Eigen::Vector3d c(150, 50, 100), r(140, 45, 95);
  m.points.push_back(c + Eigen::Vector3d(0, r.y(), 0));
  for (int i = 1; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double phi = M_PI * i / rings, th = 2 * M_PI * j / segments;
      m.points.push_back(c + Eigen::Vector3d(std::sin(phi) * std::cos(th), std::cos(phi), std::sin(phi) * std::sin(th)).cwiseProduct(r));
    }
  m.points.push_back(c - Eigen::Vector3d(0, r.y(), 0));
  auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + j % segments; };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j)});
      m.triangles.push_back({ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)});
    }
  const int south = int(m.points.size()) - 1;
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, ring(rings - 1, j), ring(rings - 1, j + 1)});
  return m;
}

std::shared_ptr<const BodyModelN<3>> Table3(int points = 0, int mesh_vertices = 0) {
  BodyDefN<3> def = formats::ReadObjectFile<3>(kDataDir + "/table3.obj");
  if (mesh_vertices > 0) def.mesh = EllipsoidInTable(mesh_vertices);
  if (points > 0) {
    const double total = std::accumulate(def.masses.begin(), def.masses.end(), 0.0);
    const std::vector<Eigen::Vector3d> file = def.mass_positions;  // 15 top, then 12 leg points
    def.mass_positions.clear();
    if (points == 20) {
      for (int k : {0, 2, 4, 5, 9, 10, 12, 14}) def.mass_positions.push_back(file[k]);
      for (int k = 15; k < 27; ++k) def.mass_positions.push_back(file[k]);
    } else {
      for (int k = 0; k < points; ++k) {
        const Eigen::Vector3d jitter(std::sin(1.3 * k), -std::abs(std::cos(0.7 * k)), std::sin(2.9 * k));
        Eigen::Vector3d p = file[k % file.size()] + 2.0 * jitter;
        def.mass_positions.push_back(p.cwiseMax(Eigen::Vector3d::Zero()).cwiseMin(Eigen::Vector3d(300, 100, 200)));
      }
    }
    def.masses.assign(def.mass_positions.size(), total / double(def.mass_positions.size()));
  }
  std::vector<DeformationModeN<3>> modes = formats::ReadDeformationFile(kDataDir + "/table3_modes.def3", def.lattice);
  return std::make_shared<const BodyModelN<3>>(def, modes);
}

void TimeSteps3(benchmark::State& state, const BodyModelN<3>& body, const WorldParams& w, double dt,
                BodyState<3, double>* s, Integrator integrator = Integrator::kThesis) {
  for (auto _ : state) {
    const StepStatus st = StepBody(body, w, 0, integrator, dt, s);
    if (!st.ok()) {
      state.SkipWithError(StatusCodeName(st.code).c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["contacts"] = double(s->contacts.size());
}

// Resting on its four feet after a drop, as BM_TableRestingOnGround does for the 2D table.
void BM_Table3RestingOnGround(benchmark::State& state) {
  const std::shared_ptr<const BodyModelN<3>> body = Table3();
  WorldParams w;
  w.ground_plane.enabled = true;
  BodyState<3, double> s = RestState<3, double>(*body);
  s.translation().y() = 10.0;
  for (int i = 0; i < 3000; ++i)
    if (!StepBody(*body, w, 0, Integrator::kThesis, 0.01, &s).ok()) {
      state.SkipWithError("the table did not settle");
      return;
    }
  TimeSteps3(state, *body, w, 0.01, &s);
}
BENCHMARK(BM_Table3RestingOnGround);

// Falling freely, far above a ground (the convex-hull test only) or with none: 27 points (the
// file) against 20 and 1,000 redistributed points, and 1,000 with a 10,000-vertex mesh.
void BM_Table3OutOfContact(benchmark::State& state) {
  const std::shared_ptr<const BodyModelN<3>> body = Table3(int(state.range(0)), int(state.range(2)));
  state.counters["mesh_vertices"] = double(body->def().mesh.points.size());
  WorldParams w;
  w.ground_plane.enabled = state.range(1) != 0;
  w.ground_plane.point = Eigen::Vector3d(0.0, -1e12, 0.0);
  BodyState<3, double> s = RestState<3, double>(*body);
  TimeSteps3(state, *body, w, 0.01, &s);
}
BENCHMARK(BM_Table3OutOfContact)
    ->ArgNames({"points", "ground", "mesh"})
    ->ArgsProduct({{0, 20, 1000}, {1, 0}, {0}})
    ->Args({1000, 1, 10000});  // issue 15: a 10,000-vertex mesh and 1,000 points vs 20 points

// Resting with 1,000 points: the point groups keep the scan near the feet.
void BM_Table3kRestingOnGround(benchmark::State& state) {
  const std::shared_ptr<const BodyModelN<3>> body = Table3(1000);
  WorldParams w;
  w.ground_plane.enabled = true;
  BodyState<3, double> s = RestState<3, double>(*body);
  s.translation().y() = 10.0;
  for (int i = 0; i < 3000; ++i)
    if (!StepBody(*body, w, 0, Integrator::kThesis, 0.01, &s).ok()) {
      state.SkipWithError("the table did not settle");
      return;
    }
  TimeSteps3(state, *body, w, 0.01, &s);
}
BENCHMARK(BM_Table3kRestingOnGround);

// The variational integrator (variational.h) on the 3D table: tumbling and vibrating with no
// ground (ground 0), and resting on its feet after a drop (ground 1).
void BM_Table3Variational(benchmark::State& state) {
  const std::shared_ptr<const BodyModelN<3>> body = Table3();
  WorldParams w;
  BodyState<3, double> s = RestState<3, double>(*body);
  if (state.range(0) != 0) {
    w.ground_plane.enabled = true;
    s.translation().y() = 10.0;
    for (int i = 0; i < 3000; ++i)
      if (!StepBody(*body, w, 0, Integrator::kVariational, 0.01, &s).ok()) {
        state.SkipWithError("the table did not settle");
        return;
      }
  } else {
    w.gravity_on = false;
    s.qd.segment<3>(3) = Eigen::Vector3d(0.8, 1.5, -0.6);
    for (int d = 0; d < body->num_modes(); ++d) s.qd[Group<3>::kRigidDofs + d] = 0.5;
  }
  TimeSteps3(state, *body, w, 0.01, &s, Integrator::kVariational);
}
BENCHMARK(BM_Table3Variational)->ArgName("ground")->Arg(0)->Arg(1);

// Issue 45: the resting table of either dimension stepped through World (what simulate, the
// scene and Python run), thesis integrator, dt 0.01: dim 2 is BM_TableRestingOnGround's table,
// dim 3 the 3D table (27 points, 3 modes). The ratio of the two rows is the 3D step's cost
// against the 2D one in the same run.
void BM_WorldTableResting(benchmark::State& state) {
  const int dim = int(state.range(0));
  WorldOptions options;
  options.params.ground_plane.enabled = true;
  World world(options);
  if (dim == 2) {
    world.AddBody(Table11());
    world.SetState(0, TableQ(*Table11(), 10.0), Eigen::VectorXd::Zero(Table11()->num_q()));
  } else {
    const std::shared_ptr<const BodyModelN<3>> body = Table3();
    world.AddBody(body);
    Eigen::VectorXd coordinates = Eigen::VectorXd::Zero(body->num_q());  // t, rotation vector, γ
    coordinates[1] = 10.0;
    world.SetCoordinates(0, coordinates, Eigen::VectorXd::Zero(coordinates.size()));
  }
  for (int i = 0; i < 3000; ++i)
    if (!world.Step()) {
      state.SkipWithError(world.status().message.c_str());
      return;
    }
  for (auto _ : state) {
    if (!world.Step()) {
      state.SkipWithError(world.status().message.c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["contacts"] = double(dim == 2 ? world.state<2>(0).contacts.size() : world.state<3>(0).contacts.size());
}
BENCHMARK(BM_WorldTableResting)->ArgName("dim")->Arg(2)->Arg(3);

}  // namespace
}  // namespace wobble

BENCHMARK_MAIN();
