// Control of active characters (Faloutsos 1995, chapter 5 and §4.10.1).
//
// Low level: one PD controller per deformation mode (chapter 5),
//     Q_r = −(C (γ − γ0) + D γ̇),   C = 2K, D = c,
// i.e. the mode's own potential V = K γ² and damping c (§4.7) pulled towards a moving target
// γ0 instead of the rest shape. Passive modes keep γ0 = 0; active modes get their targets from
// a high-level controller: a pose graph (chapter 5) or keyframes (§4.10.1). The dynamics apply
// the targets through BodyState::mode_target (World::SetModeTargets).
//
// The control energy of a run — the thesis' "total energy consumed by the deformation forces
// throughout the forward simulation (including the forces associated with passive deformation
// modes)" — is defined here as
//     E = Σ_d ∫ |Q_r,d γ̇_d| dt
// (the absolute mechanical power of every mode force, passive and active: a mode that brakes
// consumes energy as much as one that pushes, like an actuator that cannot store it). The signed
// work Σ_d ∫ Q_r,d γ̇_d dt is kept beside it. Both are integrated by the rectangle rule on the
// state after each step.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/dynamics/forces.h"
#include "wobble/dynamics/step.h"

namespace wobble::control {

// Indices (0-based) of the body's active modes, in order: a pose lists one target per entry.
// 2D and 3D bodies alike.
template <int Dim> std::vector<int> ActiveModes(const BodyModelN<Dim>& body) {
  std::vector<int> active;
  for (int d = 0; d < body.num_modes(); ++d)
    if (body.modes()[size_t(d)].active) active.push_back(d);
  return active;
}

// Full target vector γ0 (one per mode): the pose's values on the active modes, 0 elsewhere.
template <int Dim> Eigen::VectorXd TargetsFromPose(const BodyModelN<Dim>& body, const Eigen::VectorXd& pose) {
  const std::vector<int> active = ActiveModes(body);
  Eigen::VectorXd targets = Eigen::VectorXd::Zero(body.num_modes());
  for (int i = 0; i < int(active.size()) && i < pose.size(); ++i) targets[active[size_t(i)]] = pose[i];
  return targets;
}

// Q_r,d = −(2K_d (γ_d − γ0_d) + c_d γ̇_d) of every mode (the modes' block of the generalized
// forces). `targets` empty means all zero.
Eigen::VectorXd ModeControlForces(const BodyModel& body, const BodyState<2, double>& s);
Eigen::VectorXd ModeControlForces(const BodyModelN<3>& body, const BodyState<3, double>& s);  // 3D: γ, γ̇ of s.gamma, s.v

struct ControlEnergy {
  double consumed = 0.0;  // Σ_d ∫ |Q_r,d γ̇_d| dt
  double work = 0.0;      // Σ_d ∫ Q_r,d γ̇_d dt (signed)
  // Adds one step of length dt at the state after the step.
  void Accumulate(const BodyModel& body, const BodyState<2, double>& s, double dt);
  void Accumulate(const BodyModelN<3>& body, const BodyState<3, double>& s, double dt);
};

// A pose graph (chapter 5): poses (targets for the active modes) each held for its transition
// time. Cyclic graphs cycle from the first pose for ever; acyclic ones (a sequence) hold the
// last pose after the end.
struct PoseGraph {
  std::vector<Eigen::VectorXd> poses;  // one target per active mode
  std::vector<double> durations;       // transition times, > 0
  bool cyclic = true;

