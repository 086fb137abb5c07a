#include "wobble/record/trajectory.h"

#include "wobble/body/group.h"
#include "wobble/core/errors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace wobble::record {

namespace {
const char* const kEnergyNames[] = {"kinetic", "gravity", "modes", "ground", "springs", "total"};
constexpr int kNumEnergies = 6;
using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

}  // namespace

BodyInfo DescribeBody(const World& world, int body) {
  BodyInfo info;
  info.name = world.body_name(body);
  info.kind = world.kind(body);
  info.dim = world.dim(body);
  if (world.IsFfd(body, 2)) {
    const BodyModel& m = world.body<2>(body);
    info.set_ffd(world.shared_body<2>(body));  // drawing after the world is gone
    info.coordinate_names = {"tx", "ty", "theta"};
    for (const DeformationMode& mode : m.modes()) info.coordinate_names.push_back(mode.name);
  } else if (world.IsFfd(body, 3)) {
    info.set_ffd(world.shared_body<3>(body));
    info.coordinate_names = {"tx", "ty", "tz", "qw", "qx", "qy", "qz"};
    info.velocity_names = {"dtx", "dty", "dtz", "wx", "wy", "wz"};
    for (const DeformationModeN<3>& mode : world.body<3>(body).modes()) {
      info.coordinate_names.push_back(mode.name);
      info.velocity_names.push_back("d" + mode.name);
    }
  } else {
    const LinearBodyModel& m = world.linear_model(body);
    info.linear = world.shared_linear_model(body);
    info.ground_contact = world.ground_contact(body);
    for (int i = 0; i < m.dim(); ++i)
      for (int s = 0; s < m.basis_size(); ++s) info.coordinate_names.push_back("r" + std::to_string(i) + "_" + std::to_string(s));
  }
  if (info.velocity_names.empty())
    for (const std::string& name : info.coordinate_names) info.velocity_names.push_back("d" + name);
  info.num_q = int(info.coordinate_names.size());
  info.num_v = int(info.velocity_names.size());
  return info;
}

int BodyInfo::num_modes() const {
  if (kind == BodyKind::kLinear) return 0;
  const int of_model = std::visit([](const auto& m) { return m ? m->num_modes() : -1; }, ffd_);
  if (of_model >= 0) return of_model;
  const int rigid = dim == 3 ? Group<3>::kRigidParams : Group<2>::kRigidParams;
  if (num_q < rigid)
    throw std::logic_error("BodyInfo::num_modes: the FFD body '" + name + "' has neither a model nor its coordinates (num_q " +
                           std::to_string(num_q) + " < " + std::to_string(rigid) + " rigid ones)");
  return num_q - rigid;
}

Trajectory::Trajectory(const World& world) {
  for (int b = 0; b < world.num_bodies(); ++b) bodies_.push_back(DescribeBody(world, b));
  Build();
}

Trajectory::Trajectory(std::vector<BodyInfo> bodies) : bodies_(std::move(bodies)) { Build(); }

void Trajectory::Build() {
  columns_ = {"t"};
  layout_.clear();
  const bool prefixed = bodies_.size() > 1;
  for (BodyInfo& b : bodies_) {  // bodies built by hand may leave the velocities to us
    if (b.velocity_names.empty())
      for (const std::string& name : b.coordinate_names) b.velocity_names.push_back("d" + name);
    b.num_v = int(b.velocity_names.size());
  }
  for (const BodyInfo& b : bodies_) {
    const std::string p = prefixed ? b.name + "." : "";
    Layout l;
    l.q = int(columns_.size());
    for (const std::string& c : b.coordinate_names) columns_.push_back(p + c);
    l.qd = int(columns_.size());
    for (const std::string& c : b.velocity_names) columns_.push_back(p + c);
    l.targets = int(columns_.size());
    if (b.kind != BodyKind::kLinear) {
      l.num_targets = b.num_modes();
      for (int d = b.num_q - l.num_targets; d < b.num_q; ++d) columns_.push_back(p + "target_" + b.coordinate_names[d]);
    }
    l.energies = int(columns_.size());
    for (const char* e : kEnergyNames) columns_.push_back(p + e);
    l.contacts = int(columns_.size());
    columns_.push_back(p + "contacts");
    columns_.push_back(p + "penetration");
    layout_.push_back(l);
  }
  for (const char* c : {"control_energy", "pose", "violation"}) columns_.push_back(c);
  width_ = int(columns_.size());
  data_.clear();
}

