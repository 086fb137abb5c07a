// A user's mesh as a 3D FFD character (issue 15): the mesh measures, the lattice fitted around
// it, mass points sampled from its surface and volume, the object file's mesh statements, and
// every vertex carried by the FFD. Checked against closed forms: a cube's area and volume, the
// discrete second moment of a midpoint grid, a ball's inertia 2/5 m r², and the FFD of a
// vertex evaluated directly from the deformed control points (Eq. 4.1/4.2).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "support/test_bodies.h"
#include "wobble/body/body_model.h"
#include "wobble/body/surface_mesh.h"
#include "wobble/core/errors.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"

namespace wobble {
namespace {

using Vec3 = Eigen::Vector3d;

SurfaceMesh Box(const Vec3& lo, const Vec3& hi, bool inward = false) { return testing::BoxMesh(lo, hi, inward); }
SurfaceMesh Join(SurfaceMesh a, const SurfaceMesh& b) { return testing::JoinMeshes(std::move(a), b); }

// A UV sphere of radius r about c: `rings` latitude bands, `segments` longitudes.
SurfaceMesh Sphere(const Vec3& c, double r, int rings, int segments) {
  SurfaceMesh m;
  m.points.push_back(c + Vec3(0, r, 0));
  for (int i = 1; i < rings; ++i) {
    const double phi = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double th = 2 * M_PI * j / segments;
      m.points.push_back(c + r * Vec3(std::sin(phi) * std::cos(th), std::cos(phi), std::sin(phi) * std::sin(th)));
    }
  }
  m.points.push_back(c - Vec3(0, r, 0));
  const int south = int(m.points.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) m.triangles.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j)});
      m.triangles.push_back({ring(i, j + 1), ring(i + 1, j + 1), ring(i + 1, j)});
    }
  for (int j = 0; j < segments; ++j) m.triangles.push_back({south, ring(rings - 1, j), ring(rings - 1, j + 1)});
  return m;
}

TEST(Mesh3, CubeAreaVolumeAndWindingNumber) {
  const SurfaceMesh cube = Box(Vec3(1, 2, 3), Vec3(3, 5, 7));  // 2 x 3 x 4
  EXPECT_NEAR(SurfaceArea(cube), 2 * (6 + 8 + 12), 1e-12);
  EXPECT_NEAR(EnclosedVolume(cube), 24, 1e-12);
  EXPECT_NEAR(WindingNumber(cube, Vec3(2, 3, 4)), 1.0, 1e-12);
  EXPECT_NEAR(WindingNumber(cube, Vec3(2.9, 4.9, 6.9)), 1.0, 1e-12);
  EXPECT_NEAR(WindingNumber(cube, Vec3(0, 0, 0)), 0.0, 1e-12);
  EXPECT_NEAR(WindingNumber(cube, Vec3(3.1, 4, 5)), 0.0, 1e-12);
  EXPECT_NEAR(WindingNumber(Box(Vec3(1, 2, 3), Vec3(3, 5, 7), true), Vec3(2, 3, 4)), -1.0, 1e-12);
  // two overlapping boxes: 2 where they overlap
  const SurfaceMesh two = Join(cube, Box(Vec3(2, 2, 3), Vec3(4, 5, 7)));
  EXPECT_NEAR(WindingNumber(two, Vec3(2.5, 3, 4)), 2.0, 1e-12);
}

TEST(Mesh3, BadMeshesAreRefusedByName) {
  SurfaceMesh m = Box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  m.triangles[3][1] = 8;
  EXPECT_THROW(CheckSurfaceMesh(m), InputError);
  m = Box(Vec3(0, 0, 0), Vec3(1, 1, 1));
  m.points[2].y() = NAN;
  EXPECT_THROW(CheckSurfaceMesh(m), InputError);
  EXPECT_THROW(CheckSurfaceMesh(SurfaceMesh{}), InputError);
  EXPECT_THROW(SampleVolume(Sphere(Vec3::Zero(), 1, 4, 8), 0), InputError);
  SurfaceMesh sheet;
  sheet.points = {{0, 0, 0}, {1, 0, 0}, {0, 0, 1}};
  sheet.triangles = {{0, 1, 2}};
  EXPECT_THROW(SampleVolume(sheet, 10), InputError);  // no volume: sample the surface
  EXPECT_EQ(SampleSurface(sheet, 10).size(), 10u);
}

