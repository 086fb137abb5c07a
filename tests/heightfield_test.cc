// The 3D heightfield ground (lib/wobble/dynamics/heightfield.h, issue 19) against closed forms:
// a plane given as a grid is that plane (heights, faces, and whole runs of a body on it); a
// point in a crease feels both faces; a box at rest in a frictionless V valley is held by
// m g / (2 cos α) on each face; sliding down a slope of many triangles at g (sin α − μ cos α);
// a region of cells with its own friction cap deciding whether a box slides; sliding off the
// edge of a drop into free fall without touching the drop's face.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <utility>

#include "support/test_bodies.h"
#include "wobble/core/errors.h"
#include "wobble/dynamics/heightfield.h"
#include "wobble/dynamics/step.h"
#include "wobble/formats/heightfield_file.h"
#include "wobble/formats/parse_error.h"

namespace wobble {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
using testing::Box;

// Nodes of y = f(x, z) on nx × nz nodes from (x0, z0) with spacing (dx, dz).
template <class F>
std::shared_ptr<const Heightfield> Sampled(F&& f, Vector2d origin, Vector2d spacing, int nx, int nz) {
  std::vector<double> h;
  for (int j = 0; j < nz; ++j)
    for (int i = 0; i < nx; ++i) h.push_back(f(origin.x() + i * spacing.x(), origin.y() + j * spacing.y()));
  return Heightfield::Make(origin, spacing, nx, nz, std::move(h));
}

Vector3d LinearMomentum(const BodyModelN<3>& body, const BodyState<3, double>& s) {
  const ShapeMoments<double> sm(body.moments(), s.gamma());
  Vector3d P, L;
  Momentum(body.moments(), sm, Frame<3, double>(s.q), s.qd, &P, &L);
  return P;
}

TEST(Heightfield, APlaneGivenAsAGridIsThatPlane) {
  auto plane = [](double x, double z) { return 0.3 * x - 0.2 * z + 1.0; };
  const auto field = Sampled(plane, {-2.0, -1.0}, {0.5, 0.25}, 9, 9);
  const Vector3d n = Vector3d(-0.3, 1.0, 0.2).normalized();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> x(-2.0, 2.0), z(-1.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    const double xk = x(rng), zk = z(rng);
    EXPECT_NEAR(field->HeightAt(xk, zk), plane(xk, zk), 1e-12);
    std::vector<int> faces;
    field->FacesFelt(Vector3d(xk, plane(xk, zk) - 0.01, zk), &faces);
    ASSERT_EQ(faces.size(), 1u) << "a flat field has no valleys";
    Vector3d p, normal;
    field->FacePlane(faces[0], Vector3d(xk, 0, zk), &p, &normal);
    EXPECT_LT((normal - n).norm(), 1e-12);
    faces.clear();
    field->FacesFelt(Vector3d(xk, plane(xk, zk) + 0.01, zk), &faces);
    EXPECT_TRUE(faces.empty()) << "above the surface";
  }
  // beyond the grid: level at the nearest edge node's height
  EXPECT_NEAR(field->HeightAt(5.0, 0.5), plane(2.0, 0.5), 1e-12);
  EXPECT_NEAR(field->HeightAt(-7.0, -3.0), plane(-2.0, -1.0), 1e-12);
  std::vector<int> faces;
  field->FacesFelt(Vector3d(5.0, plane(2.0, 0.5) - 0.1, 0.5), &faces);
  EXPECT_EQ(faces, std::vector<int>{field->outside_face()});
  EXPECT_DOUBLE_EQ(field->max_height(), plane(2.0, -1.0));
}

// A body dropped onto a tilted plane and onto the same plane as a heightfield of many
// triangles moves the same: contacts carried across the triangles' edges keep their anchors.
TEST(Heightfield, ABodyOnAGridOfAPlaneMovesAsOnThePlane) {
  const BodyModelN<3> chair = testing::Chair3();
  const double a = 0.1, b = -0.05;  // y = a x + b z
  WorldParams on_plane;
  on_plane.ground_plane.enabled = true;
  on_plane.ground_plane.normal = Vector3d(-a, 1.0, -b).normalized();
  on_plane.ground_plane.stiffness = 2e4;  // per point of 1/3 kg
  on_plane.ground_plane.normal_damping = 100;
  on_plane.ground_plane.friction_damping = 100;
  on_plane.ground_plane.friction_cap = 0.3;
  WorldParams on_grid = on_plane;
  on_grid.ground_plane.heightfield = Sampled([&](double x, double z) { return a * x + b * z; }, {-300, -300}, {15, 15}, 41, 41);
  BodyState<3, double> s1 = RestState<3, double>(chair), s2;
  s1.translation() = Vector3d(-40, 2, 10);
  s1.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3d(1, 0, 1).normalized())));
  s1.qd.head<3>() = Vector3d(60, -5, 25);  // it slides across many triangles
  s1.qd.segment<3>(3) = Vector3d(0.2, 0.5, -0.3);
  s2 = s1;
  int contacts_seen = 0, faces_seen = 0;
  std::vector<char> face_used(size_t(on_grid.ground_plane.heightfield->num_faces()), 0);
  for (int step = 0; step < 3000; ++step) {
    ASSERT_TRUE(StepBody(chair, on_plane, 0, Integrator::kSymplecticEuler, 5e-4, &s1).ok());
    ASSERT_TRUE(StepBody(chair, on_grid, 0, Integrator::kSymplecticEuler, 5e-4, &s2).ok());
    ASSERT_EQ(s1.contacts.size(), s2.contacts.size()) << "step " << step;
    for (size_t c = 0; c < s1.contacts.size(); ++c) {
      ASSERT_EQ(s1.contacts[c].point, s2.contacts[c].point);
      ASSERT_LT((s1.contacts[c].anchor - s2.contacts[c].anchor).norm(), 1e-7) << "step " << step;
      if (!face_used[size_t(s2.contacts[c].face)]) ++faces_seen, face_used[size_t(s2.contacts[c].face)] = 1;
    }
    contacts_seen += int(s1.contacts.size());
  }
  EXPECT_LT((s1.translation() - s2.translation()).norm(), 1e-7);
  EXPECT_LT((s1.qd - s2.qd).norm(), 1e-7 * s1.qd.norm() + 1e-9);
  EXPECT_LT((s1.gamma() - s2.gamma()).norm(), 1e-9);
  EXPECT_GT(contacts_seen, 1000) << "it bounces and slides along the ground";
  EXPECT_GE(faces_seen, 10) << "contacts on many triangles";
}