int Trajectory::Column(const std::string& name) const {
  for (int i = 0; i < num_columns(); ++i)
    if (columns_[i] == name) return i;
  return -1;
}

int Trajectory::Append(const World& world, double control_energy, int pose) {
  if (world.num_bodies() != num_bodies())
    throw std::invalid_argument("Trajectory::Append: the world has " + std::to_string(world.num_bodies()) +
                                " bodies, the trajectory " + std::to_string(num_bodies()));
  const size_t start = data_.size();
  data_.resize(start + size_t(width_), 0.0);
  double* row = data_.data() + start;
  row[0] = world.time();
  for (int b = 0; b < num_bodies(); ++b) {
    const Layout& l = layout_[b];
    const int nq = bodies_[b].num_q;
    if (bodies_[b].IsFfd(2)) {
      const BodyState<2, double>& s = world.state<2>(b);
      Eigen::Map<Eigen::VectorXd>(row + l.q, nq) = s.q;
      Eigen::Map<Eigen::VectorXd>(row + l.qd, nq) = s.qd;
      if (s.mode_target.size() == l.num_targets) Eigen::Map<Eigen::VectorXd>(row + l.targets, l.num_targets) = s.mode_target;
      row[l.contacts] = double(s.contacts.size());
      row[l.contacts + 1] = s.penetration;
    } else if (bodies_[b].IsFfd(3)) {
      const BodyState<3, double>& s = world.state<3>(b);
      Eigen::Map<Eigen::Vector3d>(row + l.q) = s.translation();
      const Eigen::Quaterniond& o = s.orientation();
      row[l.q + 3] = o.w(), row[l.q + 4] = o.x(), row[l.q + 5] = o.y(), row[l.q + 6] = o.z();
      Eigen::Map<Eigen::VectorXd>(row + l.q + 7, s.gamma().size()) = s.gamma();
      Eigen::Map<Eigen::VectorXd>(row + l.qd, bodies_[b].num_v) = s.qd;
      if (s.mode_target.size() == l.num_targets) Eigen::Map<Eigen::VectorXd>(row + l.targets, l.num_targets) = s.mode_target;
      row[l.contacts] = double(s.contacts.size());
      row[l.contacts + 1] = s.penetration;
    } else {
      const Eigen::MatrixXd& R = world.linear_R(b);
      const Eigen::MatrixXd& Rd = world.linear_R_dot(b);
      Eigen::Map<RowMajor>(row + l.q, R.rows(), R.cols()) = R;
      Eigen::Map<RowMajor>(row + l.qd, R.rows(), R.cols()) = Rd;
      const LinearContacts& c = world.linear_contacts(b);
      row[l.contacts] = double(c.size());
      row[l.contacts + 1] = c.penetration;
    }
    const Energies e = world.ComputeEnergies(b);
    const double values[kNumEnergies] = {e.kinetic, e.gravity, e.modes, e.ground, e.springs, e.total()};
    for (int i = 0; i < kNumEnergies; ++i) row[l.energies + i] = values[i];
  }
  row[width_ - 3] = control_energy;
  row[width_ - 2] = pose;
  row[width_ - 1] = world.num_enabled_constraints() > 0 ? world.MaxViolation() : 0.0;
  for (int c = 0; c < width_; ++c)
    if (!std::isfinite(row[c])) {
      data_.resize(start);
      return c;
    }
  return -1;
}

void Trajectory::AppendRow(const std::vector<double>& row) {
  if (int(row.size()) != width_)
    throw std::invalid_argument("Trajectory::AppendRow: " + std::to_string(row.size()) + " values for " +
                                std::to_string(width_) + " columns");
  data_.insert(data_.end(), row.begin(), row.end());
}

