#include "wobble/analysis/conditioning.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "wobble/dynamics/kinematics.h"
#include "wobble/dynamics/step.h"

namespace wobble::analysis {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

double RadToDeg(double a) { return a * 180.0 / kPi; }

// σ_max/σ_min with the numerical-rank test of ConditionNumber.
double CondFromSingularValues(const Eigen::VectorXd& sv, bool* singular) {
  const double hi = sv.maxCoeff(), lo = sv.minCoeff();
  *singular = !(lo > double(sv.size()) * std::numeric_limits<double>::epsilon() * hi);
  return *singular ? kInf : hi / lo;
}

std::string Join(const std::vector<Participant>& parts) {
  std::ostringstream out;
  for (size_t i = 0; i < parts.size(); ++i) {
    if (i) out << (parts[i].weight < 0 ? " - " : " + ");
    else if (parts[i].weight < 0) out << "-";
    out << std::abs(parts[i].weight) << " '" << parts[i].dof << "'";
  }
  return out.str();
}

std::string Degrees(double deg) {
  std::ostringstream out;
  out.precision(deg < 0.1 ? 2 : 3);
  out << deg << "°";
  return out.str();
}

}  // namespace

ConditionNumber Condition(const Eigen::MatrixXd& M) {
  ConditionNumber c;
  c.singular_values = Eigen::JacobiSVD<Eigen::MatrixXd>(M).singularValues();
  c.cond = CondFromSingularValues(c.singular_values, &c.singular);
  const Eigen::VectorXd diag = M.diagonal();
  if ((diag.array() > 0.0).all()) {
    const Eigen::VectorXd s = diag.array().rsqrt();
    const Eigen::MatrixXd scaled = s.asDiagonal() * M * s.asDiagonal();
    bool scaled_singular = false;
    c.cond_scaled = CondFromSingularValues(Eigen::JacobiSVD<Eigen::MatrixXd>(scaled).singularValues(), &scaled_singular);
  } else {
    c.cond_scaled = kInf;
  }
  return c;
}

ConditionNumber MassMatrixCondition(const BodyModel& body, const Eigen::VectorXd& q) {
  MatQ<double> M;
  MassMatrix(body.moments(), VecQ<double>(q), &M);
  return Condition(M);
}

double Cond1Estimate(const Eigen::MatrixXd& A) {
  const int n = int(A.rows());
  if (n == 0) return 1.0;
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(A);
  const double norm_a = A.cwiseAbs().colwise().sum().maxCoeff();
  auto solve = [&](const Eigen::VectorXd& b) { return Eigen::VectorXd(lu.solve(b)); };
  auto solve_t = [&](const Eigen::VectorXd& b) { return Eigen::VectorXd(lu.transpose().solve(b)); };
  auto sign = [](const Eigen::VectorXd& v) {
    return Eigen::VectorXd(v.unaryExpr([](double x) { return x >= 0.0 ? 1.0 : -1.0; }));
  };
  // Hager (1984) as refined by Higham (1988): a gradient ascent of ‖A⁻¹x‖₁ over ‖x‖₁ = 1.
  Eigen::VectorXd x = Eigen::VectorXd::Constant(n, 1.0 / n);
  Eigen::VectorXd y = solve(x);
  if (!y.allFinite()) return kInf;
  double estimate = y.lpNorm<1>();
  Eigen::VectorXd xi = sign(y);
  Eigen::VectorXd z = solve_t(xi);
  for (int iter = 0; iter < 5; ++iter) {
    Eigen::Index j;
    const double z_max = z.cwiseAbs().maxCoeff(&j);
    if (z_max <= z.dot(x)) break;
    x.setZero();
    x[j] = 1.0;
    y = solve(x);
    if (!y.allFinite()) return kInf;
    const Eigen::VectorXd xi_new = sign(y);
    const double next = y.lpNorm<1>();
    if (next <= estimate) break;
    estimate = next;
    if (xi_new == xi) break;  // the same sign pattern again: converged
    xi = xi_new;
    z = solve_t(xi);
  }
  // Higham's safeguard against the iteration's blind spots: an alternating, growing vector.
  Eigen::VectorXd alt(n);
  for (int i = 0; i < n; ++i) alt[i] = (i % 2 ? -1.0 : 1.0) * (1.0 + (n > 1 ? double(i) / (n - 1) : 0.0));
  const Eigen::VectorXd y_alt = solve(alt);
  if (!y_alt.allFinite()) return kInf;
  estimate = std::max(estimate, 2.0 * y_alt.lpNorm<1>() / (3.0 * n));
  return norm_a * estimate;
}

