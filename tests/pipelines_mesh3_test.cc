// A 3D character with its own mesh, end to end below the pictures (issue 15): the meshes wobble
// makes (pipelines/mesh_io.h) against closed-form volumes, mesh files through VTK's readers and
// writers, bad mesh files as FILE errors, the sources of a 3D FFD body against Eq. 4.1/4.2
// evaluated directly and against finite differences, and the 3D body's record round trip.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkImageData.h>
#include <vtkDataArray.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include "pipelines/energy_charts.h"
#include "pipelines/exports.h"
#include "pipelines/mesh_io.h"
#include "pipelines/world_sources.h"
#include "support/pipelines_test_util.h"
#include "wobble/dynamics/step.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/parse_error.h"
#include "wobble/core/rotation3.h"
#include "wobble/record/trajectory.h"
#include "support/source_paths.h"

namespace wobble::pipelines {
namespace {

using testing::Source;
using Vec3 = Eigen::Vector3d;
const std::string kData = wobble::test_env::DataDir();

std::string TempDir() {
  const std::string dir = (std::filesystem::temp_directory_path() / "wobble_mesh3_test").string();
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(Mesh3Io, PotIsTheRevolvedOutlineToTheInscribedPolygonsVolume) {
  // the 2D pot's outline about its axis: a frustum r 60 -> 75 over 120, then a disc r 100 over
  // 40; revolved in 48 steps each circle is an inscribed 48-gon, whose area is
  // (n / 2π) sin(2π / n) of the circle's, and so is every slice's: the volume scales the same
  const double n = 48, polygon = n / (2 * M_PI) * std::sin(2 * M_PI / n);
  const double smooth = M_PI * (120.0 / 3 * (60 * 60 + 60 * 75 + 75 * 75) + 100.0 * 100 * 40);
  const SurfaceMesh pot = MakePotMesh();
  // vtkRotationalExtrusionFilter stores its points in single precision (vtkPoints' default):
  // every coordinate is a float, so the volume is exact to about 3 float roundings, 3 · 2^-24
  for (const Vec3& p : pot.points)
    for (int a = 0; a < 3; ++a) ASSERT_EQ(double(float(p[a])), p[a]);
  EXPECT_NEAR(EnclosedVolume(pot) / (polygon * smooth), 1.0, 3 * std::ldexp(1.0, -24));
  // closed: inside the axis winding 1, beside the pot 0
  EXPECT_NEAR(std::abs(WindingNumber(pot, Vec3(0, 80, 0))), 1.0, 1e-9);
  EXPECT_NEAR(WindingNumber(pot, Vec3(90, 60, 0)), 0.0, 1e-9);  // outside the wall, below the rim
}

TEST(Mesh3Io, TableIsItsFiveBoxes) {
  const SurfaceMesh table = MakeTableMesh();
  EXPECT_EQ(table.triangles.size(), 5u * 12);
  // overlapping closed boxes: the divergence theorem sums them (the legs go 5 into the top)
  EXPECT_NEAR(EnclosedVolume(table), 300.0 * 200 * 20 + 4 * 20.0 * 20 * 85, 1e-6);
  EXPECT_NEAR(SurfaceArea(table), 2 * (300.0 * 200 + 300 * 20 + 200 * 20) + 4 * 2 * (20.0 * 20 + 2 * 20 * 85), 1e-6);
  EXPECT_NEAR(WindingNumber(table, Vec3(10, 82, 10)), 2.0, 1e-9);  // where a leg meets the top
}

TEST(Mesh3Io, EveryFormatRoundTrips) {
  const SurfaceMesh pot = MakePotMesh();
  for (const char* ext : {".vtp", ".obj", ".stl", ".ply"}) {
    const std::string path = TempDir() + "/pot" + ext;
    WriteSurfaceMesh(path, pot);
    const SurfaceMesh back = ReadSurfaceMesh(path);
    EXPECT_EQ(back.triangles.size(), pot.triangles.size()) << ext;
    EXPECT_EQ(back.points.size(), pot.points.size()) << ext;  // STL repeats corners: merged again
    EXPECT_NEAR(EnclosedVolume(back) / EnclosedVolume(pot), 1.0, 1e-6) << ext;  // STL and OBJ keep floats
  }
}

void ExpectReadError(const std::string& path, const std::string& needle) {
  try {
    ReadSurfaceMesh(path);
    FAIL() << "no error for " << path;
  } catch (const formats::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Mesh3Io, BadMeshFilesAreNamed) {
  const std::string dir = TempDir();
  ExpectReadError(dir + "/missing.stl", "no such file");
  ExpectReadError(dir, "is a directory");
  std::ofstream(dir + "/model.xyz") << "1 2 3\n";
  ExpectReadError(dir + "/model.xyz", "unknown mesh format '.xyz'");
  std::ofstream(dir + "/broken.vtp") << "<VTKFile type=\"PolyData\"><garbage";
  ExpectReadError(dir + "/broken.vtp", "VTK cannot read it");
  std::ofstream(dir + "/lines.obj") << "v 0 0 0\nv 1 0 0\nl 1 2\n";
  ExpectReadError(dir + "/lines.obj", "holds no triangles");
}

TEST(Mesh3Io, ShippedObjectsLoadWithTheirMass) {
  const BodyDefN<3> pot = ReadObject<3>(kData + "/pot3.obj");
  double total = 0;
  for (double m : pot.masses) total += m;
  EXPECT_NEAR(total, 750, 1e-9);
  EXPECT_EQ(pot.mesh.triangles.size(), MakePotMesh().triangles.size());
  EXPECT_NEAR(double(pot.masses.size() - 240) / 400, 1.0, 0.05);  // "about 400" in the volume, 240 on the surface
  // a mesh line that cannot be read names the object file's line
  const std::string obj = TempDir() + "/bad_mesh.obj";
  std::ofstream(obj) << "dimension 3\n# a missing mesh\nmesh nowhere.stl\nsample volume 10 1\n";
  try {
    ReadObject<3>(obj);
    FAIL();
  } catch (const formats::ParseError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos) << e.what();
  }
}

// A 3D body made of the shipped pot and its modes, turned, moving and deformed.
World MovingPot() {
  BodyDefN<3> def = ReadObject<3>(kData + "/pot3.obj");
  std::vector<DeformationModeN<3>> modes = formats::ReadDeformationFile(kData + "/pot3_modes.def3", def.lattice);
  WorldOptions options;
  options.params.ground_plane.enabled = false;
  World w(options);
  w.AddBody(std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes)));
  Eigen::VectorXd v(9);
  v << 3, -2, 1, 0.4, -0.7, 0.25, 0.5, -0.3, 0.8;
  w.SetState(0, PositionsOf(Vec3(10, 40, -5), Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Vec3(1, 2, -1).normalized())), Eigen::Vector3d(0.3, -0.2, 0.15)), v);
  return w;
}