TEST(Mesh3, FittedLatticeHoldsTheMeshWithTheMargin) {
  const SurfaceMesh m = Box(Vec3(-10, 0, 5), Vec3(30, 20, 15));  // largest side 40
  const LatticeN<3> lat = FitLattice(m, {4, 5, 6}, BasisKind::kCubicBSpline, 0.05);
  EXPECT_EQ(lat.sizes(), (LatticeN<3>::Sizes{4, 5, 6}));
  EXPECT_EQ(lat.basis(), BasisKind::kCubicBSpline);
  EXPECT_TRUE(lat.origin().isApprox(Vec3(-12, -2, 3), 1e-12));
  EXPECT_NEAR(lat.axis(0).x(), 44, 1e-12);
  EXPECT_NEAR(lat.axis(1).y(), 24, 1e-12);
  EXPECT_NEAR(lat.axis(2).z(), 14, 1e-12);
  for (const Vec3& p : m.points) {
    const Vec3 u = lat.LocalCoords(p);
    EXPECT_TRUE((u.array() > 0).all() && (u.array() < 1).all()) << u.transpose();
  }
}

TEST(Mesh3, SurfaceSamplesLieOnTheFacesSpreadByArea) {
  const Vec3 lo(0, 0, 0), hi(1, 2, 3);
  const SurfaceMesh m = Box(lo, hi);
  const int n = 2200;  // area 22: 100 per unit area
  const std::vector<Vec3> pts = SampleSurface(m, n);
  ASSERT_EQ(int(pts.size()), n);
  std::array<int, 6> on_face{};  // x=0, x=1, y=0, y=2, z=0, z=3
  for (const Vec3& p : pts) {
    int faces = 0;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(p[a] - lo[a]) < 1e-12) ++on_face[size_t(2 * a)], ++faces;
      if (std::abs(p[a] - hi[a]) < 1e-12) ++on_face[size_t(2 * a + 1)], ++faces;
      EXPECT_GE(p[a], lo[a] - 1e-12);
      EXPECT_LE(p[a], hi[a] + 1e-12);
    }
    EXPECT_GE(faces, 1) << p.transpose();
  }
  // each face gets n·area/total points, to within the triangles' rounding (two per face)
  const double per_area = n / 22.0;
  const double area[6] = {6, 6, 3, 3, 2, 2};
  for (int f = 0; f < 6; ++f) EXPECT_NEAR(on_face[size_t(f)], per_area * area[f], 2.0) << "face " << f;
}

TEST(Mesh3, VolumeGridMatchesTheMidpointSumsClosedForm) {
  // side 2 and n = 1000: spacing (8/1000)^(1/3) = 0.2, exactly 10 cells per axis, all inside
  const SurfaceMesh cube = Box(Vec3(-1, -1, -1), Vec3(1, 1, 1));
  const std::vector<Vec3> pts = SampleVolume(cube, 1000);
  ASSERT_EQ(pts.size(), 1000u);
  Vec3 mean = Vec3::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (const Vec3& p : pts) {
    mean += p / 1000.0;
    second += p * p.transpose() / 1000.0;
  }
  EXPECT_LT(mean.norm(), 1e-12);
  // the variance of N midpoints over [0, a] is a² (N² − 1) / (12 N²)
  const double variance = 4.0 * (100 - 1) / (12.0 * 100);
  EXPECT_TRUE(second.isApprox(variance * Eigen::Matrix3d::Identity(), 1e-12)) << second;
}

