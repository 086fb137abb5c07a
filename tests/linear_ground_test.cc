// Ground contact of Witkin & Welch linear bodies (issue 19), against closed forms: a block at
// rest on flat ground carries its weight equally on its bottom row (depth m g / (rows K)), at
// rest on each face of a valley (Coulomb statics), corner-down in a valley (m g / √2 per face),
// sliding down a slope above the cap (g (sin α − μ cos α), 2D and 3D), off a cliff's edge (the
// discrete free-fall parabola, no sticking, no tunnelling); energy kept by an undamped bounce;
// the ground acting through the multiplier step; the point bound never skips a point below.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "wobble/world/world.h"

namespace wobble {
namespace {

constexpr double kG = 9.81;
constexpr double kPi = 3.14159265358979323846;

// A 2 × 1 block (3 × 3 points) of 6 kg, or a 1 × 1 one, with stiff, damped affine elasticity.
std::shared_ptr<const LinearBodyModel> Block(double hx, double hy, int dim = 2, double hz = 0.5) {
  Eigen::VectorXd half(dim);
  if (dim == 2) half << hx, hy;
  else half << hx, hy, hz;
  return std::make_shared<LinearBodyModel>(MakeBoxBody("block", dim, LinearOrder::kAffine, half, 3, 6.0));
}
AffineMaterial Stiff(double damping = 0.02) { return {2e4, 2e4, damping, 0.0}; }

Eigen::Matrix2d Rotation(double a) {
  Eigen::Matrix2d r;
  r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return r;
}

Eigen::VectorXd CentreOfMass(const World& w, int b) {
  const LinearBodyModel& m = w.linear_model(b);
  return w.linear_R(b) * m.first_moment() / m.total_mass();
}
Eigen::VectorXd CentreOfMassVelocity(const World& w, int b) {
  const LinearBodyModel& m = w.linear_model(b);
  return w.linear_R_dot(b) * m.first_moment() / m.total_mass();
}

// The ground's force on the body, summed per face (2D; one entry for the line).
std::vector<Eigen::Vector2d> ForcePerFace(const World& w, int b) {
  const Ground& g = w.options().params.ground;
  std::vector<Eigen::Vector2d> per_face(g.terrain ? g.terrain->num_faces() : 1, Eigen::Vector2d::Zero());
  const LinearContacts& c = w.linear_contacts(b);
  const std::vector<Eigen::VectorXd> f =
      LinearContactForces(w.linear_model(b), w.linear_ground(), w.linear_R(b), w.linear_R_dot(b), c);
  for (size_t i = 0; i < f.size(); ++i) per_face[c.list<2>()[i].face] += f[i];
  return per_face;
}

Eigen::VectorXd Point(const World& w, int b, int k) { return w.linear_R(b) * w.linear_model(b).point_bases().col(k); }

TEST(LinearGround, OffByDefaultAndTheBlockFallsThrough) {
  World w;
  const int b = w.AddLinearBody(Block(1, 0.5), Stiff());
  w.SetLinearState(b, w.linear_model(b).PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(0, 1)),
                   Eigen::MatrixXd::Zero(2, 3));
  EXPECT_FALSE(w.ground_contact(b));
  ASSERT_TRUE(w.RunUntil(1.0));
  EXPECT_LT(CentreOfMass(w, b).y(), -2.0);  // ½ g t² = 4.9 below where it started
  EXPECT_EQ(w.linear_contacts(b).size(), 0);
}

// On flat ground the bottom row of three points carries the weight: by symmetry the affine
// map keeps the row level, so each point sinks m g / (3 K) and nothing else touches.
TEST(LinearGround, RestsOnFlatGroundWithTheWeightOnItsBottomRow) {
  WorldOptions o;
  o.dt = 0.001;
  o.params.ground.friction_cap = 0;  // frictionless: no tangential spring holds a spread
  World w(o);
  const int b = w.AddLinearBody(Block(1, 0.5), Stiff());
  w.SetGroundContact(b, true);
  w.SetLinearState(b, w.linear_model(b).PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(0, 0.7)),
                   Eigen::MatrixXd::Zero(2, 3));
  ASSERT_TRUE(w.RunUntil(6.0)) << w.status().message;
  const double weight = 6.0 * kG, K = o.params.ground.stiffness;
  const LinearContacts& c = w.linear_contacts(b);
  ASSERT_EQ(c.list<2>().size(), 3u);
  for (const Contact<2, double>& contact : c.list<2>()) {
    EXPECT_NEAR(w.linear_model(b).def().points[contact.point].y(), -0.5, 0.0);  // the bottom row
    EXPECT_NEAR(Point(w, b, contact.point).y(), -weight / (3 * K), 1e-6 * weight / K);
  }
  EXPECT_NEAR(ForcePerFace(w, b)[0].y(), weight, 1e-6 * weight);
  EXPECT_NEAR(c.penetration, weight / (3 * K), 1e-6 * weight / K);
  EXPECT_NEAR(w.Penetration(b), c.penetration, 0.0);
  // the energy's ground term is the three springs' ½ K d²
  const double d = weight / (3 * K);
  EXPECT_NEAR(w.ComputeEnergies(b).ground, 3 * 0.5 * K * d * d, 1e-5 * K * d * d);
}

