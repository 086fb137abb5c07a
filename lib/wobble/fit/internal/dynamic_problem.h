// Internals of the dynamic fits (not part of the public API), shared by the Jet path
// (dynamic_fit.cc) and the adjoint path (dynamic_fit_adjoint.cc): what differs between 2D and
// 3D, the simulation the fits differentiate, the parameter blocks Ceres sees, the reference.
#pragma once

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "wobble/core/rotation3.h"
#include "wobble/fit/dynamic_fit.h"
#include "wobble/fit/internal/mode_force.h"
#include "wobble/fit/internal/residuals.h"
#include "wobble/fit/pose_fit.h"
#include "wobble/fit/trajectory_fit.h"

namespace wobble::fit::internal {

// What differs between the dimensions: the state, its step, where a body point is in a state,
// the fits' q of a state, and how q0 is held as a parameter block. In 3D the block is [t, δ, γ] with the
// orientation chart · exp(δ̂) (as the pose fits, pose_fit.h), so the solver never meets a
// rotation-vector singularity.
template <int Dim> struct Dimension;

template <> struct Dimension<2> {
  using Body = BodyModel;
  template <class T> using State = BodyState<2, T>;
  template <class T> static State<T> Start(const Body& body, const WorldParams& w, const T* q0, const T* qd0,
                                           const Eigen::Quaterniond&) {
    State<T> s;
    s.q = Eigen::Map<const VecQ<T>>(q0, body.num_q());
    s.qd = Eigen::Map<const VecQ<T>>(qd0, body.num_q());
    UpdateContacts(body, w.ground, &s);
    return s;
  }
  template <class T, class Extra> static bool Step(const Body& body, const WorldParams& w, double dt, State<T>* s,
                                                   const Extra& extra) {
    if (!StepBody(body, w, 0, Integrator::kThesis, dt, s, extra).ok()) return false;
    for (int i = 0; i < s->q.size(); ++i)
      if (!std::isfinite(ScalarValue(s->q[i])) || !std::isfinite(ScalarValue(s->qd[i]))) return false;
    return true;
  }
  template <class T> static Vec2<T> Position(const PointBasisN<2>& p, const State<T>& s) {
    return PointPosition(p, s.q.data(), int(s.q.size()));
  }
  static Eigen::VectorXd Q(const State<double>& s) { return s.q; }
  // q0 as a block, and back
  static Eigen::Quaterniond Chart(const Eigen::VectorXd&) { return Eigen::Quaterniond::Identity(); }
  static Eigen::VectorXd ToBlock(const Eigen::VectorXd& q, const Eigen::Quaterniond&) { return q; }
  static Eigen::VectorXd FromBlock(const Eigen::VectorXd& b, const Eigen::Quaterniond&) { return b; }
  // the velocity between two poses h apart
  static Eigen::VectorXd Velocity(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double h) { return (b - a) / h; }
};

template <> struct Dimension<3> {
  using Body = BodyModelN<3>;
  template <class T> using State = BodyState<3, T>;
  template <class T> static State<T> Start(const Body& body, const WorldParams& w, const T* q0, const T* qd0,
                                           const Eigen::Quaterniond& chart) {
    const int D = body.num_modes();
    State<T> s = RestState<3, T>(body);
    s.translation() = Vec3<T>(q0[0], q0[1], q0[2]);
    Group<3>::SetOrientation(
        Eigen::Quaternion<T>(chart.cast<T>() * ExpRotation<T>(Vec3<T>(q0[3], q0[4], q0[5]))).normalized(), &s.q);
    for (int d = 0; d < D; ++d) s.gamma()[d] = q0[Group<3>::kRigidDofs + d];
    s.qd = Eigen::Map<const VecQ<T>>(qd0, body.num_q());
    UpdateContacts(body, w.ground_plane, &s);
    return s;
  }
  template <class T, class Extra> static bool Step(const Body& body, const WorldParams& w, double dt, State<T>* s,
                                                   const Extra& extra) {
    return StepBody(body, w, 0, Integrator::kThesis, dt, s, extra).ok();  // non-finite states fail inside
  }
  template <class T> static Vec3<T> Position(const PointBasisN<3>& p, const State<T>& s) {
    Vec3<T> l = p.b0.cast<T>();
    for (int d = 0; d < s.gamma().size(); ++d) l += p.B.col(d).cast<T>() * s.gamma()[d];
    return s.translation() + s.orientation().toRotationMatrix() * l;
  }
  static Eigen::VectorXd Q(const State<double>& s) {
    Eigen::VectorXd q(Group<3>::kRigidDofs + s.gamma().size());
    q << s.translation(), LogRotation<double>(s.orientation()), s.gamma();
    return q;
  }
  static Eigen::Quaterniond Chart(const Eigen::VectorXd& q) { return ExpRotation<double>(q.segment<3>(3)); }
  static Eigen::VectorXd ToBlock(const Eigen::VectorXd& q, const Eigen::Quaterniond&) {
    Eigen::VectorXd b = q;
    b.segment<3>(3).setZero();  // the chart is q's own orientation
    return b;
  }
  static Eigen::VectorXd FromBlock(const Eigen::VectorXd& b, const Eigen::Quaterniond& chart) {
    Eigen::VectorXd q = b;
    q.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(chart * ExpRotation<double>(b.segment<3>(3))));
    return q;
  }
  // v = [ṫ, body ω, γ̇] with ω = log(R_aᵀ R_b)/h
  static Eigen::VectorXd Velocity(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double h) {
    Eigen::VectorXd v = (b - a) / h;
    v.segment<3>(3) = LogRotation<double>(Eigen::Quaterniond(ExpRotation<double>(a.segment<3>(3)).conjugate() *
                                                             ExpRotation<double>(b.segment<3>(3)))) / h;
    return v;
  }
};