// Eq. 4.1/4.2 at a body-frame point: the deformed control points L + Σ γ_d d^d weighted at
// the point's lattice coordinates, then into the world.
Vec3 DirectWorldPoint(const World& w, const Vec3& body_point) {
  const BodyModelN<3>& m = w.body<3>(0);
  const BodyState<3, double>& s = w.state<3>(0);
  std::vector<Vec3> control = m.lattice().RestPoints();
  for (size_t c = 0; c < control.size(); ++c)
    for (int d = 0; d < m.num_modes(); ++d) control[c] += s.gamma()[d] * m.modes()[size_t(d)].displacement[c];
  return s.translation() + s.orientation() * m.lattice().Evaluate(control, m.lattice().LocalCoords(body_point));
}

TEST(Mesh3Sources, SpringsOfA3dBodyRunFromTheAnchorToTheHeldPoint) {
  BodyDefN<3> def = ReadObject<3>(kData + "/pot3.obj");
  std::vector<DeformationModeN<3>> modes = formats::ReadDeformationFile(kData + "/pot3_modes.def3", def.lattice);
  auto body = std::make_shared<const BodyModelN<3>>(std::move(def), std::move(modes));
  WorldOptions options;
  const Vec3 coords(0.5, 1.0, 0.25), anchor(0, 300, 20);
  options.params.springs.push_back(MakeSpring(*body, coords, anchor, 100.0, 1.0, 20.0));
  World w(options);
  w.AddBody(body);
  w.SetState(0, PositionsOf(Vec3(10, 40, -5), Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Vec3(1, 2, -1).normalized())), Eigen::Vector3d(0.3, -0.2, 0.15)), Eigen::VectorXd::Zero(9));
  const auto springs = Source<SpringSource>(w);
  vtkPolyData* out = springs->GetOutput();
  ASSERT_EQ(out->GetNumberOfLines(), 1);
  double a[3], x[3];
  out->GetPoint(0, a);
  out->GetPoint(1, x);
  EXPECT_LT((Vec3(a[0], a[1], a[2]) - anchor).norm(), 1e-12);
  const Vec3 held = DirectWorldPoint(w, body->lattice().Evaluate(body->lattice().RestPoints(), coords));
  EXPECT_LT((Vec3(x[0], x[1], x[2]) - held).norm(), 1e-9 * 200);
  EXPECT_NEAR(out->GetCellData()->GetArray("stretch")->GetTuple1(0), (held - anchor).norm() - 20.0, 1e-9);
}