template <int Dim>
DeformationModeN<Dim> SquashMode(const LatticeN<Dim>& lattice, double phi, const Squash& squash,
                                 const std::string& name) {
  using Point = Eigen::Matrix<double, Dim, 1>;
  using Matrix = Eigen::Matrix<double, Dim, Dim>;
  Matrix R;  // the squash axis turned by φ in the x–y plane (about z in 3D)
  if constexpr (Dim == 2) R = Eigen::Rotation2Dd(phi).toRotationMatrix();
  else R = Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Point scale = Point::Constant(squash.expand);  // bulging across the axis in every other direction
  scale[0] = -squash.compress;
  const Matrix A = R * scale.asDiagonal() * R.transpose();
  Point anchor = lattice.origin() + squash.anchor_st.x() * lattice.axis(0) + squash.anchor_st.y() * lattice.axis(1);
  if constexpr (Dim == 3) anchor += 0.5 * lattice.axis(2);
  DeformationModeN<Dim> mode;
  mode.name = name;
  mode.lattice_size = lattice.sizes();
  for (const Point& p : lattice.RestPoints()) mode.displacement.push_back(A * (p - anchor));
  return mode;
}
template DeformationModeN<2> SquashMode(const LatticeN<2>&, double, const Squash&, const std::string&);
template DeformationModeN<3> SquashMode(const LatticeN<3>&, double, const Squash&, const std::string&);

std::vector<SweepSample> AngleSweep(const BodyDef& def, const std::vector<double>& phis, const Squash& squash,
                                    const Eigen::VectorXd& q) {
  const DeformationMode vertical = SquashMode(def.lattice, kPi / 2, squash, "vsquash");
  std::vector<SweepSample> out;
  for (double phi : phis) {
    const BodyModel body(def, {vertical, SquashMode(def.lattice, phi, squash, "squash(phi)")});
    out.push_back({phi, MassMatrixCondition(body, q)});
  }
  return out;
}

std::vector<SweepSample> AngleSweep(const BodyDefN<3>& def, const std::vector<double>& phis, const Squash& squash) {
  const DeformationModeN<3> vertical = SquashMode(def.lattice, kPi / 2, squash, "vsquash");
  std::vector<SweepSample> out;
  for (double phi : phis) {
    const BodyModelN<3> body(def, {vertical, SquashMode(def.lattice, phi, squash, "squash(phi)")});
    out.push_back({phi, MassMatrixCondition(body, RestState<3, double>(body))});
  }
  return out;
}

std::string LevelName(ModeSetReport::Level level) {
  switch (level) {
    case ModeSetReport::Level::kOk: return "ok";
    case ModeSetReport::Level::kWarning: return "warning";
    case ModeSetReport::Level::kError: return "error";
  }
  return "?";
}