Eigen::Map<const Eigen::VectorXd> Trajectory::q(int k, int body) const {
  return {Row(k) + layout_[body].q, bodies_[body].num_q};
}
Eigen::Map<const Eigen::VectorXd> Trajectory::qd(int k, int body) const {
  return {Row(k) + layout_[body].qd, bodies_[body].num_v};
}
Eigen::Map<const Eigen::VectorXd> Trajectory::targets(int k, int body) const {
  return {Row(k) + layout_[body].targets, layout_[body].num_targets};
}

Energies Trajectory::energies(int k, int body) const {
  const double* e = Row(k) + layout_[body].energies;
  Energies out;
  out.kinetic = e[0];
  out.gravity = e[1];
  out.modes = e[2];
  out.ground = e[3];
  out.springs = e[4];
  const BodyInfo& b = bodies_[body];
  if (b.has_ffd() && layout_[body].num_targets == b.num_modes()) {  // K (γ − γ0)² per mode
    const Eigen::Map<const Eigen::VectorXd> qk = q(k, body), tk = targets(k, body);
    const int first = b.num_q - b.num_modes();
    for (int d = 0; d < b.num_modes(); ++d) {
      const double offset = qk[first + d] - tk[d];
      out.per_mode.push_back(b.mode_stiffness(d) * offset * offset);
    }
  }
  return out;
}

int Trajectory::contacts(int k, int body) const { return int(Row(k)[layout_[body].contacts]); }
double Trajectory::penetration(int k, int body) const { return Row(k)[layout_[body].contacts + 1]; }

void Trajectory::Restore(int k, World& world) const {
  RestoreRow(Row(k), world);
  world.SetTime(time(k));
}

void Trajectory::RestoreRow(const double* row, World& world) const {
  if (world.num_bodies() != num_bodies()) throw std::invalid_argument("Trajectory::Restore: another world's trajectory");
  for (int b = 0; b < num_bodies(); ++b) {
    const Eigen::Map<const Eigen::VectorXd> qb(row + layout_[b].q, bodies_[b].num_q),
        qdb(row + layout_[b].qd, bodies_[b].num_v), targets(row + layout_[b].targets, layout_[b].num_targets);
    if (bodies_[b].IsFfd(2)) {
      world.SetState(b, qb, qdb);
      world.SetModeTargets(b, targets.isZero(0.0) ? Eigen::VectorXd() : Eigen::VectorXd(targets));
    } else if (bodies_[b].IsFfd(3)) {
      const Eigen::Quaterniond o(qb[3], qb[4], qb[5], qb[6]);  // unit as recorded, to rounding
      world.SetState(b, PositionsOf(qb.head<3>(), o.normalized(), qb.tail(bodies_[b].num_modes())), qdb);
      world.SetModeTargets(b, targets.isZero(0.0) ? Eigen::VectorXd() : Eigen::VectorXd(targets));
    } else {
      const int d = bodies_[b].dim, n = bodies_[b].num_q / d;
      world.SetLinearState(b, Eigen::Map<const RowMajor>(qb.data(), d, n), Eigen::Map<const RowMajor>(qdb.data(), d, n));
    }
  }
}

void Trajectory::RestoreAt(double t, World& world) const {
  if (empty()) throw std::invalid_argument("Trajectory::RestoreAt: no samples");
  // the last sample at or before t (the first when t is before it)
  int k = 0, above = size();
  while (above - k > 1) {
    const int mid = (k + above) / 2;
    if (time(mid) <= t) k = mid;
    else above = mid;
  }
  if (k + 1 == size() || !(t > time(k))) {
    Restore(k, world);
    world.SetTime(t);
    return;
  }
  const double alpha = (t - time(k)) / (time(k + 1) - time(k));
  const double *a = Row(k), *b = Row(k + 1);
  std::vector<double> row(static_cast<size_t>(width_));
  for (int i = 0; i < width_; ++i) row[size_t(i)] = a[i] + alpha * (b[i] - a[i]);
  for (int body = 0; body < num_bodies(); ++body) {  // a quaternion and its negative are one turn
    if (!bodies_[body].IsFfd(3)) continue;
    const int o = layout_[body].q + 3;
    double dot = 0;
    for (int i = 0; i < 4; ++i) dot += a[o + i] * b[o + i];
    if (dot < 0)
      for (int i = 0; i < 4; ++i) row[size_t(o + i)] = a[o + i] + alpha * (-b[o + i] - a[o + i]);
  }
  RestoreRow(row.data(), world);
  world.SetTime(t);
}