// The 3D displacement volume (render --what disp): every voxel's vector against the body's own
// basis path, x = t + R (b0 + B γ) at the voxel's lattice coordinates, minus the rest point;
// the voxel's place from the image's origin, spacing and direction is that rest point.
TEST(Mesh3Sources, DisplacementVolumeHoldsEachVoxelsMotion) {
  const World w = MovingPot();
  const BodyModelN<3>& body = w.body<3>(0);
  const BodyState<3, double>& s = w.state<3>(0);
  const int nx = 8, ny = 6, nz = 5;
  const vtkSmartPointer<vtkImageData> image = pipelines::DisplacementVolume(w, 0, nx, ny, nz);
  int dims[3];
  image->GetDimensions(dims);
  ASSERT_EQ(dims[0] * dims[1] * dims[2], nx * ny * nz);
  vtkDataArray* disp = image->GetPointData()->GetArray("disp");
  ASSERT_NE(disp, nullptr);
  for (int i : {0, 3, 7})
    for (int j : {0, 5})
      for (int k : {0, 2, 4}) {
        const Vec3 u((i + 0.5) / nx, (j + 0.5) / ny, (k + 0.5) / nz);
        Vec3 b0;
        BodyModelN<3>::ModeMatrix B;
        body.LocalBasis(u, &b0, &B);
        const Vec3 rest = body.lattice().Evaluate(body.lattice().RestPoints(), u);
        const Vec3 moved = s.translation() + s.orientation() * (b0 + B * s.gamma());
        const vtkIdType id = image->ComputePointId(std::array<int, 3>{i, j, k}.data());
        double d[3], x[3];
        disp->GetTuple(id, d);
        EXPECT_LT((Vec3(d[0], d[1], d[2]) - (moved - rest)).norm(), 1e-9 * 200) << i << " " << j << " " << k;
        image->TransformIndexToPhysicalPoint(i, j, k, x);
        EXPECT_LT((Vec3(x[0], x[1], x[2]) - rest).norm(), 1e-9 * 200) << i << " " << j << " " << k;
      }
}

TEST(Mesh3Sources, TheMeshIsMovedByTheFfdOfItsLattice) {
  const World w = MovingPot();
  const auto shape = Source<ShapeSource>(w);
  vtkPolyData* out = shape->GetOutput();
  const SurfaceMesh& mesh = w.body<3>(0).def().mesh;
  ASSERT_EQ(out->GetNumberOfPolys(), vtkIdType(mesh.triangles.size()));
  ASSERT_GE(out->GetNumberOfPoints(), vtkIdType(mesh.points.size()));
  double worst = 0;
  for (size_t v = 0; v < mesh.points.size(); ++v) {
    Vec3 x;
    out->GetPoint(vtkIdType(v), x.data());
    worst = std::max(worst, (x - DirectWorldPoint(w, mesh.points[v])).norm());
  }
  EXPECT_LT(worst, 1e-9 * 200) << "worst vertex deviation";
  EXPECT_NE(out->GetPointData()->GetArray("displacement"), nullptr);
}

