// The hop of issue 18, shared by tests/spacetime_test.cc and bench/spacetime_bench.cc: the
// table of the synthesis scenes (bend, shear and both squashes at K 4e7, c 4e6; the ground of
// data/bounding_table.wob) standing at rest, asked to have its centre of mass `rise` higher
// than at rest at 0.7 s and to come down upright at 1 s, with PD targets within ±0.3 at 21
// knots and control energy weighed 1 (Δt 0.01, thesis integrator).
#pragma once

#include "support/test_bodies.h"
#include "wobble/fit/spacetime.h"

namespace wobble::testing {

inline const BodyModel& HopTable() {
  static const BodyModel body(TableDef(), TableModes(4e7, 4e6));
  return body;
}

constexpr int kHopSteps = 100, kHopPeak = 70;

inline fit::SpacetimeProblem TableHop(double rise = 2.0) {
  const BodyModel& body = HopTable();
  fit::SpacetimeProblem p;
  fit::ControlledRollout& r = p.rollout;
  r.world.ground.enabled = true;
  r.world.ground.stiffness = 45000;
  r.world.ground.normal_damping = 3000;
  r.world.ground.friction_damping = 3000;
  r.world.ground.friction_cap = 0.5;
  r.integrator = Integrator::kThesis;
  r.dt = 0.01;
  const int nq = body.num_q(), D = body.num_modes();
  r.start.q = Eigen::VectorXd::Zero(nq);  // the legs' feet on the ground
  r.start.qd = Eigen::VectorXd::Zero(nq);
  r.stiffness = Eigen::VectorXd::Constant(D, 4e7);
  r.damping = Eigen::VectorXd::Constant(D, 4e6);
  r.targets = Eigen::MatrixXd::Zero(D, kHopSteps);
  p.knots = 21;
  p.lower = Eigen::VectorXd::Constant(D, -0.3);
  p.upper = Eigen::VectorXd::Constant(D, 0.3);
  p.control_weight = 1.0;
  const double rest_height = body.moments().c0.y() / body.moments().m;
  fit::Axes height_only;
  height_only.x = false;
  p.task = fit::SumOf({fit::CentreOfMassAt(body, kHopPeak, {0.0, rest_height + rise}, 2e3, height_only),
                       fit::UprightAt<2>(kHopSteps, 2e3, 0.1)});
  return p;
}

}  // namespace wobble::testing