// The thesis integrator (Eq. 4.22/4.23), exactly as World runs it: the body's step with the mode
// forces from `p` and the controller's targets at the start of every step (as the World's pose
// graph sets them). Calls on_frame(f, state) at every frame step.
template <int Dim, class T, class F>
bool Simulate(const BodyModelN<Dim>& passive, const DynamicFitOptionsN<Dim>& o, const T* q0, const T* qd0,
              const Eigen::Quaterniond& chart, const ModeParams<T>& p, const control::PoseGraphOf<T>& control,
              const std::vector<int>& steps, F&& on_frame) {
  using Dims = Dimension<Dim>;
  const auto& w = o.world;
  typename Dims::template State<T> s = Dims::template Start<T>(passive, w, q0, qd0, chart);
  VecD<T> target = VecD<T>::Zero(passive.num_modes());
  int step = 0;
  for (size_t f = 0; f < steps.size(); ++f) {
    for (; step < steps[f]; ++step) {
      if (!control.empty()) target = control::SmoothPoseTargets(control, passive.num_modes(), step * o.dt, o.switch_width);
      if (!Dims::Step(passive, w, o.dt, &s, ModeForce<T>{&p, &target})) return false;
    }
    on_frame(int(f), s);
  }
  return true;
}

// G_dd, the generalized mass of each mode: the damping scale 2 sqrt(2 K G_dd) is the critical
// damping of γ̈ G_dd = −2 K γ − c γ̇.
template <int Dim> VecD<double> ModeMasses(const BodyModelN<Dim>& body) {
  VecD<double> g(body.num_modes());
  for (int d = 0; d < body.num_modes(); ++d) g[d] = body.moments().G(d, d);
  return g;
}

