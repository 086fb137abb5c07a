// The dynamics are templates on the scalar: with ceres::Jet they give exact derivatives of a
// step (and so of a simulation) with respect to the state, checked here against central
// differences of the double version.
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <memory>

#include "support/test_bodies.h"
#include "wobble/dynamics/step.h"
#include "wobble/dynamics/step.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "support/source_paths.h"

namespace wobble {
namespace {

constexpr int kNq = 7;  // the table with 4 modes
using Jet = ceres::Jet<double, 2 * kNq>;

WorldParams GroundedParams() {
  WorldParams p;
  p.ground.point = Eigen::Vector2d(0, 0);
  p.ground.slope = 0.1;
  return p;
}

// State with one leg pushed into a sloped ground, turning and wobbling.
BodyState<2, double> Start() {
  BodyState<2, double> s;
  s.q.resize(kNq);
  s.qd.resize(kNq);
  s.q << 10, 0.5, 0.05, 0.02, -0.01, 0.03, 0.01;
  s.qd << 0.3, -2, 0.1, 0.05, 0.02, -0.04, 0.03;
  return s;
}

template <class T> VecQ<T> Simulate(const BodyModel& body, const WorldParams& p, Integrator integrator,
                                    const VecQ<T>& q0, const VecQ<T>& qd0, int steps) {
  BodyState<2, T> s;
  s.q = q0;
  s.qd = qd0;
  UpdateContacts(body, p.ground, &s);
  for (int i = 0; i < steps; ++i) EXPECT_TRUE(StepBody(body, p, 0, integrator, 0.005, &s).ok());
  VecQ<T> out(2 * kNq);
  out << s.q, s.qd;
  return out;
}

TEST(Jet, StepDerivativesMatchFiniteDifferences) {
  const BodyModel body(testing::TableDef(), testing::TableModes(4e5, 1e4));
  const WorldParams p = GroundedParams();
  const BodyState<2, double> s0 = Start();
  for (Integrator integrator : {Integrator::kThesis, Integrator::kRK4}) {
    // contacts are created in the first step and kept: the same branch for every probe
    VecQ<Jet> q(kNq), qd(kNq);
    for (int i = 0; i < kNq; ++i) {
      q[i] = Jet(s0.q[i], i);
      qd[i] = Jet(s0.qd[i], kNq + i);
    }
    const VecQ<Jet> out = Simulate<Jet>(body, p, integrator, q, qd, 10);
    for (int j = 0; j < 2 * kNq; ++j) {
      const double h = 1e-6;
      VecQ<double> qp = s0.q, qm = s0.q, vp = s0.qd, vm = s0.qd;
      if (j < kNq) {
        qp[j] += h;
        qm[j] -= h;
      } else {
        vp[j - kNq] += h;
        vm[j - kNq] -= h;
      }
      const VecQ<double> fd = (Simulate<double>(body, p, integrator, qp, vp, 10) -
                               Simulate<double>(body, p, integrator, qm, vm, 10)) / (2 * h);
      for (int i = 0; i < 2 * kNq; ++i)
        EXPECT_NEAR(out[i].v[j], fd[i], 1e-5 * (1.0 + std::abs(fd[i])))
            << IntegratorName(integrator) << ": d out" << i << " / d in" << j;
    }
    // and the values are those of the double simulation (up to rounding: Eigen vectorizes
    // double arithmetic but not Jet arithmetic)
    const VecQ<double> plain = Simulate<double>(body, p, integrator, s0.q, s0.qd, 10);
    for (int i = 0; i < 2 * kNq; ++i) EXPECT_NEAR(out[i].a, plain[i], 1e-13 * (1.0 + std::abs(plain[i])));
  }
}


// The 3D body with Jets: derivatives of its position, shape and velocity after 10 steps with
// respect to the start velocity v0 = (ṫ, ω, γ̇), through contacts with a tilted plane.
using Jet3 = ceres::Jet<double, 10>;  // the 3D table: 6 + 4 velocities

template <class T>
Eigen::Matrix<T, Eigen::Dynamic, 1> Simulate3(const BodyModelN<3>& body, const WorldParams& w, Integrator integrator,
                                              const VecQ<T>& v0, int steps) {
  BodyState<3, T> s = RestState<3, T>(body);
  s.translation() = Vec3<T>(T(0.0), T(-0.5), T(0.0));
  s.set_orientation(Eigen::Quaternion<T>(T(0.999), T(0.02), T(0.01), T(-0.03)).normalized());
  for (int d = 0; d < body.num_modes(); ++d) s.gamma()[d] = T(0.01 * (d + 1));
  s.qd = v0;
  UpdateContacts(body, w.ground_plane, &s);
  for (int i = 0; i < steps; ++i) EXPECT_TRUE(StepBody(body, w, 0, integrator, 0.005, &s).ok());
  Eigen::Matrix<T, Eigen::Dynamic, 1> out(7 + 2 * body.num_modes() + 6);
  out << s.translation(), s.orientation().coeffs(), s.gamma(), s.qd;
  return out;
}

TEST(Jet, Step3DerivativesMatchFiniteDifferences) {
  const BodyDefN<3> def = formats::ReadObjectFile<3>(wobble::test_env::DataDir() + "/table3.obj");
  std::vector<DeformationModeN<3>> modes =
      formats::ReadDeformationFile(wobble::test_env::DataDir() + "/table3_modes.def3", def.lattice);
  for (DeformationModeN<3>& m : modes) m.stiffness = 4e5, m.damping = 1e4;
  const BodyModelN<3> body(def, modes);
  WorldParams w;
  w.ground_plane.enabled = true;
  w.ground_plane.normal = Eigen::Vector3d(0.1, 1.0, 0.05).normalized();
  VecQ<double> v0(10);
  v0 << 0.3, -2, 0.2, 0.05, 0.1, -0.08, 0.05, 0.02, -0.04, 0.03;
  for (Integrator integrator : {Integrator::kThesis, Integrator::kRK4}) {
    VecQ<Jet3> v(10);
    for (int i = 0; i < 10; ++i) v[i] = Jet3(v0[i], i);
    const auto out = Simulate3<Jet3>(body, w, integrator, v, 10);
    const Eigen::VectorXd plain = Simulate3<double>(body, w, integrator, v0, 10);
    for (int j = 0; j < 10; ++j) {
      const double h = 1e-6;
      VecQ<double> vp = v0, vm = v0;
      vp[j] += h;
      vm[j] -= h;
      const Eigen::VectorXd fd = (Simulate3<double>(body, w, integrator, vp, 10) -
                                  Simulate3<double>(body, w, integrator, vm, 10)) / (2 * h);
      for (int i = 0; i < fd.size(); ++i)
        EXPECT_NEAR(out[i].v[j], fd[i], 1e-5 * (1.0 + std::abs(fd[i])))
            << IntegratorName(integrator) << ": d out" << i << " / d v" << j;
    }
    for (int i = 0; i < plain.size(); ++i) EXPECT_NEAR(out[i].a, plain[i], 1e-12 * (1.0 + std::abs(plain[i])));
  }
}

}  // namespace
}  // namespace wobble