TEST(Mesh3, SampledBallHasTheSolidBallsInertia) {
  const double r = 50, m = 10;
  const SurfaceMesh ball = Sphere(Vec3(100, 60, -20), r, 48, 96);
  const double exact_volume = 4.0 / 3.0 * M_PI * r * r * r;
  EXPECT_NEAR(EnclosedVolume(ball) / exact_volume, 1.0, 0.005);  // the polyhedron is a bit smaller
  const std::vector<Vec3> pts = SampleVolume(ball, 4000);
  EXPECT_NEAR(double(pts.size()) / 4000, 1.0, 0.03);
  Vec3 mean = Vec3::Zero();
  for (const Vec3& p : pts) mean += p / double(pts.size());
  EXPECT_LT((mean - Vec3(100, 60, -20)).norm(), 0.01 * r);
  // inertia about the centre vs 2/5 m r² (the grid's error is of order h/r ≈ 5%: 3% bound)
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (const Vec3& p : pts) {
    const Vec3 d = p - mean;
    inertia += m / double(pts.size()) * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  const double solid = 0.4 * m * r * r;
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(inertia(a, a) / solid, 1.0, 0.03) << "axis " << a;
}

// The stand-in reader of the object-file tests: "box" is [0,100] x [0,50] x [0,80].
SurfaceMesh BoxReader(const std::string& path) {
  if (path.size() >= 3 && path.substr(path.size() - 3) == "box") return Box(Vec3(0, 0, 0), Vec3(100, 50, 80));
  throw std::runtime_error("cannot read " + path);
}

BodyDefN<3> Parse(const std::string& text) {
  std::istringstream in(text);
  return formats::ParseObject<3>(in, "dir/m.obj", BoxReader);
}

void ExpectParseError(const std::string& text, int line, const std::string& needle, const formats::MeshReader& reader = BoxReader) {
  std::istringstream in(text);
  try {
    formats::ParseObject<3>(in, "m.obj", reader);
    FAIL() << "no error for:\n" << text;
  } catch (const formats::ParseError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(Mesh3, ObjectFileFitsTheLatticeAndSamplesTheMass) {
  const BodyDefN<3> def = Parse("dimension 3\nmesh box\nsample volume 400 1000\nsample surface 50 20\n");
  EXPECT_EQ(def.mesh.triangles.size(), 12u);
  EXPECT_EQ(def.lattice.sizes(), (LatticeN<3>::Sizes{4, 4, 4}));  // the default fit
  EXPECT_TRUE(def.lattice.origin().isApprox(Vec3(-5, -5, -5)));  // 5% of the largest side, 100
  double total = 0;
  for (double mass : def.masses) total += mass;
  EXPECT_NEAR(total, 1020, 1e-9);
  EXPECT_EQ(def.masses.back(), 20.0 / 50);
  EXPECT_NEAR(BodyModelN<3>(def, {}).moments().m, 1020, 1e-9);
  // the volume grid is symmetric in the box: its centre of mass is the box's
  const BodyModelN<3> solid(Parse("dimension 3\nmesh box\nsample volume 400 1000\n"), {});
  EXPECT_TRUE((solid.moments().c0 / solid.moments().m).isApprox(Vec3(50, 25, 40), 1e-12));
}

TEST(Mesh3, ObjectFileMeshErrorsNameTheLine) {
  ExpectParseError("dimension 3\nmesh box\nmesh box\nsample volume 10 1\n", 3, "mesh given twice");
  ExpectParseError("dimension 3\nsample volume 10 1\nlattice 0 0 0 1 1 1\n", 2, "no mesh to fit or sample");
  ExpectParseError("dimension 3\nmesh nothing\nsample volume 10 1\n", 2, "cannot read");
  ExpectParseError("dimension 3\nmesh box\nsample volume 10 1\n", 2, "cannot read mesh files", nullptr);
  ExpectParseError("dimension 3\nmesh box\nlattice 0 0 0 100 50 70\nsample volume 10 1\n", 2, "lies outside the lattice on line 3");
  ExpectParseError("dimension 3\nmesh box\nsample volume 0 1\n", 3, "point count");
  ExpectParseError("dimension 3\nmesh box\nsample volume 10 -1\n", 3, "total mass");
  ExpectParseError("dimension 3\nmesh box\nsample inside 10 1\n", 3, "'sample surface' or 'sample volume'");
  ExpectParseError("dimension 3\nmesh box\nlattice fit 4 1 4\nsample volume 10 1\n", 3, "num_t");
  ExpectParseError("dimension 3\nmesh box\nlattice fit margin -1\nsample volume 10 1\n", 3, "margin");
  ExpectParseError("dimension 3\nmesh box\nlattice 0 0 0 100 50 80\nlattice fit\nmass 1 1 1 1\n", 4, "lattice given twice");
  std::istringstream flat("lattice 0 0 1 1\nmesh box\nmass 0 0 1\n");
  EXPECT_THROW(formats::ParseObject(flat, "flat.obj"), formats::ParseError);
}

TEST(Mesh3, EveryVertexFollowsTheFfdOfItsLattice) {
  // the vertex bases of BodyModelN<3> against Eq. 4.1/4.2 evaluated directly: the deformed control
  // points L + Σ γ_d d^d, weighted at the vertex's lattice coordinates
  BodyDefN<3> def = Parse("dimension 3\nmesh box\nlattice fit 4 5 6 bspline margin 0.1\nsample surface 30 10\n");
  def.mesh = Join(def.mesh, Box(Vec3(10, 10, 10), Vec3(20, 45, 30)));  // more vertices, inside
  std::istringstream modes_text("dimension 3\nmode bend\n  bend x y 20\nmode twist\n  twist y 25\nmode squash\n  squash y 0.3\n");
  const std::vector<DeformationModeN<3>> modes = formats::ParseDeformations(modes_text, "m.def3", def.lattice);
  const BodyModelN<3> body(def, modes);
  const Eigen::Vector3d gamma(0.7, -0.4, 1.3);
  std::vector<Vec3> control = def.lattice.RestPoints();
  for (size_t c = 0; c < control.size(); ++c)
    for (int d = 0; d < 3; ++d) control[c] += gamma[d] * modes[size_t(d)].displacement[c];
  for (int v = 0; v < int(def.mesh.points.size()); ++v) {
    const Vec3& p = def.mesh.points[size_t(v)];
    EXPECT_LT((body.mesh_rest_local(v) - p).norm(), 1e-12 * 100) << "vertex " << v;  // linear precision; body ~100
    const Vec3 direct = def.lattice.Evaluate(control, def.lattice.LocalCoords(p));
    const Vec3 fast = body.mesh_rest_local(v) + body.mesh_mode_matrix(v) * gamma;
    EXPECT_LT((fast - direct).norm(), 1e-10 * direct.norm()) << "vertex " << v;
  }
}

}  // namespace
}  // namespace wobble
