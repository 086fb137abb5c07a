// The one recorder of wobble: a Trajectory is what a run leaves behind (t, q and q̇ of every
// body, every energy term, contacts, control energy, the active pose, the constraint
// violation), filled by the world's step through a Recorder, written and read as one CSV
// schema (record/trajectory_csv.h), drawn by the one render driver (pipelines/).
//
// Storage is one flat row of numbers per sample (the CSV's row), so recording a step appends
// to one vector and allocates nothing once it has grown; Sample() views a row.
//
// Columns (Columns()), for each body b in order, prefixed "NAME." when the world has more than
// one body:
//   FFD body:     tx ty theta <mode names> | dtx dty dtheta d<mode names> | target_<mode names>
//   3D FFD body:  tx ty tz qw qx qy qz <mode names> (orientation as a unit quaternion)
//                 | dtx dty dtz wx wy wz d<mode names> (ω in the body frame) | target_<mode names>
//   linear body:  r<i>_<s> (R row i, basis s) | dr<i>_<s>
//   every body:   kinetic gravity modes ground springs total | contacts penetration
// then, once: t first, and at the end control_energy pose violation.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "wobble/control/control.h"
#include "wobble/control/controllers.h"
#include "wobble/world/controller.h"
#include "wobble/world/world.h"

namespace wobble::record {

// What a trajectory knows of each body: enough to name its columns and to draw it again.
struct BodyInfo {
  std::string name;
  BodyKind kind = BodyKind::kFfd;
  int dim = 2;
  int num_q = 0;
  int num_v = 0;                                  // velocities: num_q, but 6 + D for a 3D FFD body
  std::shared_ptr<const LinearBodyModel> linear;  // linear bodies
  bool ground_contact = false;                    // a linear body that touches the ground (FFD: always)
  std::vector<std::string> coordinate_names;      // one per q entry
  std::vector<std::string> velocity_names;        // one per q̇ (v) entry

  // An FFD body's model (modes included), of either dimension; setting it sets `dim` and
  // `kind` too, so the two cannot disagree. ffd<Dim>() is null for a body of the other
  // dimension, a linear body, or one read from a file without its model.
  template <int Dim> void set_ffd(std::shared_ptr<const BodyModelN<Dim>> model) {
    kind = BodyKind::kFfd;
    dim = Dim;
    ffd_ = std::move(model);
  }
  template <int Dim> const BodyModelN<Dim>* ffd() const { return shared_ffd<Dim>().get(); }
  template <int Dim> std::shared_ptr<const BodyModelN<Dim>> shared_ffd() const {
    const auto* p = std::get_if<std::shared_ptr<const BodyModelN<Dim>>>(&ffd_);
    return p ? *p : nullptr;
  }
  bool has_ffd() const { return ffd<2>() || ffd<3>(); }
  // An FFD body's modes: its model's, or, for a body read without its model, the coordinates
  // after the rigid ones (num_q); 0 for a linear body. std::logic_error for an FFD body with
  // neither: "no modes" would be a guess, and a wrong one shifts every column after q.
  int num_modes() const;
  // Mode d of the model's (has_ffd()).
  const std::string& mode_name(int d) const {
    return std::visit([d](const auto& m) -> const std::string& { return m->modes().at(size_t(d)).name; }, ffd_);
  }
  double mode_stiffness(int d) const {
    return std::visit([d](const auto& m) { return m->modes().at(size_t(d)).stiffness; }, ffd_);
  }
  bool IsFfd(int d) const { return kind == BodyKind::kFfd && dim == d; }

 private:
  // One model: a 2D and a 3D pointer side by side could both be set.
  std::variant<std::shared_ptr<const BodyModel>, std::shared_ptr<const BodyModelN<3>>> ffd_;
};

class Trajectory {
 public:
  Trajectory() = default;
  // The bodies of `world` (in its numbering) define the columns.
  explicit Trajectory(const World& world);
  // The bodies given (a trajectory read from a file, or one built by hand).
  explicit Trajectory(std::vector<BodyInfo> bodies);

  const std::vector<BodyInfo>& bodies() const { return bodies_; }
  int num_bodies() const { return int(bodies_.size()); }
  const std::vector<std::string>& Columns() const { return columns_; }
  int num_columns() const { return int(columns_.size()); }
  // The column's index, or -1.
  int Column(const std::string& name) const;

  int size() const { return width_ == 0 ? 0 : int(data_.size() / size_t(width_)); }
  bool empty() const { return size() == 0; }
  void clear() { data_.clear(); }
  void reserve(int samples) { data_.reserve(size_t(samples) * size_t(width_)); }

