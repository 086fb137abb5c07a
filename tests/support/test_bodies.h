// Bodies built in code for the dynamics tests, so that physics tests do not depend on the
// file readers (those have their own tests).
#pragma once

#include <random>
#include <sstream>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/body/surface_mesh.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"

namespace wobble::testing {

// The Witkin & Welch tests' world: the step of the constraint scenes (0.002), gravity −y.
inline WorldOptions WitkinWelchOptions() {
  WorldOptions o;
  o.dt = 0.002;
  return o;
}

// The table of Fig. 1.2 on a 300 x 100 lattice: top and two legs, 11 points of 50 kg (Fig. 4.3).
inline BodyDef TableDef(int points_per_leg = 3, int top_points = 5, double mass_per_point = 50.0) {
  BodyDef def;
  def.name = "table";
  def.lattice = Lattice({0, 0}, {300, 0}, {0, 100});
  for (int i = 0; i < top_points; ++i) def.mass_positions.push_back({300.0 * i / (top_points - 1), 100.0});
  for (double x : {0.0, 300.0})
    for (int j = 0; j < points_per_leg; ++j) def.mass_positions.push_back({x, 100.0 * j / points_per_leg});
  def.masses.assign(def.mass_positions.size(), mass_per_point);
  def.shapes = {{{{0, 100}, {300, 100}}, false}, {{{0, 0}, {0, 100}}, false}, {{{300, 0}, {300, 100}}, false}};
  return def;
}

// A mode from the thesis' printed layout: rows from t = 0 upward, columns s = 0..1.
inline DeformationMode ModeFromRows(const std::string& name, const std::vector<std::vector<double>>& x_rows,
                                    const std::vector<std::vector<double>>& y_rows, double stiffness = 0,
                                    double damping = 0) {
  DeformationMode m;
  m.name = name;
  m.lattice_size[1] = int(x_rows.size());
  m.lattice_size[0] = int(x_rows[0].size());
  m.displacement.resize(m.lattice_size[0] * m.lattice_size[1]);
  for (int j = 0; j < m.lattice_size[1]; ++j)
    for (int i = 0; i < m.lattice_size[0]; ++i) m.displacement[i * m.lattice_size[1] + j] = {x_rows[j][i], y_rows[j][i]};
  m.stiffness = stiffness;
  m.damping = damping;
  return m;
}

// The bend of §4.10.1, exactly as printed.
inline DeformationMode Bend(double stiffness = 0, double damping = 0) {
  return ModeFromRows("bend", {{150, 150, -150, -150}, {50, 50, -50, -50}, {-50, -50, 50, 50}, {-150, -150, 150, 150}},
                      {{0, 100, 100, 0}, {0, 100, 100, 0}, {0, 100, 100, 0}, {0, 100, 100, 0}}, stiffness, damping);
}
inline DeformationMode Shear(double stiffness = 0, double damping = 0) {
  return ModeFromRows("shear", {{0, 0, 0, 0}, {50, 50, 50, 50}, {100, 100, 100, 100}, {150, 150, 150, 150}},
                      {{0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 0}}, stiffness, damping);
}
inline DeformationMode VerticalSquash(double stiffness = 0, double damping = 0) {
  return ModeFromRows("vsquash", {{-30, -10, 10, 30}, {-30, -10, 10, 30}, {-30, -10, 10, 30}, {-30, -10, 10, 30}},
                      {{0, 0, 0, 0}, {-33, -33, -33, -33}, {-67, -67, -67, -67}, {-100, -100, -100, -100}},
                      stiffness, damping);
}
inline DeformationMode HorizontalSquash(double stiffness = 0, double damping = 0) {
  return ModeFromRows("hsquash", {{150, 50, -50, -150}, {150, 50, -50, -150}, {150, 50, -50, -150}, {150, 50, -50, -150}},
                      {{-10, -10, -10, -10}, {0, 0, 0, 0}, {0, 0, 0, 0}, {10, 10, 10, 10}}, stiffness, damping);
}

inline std::vector<DeformationMode> TableModes(double stiffness = 0, double damping = 0) {
  return {Bend(stiffness, damping), Shear(stiffness, damping), VerticalSquash(stiffness, damping),
          HorizontalSquash(stiffness, damping)};
}

// Appendix A: two 50 kg points joined through the mode d_y = C j (rows t = 0..3), C = −100.
inline BodyModel Rod(double stiffness, double C = -100.0) {
  BodyDef def;
  def.name = "rod";
  def.lattice = Lattice({0, 0}, {100, 0}, {0, 300});
  def.mass_positions = {{50, 0}, {50, 300}};
  def.masses = {50, 50};
  std::vector<std::vector<double>> zero(4, std::vector<double>(4, 0.0)), y;
  for (int j = 0; j < 4; ++j) y.push_back(std::vector<double>(4, C * j));
  return BodyModel(def, {ModeFromRows("stretch", zero, y, stiffness)});
}

// A random body: lattice of any size and basis, random points, masses and modes.
inline BodyModel RandomBody(std::mt19937& rng, int num_s, int num_t, BasisKind basis, int num_modes, int num_points) {
  std::uniform_real_distribution<double> u(0.0, 1.0), disp(-40.0, 40.0), mass(1.0, 80.0);
  BodyDef def;
  def.name = "random";
  def.lattice = Lattice({-20, 5}, {250, 20}, {-30, 120}, num_s, num_t, basis);
  for (int k = 0; k < num_points; ++k) {
    def.mass_positions.push_back(def.lattice.origin() + u(rng) * def.lattice.axis_s() + u(rng) * def.lattice.axis_t());
    def.masses.push_back(mass(rng));
  }
  std::vector<DeformationMode> modes(num_modes);
  for (int d = 0; d < num_modes; ++d) {
    modes[d].name = "m" + std::to_string(d);
    modes[d].lattice_size = {num_s, num_t};
    for (int c = 0; c < num_s * num_t; ++c) modes[d].displacement.push_back({disp(rng), disp(rng)});
  }
  return BodyModel(def, modes);
}

// ---- 3D meshes made of boxes ----

// An axis-aligned box [lo, hi], 12 triangles, outward (or inward) normals.
inline SurfaceMesh BoxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, bool inward = false) {
  SurfaceMesh m;
  for (int i = 0; i < 8; ++i) m.points.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  if (inward)
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  return m;
}