// The raw parameter blocks Ceres sees: q0 (3D: in its chart), q̇0, log K, ζ.
template <int Dim> struct Blocks {
  using Dims = Dimension<Dim>;
  std::vector<double> q0, qd0, log_k, zeta;
  std::vector<double> poses, log_times;  // the controller: poses flattened, log transition times
  int pose_size = 0;
  bool cyclic = true;
  Eigen::Quaterniond chart = Eigen::Quaterniond::Identity();
  static Blocks From(const DynamicParameters& p, const VecD<double>& G) {
    Blocks b;
    b.chart = Dims::Chart(p.q0);
    const Eigen::VectorXd q0 = Dims::ToBlock(p.q0, b.chart);
    b.q0.assign(q0.data(), q0.data() + q0.size());
    b.qd0.assign(p.qd0.data(), p.qd0.data() + p.qd0.size());
    for (int d = 0; d < p.stiffness.size(); ++d) {
      b.log_k.push_back(std::log(p.stiffness[d]));
      b.zeta.push_back(p.damping[d] / (2.0 * std::sqrt(2.0 * p.stiffness[d] * G[d])));
    }
    b.cyclic = p.graph.cyclic;
    for (size_t i = 0; i < p.graph.poses.size(); ++i) {
      b.pose_size = int(p.graph.poses[i].size());
      for (int k = 0; k < b.pose_size; ++k) b.poses.push_back(p.graph.poses[i][k]);
      b.log_times.push_back(std::log(p.graph.durations[i]));
    }
    return b;
  }
  DynamicParameters To(const VecD<double>& G) const {
    DynamicParameters p;
    p.q0 = Dims::FromBlock(Eigen::Map<const Eigen::VectorXd>(q0.data(), q0.size()), chart);
    p.qd0 = Eigen::Map<const Eigen::VectorXd>(qd0.data(), qd0.size());
    p.stiffness.resize(log_k.size());
    p.damping.resize(log_k.size());
    for (size_t d = 0; d < log_k.size(); ++d) {
      p.stiffness[d] = std::exp(log_k[d]);
      p.damping[d] = zeta[d] * 2.0 * std::sqrt(2.0 * p.stiffness[d] * G[d]);
    }
    p.graph.cyclic = cyclic;
    for (size_t i = 0; i < log_times.size(); ++i) {
      p.graph.poses.push_back(Eigen::Map<const Eigen::VectorXd>(poses.data() + i * pose_size, pose_size));
      p.graph.durations.push_back(std::exp(log_times[i]));
    }
    return p;
  }
};

// The reference: body points (bases) and their targets, per frame.
template <int Dim> struct Reference {
  struct Point {
    PointBasisN<Dim> basis;
    Eigen::Matrix<double, Dim, 1> target;
    double sqrt_weight = 1.0;
  };
  std::vector<int> steps;
  std::vector<std::vector<Point>> points;
  int num_residuals = 0;
};
template <int Dim>
Reference<Dim> MakeReference(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                             double dt) {
  Reference<Dim> r;
  r.steps = FrameSteps(frames, dt);
  for (const auto& f : frames) {
    std::vector<typename Reference<Dim>::Point> pts;
    for (const auto& t : f.points) {
      if (!(t.weight > 0) || !std::isfinite(t.weight)) throw std::invalid_argument("dynamic fit: weights must be > 0");
      if (t.mass_point >= body.num_points())
        throw std::invalid_argument("dynamic fit: mass point " + std::to_string(t.mass_point) + " does not exist");
      pts.push_back({BasisOf(body, t.mass_point, t.lattice_coords), t.position, std::sqrt(t.weight)});
      r.num_residuals += Dim;
    }
    r.points.push_back(pts);
  }
  return r;
}