// A V valley with faces at ±15° and a friction cap of tan 25°: a block put on either face
// stays, and the ground holds its weight, m g cos α along the normal and m g sin α up the face.
TEST(LinearGround, BlockAtRestOnEachFaceOfAValley) {
  const double alpha = 15 * kPi / 180, mu = std::tan(25 * kPi / 180);
  for (int side : {-1, 1}) {
    SCOPED_TRACE(side);
    WorldOptions o;
    o.dt = 0.001;
    o.params.ground.friction_cap = mu;
    o.params.ground.friction_damping = 500;
    o.params.ground.terrain = Terrain::Make({{-50, 50 * std::tan(alpha)}, {0, 0}, {50, 50 * std::tan(alpha)}});
    World w(o);
    const int b = w.AddLinearBody(Block(1, 0.5), Stiff());
    w.SetGroundContact(b, true);
    const int face = side < 0 ? 1 : 2;
    const GroundFace f = o.params.ground.Face(face);
    // 5 along the face from the valley's bottom (0, 0), 1 cm above it
    const Eigen::Vector2d centre = side * 5.0 * f.tau + 0.51 * f.n;
    w.SetLinearState(b, w.linear_model(b).PlacedState(Rotation(side * alpha), centre), Eigen::MatrixXd::Zero(2, 3));
    ASSERT_TRUE(w.RunUntil(4.0)) << w.status().message;
    const double s1 = f.tau.dot(CentreOfMass(w, b));
    ASSERT_TRUE(w.RunUntil(8.0)) << w.status().message;
    EXPECT_LT(std::abs(f.tau.dot(CentreOfMass(w, b)) - s1), 1e-6);  // a slide would go metres
    const std::vector<Eigen::Vector2d> per_face = ForcePerFace(w, b);
    const double weight = 6.0 * kG;
    for (int i = 0; i < int(per_face.size()); ++i) {
      if (i != face) {
        EXPECT_EQ(per_face[i], Eigen::Vector2d::Zero()) << "face " << i;
      }
    }
    EXPECT_NEAR(per_face[face].dot(f.n), weight * std::cos(alpha), 1e-6 * weight);
    EXPECT_NEAR(per_face[face].dot(f.tau), side * weight * std::sin(alpha), 1e-6 * weight);  // up the face
  }
}

// A square block corner-down in a right-angled valley, frictionless: the corner point feels
// both faces, and at rest each face pushes with m g / √2 along its normal.
TEST(LinearGround, BlockCornerDownInAValleyFeelsBothFaces) {
  WorldOptions o;
  o.dt = 0.001;
  o.params.ground.friction_cap = 0;
  o.params.ground.terrain = Terrain::Make({{-50, 50}, {0, 0}, {50, 50}});
  World w(o);
  const int b = w.AddLinearBody(Block(0.5, 0.5), Stiff(0.05));
  w.SetGroundContact(b, true);
  // turned 45°, the corner u = (−0.5, −0.5) is lowest: put it 0.05 above the valley's corner
  w.SetLinearState(b, w.linear_model(b).PlacedState(Rotation(kPi / 4), Eigen::Vector2d(0, 0.05 + std::sqrt(0.5))),
                   Eigen::MatrixXd::Zero(2, 3));
  ASSERT_TRUE(w.RunUntil(6.0)) << w.status().message;
  const double weight = 6.0 * kG;
  EXPECT_LT(w.ComputeEnergies(b).kinetic, 1e-9 * weight);
  const std::vector<Eigen::Vector2d> per_face = ForcePerFace(w, b);
  for (int face : {1, 2}) {
    SCOPED_TRACE(face);
    EXPECT_NEAR(per_face[face].dot(o.params.ground.Face(face).n), weight / std::sqrt(2.0), 1e-6 * weight);
    EXPECT_NEAR(per_face[face].dot(o.params.ground.Face(face).tau), 0.0, 1e-12 * weight);  // no friction
  }
  int corner_contacts = 0;
  for (const Contact<2, double>& c : w.linear_contacts(b).list<2>()) corner_contacts += c.point == 0;
  EXPECT_EQ(corner_contacts, 2);  // point 0 is u = (−0.5, −0.5)
}