namespace {
// The check on a body's mass matrix M at some state: the same in 2D (rigid dofs tx, ty, θ) and
// 3D (tx, ty, tz and the three body-frame rotations).
template <int Dim>
ModeSetReport CheckModes(const BodyModelN<Dim>& body, const Eigen::MatrixXd& M, const ModeCheckOptions& options) {
  const int D = body.num_modes(), nq = body.num_q();
  constexpr int kRigid = Group<Dim>::kRigidDofs;
  ModeSetReport report;
  if (Dim == 2)
    report.dofs = {"translation x", "translation y", "rotation"};
  else
    report.dofs = {"translation x", "translation y", "translation z", "rotation x", "rotation y", "rotation z"};
  for (const auto& m : body.modes()) report.dofs.push_back(m.name);
  report.condition = Condition(M);

  std::vector<std::string> errors, warnings;
  // Visibility: what the mass points see of each mode's lattice motion (§4.10.3).
  const MassMomentsN<Dim>& mm = body.moments();
  std::vector<bool> visible(nq, true);
  report.modes.resize(D);
  for (int d = 0; d < D; ++d) {
    ModeFinding& f = report.modes[d];
    f.mode = body.modes()[d].name;
    double lattice_ms = 0.0;
    for (const auto& u : body.modes()[d].displacement) lattice_ms += u.squaredNorm();
    lattice_ms /= double(body.modes()[d].displacement.size());
    if (!(lattice_ms > 0.0)) {
      errors.push_back("mode '" + f.mode + "' is zero: it moves no lattice point");
      visible[kRigid + d] = false;
      continue;
    }
    f.visibility = std::sqrt(std::max(0.0, mm.G(d, d)) / mm.m / lattice_ms);
    if (f.visibility < 1e-9) {
      errors.push_back("mode '" + f.mode + "' moves no mass point: the lattice region it moves holds no mass (" +
                       "§4.10.3), so M is singular");
      visible[kRigid + d] = false;
    } else if (f.visibility < options.warn_visibility) {
      std::ostringstream w;
      w << "mode '" << f.mode << "' barely moves the mass points (visibility " << f.visibility
        << "): most of what it moves is lattice without mass";
      warnings.push_back(w.str());
    }
  }
  // Pairwise angles between the modes' fields, ⟨u, v⟩ = Σ m_k u_k·v_k = G.
  report.pair_angle_deg = Eigen::MatrixXd::Zero(D, D);
  for (int a = 0; a < D; ++a)
    for (int b = 0; b < D; ++b) {
      const double denom = std::sqrt(mm.G(a, a) * mm.G(b, b));
      const double c = denom > 0 ? std::min(1.0, std::abs(mm.G(a, b)) / denom) : 1.0;
      report.pair_angle_deg(a, b) = a == b ? 0.0 : RadToDeg(std::acos(c));
    }

  // Angle of each mode to the span of all other visible degrees of freedom, in the unit-free
  // scaled Gram matrix N = S M S (M is the Gram matrix of the fields J_k columns).
  std::vector<int> idx;
  for (int i = 0; i < nq; ++i)
    if (visible[i]) idx.push_back(i);
  const int n = int(idx.size());
  Eigen::MatrixXd N(n, n);
  Eigen::VectorXd s(n);
  for (int a = 0; a < n; ++a) s[a] = 1.0 / std::sqrt(M(idx[a], idx[a]));
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) N(a, b) = s[a] * M(idx[a], idx[b]) * s[b];
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(N);
  const double tol = double(n) * std::numeric_limits<double>::epsilon() * eig.eigenvalues().maxCoeff();
  const bool dependent = eig.eigenvalues().minCoeff() <= tol;
  Eigen::MatrixXd Ninv;
  if (!dependent) Ninv = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  for (int a = 0; a < n; ++a) {
    const int dof = idx[a];
    if (dof < kRigid) continue;
    ModeFinding& f = report.modes[dof - kRigid];
    Eigen::VectorXd combo = Eigen::VectorXd::Zero(n);  // mode ≈ Σ combo_b dof_b (scaled)
    if (dependent) {
      // the null vectors v (N v = 0) this mode takes part in: mode = −Σ_{b≠a} v_b/v_a dof_b
      int best = -1;
      double best_share = 0.0;
      for (int k = 0; k < n; ++k) {
        if (eig.eigenvalues()[k] > tol) continue;
        const double share = std::abs(eig.eigenvectors()(a, k));
        if (share > best_share) best_share = share, best = k;
      }
      if (best >= 0 && best_share > 1e-6) {
        f.angle_to_others_deg = 0.0;
        combo = -eig.eigenvectors().col(best) / eig.eigenvectors()(a, best);
      } else {
        f.angle_to_others_deg = 90.0;  // not part of the dependency; its own angle is undefined here
      }
    } else {
      const double sin2 = std::clamp(1.0 / Ninv(a, a), 0.0, 1.0);
      f.angle_to_others_deg = RadToDeg(std::asin(std::sqrt(sin2)));
      combo = -Ninv.col(a) / Ninv(a, a);
    }
    combo[a] = 0.0;
    const double biggest = combo.cwiseAbs().maxCoeff();
    if (biggest > 0.0) {
      for (int b = 0; b < n; ++b)
        if (std::abs(combo[b]) >= 0.1 * biggest) f.closest_combination.push_back({report.dofs[idx[b]], combo[b] / biggest});
      std::sort(f.closest_combination.begin(), f.closest_combination.end(),
                [](const Participant& x, const Participant& y) { return std::abs(x.weight) > std::abs(y.weight); });
    }
    if (f.angle_to_others_deg < report.smallest_angle_deg) {
      report.smallest_angle_deg = f.angle_to_others_deg;
      report.smallest_mode = f.mode;
    }
  }
  // Messages for the closest dependency (one per dependency, not once per member).
  if (!report.smallest_mode.empty()) {
    const ModeFinding* worst = nullptr;
    for (const ModeFinding& f : report.modes)
      if (f.mode == report.smallest_mode) worst = &f;
    const std::string what = "mode '" + worst->mode + "' is " +
                             (report.smallest_angle_deg == 0.0 ? std::string("a combination of ")
                                                               : "within " + Degrees(report.smallest_angle_deg) + " of ") +
                             Join(worst->closest_combination) + " (mass inner product)";
    if (report.smallest_angle_deg == 0.0)
      errors.push_back(what + ": the modes are dependent and M is singular");
    else if (report.smallest_angle_deg < options.warn_angle_deg)
      warnings.push_back(what + ": M is ill-conditioned (cond " + std::to_string(report.condition.cond) + ")");
  }
  if (report.condition.singular && errors.empty())
    errors.push_back("the mass matrix is singular at this state");
  report.messages = errors;
  report.messages.insert(report.messages.end(), warnings.begin(), warnings.end());
  report.level = !errors.empty() ? ModeSetReport::Level::kError
                 : !warnings.empty() ? ModeSetReport::Level::kWarning
                                     : ModeSetReport::Level::kOk;
  return report;
}

}  // namespace

