#include "inspect.h"

#include <Eigen/SVD>
#include <cmath>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>

namespace wobble::app {
namespace {

using nlohmann::json;

json Point(const Eigen::Vector2d& p) { return json::array({p.x(), p.y()}); }

template <class Derived> json Vector(const Eigen::MatrixBase<Derived>& v) {
  json a = json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(double(v[i]));
  return a;
}

template <class Derived> json Matrix(const Eigen::MatrixBase<Derived>& m) {
  json a = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) a.push_back(Vector(m.row(r).transpose()));
  return a;
}

// [s-index][t-index][2] of a flat i*num_t + j array of points.
json Grid(const std::vector<Eigen::Vector2d>& flat, int num_s, int num_t) {
  json grid = json::array();
  for (int i = 0; i < num_s; ++i) {
    json column = json::array();
    for (int j = 0; j < num_t; ++j) column.push_back(Point(flat[size_t(i) * num_t + j]));
    grid.push_back(std::move(column));
  }
  return grid;
}

}  // namespace

CLI::App* AddInspectCommand(CLI::App* app, InspectArgs* a) {
  CLI::App* cmd = app->add_subcommand("inspect", "Print the model and the dynamics at one state as a JSON object");
  AddBodyFlags(cmd, &a->files);
  cmd->add_option("--q", a->q, "State q = \"tx ty theta g1 ..\" (default: zeros)")->type_name("\"NUMS\"");
  cmd->add_option("--qdot", a->qdot, "Velocity q-dot, same layout (default: zeros)")->type_name("\"NUMS\"");
  AddWorldFlags(cmd, &a->world);
  cmd->add_option("--indent", a->indent, "Pretty-print with this many spaces (default: one line)")->type_name("N");
  cmd->footer(
      "Keys: masses, lattice_coords, lattice [s][t][2], modes [mode][s][t][2], x, M, velocity_terms\n"
      "(-sum m J^T Jdot qdot), forces {gravity, modes, ground, total}, qddot, cond (2-norm of M).\n"
      "Example:\n"
      "  wobble inspect --object data/table.obj --modes data/table_modes.def \\\n"
      "      --q \"0 10 0.1 0.2 0 0 0\" --qdot \"1 0 0.5 0 0 0 0\" --indent 2");
  return cmd;
}

int RunInspect(const InspectArgs& a) {
  if (a.indent < -1 || a.indent > 16) throw UsageError("--indent must be between 0 and 16");
  const StartingWorld setup = LoadStartingWorld(a.files, a.q, a.qdot, a.world, Integrator::kThesis, 0.01);
  if (setup.dim() == 3) throw UsageError("inspect takes 2D objects only so far; for a 3D object use condition check or simulate");
  const std::shared_ptr<const BodyModel>& body = setup.body<2>();
  const World world = setup.MakeWorld();
  const BodyState<2, double>& s = world.state<2>(0);
  const Lattice& lat = body->lattice();

  json out = json::object();
  // the model: masses, where they sit in the lattice, the lattice and the modes
  json masses = json::array(), coords = json::array();
  for (int k = 0; k < body->num_points(); ++k) {
    masses.push_back(body->mass(k));
    coords.push_back(Point(body->lattice_coords(k)));
  }
  out["masses"] = std::move(masses);
  out["lattice_coords"] = std::move(coords);
  out["lattice"] = Grid(lat.RestPoints(), lat.num_s(), lat.num_t());
  json modes = json::array();
  for (const DeformationMode& m : body->modes()) modes.push_back(Grid(m.displacement, lat.num_s(), lat.num_t()));
  out["modes"] = std::move(modes);

  // the state: world positions, inertia, velocity terms, forces, accelerations
  json x = json::array();
  for (const Eigen::Vector2d& p : world.PointPositions<2>(0)) x.push_back(Point(p));
  out["x"] = std::move(x);
  MatQ<double> M;
  MassMatrix(body->moments(), s.q, &M);
  out["M"] = Matrix(M);
  VecQ<double> w;
  VelocityTerms(body->moments(), s.q, s.qd, &w);
  out["velocity_terms"] = Vector(-w);
  const ForceBreakdown<2, double> f = world.Forces<2>(0);
  out["forces"] = {{"gravity", Vector(f.gravity)}, {"modes", Vector(f.modes)}, {"ground", Vector(f.ground)},
                   {"total", Vector(f.total)}};
  VecQ<double> qdd;
  const StepStatus st = wobble::Accelerations(*body, world.options().params, 0, s, &qdd);
  out["qddot"] = st.ok() ? Vector(qdd) : json(nullptr);
  const Eigen::MatrixXd M_dense = M;
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M_dense);
  const auto& sv = svd.singularValues();
  const double cond = sv.minCoeff() > 0.0 ? sv.maxCoeff() / sv.minCoeff() : std::numeric_limits<double>::infinity();
  out["cond"] = std::isfinite(cond) ? json(cond) : json(nullptr);

  std::cout << out.dump(a.indent) << std::endl;
  if (!st.ok()) {
    std::cerr << "wobble: no accelerations at this state: " << StatusCodeName(st.code);
    if (st.code == StepStatus::Code::kIllConditioned) std::cerr << " (condition estimate " << st.value << ")";
    std::cerr << "; qddot is null" << std::endl;
    return kExitSimStopped;
  }
  return kExitOk;
}

}  // namespace wobble::app