// A slope face of 30° with a cap of its own, tan 20°, under a ground whose cap is 1: the block
// slides with g (sin α − μ cos α), measured between 2 s and 4 s, after the landing's transient.
TEST(LinearGround, SlidesDownASlopeFaceAboveItsFrictionCap) {
  const double alpha = 30 * kPi / 180, mu = std::tan(20 * kPi / 180);
  WorldOptions o;
  o.dt = 0.0005;
  o.params.ground.friction_cap = 1.0;
  o.params.ground.friction_damping = 500;
  SurfaceOverrides slope;
  slope.friction_cap = mu;
  o.params.ground.terrain = Terrain::Make({{-100, 100 * std::tan(alpha)}, {100, -100 * std::tan(alpha)}}, {slope});
  World w(o);
  const int b = w.AddLinearBody(Block(1, 0.5), Stiff());
  w.SetGroundContact(b, true);
  const GroundFace face = o.params.ground.Face(1);
  w.SetLinearState(b, w.linear_model(b).PlacedState(Rotation(-alpha), 0.5 * face.n),  // at x = 0
                   Eigen::MatrixXd::Zero(2, 3));
  ASSERT_TRUE(w.RunUntil(2.0)) << w.status().message;
  const double v1 = face.tau.dot(CentreOfMassVelocity(w, b));
  ASSERT_TRUE(w.RunUntil(4.0)) << w.status().message;
  const double v2 = face.tau.dot(CentreOfMassVelocity(w, b));
  const double a = kG * (std::sin(alpha) - mu * std::cos(alpha));  // down the face is +τ
  EXPECT_NEAR((v2 - v1) / 2.0, a, 1e-3 * a);
}

// The same in 3D on a plane tilted 30° about z, with the plane's cap tan 20° (damping as below);
// and on that plane given as a heightfield of triangles 0.25 wide (the block crosses dozens).
TEST(LinearGround, SlidesDownATiltedPlaneIn3D) {
  const double alpha = 30 * kPi / 180, mu = std::tan(20 * kPi / 180);
  for (bool heightfield : {false, true}) {
    WorldOptions o;
    o.dt = 0.0005;
    o.params.ground_plane.enabled = true;
    o.params.ground_plane.normal = Eigen::Vector3d(std::sin(alpha), std::cos(alpha), 0);
    o.params.ground_plane.friction_cap = mu;
    o.params.ground_plane.normal_damping = 100;
    o.params.ground_plane.friction_damping = 500;
    if (heightfield) {
      const int nx = 161, nz = 25;
      std::vector<double> h;
      for (int j = 0; j < nz; ++j)
        for (int i = 0; i < nx; ++i) h.push_back(-std::tan(alpha) * (-10.0 + 0.25 * i));
      o.params.ground_plane.heightfield = Heightfield::Make({-10.0, -3.0}, {0.25, 0.25}, nx, nz, h);
    }
    World w(o);
    const int b = w.AddLinearBody(Block(1, 0.5, 3), Stiff());
    w.SetGroundContact(b, true);
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(-alpha, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    w.SetLinearState(b, w.linear_model(b).PlacedState(turn, 0.5 * o.params.ground_plane.normal), Eigen::MatrixXd::Zero(3, 4));
    const Eigen::Vector3d down_slope(std::cos(alpha), -std::sin(alpha), 0);
    ASSERT_TRUE(w.RunUntil(2.0)) << w.status().message;
    const double v1 = down_slope.dot(CentreOfMassVelocity(w, b));
    ASSERT_TRUE(w.RunUntil(4.0)) << w.status().message;
    const double v2 = down_slope.dot(CentreOfMassVelocity(w, b));
    const double a = kG * (std::sin(alpha) - mu * std::cos(alpha));
    EXPECT_NEAR((v2 - v1) / 2.0, a, 1e-3 * a) << (heightfield ? "heightfield" : "plane");
    EXPECT_EQ(w.linear_contacts(b).list<3>().size(), 9u);  // the bottom face's 3 × 3 points
    if (heightfield) {
      EXPECT_GT(CentreOfMass(w, b).x(), 8.0) << "slid over dozens of triangles";
    }
  }
}

// 3D, flat: the bottom face's nine points each carry a ninth of the weight. The 3D tests damp
// each point with 100, not the default 550 (made for the thesis' 100-unit table): 550 on each of
// nine points of a 6 kg block is more damping than an explicit step of 1 ms can take.
TEST(LinearGround, RestsOnThePlaneIn3DWithTheWeightOnItsBottomFace) {
  WorldOptions o;
  o.dt = 0.001;
  o.params.ground_plane.enabled = true;
  o.params.ground_plane.normal_damping = 100;
  World w(o);
  const int b = w.AddLinearBody(Block(1, 0.5, 3), Stiff());
  w.SetGroundContact(b, true);
  w.SetLinearState(b, w.linear_model(b).PlacedState(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0.6, 0)),
                   Eigen::MatrixXd::Zero(3, 4));
  ASSERT_TRUE(w.RunUntil(6.0)) << w.status().message;
  const double weight = 6.0 * kG, K = o.params.ground_plane.stiffness;
  ASSERT_EQ(w.linear_contacts(b).list<3>().size(), 9u);
  for (const Contact<3, double>& c : w.linear_contacts(b).list<3>())
    EXPECT_NEAR(Point(w, b, c.point).y(), -weight / (9 * K), 1e-6 * weight / K);
}