TEST(Mesh3Sources, LatticeAndMassPointsOfA3dBody) {
  const World w = MovingPot();
  const auto lattice = Source<LatticeSource>(w);
  EXPECT_EQ(lattice->GetOutput()->GetNumberOfPoints(), 64);
  EXPECT_EQ(lattice->GetOutput()->GetNumberOfLines(), 3 * 16);  // 4 x 4 rows along each axis
  const auto points = Source<MassPointSource>(w);
  vtkPolyData* pd = points->GetOutput();
  const BodyModelN<3>& m = w.body<3>(0);
  ASSERT_EQ(pd->GetNumberOfPoints(), m.num_points());
  // velocities against a central difference of the positions: t + h ṫ, R exp(h ω̂) (ω in the
  // body frame), γ + h γ̇
  const BodyState<3, double>& s = w.state<3>(0);
  const double h = 1e-6;
  auto moved = [&](double sign) {
    World copy = w;
    const Vec3 omega = s.qd.segment<3>(3);
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(sign * h * omega.norm(), omega.normalized()));
    copy.SetState(0, PositionsOf(s.translation() + sign * h * s.qd.head<3>(), s.orientation() * turn, s.gamma() + sign * h * s.qd.tail(3)), s.qd);
    return copy;
  };
  const World ahead = moved(1), behind = moved(-1);
  vtkDataArray* velocity = pd->GetPointData()->GetArray("velocity");
  double worst = 0, scale = 0;
  for (int k = 0; k < m.num_points(); k += 7) {
    auto at = [&](const World& world) { return WorldPosition(world, 0, m.rest_local(k), m.mode_matrix(k)); };
    const Vec3 fd = (at(ahead) - at(behind)) / (2 * h);
    Vec3 v;
    velocity->GetTuple(k, v.data());
    worst = std::max(worst, (v - fd).norm());
    scale = std::max(scale, fd.norm());
  }
  EXPECT_LT(worst, 1e-6 * scale);
}

TEST(Mesh3Sources, AppliedForcesSumToTheGeneralizedForcesTranslationRows) {
  // the pot pressed into the ground plane and sliding: Σ_k f_k over the mass points (gravity
  // plus each contact's penalty and capped friction) is the translation rows of Q, since
  // J_t = 1 for every point (EvaluateForces3, the step's own forces, frozen at the contacts)
  BodyDefN<3> def = ReadObject<3>(kData + "/pot3.obj");
  WorldOptions options;
  options.params.ground_plane.enabled = true;
  World w(options);
  w.AddBody(std::make_shared<const BodyModelN<3>>(std::move(def), std::vector<DeformationModeN<3>>()));
  w.SetState(0, PositionsOf(Vec3(0, -2, 0), Eigen::Quaterniond(Eigen::AngleAxisd(0.05, Vec3::UnitX())), Eigen::VectorXd()), (Eigen::VectorXd(6) << 30, -5, 10, 0, 0.4, 0).finished());
  ASSERT_TRUE(w.Step());
  ASSERT_GT(w.state<3>(0).contacts.size(), 10u);
  const auto points = Source<MassPointSource>(w);
  vtkDataArray* applied = points->GetOutput()->GetPointData()->GetArray("applied_force");
  Vec3 sum = Vec3::Zero();
  for (vtkIdType k = 0; k < applied->GetNumberOfTuples(); ++k) {
    Vec3 f;
    applied->GetTuple(k, f.data());
    sum += f;
  }
  const BodyState<3, double>& s = w.state<3>(0);
  const WorldParams& params = options.params;
  ForceBreakdown<3, double> Q;
  EvaluateForces(w.body<3>(0), params, 0, s, Frame<3, double>(s.q), &Q, ContactSet::kFrozen);
  const Vec3 expected = (Q.gravity + Q.ground).head<3>();
  EXPECT_LT((sum - expected).norm(), 1e-9 * expected.norm()) << sum.transpose() << " vs " << expected.transpose();
}