// y = |x| tan α: a point in the crease feels both faces; one on a face only that face.
TEST(Heightfield, APointInACreaseFeelsBothFaces) {
  const double tan_a = std::tan(0.5);
  const auto valley = Sampled([&](double x, double) { return std::abs(x) * tan_a; }, {-4, -2}, {1, 1}, 9, 5);
  std::vector<int> faces;
  valley->FacesFelt(Vector3d(0.01, -0.05, 0.3), &faces);
  ASSERT_EQ(faces.size(), 2u);
  Vector3d p, n0, n1;
  valley->FacePlane(faces[0], Vector3d::Zero(), &p, &n0);
  valley->FacePlane(faces[1], Vector3d::Zero(), &p, &n1);
  EXPECT_NEAR(n0.x() * n1.x(), -std::sin(0.5) * std::sin(0.5), 1e-12) << "the two walls of the valley";
  faces.clear();
  valley->FacesFelt(Vector3d(1.5, 1.5 * tan_a - 0.05, 0.3), &faces);
  EXPECT_EQ(faces.size(), 1u);
  // a ridge, y = −|x| tan α: a point just under its top feels one face, never across the ridge
  const auto ridge = Sampled([&](double x, double) { return -std::abs(x) * tan_a; }, {-4, -2}, {1, 1}, 9, 5);
  faces.clear();
  ridge->FacesFelt(Vector3d(0.01, -0.05, 0.3), &faces);
  EXPECT_EQ(faces.size(), 1u);
}

// A box with its bottom corners on the two walls of a frictionless V valley (y = |x| tan α)
// settles there; each wall then holds N = m g / (2 cos α) along its normal.
TEST(Heightfield, ABoxInAFrictionlessValleyIsHeldByBothWalls) {
  const double alpha = 0.4, width = 1.0, mass = 1.0, g = 9.81;
  const BodyModelN<3> box = Box(width, 0.4, 0.6, mass);
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.stiffness = 2e4;
  w.ground_plane.normal_damping = 200.0;
  w.ground_plane.friction_damping = 0.0;
  w.ground_plane.friction_cap = 0.0;
  w.ground_plane.heightfield = Sampled([&](double x, double) { return std::abs(x) * std::tan(alpha); }, {-3, -2}, {0.5, 0.5}, 13, 9);
  BodyState<3, double> s = RestState<3, double>(box);
  s.translation() = Vector3d(-width / 2, width / 2 * std::tan(alpha) + 0.01, -0.3);
  for (int step = 0; step < 8000; ++step) ASSERT_TRUE(StepBody(box, w, 0, Integrator::kSymplecticEuler, 5e-4, &s).ok());
  EXPECT_LT(s.qd.norm(), 1e-6);
  Vector3d on_face[2] = {Vector3d::Zero(), Vector3d::Zero()};
  const Frame<3, double> frame(s.q);
  ForEachPointInContact(box, w.ground_plane, s, frame, [&](int, const Vector3d&, const Vector3d& x, const Vector3d& v, const Vector3d& anchor, const GroundPlane& plane, int) {
    bool slipping;
    on_face[plane.normal.x() > 0 ? 0 : 1] += GroundForce(plane, x, v, anchor, &slipping);
  }, ContactSet::kFrozen);
  const double N = mass * 8 * g / (2 * std::cos(alpha));
  EXPECT_LT((on_face[0] - N * Vector3d(std::sin(alpha), std::cos(alpha), 0)).norm(), 1e-6 * N);
  EXPECT_LT((on_face[1] - N * Vector3d(-std::sin(alpha), std::cos(alpha), 0)).norm(), 1e-6 * N);
}