  bool empty() const { return poses.empty(); }
  double Period() const;  // the sum of the transition times
  // Index of the pose active at time t since the graph started (t >= 0).
  int PoseAt(double t) const;
  // Checks sizes and durations; returns an empty string or what is wrong.
  std::string Validate(int num_active) const;
};

// A pose graph whose targets switch smoothly, for fits through the simulation (lib/wobble/fit),
// where transition times need a gradient:
//     γ0(t) = P_0 + Σ_k (P_{k mod n} − P_{(k−1) mod n}) σ((t − S_k)/w),  S_k = τ_0 + … + τ_{k−1},
// σ the logistic function, w the switch width (the set point moves in about 4w). As w → 0 it is
// the pose graph above (w = 0: exactly, a hard switch at S_k). Scalar T: double or a Ceres Jet.
template <class T> struct PoseGraphOf {
  std::vector<VecD<T>> poses;  // one target per active mode
  std::vector<T> durations;
  bool cyclic = true;
  std::vector<int> active;     // mode index of each pose entry (ActiveModes)
  bool empty() const { return poses.empty(); }
  template <int Dim> static PoseGraphOf From(const BodyModelN<Dim>& body, const PoseGraph& g) {
    PoseGraphOf c;
    c.cyclic = g.cyclic;
    c.active = ActiveModes(body);
    for (const Eigen::VectorXd& pose : g.poses) c.poses.push_back(pose.cast<T>());
    for (double d : g.durations) c.durations.push_back(T(d));
    return c;
  }
};

// γ0(t) of the smoothed graph, one per mode (0 on passive modes).
template <class T> VecD<T> SmoothPoseTargets(const PoseGraphOf<T>& c, int num_modes, double t, double width) {
  VecD<T> target = VecD<T>::Zero(num_modes);
  if (c.empty()) return target;
  const int n = int(c.poses.size());
  VecD<T> active = c.poses[0];
  T switch_time(0.0);
  // switches far after t add nothing (σ < e^-30); the count bound only guards silly times
  for (int k = 1; k < 1000000; ++k) {
    if (!c.cyclic && k >= n) break;
    switch_time += c.durations[(k - 1) % n];
    if (ScalarValue(switch_time) > t + 30.0 * width) break;
    const VecD<T> jump = c.poses[k % n] - c.poses[(k - 1) % n];
    if (width > 0) {
      using std::exp;
      const T sigma = T(1.0) / (T(1.0) + exp(-(T(t) - switch_time) / T(width)));
      active += jump * sigma;
    } else if (ScalarValue(switch_time) <= t) {
      active += jump;  // a hard switch
    }
  }
  for (size_t i = 0; i < c.active.size(); ++i) target[c.active[i]] = active[int(i)];
  return target;
}
template <int Dim>
Eigen::VectorXd SmoothPoseTargets(const BodyModelN<Dim>& body, const PoseGraph& g, double t, double width) {
  return SmoothPoseTargets(PoseGraphOf<double>::From(body, g), body.num_modes(), t, width);
}

// Keyframed mode amplitudes (§4.10.1): keys (time, amplitudes of every mode) interpolated
// linearly, as in the thesis, or by a C1 cubic (Catmull–Rom tangents) as an option.
enum class Interpolation { kLinear, kSmooth };

struct Keyframes {
  std::vector<double> times;              // strictly increasing, the first is 0
  std::vector<Eigen::VectorXd> amplitudes;  // one per key, one value per mode
  Interpolation interpolation = Interpolation::kLinear;

  double Duration() const { return times.empty() ? 0.0 : times.back(); }
  // γ(t) and γ̇(t), t clamped to [0, Duration()]. At a key, γ̇ is the slope of the segment
  // that ends there (the velocity the keyframed motion "had"), so the hand-over at the end
  // keeps the velocity of the last segment.
  void Evaluate(double t, Eigen::VectorXd* gamma, Eigen::VectorXd* gamma_dot) const;
  std::string Validate(int num_modes) const;
};

// A point of the body held in place while keyframed deformation runs (§4.10.1: "so that when
// the object deforms this point remains in place", e.g. a foot on the ground).
struct HeldPoint {
  bool enabled = false;
  // (s, t, u); a 2D body reads (s, t), as constraint ends keep three rows for either dimension
  Eigen::Vector3d lattice_coords = Eigen::Vector3d::Zero();
  // The coordinates for a body of dimension Dim.
  template <int Dim> Eigen::Matrix<double, Dim, 1> coords() const { return lattice_coords.head<Dim>(); }
};

// The full state (q, q̇ in body/group.h's layout) of a keyframed body at amplitudes γ, γ̇,
// placed by `placement` (positions whose first Group<Dim>::kRigidParams entries, the
// translation and the rotation, are kept; the rest is ignored): when a point is held, t is
// solved so that the point stays at `anchor`: t = anchor − R (b0 + B γ) and ṫ = −R B γ̇
// (the rotation does not turn: θ̇ = 0, ω = 0); otherwise t is the placement's and ṫ = 0.
template <int Dim>
void KeyframedState(const BodyModelN<Dim>& body, const HeldPoint& hold, const Eigen::Matrix<double, Dim, 1>& anchor,
                    const Eigen::VectorXd& placement, const Eigen::VectorXd& gamma, const Eigen::VectorXd& gamma_dot,
                    Eigen::VectorXd* q, Eigen::VectorXd* qd);

// World position of a point given by lattice coordinates at positions q.
template <int Dim>
Eigen::Matrix<double, Dim, 1> PointAt(const BodyModelN<Dim>& body, const Eigen::Matrix<double, Dim, 1>& lattice_coords,
                                      const Eigen::VectorXd& q);

}  // namespace wobble::control