// cond(M) over a 3D run (Fig. 4.9 for the 3D pot): against M summed over the mass points,
// M = Σ m_k J_kᵀ J_k with J_k = ∂x_k/∂(ṫ, ω, γ̇) = [I, −R [l_k]×, R B_k] at each recorded state.
TEST(Mesh3Record, ConditionNumberOverA3dRunIsThePerPointMassMatrixs) {
  World w = MovingPot();
  record::Trajectory run(w);
  for (int k = 0; k < 40; ++k) {
    ASSERT_EQ(run.Append(w), -1);
    ASSERT_TRUE(w.Step());
  }
  const std::vector<double> cond = pipelines::ConditionNumbers(run, 0);
  ASSERT_EQ(int(cond.size()), run.size());
  const BodyModelN<3>& body = w.body<3>(0);
  const int n = body.num_q();
  double lo = HUGE_VAL, hi = 0;
  for (int k = 0; k < run.size(); k += 13) {
    const Eigen::VectorXd q = run.q(k, 0);
    const Eigen::Matrix3d R = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
    const Eigen::VectorXd gamma = q.tail(body.num_modes());
    Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < body.num_points(); ++i) {
      const Vec3 l = body.rest_local(i) + body.mode_matrix(i) * gamma;
      Eigen::MatrixXd J(3, n);
      J.leftCols<3>().setIdentity();
      J.middleCols<3>(3) = -R * Skew<double>(l);
      J.rightCols(body.num_modes()) = R * body.mode_matrix(i);
      M += body.mass(i) * J.transpose() * J;
    }
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(M).singularValues();
    EXPECT_NEAR(cond[size_t(k)] / (sv[0] / sv[n - 1]), 1.0, 1e-9) << "sample " << k;
    lo = std::min(lo, cond[size_t(k)]);
    hi = std::max(hi, cond[size_t(k)]);
  }
  EXPECT_GT(hi / lo, 1.0 + 1e-6);  // the modes move: cond(M) changes over the run
  const pipelines::ChartSpec chart = pipelines::ConditionChart(run, 0, "cond(M)");
  EXPECT_EQ(chart.series.at(0).y, cond);
}

TEST(Mesh3Record, A3dBodyRecordsAndRestoresExactly) {
  World w = MovingPot();
  w.SetModeTargets(0, Eigen::Vector3d(0.1, 0.0, -0.2));
  record::Trajectory run(w);
  for (const char* name : {"tx", "tz", "qw", "qz", "squash", "sway", "twist", "dtx", "wx", "wz", "dtwist",
                           "target_twist", "kinetic", "penetration"})
    EXPECT_GE(run.Column(name), 0) << name;
  EXPECT_EQ(run.Column("dqw"), -1);  // velocities are ṫ, ω, γ̇: 6 + D, not 7 + D
  ASSERT_EQ(run.Append(w), -1);
  World fresh = MovingPot();
  fresh.SetState(0, PositionsOf(Vec3::Zero(), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()), Eigen::VectorXd::Zero(9));
  run.Restore(0, fresh);
  const BodyState<3, double>& a = w.state<3>(0);
  const BodyState<3, double>& b = fresh.state<3>(0);
  EXPECT_EQ(a.translation(), b.translation());
  EXPECT_LT((a.orientation().coeffs() - b.orientation().coeffs()).norm(), 1e-15);
  EXPECT_EQ(a.gamma(), b.gamma());
  EXPECT_EQ(a.qd, b.qd);
  EXPECT_EQ(a.mode_target, b.mode_target);
  // the recorded energies are the world's, and the per-mode terms K (γ − γ0)² sum to the modes'
  const Energies e = run.energies(0, 0), direct = w.ComputeEnergies(0);
  EXPECT_EQ(e.kinetic, direct.kinetic);
  double modes = 0;
  for (double pm : e.per_mode) modes += pm;
  EXPECT_NEAR(modes, direct.modes, 1e-12 * std::max(1.0, direct.modes));
}

}  // namespace
}  // namespace wobble::pipelines