// A box let go at rest on the slope y = x tan α of `field`'s triangles, ground cap `mu`: its
// speed downhill after 1 s and 2 s, and its contacts at the end.
struct Slide {
  double v_at_1, v_at_2, travelled;
  size_t contacts;
};
Slide SlideDownTheSlope(const BodyModelN<3>& block, double alpha, double mu, std::shared_ptr<const Heightfield> field) {
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.friction_cap = mu;
  w.ground_plane.stiffness = 2e4;
  w.ground_plane.normal_damping = 100.0;
  w.ground_plane.friction_damping = 100.0;
  w.ground_plane.heightfield = std::move(field);
  const Vector3d downhill(-std::cos(alpha), -std::sin(alpha), 0.0);
  BodyState<3, double> s = RestState<3, double>(block);
  s.set_orientation(Eigen::Quaterniond(Eigen::AngleAxisd(alpha, Vector3d::UnitZ())));
  s.translation() = Vector3d(0, 1e-4, -0.15);
  const double dt = 2e-4;
  Slide out{};
  for (int step = 1; step <= int(2.0 / dt); ++step) {
    EXPECT_TRUE(StepBody(block, w, 0, Integrator::kSymplecticEuler, dt, &s).ok());
    if (step == int(1.0 / dt)) out.v_at_1 = LinearMomentum(block, s).dot(downhill) / block.moments().m;
  }
  out.v_at_2 = LinearMomentum(block, s).dot(downhill) / block.moments().m;
  out.travelled = -s.translation().x();
  out.contacts = s.contacts.size();
  return out;
}

std::shared_ptr<const Heightfield> SlopeOfTriangles(double alpha) {
  return Sampled([&](double x, double) { return x * std::tan(alpha); }, {-30, -2}, {0.2, 0.2}, 161, 21);
}

// Down a 35° slope made of triangles 0.2 wide (the box crosses dozens of them) with friction
// cap μ = 0.4: the acceleration is g (sin α − μ cos α); at 15° (tan α < μ) it holds.
TEST(Heightfield, SlidesDownASlopeOfTrianglesAtTheClosedForm) {
  const BodyModelN<3> block = Box(0.4, 0.2, 0.3, 0.5);
  const double mu = 0.4, g = 9.81;
  for (double alpha_deg : {15.0, 35.0}) {
    const double alpha = alpha_deg * M_PI / 180.0;
    const Slide slide = SlideDownTheSlope(block, alpha, mu, SlopeOfTriangles(alpha));
    if (std::tan(alpha) < mu) {
      EXPECT_LT(std::abs(slide.v_at_2), 1e-3) << alpha_deg << " degrees";
    } else {
      const double expected = g * (std::sin(alpha) - mu * std::cos(alpha));
      EXPECT_NEAR(slide.v_at_2 - slide.v_at_1, expected, 0.01 * expected) << alpha_deg << " degrees";
      EXPECT_GT(slide.travelled, 3.5) << "it slid over many triangles (3.5 is 17 of them)";
    }
    EXPECT_EQ(slide.contacts, 4u) << alpha_deg << " degrees: the four bottom corners";
  }
}