template <int Dim> void CheckParameters(const BodyModelN<Dim>& body, const DynamicParameters& p) {
  const int nq = body.num_q(), D = body.num_modes();
  if (p.q0.size() != nq || p.qd0.size() != nq) throw std::invalid_argument("dynamic fit: q0 and qdot0 need num_q values");
  for (int i = 0; i < nq; ++i)
    if (!std::isfinite(p.q0[i]) || !std::isfinite(p.qd0[i])) throw std::invalid_argument("dynamic fit: q0 and qdot0 must be finite");
  if (p.stiffness.size() != D || p.damping.size() != D)
    throw std::invalid_argument("dynamic fit: stiffness and damping need one value per mode");
  for (int d = 0; d < D; ++d) {
    if (!(p.stiffness[d] > 0) || !std::isfinite(p.stiffness[d]))
      throw std::invalid_argument("dynamic fit: mode '" + body.modes()[d].name +
                                  "' needs a positive starting stiffness (it is fitted as log K)");
    if (!(p.damping[d] >= 0) || !std::isfinite(p.damping[d]))
      throw std::invalid_argument("dynamic fit: damping must be >= 0");
  }
  if (!p.graph.empty()) {
    const std::string invalid = p.graph.Validate(int(control::ActiveModes(body).size()));
    if (!invalid.empty()) throw std::invalid_argument("dynamic fit: pose graph: " + invalid);
  }
}

// Fills an empty q0 / q̇0 from pose fits of the first two frames.
template <int Dim>
DynamicParameters Completed(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                            DynamicParameters p) {
  using Dims = Dimension<Dim>;
  if (p.stiffness.size() == 0 && p.damping.size() == 0) body.ModeGains(&p.stiffness, &p.damping);
  if (p.q0.size() && p.qd0.size()) return p;
  PoseFitOptions o;
  o.gamma_lower = -10;
  o.gamma_upper = 10;
  o.analyze_conditioning = false;
  const Eigen::VectorXd a = FitPose(body, frames[0].points, o).q;
  if (!p.q0.size()) p.q0 = a;
  if (!p.qd0.size()) {
    if (frames.size() < 2) {
      p.qd0 = Eigen::VectorXd::Zero(body.num_q());
    } else {
      o.initial_q = a;
      const Eigen::VectorXd b = FitPose(body, frames[1].points, o).q;
      p.qd0 = Dims::Velocity(a, b, frames[1].time - frames[0].time);
    }
  }
  return p;
}

// The plain simulation with parameters p: on_frame(f, state) at every frame step.
template <int Dim, class F>
bool SimulatePlain(const BodyModelN<Dim>& body, const DynamicFitOptionsN<Dim>& o, const DynamicParameters& p,
                   const std::vector<int>& frame_steps, F&& on_frame) {
  using Dims = Dimension<Dim>;
  CheckParameters(body, p);
  const BodyModelN<Dim> passive = body.WithoutModeGains();
  ModeParams<double> mp;
  mp.K = p.stiffness;
  mp.c = p.damping;
  const Eigen::Quaterniond chart = Dims::Chart(p.q0);
  const Eigen::VectorXd q0 = Dims::ToBlock(p.q0, chart);
  return Simulate(passive, o, q0.data(), p.qd0.data(), chart, mp, control::PoseGraphOf<double>::From(body, p.graph),
                  frame_steps, on_frame);
}

template <int Dim>
double CostOf(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
              const DynamicParameters& p, const DynamicFitOptionsN<Dim>& o) {
  using Dims = Dimension<Dim>;
  const Reference<Dim> ref = MakeReference(body, frames, o.dt);
  double cost = 0;
  const bool ok = SimulatePlain(body, o, p, ref.steps, [&](int f, const auto& state) {
    for (const auto& s : ref.points[f])
      cost += 0.5 * s.sqrt_weight * s.sqrt_weight * (Dims::Position(s.basis, state) - s.target).squaredNorm();
  });
  return ok ? cost : std::numeric_limits<double>::infinity();
}


// The fit with the adjoint gradient and Ceres' line search (DynamicFitOptionsN::gradient ==
// kAdjoint): dynamic_fit_adjoint.cc.
template <int Dim>
DynamicFitResult FitDynamicByAdjoint(const BodyModelN<Dim>& body, const std::vector<ReferenceFrameN<Dim>>& frames,
                                     const DynamicParameters& initial, const DynamicFitOptionsN<Dim>& o);

}  // namespace wobble::fit::internal