// A block slides frictionless along a cliff top and over its edge: no point ever touches the
// cliff face below the edge's corner region, every point inside the terrain has a contact (no
// tunnelling), and after its last contact the centre of mass follows the free fall of the
// semi-implicit Euler step exactly: x0 + v0 t − ½ g t² − ½ g h t (the scheme's own parabola).
TEST(LinearGround, BlockSlidingOffACliffEdgeFollowsTheFreeFall) {
  WorldOptions o;
  o.dt = 0.001;
  o.params.ground.friction_cap = 0;
  o.params.ground.terrain = Terrain::Make({{0, 10}, {0, 0}});
  World w(o);
  const int b = w.AddLinearBody(Block(0.5, 0.25), Stiff());
  w.SetGroundContact(b, true);
  Eigen::MatrixXd R_dot = Eigen::MatrixXd::Zero(2, 3);
  R_dot(0, 2) = 4.0;  // 4 m/s to the right
  w.SetLinearState(b, w.linear_model(b).PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(-2, 10.24)), R_dot);
  const Terrain& terrain = *o.params.ground.terrain;
  double wall_depth = 0, free_since = -1;
  int checked = 0;  // states compared with the parabola
  bool touched = false, landed = false;
  Eigen::VectorXd x_off, v_off;  // at the first state with no contact: the free fall's start
  while (w.time() < 4.0 && !landed) {
    ASSERT_TRUE(w.Step()) << w.status().message;
    const LinearContacts& c = w.linear_contacts(b);
    for (int k = 0; k < w.linear_model(b).num_points(); ++k) {
      const bool has = std::any_of(c.list<2>().begin(), c.list<2>().end(), [k](const Contact<2, double>& x) { return x.point == k; });
      ASSERT_EQ(terrain.Inside(Point(w, b, k)), has) << "point " << k << " at t = " << w.time();
    }
    for (const Contact<2, double>& contact : c.list<2>()) {
      if (contact.face == 1) wall_depth = std::max(wall_depth, 10 - Point(w, b, contact.point).y());
      landed = landed || contact.face == 2;
    }
    if (!c.list<2>().empty()) {
      touched = true;
      free_since = -1;  // (a corner may touch again as the block tips over the edge)
      continue;
    }
    if (!touched) continue;
    if (free_since < 0) {
      free_since = w.time();
      x_off = CentreOfMass(w, b);
      v_off = CentreOfMassVelocity(w, b);
      continue;
    }
    const double t = w.time() - free_since, h = o.dt;
    const Eigen::Vector2d expected = x_off + v_off * t - (0.5 * kG * t * t + 0.5 * kG * h * t) * Eigen::Vector2d::UnitY();
    ASSERT_LT((CentreOfMass(w, b) - expected).norm(), 1e-9) << "t = " << w.time();
    ++checked;
  }
  EXPECT_GT(checked, 1200);  // 10 m of fall: 1.4 s
  EXPECT_TRUE(landed);
  EXPECT_GT(x_off.x(), 0.0);         // it left past the edge ...
  EXPECT_NEAR(v_off.x(), 4.0, 1e-9);  // frictionless: the ground never pushed it sideways
  EXPECT_LT(wall_depth, 0.05);       // at most the corner's dip, never a slide down the wall
}