ModeSetReport CheckModeSet(const BodyModel& body, const Eigen::VectorXd& q_in, const ModeCheckOptions& options) {
  const Eigen::VectorXd q = q_in.size() ? q_in : Eigen::VectorXd::Zero(body.num_q());
  MatQ<double> M;
  MassMatrix(body.moments(), VecQ<double>(q), &M);
  return CheckModes(body, Eigen::MatrixXd(M), options);
}

ModeSetReport CheckModeSet(const BodyModelN<3>& body, const ModeCheckOptions& options) {
  const BodyState<3, double> rest = RestState<3, double>(body);
  const ShapeMoments<double> sm(body.moments(), rest.gamma());
  MatQ<double> M;
  MassMatrix(body.moments(), sm, Mat3<double>(Mat3<double>::Identity()), &M);
  return CheckModes(body, Eigen::MatrixXd(M), options);
}

ConditionNumber MassMatrixCondition(const BodyModelN<3>& body, const BodyState<3, double>& s) {
  const ShapeMoments<double> sm(body.moments(), s.gamma());
  MatQ<double> M;
  MassMatrix(body.moments(), sm, Mat3<double>(s.orientation().toRotationMatrix()), &M);
  return Condition(Eigen::MatrixXd(M));
}

}  // namespace wobble::analysis