inline SurfaceMesh JoinMeshes(SurfaceMesh a, const SurfaceMesh& b) {
  const int offset = int(a.points.size());
  a.points.insert(a.points.end(), b.points.begin(), b.points.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return a;
}

// A chair without any symmetry (a seat, a back and one arm), for fits without correspondences.
inline SurfaceMesh ChairMesh() {
  using V = Eigen::Vector3d;
  return JoinMeshes(JoinMeshes(BoxMesh(V(0, 0, 0), V(100, 20, 60)), BoxMesh(V(0, 20, 0), V(20, 90, 60))),
                    BoxMesh(V(70, 20, 0), V(100, 40, 15)));
}

// The chair as a 3D FFD character: its lattice fitted with a 5% margin, 100 kg on a volume grid
// of about 300 points, and three modes from generators (bend x by y, twist about y, squash y).
inline BodyModelN<3> Chair3() {
  std::istringstream object("dimension 3\nmesh chair\nlattice fit 4 4 3 margin 0.05\nsample volume 300 100\n");
  BodyDefN<3> def = formats::ParseObject<3>(object, "chair.obj", [](const std::string&) { return ChairMesh(); });
  std::istringstream text("dimension 3\nmode bend\n  bend x y 20\nmode twist\n  twist y 25\nmode squash\n  squash y 0.3\n");
  std::vector<DeformationModeN<3>> modes = formats::ParseDeformations(text, "chair.def3", def.lattice);
  return BodyModelN<3>(def, modes);
}

// A 3D box of eight corner masses with unequal sides: principal axes along the lattice axes,
// centre of mass away from the body origin (the lattice corner).
inline BodyModelN<3> Box(double a, double b, double c, double mass = 1.0) {
  BodyDefN<3> def;
  def.name = "box";
  def.lattice = LatticeN<3>(Eigen::Vector3d::Zero(), {Eigen::Vector3d(a, 0, 0), Eigen::Vector3d(0, b, 0), Eigen::Vector3d(0, 0, c)},
                         {2, 2, 2}, BasisKind::kBernstein);
  for (int i = 0; i < 8; ++i) def.mass_positions.push_back(Eigen::Vector3d(a * (i & 1), b * ((i >> 1) & 1), c * ((i >> 2) & 1)));
  def.masses.assign(8, mass);
  return BodyModelN<3>(def, {});
}

}  // namespace wobble::testing