// A region's own friction cap: on the 35° slope (tan α = 0.70) with the ground's cap 0.8 the
// box holds, but where a region of the cells under its path sets frsin 0.4 it slides at
// g (sin α − 0.4 cos α); and the other way round. Cells outside the region keep the ground's.
TEST(Heightfield, ARegionsOwnFrictionCapDecidesWhetherItSlides) {
  const BodyModelN<3> block = Box(0.4, 0.2, 0.3, 0.5);
  const double alpha = 35.0 * M_PI / 180.0, g = 9.81;
  const Vector2d lo(-30, -2), hi(2, 1);  // the box's path, z from −0.3 to 0.15; not the cells beyond z = 1
  for (const auto& [ground_cap, region_cap] : {std::pair{0.8, 0.4}, std::pair{0.4, 0.8}}) {
    SCOPED_TRACE(region_cap);
    SurfaceOverrides own;
    own.friction_cap = region_cap;
    const std::shared_ptr<const Heightfield> field = SlopeOfTriangles(alpha)->WithRegion(lo, hi, own);
    const Slide slide = SlideDownTheSlope(block, alpha, ground_cap, field);
    if (region_cap < std::tan(alpha)) {
      const double expected = g * (std::sin(alpha) - region_cap * std::cos(alpha));
      EXPECT_NEAR(slide.v_at_2 - slide.v_at_1, expected, 0.01 * expected);
    } else {
      EXPECT_LT(std::abs(slide.v_at_2), 1e-3);
    }
    // a face of a cell in the region has the region's cap and the ground's other constants; one
    // beyond it (z = 1.5) the ground's cap
    GroundPlane ground;
    ground.enabled = true;
    ground.friction_cap = ground_cap;
    ground.stiffness = 2e4;
    ground.heightfield = field;
    std::vector<int> in, out;
    field->FacesFelt(Vector3d(-1.05, -1.05 * std::tan(alpha) - 0.01, 0.05), &in);
    field->FacesFelt(Vector3d(-1.05, -1.05 * std::tan(alpha) - 0.01, 1.5), &out);
    ASSERT_FALSE(in.empty());
    ASSERT_FALSE(out.empty());
    EXPECT_EQ(ground.Face(in[0], Vector3d(-1.05, 0, 0.05)).friction_cap, region_cap);
    EXPECT_EQ(ground.Face(in[0], Vector3d(-1.05, 0, 0.05)).stiffness, 2e4);
    EXPECT_EQ(ground.Face(out[0], Vector3d(-1.05, 0, 1.5)).friction_cap, ground_cap);
  }
}

TEST(Heightfield, RefusesBadRegions) {
  const std::shared_ptr<const Heightfield> field = SlopeOfTriangles(0.3);
  SurfaceOverrides negative;
  negative.stiffness = -1;
  EXPECT_THROW(field->WithRegion({-30, -2}, {2, 2}, negative), InputError);
  SurfaceOverrides fine;
  fine.friction_cap = 0.2;
  try {
    field->WithRegion({5, 5}, {6, 6}, fine);  // beyond the grid
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no cell's centre is in the region"), std::string::npos) << e.what();
  }
}

// A box sliding without friction off a plateau's edge (a drop of 3 over one cell, 72°): once
// its last point passes the edge it falls freely, step for step as the same box with no
// ground at all, until it lands (no sticking to the edge, no force from the wall). A point
// just past the edge is still inside the solid under the drop's face, by at most how far it
// had sunk into the top (m g / 4K): it feels that face only that shallowly, never deeper.
TEST(Heightfield, SlidesOffTheEdgeOfADropIntoFreeFall) {
  const BodyModelN<3> box = Box(0.5, 0.3, 0.4, 1.0);
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.stiffness = 2e4;
  w.ground_plane.normal_damping = 0.0;
  w.ground_plane.friction_damping = 0.0;
  w.ground_plane.friction_cap = 0.0;
  w.ground_plane.heightfield = Sampled([](double x, double) { return x < 0.5 ? 3.0 : 0.0; }, {-3, -2}, {1, 1}, 7, 5);
  const double sink = box.moments().m * 9.81 / (4 * w.ground_plane.stiffness);
  BodyState<3, double> s = RestState<3, double>(box);
  s.translation() = Vector3d(-1.0, 3.0 - sink, -0.2);
  s.qd.head<3>() = Vector3d(2.0, 0, 0);
  const double dt = 1e-4;
  bool airborne = false, landed = false;
  WorldParams no_ground = w;
  no_ground.ground_plane.enabled = false;
  BodyState<3, double> free;
  int checked = 0, drop_contacts = 0;
  for (int step = 0; step < int(1.2 / dt); ++step) {
    ASSERT_TRUE(StepBody(box, w, 0, Integrator::kSymplecticEuler, dt, &s).ok());
    ForEachPointInContact(box, w.ground_plane, s, Frame<3, double>(s.q),
                           [&](int, const Vector3d&, const Vector3d& x, const Vector3d&, const Vector3d&, const GroundPlane& plane, int) {
                             if (plane.normal.y() < 0.99) {
                               ++drop_contacts;
                               ASSERT_LT(-plane.Height(x), sink) << "step " << step << ": deep in the drop's face";
                             }
                           }, ContactSet::kFrozen);
    if (airborne && !landed) {
      ASSERT_TRUE(StepBody(box, no_ground, 0, Integrator::kSymplecticEuler, dt, &free).ok());
      landed = !s.contacts.empty();
      if (!landed) {
        ASSERT_TRUE(free.translation() == s.translation() && free.qd == s.qd && free.orientation().coeffs() == s.orientation().coeffs())
            << "step " << step;
        ++checked;
      }
    }
    if (!airborne && s.contacts.empty() && s.translation().x() > 0) {
      airborne = true;
      free = s;
    }
  }
  EXPECT_GT(checked, 3000) << "in the air for 0.3 s or more";
  EXPECT_LT(drop_contacts, 20) << "a few steps of a few points at the edge";
  EXPECT_TRUE(landed) << "and it lands on the floor";
}