// Undamped and frictionless, a dropped block bounces back: the total energy (kinetic, gravity,
// affine, the ground's springs) stays within the symplectic step's O(h) wobble, which halves
// with h.
TEST(LinearGround, AnUndampedBounceKeepsItsEnergy) {
  auto worst_drift = [](double h) {
    WorldOptions o;
    o.dt = h;
    o.params.ground.normal_damping = 0;
    o.params.ground.friction_damping = 0;
    o.params.ground.friction_cap = 0;
    World w(o);
    const int b = w.AddLinearBody(Block(1, 0.5), Stiff(0.0));
    w.SetGroundContact(b, true);
    w.SetLinearState(b, w.linear_model(b).PlacedState(Rotation(0.2), Eigen::Vector2d(0, 1.5)),
                     Eigen::MatrixXd::Zero(2, 3));
    const double e0 = w.TotalEnergy();
    double worst = 0;
    int bounces = 0;
    bool touching = false;
    EXPECT_TRUE(w.RunUntil(3.0, [&](const World& world) {
      worst = std::max(worst, std::abs(world.TotalEnergy() - e0));
      const bool now = world.linear_contacts(b).size() > 0;
      bounces += now && !touching;
      touching = now;
    }));
    EXPECT_GE(bounces, 2);
    return worst;
  };
  const double mgh = 6.0 * kG * 1.0;
  const double coarse = worst_drift(2e-4), fine = worst_drift(1e-4);
  EXPECT_LT(coarse, 1e-2 * mgh);
  EXPECT_NEAR(coarse / fine, 2.0, 0.3);  // first order in h: a drift would not scale so
}

// The multiplier step applies the ground too: two blocks attached end to end rest on the
// ground, and it holds their whole weight.
TEST(LinearGround, ActsThroughTheMultiplierStep) {
  WorldOptions o;
  o.dt = 0.001;
  World w(o);
  const int a = w.AddLinearBody(Block(1, 0.5), Stiff());
  const int c = w.AddLinearBody(Block(1, 0.5), Stiff());
  for (int b : {a, c}) w.SetGroundContact(b, true);
  w.SetLinearState(a, w.linear_model(a).PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(-1, 0.6)),
                   Eigen::MatrixXd::Zero(2, 3));
  w.SetLinearState(c, w.linear_model(c).PlacedState(Eigen::Matrix2d::Identity(), Eigen::Vector2d(1, 0.6)),
                   Eigen::MatrixXd::Zero(2, 3));
  Eigen::VectorXd ua(2), uc(2);
  ua << 1, 0.5;
  uc << -1, 0.5;
  w.AddAttachment(At(a, ua), At(c, uc));
  ASSERT_TRUE(w.RunUntil(6.0)) << w.status().message;
  const double held = ForcePerFace(w, a)[0].y() + ForcePerFace(w, c)[0].y();
  EXPECT_NEAR(held, 12.0 * kG, 1e-6 * 12.0 * kG);
  EXPECT_LT(w.MaxViolation(), 1e-6);
}

// The bound that skips a body in the air is never above its lowest point: for random states of
// a quadratic body near a sloped line and a terrain, the contacts made are exactly the points
// below the ground.
TEST(LinearGround, TheBoundNeverSkipsAPointBelowTheGround) {
  LinearBodyDef def = MakeBoxBody("bent", 2, LinearOrder::kQuadratic, Eigen::Vector2d(1, 0.5), 5, 1.0);
  const LinearBodyModel model(def);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (bool terrain : {false, true}) {
    Ground g;
    g.slope = terrain ? 0.0 : 0.3;
    if (terrain) g.terrain = Terrain::Make({{-1, 0.2}, {0, -0.3}, {0, 0.4}, {1, 0}});
    const GroundPlane plane;
    int touching = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      Eigen::MatrixXd R = model.PlacedState(Rotation(3 * u(rng)), Eigen::Vector2d(u(rng), 1.2 * u(rng)));
      R.rightCols(3) = 0.4 * Eigen::MatrixXd::NullaryExpr(2, 3, [&] { return u(rng); });
      LinearContacts c;
      UpdateLinearContacts(model, {g, plane}, R, Eigen::MatrixXd::Zero(2, 6), &c);
      std::vector<int> expected, got;
      for (int k = 0; k < model.num_points(); ++k) {
        const Eigen::Vector2d x = R * model.point_bases().col(k);
        if (terrain ? g.terrain->Inside(x) : g.Face(0).Height(x) < 0) expected.push_back(k);
      }
      for (const Contact<2, double>& contact : c.list<2>())
        if (got.empty() || got.back() != contact.point) got.push_back(contact.point);
      ASSERT_EQ(got, expected) << "trial " << trial;
      touching += !expected.empty() && int(expected.size()) < model.num_points();
    }
    EXPECT_GT(touching, 200);  // the states straddle the ground often
  }
}

}  // namespace
}  // namespace wobble