int Trajectory::Nearest(double t) const {
  int best = 0;
  for (int k = 1; k < size(); ++k)
    if (std::abs(time(k) - t) < std::abs(time(best) - t)) best = k;
  return best;
}

// ---------------------------------------------------------------- recorder

Recorder::Recorder(std::shared_ptr<Trajectory> trajectory, int every) : trajectory_(std::move(trajectory)), every_(every) {
  if (!trajectory_) throw std::invalid_argument("Recorder: no trajectory");
  if (every_ < 1) throw std::invalid_argument("Recorder: every must be at least 1");
}

Recorder::Recorder(std::shared_ptr<Trajectory> trajectory, double fps, double from)
    : trajectory_(std::move(trajectory)), period_(1.0 / fps), next_(from) {
  if (!trajectory_) throw std::invalid_argument("Recorder: no trajectory");
  if (!(fps > 0) || !std::isfinite(period_)) throw std::invalid_argument("Recorder: the frame rate must be positive");
}

int Recorder::Sample(const World& world) {
  const Trajectory& t = *trajectory_;
  if (!t.empty() && t.time(t.size() - 1) >= world.time() - 0.5 * world.options().dt) return -1;
  return trajectory_->Append(world, energy_.consumed, pose_ ? pose_->pose() : -1);
}

void Recorder::Refuse(const World& world, int column) const {
  throw NumericalStop("the record's '" + trajectory_->Columns()[column] + "' is not finite at t = " +
                      std::to_string(world.time()) + " (the row was not written)");
}

void Recorder::Start(const World& world) {
  counter_ = 0;
  const int bad = period_ == 0.0 ? Sample(world) : SampleFrame(world);
  if (bad >= 0) Refuse(world, bad);
}

void Recorder::AfterStep(World& world) {
  const double dt = world.options().dt;
  for (int b = 0; b < world.num_bodies(); ++b) {
    if (world.kind(b) == BodyKind::kLinear || world.kinematic(b)) continue;
    if (world.IsFfd(b, 2)) energy_.Accumulate(world.body<2>(b), world.state<2>(b), dt);
    else energy_.Accumulate(world.body<3>(b), world.state<3>(b), dt);
  }
  int bad = -1;
  if (period_ > 0.0) bad = SampleFrame(world);
  else if (++counter_ % every_ == 0) bad = Sample(world);
  // the state is finite (the world refuses steps that are not); an overflowing row (a
  // control energy past the largest double) stops the world after this step
  if (bad >= 0)
    world.Stop(StatusCode::kNonFiniteEnergy, -1, "the record's '" + trajectory_->Columns()[bad] + "' is not finite");
}

int Recorder::SampleFrame(const World& world) {
  // the frame due now, then the next frame time after it (frames closer than a step are
  // skipped, in closed form: a loop would turn dt·fps times, and forever once next_ + period_
  // rounds to next_)
  const double t = world.time(), half_step = 0.5 * world.options().dt;
  if (t + half_step < next_) return -1;
  const int bad = Sample(world);
  next_ += period_;
  if (next_ <= t + half_step) next_ += period_ * (std::floor((t + half_step - next_) / period_) + 1.0);
  if (next_ <= t + half_step) next_ = std::nextafter(t + half_step, HUGE_VAL);
  return bad;
}

void Recorder::Finish(const World& world) {
  const Trajectory& t = *trajectory_;
  if (!t.empty() && t.time(t.size() - 1) == world.time()) return;
  const int bad = trajectory_->Append(world, energy_.consumed, pose_ ? pose_->pose() : -1);
  if (bad >= 0 && world.status().ok()) Refuse(world, bad);
}

}  // namespace wobble::record