TEST(Heightfield, RefusesBadGrids) {
  EXPECT_THROW(Heightfield::Make({0, 0}, {1, 1}, 1, 3, {0, 0, 0}), InputError);
  EXPECT_THROW(Heightfield::Make({0, 0}, {1, 1}, 2, 2, {0, 0, 0}), InputError);
  EXPECT_THROW(Heightfield::Make({0, 0}, {0, 1}, 2, 2, {0, 0, 0, 0}), InputError);
  EXPECT_THROW(Heightfield::Make({0, 0}, {1, 1}, 2, 2, {0, 0, std::nan(""), 0}), InputError);
  try {
    Heightfield::Make({0, 0}, {1, 1}, 2, 2, {0, 0, HUGE_VAL, 0});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("node (1, 2)"), std::string::npos) << e.what();
  }
}

// A heightfield file's regions (formats/heightfield_file.h): read as the cells' own constants
// (later over earlier), written back cell by cell and read again bit for bit; a bad region is
// refused with its FILE:LINE.
TEST(HeightfieldFile, RegionsAreReadWrittenAndRefusedWithTheirLine) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("wobble_heightfield_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string path = (dir / "f.heightfield").string();
  auto write = [&](const std::string& text) { std::ofstream(path) << text; };
  // 3 x 3 nodes, 2 x 2 cells with centres (0.5, 1), (1.5, 1), (0.5, 3), (1.5, 3)
  write("origin 0 0\nspacing 1 2\nregion 0 0 1 2 frsin 0.25 grconst 900\n0 1 2\n0 1 2\n0 1 2\n"
        "region 1 0 2 4 grdam 7 frsin 0.5\n");
  const std::shared_ptr<const Heightfield> field = formats::ReadHeightfieldFile(path);
  EXPECT_EQ(field->CellOverrides(0).friction_cap, 0.25);
  EXPECT_EQ(field->CellOverrides(0).stiffness, 900.0);
  EXPECT_TRUE(std::isnan(field->CellOverrides(0).normal_damping));
  for (int cell : {1, 3}) {
    EXPECT_EQ(field->CellOverrides(cell).normal_damping, 7.0);
    EXPECT_EQ(field->CellOverrides(cell).friction_cap, 0.5);
  }
  EXPECT_TRUE(field->CellOverrides(2) == SurfaceOverrides());
  formats::WriteHeightfieldFile(path + ".again", *field);
  EXPECT_TRUE(*formats::ReadHeightfieldFile(path + ".again") == *field);
  EXPECT_FALSE(*Heightfield::Make(field->origin(), field->spacing(), 3, 3, field->heights()) == *field);
  const std::pair<const char*, const char*> bad[] = {
      {"region 0 0 1 1 fric 0.1", ":5: expected grconst, grdam, frconst or frsin, got 'fric'"},
      {"region 0 0 1 1 frsin -0.5", ":5: heightfield: frsin must be a finite number >= 0"},
      {"region 5 5 6 6 frsin 0.1", ":5: heightfield: no cell's centre is in the region"},
      {"region 0 0 1 frsin 0.1", ":5: expected 'region X0 Z0 X1 Z1 NAME VALUE"},
      {"region 0 0 1 1 frsin x", ":5: expected a number for frsin, got 'x'"},
  };
  for (const auto& [line, message] : bad) {
    write(std::string("origin 0 0\nspacing 1 1\n0 1\n0 1\n") + line + "\n");
    try {
      formats::ReadHeightfieldFile(path);
      ADD_FAILURE() << line;
    } catch (const formats::ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(path + message), std::string::npos) << e.what();
    }
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace wobble
