// Steps a World from a fuzzed state and fuzzed parameters: the table of data/ (an FFD body
// with four modes) or a small affine pyramid (a linear body). After every step either the
// world stopped with a named status, or every state, energy and point position is finite.
#include <cmath>
#include <cstdlib>

#include "fuzz_common.h"
#include "wobble/body/linear_shapes.h"
#include "wobble/world/world.h"

namespace {

using namespace wobble;

std::shared_ptr<const LinearBodyModel> Pyramid() {
  static const auto model = std::make_shared<const LinearBodyModel>(
      MakePyramidBody("pyramid", 2, LinearOrder::kAffine, 1.0, 2.0, /*levels=*/2, /*per_side=*/2, /*mass=*/1.0));
  return model;
}

bool Finite(const Energies& e) {
  if (!std::isfinite(e.total())) return false;
  for (double x : {e.kinetic, e.gravity, e.modes, e.ground, e.springs})
    if (!std::isfinite(x)) return false;
  for (double x : e.per_mode)
    if (!std::isfinite(x)) return false;
  return true;
}

// Prints what the world was doing (for the findings' one-line descriptions) and aborts.
[[noreturn]] void Finding(const World& world, int body, const char* what) {
  const WorldOptions& o = world.options();
  const Ground& g = o.params.ground;
  const Energies e = world.ComputeEnergies(body);
  std::fprintf(stderr,
               "fuzz_world_step: %s\n  %s body, integrator %s, dt %g, step %ld, gravity %s (%g, %g)\n"
               "  ground %s at (%g, %g) slope %g K %g C %g FR %g cap %g\n"
               "  energies: kinetic %g gravity %g modes %g ground %g springs %g\n",
               what, world.kind(body) == BodyKind::kFfd ? "FFD" : "linear", IntegratorName(o.integrator).c_str(), o.dt,
               world.steps(), o.params.gravity_on ? "on" : "off", o.params.gravity.x(), o.params.gravity.y(),
               g.enabled ? "on" : "off", g.point.x(), g.point.y(), g.slope, g.stiffness, g.normal_damping,
               g.friction_damping, g.friction_cap, e.kinetic, e.gravity, e.modes, e.ground, e.springs);
  if (world.kind(body) == BodyKind::kFfd) {
    std::fprintf(stderr, "  q:");
    for (int i = 0; i < world.q(body).size(); ++i) std::fprintf(stderr, " %g", world.q(body)[i]);
    std::fprintf(stderr, "\n  qd:");
    for (int i = 0; i < world.qd(body).size(); ++i) std::fprintf(stderr, " %g", world.qd(body)[i]);
  } else {
    std::fprintf(stderr, "  R:");
    for (int i = 0; i < world.linear_R(body).size(); ++i) std::fprintf(stderr, " %g", world.linear_R(body)(i));
    std::fprintf(stderr, "\n  R_dot:");
    for (int i = 0; i < world.linear_R_dot(body).size(); ++i) std::fprintf(stderr, " %g", world.linear_R_dot(body)(i));
  }
  std::fprintf(stderr, "\n");
  std::abort();
}

// Everything a step leaves behind must be finite (the step loop's promise, world.h).
void CheckFinite(const World& world, int body) {
  if (world.kind(body) == BodyKind::kFfd) {
    if (!world.q(body).allFinite() || !world.qd(body).allFinite()) Finding(world, body, "q or q-dot not finite after an ok step");
    for (const Eigen::Vector2d& p : world.PointPositions<2>(body))
      if (!p.allFinite()) Finding(world, body, "a mass point position not finite after an ok step");
  } else if (!world.linear_R(body).allFinite() || !world.linear_R_dot(body).allFinite()) {
    Finding(world, body, "R or R-dot not finite after an ok step");
  }
  if (!Finite(world.ComputeEnergies(body))) Finding(world, body, "an energy term not finite after an ok step");
  if (!std::isfinite(world.TotalEnergy())) Finding(world, body, "total energy not finite after an ok step");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::ByteReader in(data, size);
  const bool linear = in.Byte() & 1;
  WorldOptions o;
  o.integrator = Integrator(in.Int(0, 4));
  o.dt = in.Value(1e-4, 0.05);
  o.params.gravity_on = in.Byte() & 1;
  o.params.gravity = {in.Value(-20, 20), in.Value(-20, 20), 0.0};  // braces: read in order
  Ground& g = o.params.ground;
  g.enabled = in.Byte() & 1;
  g.point = {in.Value(-100, 100), in.Value(-100, 100)};
  g.slope = in.Value(-1.5, 1.5);
  g.stiffness = in.Value(0, 1e5);
  g.normal_damping = in.Value(0, 1e4);
  g.friction_damping = in.Value(0, 1e3);
  g.friction_cap = in.Value(0, 1);
  // a few steps: what is hunted is a step that turns a finite (hostile) state into a
  // non-finite one, and every input starts from a new one (16, not 50: four times the states
  // per second under ASan)
  const int steps = in.Int(1, 16);

  fuzz::IgnoringExpectedErrors([&] {
    World world(o);
    int body;
    if (linear) {
      AffineMaterial m;
      m.rigidity = in.Value(0, 1e3);
      m.volume = in.Value(0, 1e3);
      m.damping = in.Value(0, 10);
      body = world.AddLinearBody(Pyramid(), m);
      Eigen::MatrixXd R = world.linear_R(body), R_dot(R.rows(), R.cols());
      for (int i = 0; i < R.size(); ++i) R(i) += in.Value(-2, 2);
      for (int i = 0; i < R_dot.size(); ++i) R_dot(i) = in.Value(-50, 50);
      world.SetLinearState(body, R, R_dot);
    } else {
      body = world.AddBody(fuzz::TableBody());
      const int n = int(world.q(body).size());
      Eigen::VectorXd q(n), qd(n), targets(n - kRigidDofs);
      q[0] = in.Value(-500, 500);
      q[1] = in.Value(-100, 500);
      q[2] = in.Value(-4, 4);
      for (int i = kRigidDofs; i < n; ++i) q[i] = in.Value(-1, 1);
      qd[0] = in.Value(-500, 500);
      qd[1] = in.Value(-500, 500);
      qd[2] = in.Value(-20, 20);
      for (int i = kRigidDofs; i < n; ++i) qd[i] = in.Value(-20, 20);
      for (int i = 0; i < targets.size(); ++i) targets[i] = in.Value(-1, 1);
      world.SetState(body, q, qd);
      world.SetModeTargets(body, targets);
    }
    // a terrain in place of the line, from the bytes after the state (older inputs have none):
    // up to six vertices, cliffs (equal x) included, each segment maybe with its own parameters
    if (in.Byte() & 1) {
      std::vector<Eigen::Vector2d> vertices;
      std::vector<SurfaceOverrides> faces;
      double x = in.Value(-600, 600);
      const int nv = in.Int(2, 6);
      for (int i = 0; i < nv; ++i) {
        vertices.emplace_back(x, in.Value(-100, 400));
        x += (in.Byte() & 1) ? 0.0 : in.Value(0, 400);
      }
      for (int i = 0; i + 1 < nv; ++i) {
        SurfaceOverrides f;
        if (in.Byte() & 1) f.stiffness = in.Value(0, 1e5);
        if (in.Byte() & 1) f.friction_cap = in.Value(0, 2);
        faces.push_back(f);
      }
      world.mutable_options().params.ground.terrain = Terrain::Make(vertices, faces);  // may refuse: InputError
    }
    for (int n = 0; n < steps; ++n) {
      if (!world.Step()) {
        if (world.status().ok() || StatusCodeName(world.status().code).empty())
          Finding(world, body, "Step() failed without a named status");
        return;
      }
      CheckFinite(world, body);
    }
  });
  return 0;
}
