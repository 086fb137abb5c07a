#include "wobble/control/control.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "wobble/dynamics/kinematics.h"

namespace wobble::control {

namespace {
// −(2K_d (γ_d − γ0_d) + c_d γ̇_d) of every mode, either dimension.
template <class Modes, class G, class Gd>
Eigen::VectorXd PdForces(const Modes& modes, const G& gamma, const Gd& gamma_dot, const VecD<double>& target) {
  const int D = int(modes.size());
  Eigen::VectorXd f(D);
  for (int d = 0; d < D; ++d) {
    const double t = target.size() == D ? target[d] : 0.0;
    f[d] = -(2.0 * modes[size_t(d)].stiffness * (gamma[d] - t) + modes[size_t(d)].damping * gamma_dot[d]);
  }
  return f;
}
}  // namespace

Eigen::VectorXd ModeControlForces(const BodyModel& body, const BodyState<2, double>& s) {
  const int D = body.num_modes();
  return PdForces(body.modes(), s.q.tail(D), s.qd.tail(D), s.mode_target);
}

Eigen::VectorXd ModeControlForces(const BodyModelN<3>& body, const BodyState<3, double>& s) {
  const int D = body.num_modes();
  return PdForces(body.modes(), s.gamma(), s.qd.tail(D), s.mode_target);
}

void ControlEnergy::Accumulate(const BodyModel& body, const BodyState<2, double>& s, double dt) {
  const Eigen::VectorXd f = ModeControlForces(body, s);
  for (int d = 0; d < f.size(); ++d) {
    const double power = f[d] * s.qd[kRigidDofs + d];
    consumed += std::abs(power) * dt;
    work += power * dt;
  }
}

void ControlEnergy::Accumulate(const BodyModelN<3>& body, const BodyState<3, double>& s, double dt) {
  const Eigen::VectorXd f = ModeControlForces(body, s);
  const int first = Group<3>::kRigidDofs;
  for (int d = 0; d < f.size(); ++d) {
    const double power = f[d] * s.qd[first + d];
    consumed += std::abs(power) * dt;
    work += power * dt;
  }
}

double PoseGraph::Period() const {
  double p = 0.0;
  for (double d : durations) p += d;
  return p;
}

int PoseGraph::PoseAt(double t) const {
  if (poses.empty()) return -1;
  const double period = Period();
  if (cyclic) {
    t = std::fmod(std::max(t, 0.0), period);
  } else if (t >= period) {
    return int(poses.size()) - 1;
  }
  double end = 0.0;
  for (int i = 0; i < int(durations.size()); ++i) {
    end += durations[i];
    if (t < end) return i;
  }
  return int(poses.size()) - 1;  // t == period after rounding
}

std::string PoseGraph::Validate(int num_active) const {
  std::ostringstream err;
  if (poses.size() != durations.size()) return "every pose needs a transition time";
  for (size_t i = 0; i < poses.size(); ++i) {
    if (poses[i].size() != num_active) {
      err << "pose " << i + 1 << " has " << poses[i].size() << " targets but the body has " << num_active
          << " active modes";
      return err.str();
    }
    if (!poses[i].allFinite()) {
      err << "pose " << i + 1 << " has a non-finite target";
      return err.str();
    }
    if (!(durations[i] > 0.0) || !std::isfinite(durations[i])) {
      err << "pose " << i + 1 << " needs a positive finite transition time, got " << durations[i];
      return err.str();
    }
  }
  return "";
}

std::string Keyframes::Validate(int num_modes) const {
  std::ostringstream err;
  if (times.size() != amplitudes.size()) return "every key needs amplitudes";
  if (times.size() < 2) return "keyframing needs at least two keys";
  if (times[0] != 0.0) return "the first key must be at time 0";
  for (size_t i = 0; i < times.size(); ++i) {
    if (amplitudes[i].size() != num_modes || !amplitudes[i].allFinite()) {
      err << "key " << i + 1 << " needs one finite amplitude per mode (" << num_modes << ")";
      return err.str();
    }
    if (i > 0 && !(times[i] > times[i - 1])) {
      err << "key times must increase: key " << i + 1 << " at " << times[i] << " is not after " << times[i - 1];
      return err.str();
    }
  }
  return "";
}

void Keyframes::Evaluate(double t, Eigen::VectorXd* gamma, Eigen::VectorXd* gamma_dot) const {
  const int n = int(times.size());
  t = std::min(std::max(t, 0.0), Duration());
  // the segment [i, i+1] holding t; a t exactly at a key belongs to the segment ending there
  int i = 0;
  while (i + 2 < n && t > times[i + 1]) ++i;
  const double t0 = times[i], t1 = times[i + 1], h = t1 - t0;
  const Eigen::VectorXd& p0 = amplitudes[i];
  const Eigen::VectorXd& p1 = amplitudes[i + 1];
  const double u = (t - t0) / h;
  if (interpolation == Interpolation::kLinear) {
    *gamma = p0 + u * (p1 - p0);
    *gamma_dot = (p1 - p0) / h;
    return;
  }
  // cubic Hermite with Catmull–Rom tangents (one-sided at the ends): C1 through the keys
  auto tangent = [&](int k) -> Eigen::VectorXd {
    if (k == 0) return (amplitudes[1] - amplitudes[0]) / (times[1] - times[0]);
    if (k == n - 1) return (amplitudes[n - 1] - amplitudes[n - 2]) / (times[n - 1] - times[n - 2]);
    return (amplitudes[k + 1] - amplitudes[k - 1]) / (times[k + 1] - times[k - 1]);
  };
  const Eigen::VectorXd m0 = tangent(i) * h, m1 = tangent(i + 1) * h;
  const double u2 = u * u, u3 = u2 * u;
  *gamma = (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * m1;
  *gamma_dot = ((6 * u2 - 6 * u) * p0 + (3 * u2 - 4 * u + 1) * m0 + (-6 * u2 + 6 * u) * p1 + (3 * u2 - 2 * u) * m1) / h;
}

template <int Dim>
Eigen::Matrix<double, Dim, 1> PointAt(const BodyModelN<Dim>& body, const Eigen::Matrix<double, Dim, 1>& lattice_coords,
                                      const Eigen::VectorXd& q) {
  Eigen::Matrix<double, Dim, 1> b0;
  MatND<double, Dim> B;
  body.LocalBasis(lattice_coords, &b0, &B);
  const VecQ<double> qq = q;
  return WorldFromLocal(Frame<Dim, double>(qq), LocalPosition<double>(b0, B, qq));
}

template <int Dim>
void KeyframedState(const BodyModelN<Dim>& body, const HeldPoint& hold, const Eigen::Matrix<double, Dim, 1>& anchor,
                    const Eigen::VectorXd& placement, const Eigen::VectorXd& gamma, const Eigen::VectorXd& gamma_dot,
                    Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  const int D = body.num_modes(), rigid = Group<Dim>::kRigidParams;
  q->setZero(rigid + D);
  qd->setZero(Group<Dim>::kRigidDofs + D);
  q->head(rigid) = placement.head(rigid);
  q->tail(D) = gamma;
  qd->tail(D) = gamma_dot;
  if (!hold.enabled) return;
  // x_p = t + R (b0 + B γ) = anchor (Eq. 4.2) fixes t; differentiating with R still gives ṫ
  Eigen::Matrix<double, Dim, 1> b0;
  MatND<double, Dim> B;
  body.LocalBasis(hold.coords<Dim>(), &b0, &B);
  const Eigen::Matrix<double, Dim, Dim> R = Group<Dim>::RotationOf(VecQ<double>(*q));
  q->template head<Dim>() = anchor - R * (b0 + B * gamma);
  qd->template head<Dim>() = -R * (B * gamma_dot);
}

template Eigen::Vector2d PointAt(const BodyModel&, const Eigen::Vector2d&, const Eigen::VectorXd&);
template Eigen::Vector3d PointAt(const BodyModelN<3>&, const Eigen::Vector3d&, const Eigen::VectorXd&);
template void KeyframedState(const BodyModel&, const HeldPoint&, const Eigen::Vector2d&, const Eigen::VectorXd&,
                             const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd*, Eigen::VectorXd*);
template void KeyframedState(const BodyModelN<3>&, const HeldPoint&, const Eigen::Vector3d&, const Eigen::VectorXd&,
                             const Eigen::VectorXd&, const Eigen::VectorXd&, Eigen::VectorXd*, Eigen::VectorXd*);

}  // namespace wobble::control
