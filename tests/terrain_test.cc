// Terrain (issue 19): a 2D ground of straight faces. Contacts against closed forms: blocks at
// rest on each face of a valley and a block pressed into its corner (statics), a table sliding
// down a slope face above its own friction cap (g (sin α − μ cos α)), a ball rolling off a
// cliff edge (the free-fall parabola, no sticking, no tunnelling); which faces a point feels;
// the grouped scan against brute force; a level terrain is the ground line bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "support/test_bodies.h"
#include "wobble/core/errors.h"
#include "wobble/world/world.h"

namespace wobble {
namespace {

using testing::TableDef;

constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

Eigen::VectorXd State(std::initializer_list<double> v) {
  Eigen::VectorXd q(v.size());
  int i = 0;
  for (double x : v) q[i++] = x;
  return q;
}

std::shared_ptr<const Terrain> MakeTerrain(std::vector<Eigen::Vector2d> v, std::vector<SurfaceOverrides> s = {}) {
  return Terrain::Make(std::move(v), std::move(s));
}

// A rigid square of side 100 (lattice 100 x 100): corners and edge midpoints, 10 kg each.
BodyDef SquareDef() {
  BodyDef def;
  def.name = "square";
  def.lattice = Lattice({0, 0}, {100, 0}, {0, 100});
  def.mass_positions = {{0, 0}, {50, 0}, {100, 0}, {100, 50}, {100, 100}, {50, 100}, {0, 100}, {0, 50}};
  def.masses.assign(def.mass_positions.size(), 10.0);
  return def;
}

// A ring of 32 points of 2.5 kg, radius 20, about the centre of a 40 x 40 lattice.
BodyDef BallDef() {
  BodyDef def;
  def.name = "ball";
  def.lattice = Lattice({0, 0}, {40, 0}, {0, 40});
  for (int i = 0; i < 32; ++i) {
    const double a = 2 * kPi * i / 32;
    def.mass_positions.push_back({20 + 20 * std::cos(a), 20 + 20 * std::sin(a)});
  }
  def.masses.assign(def.mass_positions.size(), 2.5);
  return def;
}

// The ground's force on body 0 through each face, summed over the body's contacts.
std::vector<Eigen::Vector2d> ForcePerFace(const World& w) {
  const Ground& g = w.options().params.ground;
  const BodyModel& body = w.body<2>(0);
  const BodyState<2, double>& s = w.state<2>(0);
  const Frame<2, double> frame(s.q);
  std::vector<Eigen::Vector2d> per_face(g.terrain->num_faces(), Eigen::Vector2d::Zero());
  for (const Contact<2, double>& c : s.contacts) {
    const Vec2<double> l = LocalPosition<double>(body.rest_local(c.point), body.mode_matrix(c.point), s.q);
    bool slipping;
    per_face[c.face] += GroundForce(g.Face(c.face), WorldFromLocal(frame, l),
                                    PointVelocity(frame, s.qd, l, body.mode_matrix(c.point)), c.anchor, &slipping);
  }
  return per_face;
}

Eigen::Vector2d CentreOfMass(const World& w) {
  const MassMoments& mm = w.body<2>(0).moments();
  const Frame<2, double> frame(w.q(0));
  return frame.t + frame.R * (mm.c0 / mm.m);
}

Eigen::Vector2d CentreOfMassVelocity(const World& w) {
  const MassMoments& mm = w.body<2>(0).moments();
  const BodyState<2, double>& s = w.state<2>(0);
  const Frame<2, double> frame(s.q);
  return Eigen::Vector2d(s.qd[0], s.qd[1]) + s.qd[2] * (frame.R * Perp(Vec2<double>(mm.c0 / mm.m)));
}

TEST(Terrain, HeightsOfAProfileWithACliff) {
  // cliff top y = 100 up to x = 0, the cliff face, a floor that rises from x = 100 to x = 200
  const auto t = MakeTerrain({{0, 100}, {0, 0}, {100, 0}, {200, 50}});
  EXPECT_EQ(t->num_faces(), 5);
  EXPECT_EQ(t->HeightAt(-1e6), 100);  // level continuation
  EXPECT_EQ(t->HeightAt(0), 100);     // at the cliff's x: its top
  EXPECT_EQ(t->HeightAt(1e-9), 0);
  EXPECT_EQ(t->HeightAt(150), 25);
  EXPECT_EQ(t->HeightAt(1e6), 50);
  EXPECT_EQ(t->MaxHeight(10, 150), 25);
  EXPECT_EQ(t->MaxHeight(-5, 150), 100);
  EXPECT_EQ(t->MaxHeight(120, 500), 50);
  EXPECT_TRUE(t->Inside({-1, 99}));
  EXPECT_FALSE(t->Inside({1, 99}));
}

TEST(Terrain, RefusesProfilesThatAreNotHeightfields) {
  auto message = [](std::vector<Eigen::Vector2d> v, std::vector<SurfaceOverrides> s = {}) {
    try {
      MakeTerrain(std::move(v), std::move(s));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message({{0, 0}}).find("at least two vertices"), std::string::npos);
  EXPECT_NE(message({{0, 0}, {-1, 0}}).find("left of vertex 1"), std::string::npos);
  EXPECT_NE(message({{0, 0}, {0, 0}}).find("same point"), std::string::npos);
  EXPECT_NE(message({{0, 0}, {0, 5}, {0, 9}}).find("one vertical line"), std::string::npos);
  EXPECT_NE(message({{0, 0}, {NAN, 0}}).find("vertex 2"), std::string::npos);
  EXPECT_NE(message({{0, 0}, {1, 0}}, {{}, {}}).find("parameters for 2"), std::string::npos);
  SurfaceOverrides negative;
  negative.friction_cap = -1;
  EXPECT_NE(message({{0, 0}, {1, 0}}, {negative}).find("segment 1"), std::string::npos);
  EXPECT_EQ(message({{0, 100}, {0, 0}, {10, 0}}), "accepted");
}

// Which faces a point feels: the one it entered through at a cliff's edge (convex), both in
// a valley (concave).
TEST(Terrain, FacesFeltAtAConvexEdgeAndInAConcaveCorner) {
  auto felt = [](const Terrain& t, Eigen::Vector2d x, Eigen::Vector2d v, int touching = -1) {
    std::vector<int> faces;
    t.FacesFelt(x, v, [&](int i) { return i == touching; }, &faces);
    return faces;
  };
  // the edge of a cliff: face 0 the top (y = 100, x <= 0), face 1 the cliff (x = 0)
  const auto cliff = MakeTerrain({{0, 100}, {0, 0}});
  const Eigen::Vector2d near_edge(-0.1, 99.5);  // 0.1 from the cliff, 0.5 under the top
  EXPECT_EQ(felt(*cliff, near_edge, {0, -10}), std::vector<int>({0}));  // landed from above
  EXPECT_EQ(felt(*cliff, near_edge, {0, 0}), std::vector<int>({1}));    // at rest: the nearer face
  EXPECT_EQ(felt(*cliff, near_edge, {-10, -1}), std::vector<int>({1}));  // came through the cliff
  EXPECT_EQ(felt(*cliff, near_edge, {0, 0}, 0), std::vector<int>({0})); // keeps the top it touches
  EXPECT_TRUE(felt(*cliff, {0.1, 99.5}, {0, -10}).empty());             // past the edge: air
  // a valley: floor y = 0 (face 0, x <= 0), a wall up at x = 0 (face 1), level top (face 2)
  const auto valley = MakeTerrain({{0, 0}, {0, 100}});
  EXPECT_EQ(felt(*valley, {0.3, -0.5}, {0, -10}), std::vector<int>({0, 1}));
  EXPECT_EQ(felt(*valley, {0.3, -0.5}, {0, 0}, 1), std::vector<int>({0, 1}));
  EXPECT_EQ(felt(*valley, {-5, -0.5}, {0, -10}), std::vector<int>({0}));   // the floor only
  EXPECT_EQ(felt(*valley, {0.5, 50}, {10, 0}), std::vector<int>({1}));     // the wall only
}

// A V valley with faces at ±15°, friction cap tan 25°: a rigid table put on either face stays
// where it is, and at rest the ground holds exactly its weight: m g cos α along the face's
// normal and m g sin α up the face (Coulomb statics).
TEST(Terrain, BlockAtRestOnEachFaceOfAValley) {
  const double alpha = 15 * kPi / 180, mu = std::tan(25 * kPi / 180);
  for (int side : {-1, 1}) {
    SCOPED_TRACE(side);
    WorldOptions o;
    o.dt = 0.002;
    o.params.ground.friction_cap = mu;
    o.params.ground.friction_damping = 1000;
    o.params.ground.terrain =
        MakeTerrain({{-1000, 1000 * std::tan(alpha)}, {0, 0}, {1000, 1000 * std::tan(alpha)}});
    World w(o);
    w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
    const int face = side < 0 ? 1 : 2;
    const Eigen::Vector2d tau = o.params.ground.Face(face).tau, n = o.params.ground.Face(face).n;
    // the left leg's tip 100 (left face) or 300 (right face) along the face from the bottom
    const Eigen::Vector2d foot = side < 0 ? Eigen::Vector2d(-700 * std::cos(alpha), 700 * std::sin(alpha))
                                          : Eigen::Vector2d(300 * std::cos(alpha), 300 * std::sin(alpha));
    const Eigen::Vector2d t0 = foot + 0.01 * n;
    w.SetState(0, State({t0.x(), t0.y(), side * alpha}), State({0, 0, 0}));
    ASSERT_TRUE(w.RunUntil(6.0, [](const World&) {})) << w.status().message;
    const double s1 = tau.dot(Eigen::Vector2d(w.q(0)[0], w.q(0)[1]));
    ASSERT_TRUE(w.RunUntil(10.0, [](const World&) {})) << w.status().message;
    const double s2 = tau.dot(Eigen::Vector2d(w.q(0)[0], w.q(0)[1]));
    EXPECT_LT(std::abs(s2 - s1), 1e-3);  // a slide would move tens of units in 4 s
    const std::vector<Eigen::Vector2d> f = ForcePerFace(w);
    const double weight = w.body<2>(0).moments().m * kG;
    for (int i = 0; i < int(f.size()); ++i) {
      if (i == face) continue;
      EXPECT_EQ(f[i], Eigen::Vector2d::Zero()) << "face " << i;
    }
    EXPECT_NEAR(f[face].dot(n), weight * std::cos(alpha), 1e-4 * weight);
    EXPECT_NEAR(f[face].dot(tau), side * weight * std::sin(alpha), 1e-4 * weight);  // up the face
  }
}

// A square block set corner-down into a right-angled valley (faces at ±45°), frictionless: the
// corner point feels both faces, and at rest each face pushes with m g / √2 along its normal.
TEST(Terrain, BlockInAValleyCornerFeelsBothFaces) {
  WorldOptions o;
  o.dt = 0.001;
  o.params.ground.friction_cap = 0;
  o.params.ground.terrain = MakeTerrain({{-500, 500}, {0, 0}, {500, 500}});
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(SquareDef(), std::vector<DeformationMode>{}));
  // rotated 45°, its corner (0, 0) is the lowest point: put it 0.5 above the valley's corner
  w.SetState(0, State({0, 0.5, kPi / 4}), State({0, 0, 0}));
  ASSERT_TRUE(w.RunUntil(5.0, [](const World&) {})) << w.status().message;
  const std::vector<Eigen::Vector2d> f = ForcePerFace(w);
  const double weight = w.body<2>(0).moments().m * kG;
  EXPECT_LT(w.ComputeEnergies(0).kinetic, 1e-6 * weight);
  for (int face : {1, 2}) {
    SCOPED_TRACE(face);
    const Eigen::Vector2d n = o.params.ground.Face(face).n;
    EXPECT_NEAR(f[face].dot(n), weight / std::sqrt(2.0), 1e-4 * weight);
    EXPECT_NEAR(f[face].dot(o.params.ground.Face(face).tau), 0.0, 1e-9 * weight);  // no friction
  }
  int corner_contacts = 0;
  for (const Contact<2, double>& c : w.state<2>(0).contacts) corner_contacts += c.point == 0;
  EXPECT_EQ(corner_contacts, 2);
}

// A slope face with a friction cap of its own (tan 20°) under a ground whose cap is 1: the
// table slides with g (sin α − μ cos α) of the face's μ (with the ground's it would stick).
TEST(Terrain, SlidesDownASlopeFaceWithItsOwnFrictionCap) {
  const double alpha = 30 * kPi / 180, mu = std::tan(20 * kPi / 180);
  WorldOptions o;
  o.dt = 0.002;
  o.params.ground.friction_cap = 1.0;
  o.params.ground.friction_damping = 1000;
  SurfaceOverrides slope;
  slope.friction_cap = mu;
  o.params.ground.terrain =
      MakeTerrain({{-3000, 3000 * std::tan(alpha)}, {3000, -3000 * std::tan(alpha)}}, {slope});
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(TableDef(), std::vector<DeformationMode>{}));
  const GroundFace face = o.params.ground.Face(1);
  const Eigen::Vector2d t0 = Eigen::Vector2d(-1500, 1500 * std::tan(alpha)) + 0.01 * face.n;
  w.SetState(0, State({t0.x(), t0.y(), -alpha}), State({0, 0, 0}));
  auto along = [&] { return face.tau.dot(Eigen::Vector2d(w.q(0)[0], w.q(0)[1])); };
  ASSERT_TRUE(w.RunUntil(6.0, [](const World&) {})) << w.status().message;
  const double s1 = along(), v1 = face.tau.dot(Eigen::Vector2d(w.qd(0)[0], w.qd(0)[1]));
  ASSERT_TRUE(w.RunUntil(10.0, [](const World&) {})) << w.status().message;
  const double a = kG * (std::sin(alpha) - mu * std::cos(alpha));  // down the face is +τ here
  EXPECT_NEAR(v1, a * 6.0, 0.01 * a * 6.0);
  EXPECT_NEAR(along() - s1, v1 * 4.0 + 0.5 * a * 16.0, 0.01 * (along() - s1));
}

// A ball of mass points rolls along a cliff top and over its edge: it touches the cliff face
// only at the corner it pivots on (no sticking, no slide down the face), every point below the
// surface has a contact (no tunnelling), and from its last contact its centre of mass follows
// the free-fall parabola until it meets the floor.
TEST(Terrain, BallRollingOffACliffEdgeFollowsTheFreeFallParabola) {
  WorldOptions o;
  o.dt = 0.001;
  o.integrator = Integrator::kRK4;  // exact for the parabola: the comparison is to 1e-6
  o.params.ground.friction_cap = 1.0;
  o.params.ground.terrain = MakeTerrain({{0, 100}, {0, 0}});
  World w(o);
  w.AddBody(std::make_shared<BodyModel>(BallDef(), std::vector<DeformationMode>{}));
  // slow enough to stay on the ground while it rolls (v² / r < g), fast enough to clear the cliff
  const double speed = 13;
  // centre 20 above the top, 30 before the edge, rolling right (ω = −v / r)
  w.SetState(0, State({-50, 100, 0}), State({speed, 0, -speed / 20}));
  const Terrain& terrain = *o.params.ground.terrain;
  struct Sample {
    double t;
    Eigen::Vector2d com, com_velocity;
    bool on_cliff, on_floor;  // contacts with the cliff (its top or face), with the floor
  };
  std::vector<Sample> samples;
  double wall_depth = 0;  // how far below the edge a point touched the cliff face
  while (w.time() < 12.0 && (samples.empty() || !samples.back().on_floor)) {
    ASSERT_TRUE(w.Step()) << w.status().message;
    const BodyState<2, double>& s = w.state<2>(0);
    const Frame<2, double> frame(s.q);
    for (int k = 0; k < w.body<2>(0).num_points(); ++k) {
      const Eigen::Vector2d x = WorldFromLocal(frame, Vec2<double>(w.body<2>(0).rest_local(k)));
      const bool has_contact =
          std::any_of(s.contacts.begin(), s.contacts.end(), [k](const Contact<2, double>& c) { return c.point == k; });
      ASSERT_EQ(terrain.Inside(x), has_contact) << "point " << k << " at t = " << w.time();
    }
    Sample sample{w.time(), CentreOfMass(w), CentreOfMassVelocity(w), false, false};
    for (const Contact<2, double>& c : s.contacts) {
      if (c.face == 1)  // the cliff face: only where the ball pivots over the edge
        wall_depth = std::max(wall_depth, 100 - WorldFromLocal(frame, Vec2<double>(w.body<2>(0).rest_local(c.point))).y());
      (c.face == 2 ? sample.on_floor : sample.on_cliff) = true;
    }
    samples.push_back(sample);
  }
  ASSERT_TRUE(samples.back().on_floor);
  size_t last_top = 0;
  for (size_t i = 0; i < samples.size(); ++i)
    if (samples[i].on_cliff) last_top = i;
  const Sample& off = samples[last_top];
  double worst = 0;
  for (size_t i = last_top + 1; i + 1 < samples.size(); ++i) {  // the flight: no contact at all
    const double dt = samples[i].t - off.t;
    const Eigen::Vector2d expected = off.com + off.com_velocity * dt - 0.5 * kG * dt * dt * Eigen::Vector2d::UnitY();
    worst = std::max(worst, (samples[i].com - expected).norm());
  }
  EXPECT_GT(samples.size() - last_top, 3000u);  // about 4 s of free fall from the cliff to the floor
  EXPECT_GT(off.com_velocity.x(), 0.8 * speed);  // it left rolling, not stuck at the edge
  EXPECT_GT(off.com.x(), 0.0);                   // ... and past it
  EXPECT_LT(worst, 1e-6);
  EXPECT_LT(wall_depth, 1.0);  // the corner's side, not a slide down the cliff
}

// Large bodies visit only the point groups whose box reaches the terrain: the points visited
// must be exactly those below the surface.
TEST(Terrain, GroupedScanVisitsExactlyThePointsBelowTheSurface) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const BodyModel body = testing::RandomBody(rng, 4, 5, BasisKind::kBernstein, 3, 3000);
  ASSERT_GT(body.clusters().size(), 1u);
  Ground g;
  g.terrain = MakeTerrain({{-200, 60}, {-40, 60}, {-40, 0}, {40, -10}, {60, 30}, {200, 30}});
  int partial = 0;
  for (int trial = 0; trial < 40; ++trial) {
    BodyState<2, double> s;
    s.q = VecQ<double>::Zero(body.num_q());
    s.qd = VecQ<double>::Zero(body.num_q());
    s.q << 120 * u(rng), 30 + 30 * u(rng), 0.5 * u(rng), 0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng);
    std::vector<int> visited, expected;
    const Frame<2, double> frame(s.q);
    ForEachPointInContact(body, g, s, frame,
                          [&](int k, const Vec2<double>&, const Vec2<double>&, const Vec2<double>&,
                              const Vec2<double>&, const GroundFace&, int) { visited.push_back(k); });
    for (int k = 0; k < body.num_points(); ++k) {
      const Vec2<double> x = WorldFromLocal(frame, LocalPosition<double>(body.rest_local(k), body.mode_matrix(k), s.q));
      if (g.terrain->Inside(x)) expected.push_back(k);
    }
    std::sort(visited.begin(), visited.end());
    visited.erase(std::unique(visited.begin(), visited.end()), visited.end());
    EXPECT_EQ(visited, expected) << "trial " << trial;
    if (!expected.empty() && int(expected.size()) < body.num_points()) ++partial;
  }
  EXPECT_GT(partial, 10);  // the trials do cut through the groups
}

// A level terrain is the ground line: the same contacts and forces, bit for bit.
TEST(Terrain, LevelTerrainStepsExactlyAsTheGroundLine) {
  std::vector<Eigen::VectorXd> runs[2];
  for (int with_terrain : {0, 1}) {
    WorldOptions o;
    o.dt = 0.01;
    if (with_terrain) o.params.ground.terrain = MakeTerrain({{-1e4, 0}, {1e4, 0}});
    World w(o);
    w.AddBody(std::make_shared<BodyModel>(TableDef(), testing::TableModes(4e6, 5e6)));
    w.SetState(0, State({0, 50, 0.1, 0, 0, 0, 0}), State({5, 0, 0, 0, 0, 0, 0}));
    for (int i = 0; i < 800; ++i) {
      ASSERT_TRUE(w.Step()) << w.status().message;
      runs[with_terrain].push_back(w.q(0));
    }
  }
  for (size_t i = 0; i < runs[0].size(); ++i) ASSERT_EQ(runs[0][i], runs[1][i]) << "step " << i;
}

}  // namespace
}  // namespace wobble