  // Appends the world's state now (its bodies must be those of the constructor). `pose` and
  // `control_energy` come from the controllers (control::PoseGraphController, ControlEnergy).
  // Returns -1, or (the row is not kept) the first column whose value is not finite: every
  // row kept is finite.
  int Append(const World& world, double control_energy = 0.0, int pose = -1);
  // Appends a row of Columns() values (a file being read).
  void AppendRow(const std::vector<double>& row);

  // Read access to sample k.
  double time(int k) const { return Row(k)[0]; }
  Eigen::Map<const Eigen::VectorXd> q(int k, int body) const;
  Eigen::Map<const Eigen::VectorXd> qd(int k, int body) const;
  // PD targets γ0 of an FFD body's modes (empty map for a linear body).
  Eigen::Map<const Eigen::VectorXd> targets(int k, int body) const;
  Energies energies(int k, int body) const;  // per_mode is recomputed for FFD bodies
  int contacts(int k, int body) const;
  double penetration(int k, int body) const;
  double control_energy(int k) const { return Row(k)[width_ - 3]; }
  int pose(int k) const { return int(Row(k)[width_ - 2]); }
  double violation(int k) const { return Row(k)[width_ - 1]; }
  const double* Row(int k) const { return data_.data() + size_t(k) * size_t(width_); }

  // Puts the bodies of sample k back into `world` (same bodies) and its clock at the sample's
  // time; PD targets too. Constraints are not touched.
  void Restore(int k, World& world) const;
  // The bodies at time t between the samples around it, every number interpolated linearly (a
  // 3D orientation's quaternion on the shorter arc, then normalised) and the clock at t
  // exactly; before the first or after the last sample, that sample with the clock at t. For
  // frames at exact frame times, which the step grid need not hit (the render driver).
  void RestoreAt(double t, World& world) const;
  // The sample nearest to time t (the first of equals).
  int Nearest(double t) const;

 private:
  void RestoreRow(const double* row, World& world) const;  // Restore's state part
  struct Layout {
    int q = 0, qd = 0, targets = 0, energies = 0, contacts = 0;
    int num_targets = 0;
  };
  void Build();

  std::vector<BodyInfo> bodies_;
  std::vector<Layout> layout_;
  std::vector<std::string> columns_;
  int width_ = 0;
  std::vector<double> data_;
};

// Names of a body's generalized coordinates and velocities: tx ty theta <mode names> (FFD),
// tx ty tz qw qx qy qz <mode names> (3D FFD) or r<i>_<s> (linear); velocities d<name> but
// wx wy wz for a 3D body's angular velocity.
BodyInfo DescribeBody(const World& world, int body);

// The recorder: a Controller the world calls after every accepted step (World::SetRecorder),
// appending samples to its trajectory either every `every`-th step or at a frame rate. It also
// integrates the control energy of the FFD bodies the world moves (control::ControlEnergy,
// every step; kinematic bodies are moved by their controllers, not by the PD forces).
class Recorder : public Controller {
 public:
  // A sample after every `every`-th step.
  explicit Recorder(std::shared_ptr<Trajectory> trajectory, int every = 1);
  // `fps` samples per simulated second, the first due at time `from` (a film's frame times
  // from, from + 1/fps, ...): a sample of the first state at or past each (to half a step).
  Recorder(std::shared_ptr<Trajectory> trajectory, double fps, double from);
  // The start of a run: a sample of the state now when one is due (always when sampling every
  // N steps, whose count restarts here), unless the trajectory ends at this time already.
  void Start(const World& world);
  void AfterStep(World& world) override;
  // Records the state now unless it is the last sample (the end of a run recorded every N).
  void Finish(const World& world);
  // The pose to write in each sample (a pose-graph controller's), or none.
  void SetPoseSource(std::shared_ptr<const control::PoseSource> source) { pose_ = std::move(source); }
  const std::shared_ptr<Trajectory>& trajectory() const { return trajectory_; }
  const control::ControlEnergy& control_energy() const { return energy_; }
  void set_control_energy(const control::ControlEnergy& e) { energy_ = e; }

 private:
  // Appends unless the trajectory ends at this time already; returns the non-finite column of
  // a row it could not keep (Trajectory::Append), or -1.
  int Sample(const World& world);
  void Refuse(const World& world, int column) const;  // throws NumericalStop naming the column
  int SampleFrame(const World& world);  // frame-rate sampling: a sample when a frame is due
  std::shared_ptr<Trajectory> trajectory_;
  int every_ = 1;
  long counter_ = 0;
  double period_ = 0.0, next_ = 0.0;  // frame-rate sampling when period_ > 0
  control::ControlEnergy energy_;
  std::shared_ptr<const control::PoseSource> pose_;
};

}  // namespace wobble::record
