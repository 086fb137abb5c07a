// The FFD object of a scene (Faloutsos 1995, §4.10.2): the object file, its deformation modes
// with their stiffness, damping and active flags, the extra damping `codamA` of the active
// modes, the placement `trans`, and the state q, q̇ in world coordinates. What the script's
// load_obj, load_def, assign, mode, trans and set_vec change; the runs step the BodyModel that
// Body() builds from it.
//
// 2D or 3D: an object file that starts with 'dimension 3' gives a 3D FFD body (issue 15),
// built by Body3(). Its q is (t, r, γ), r the rotation vector of the orientation (the turn by
// |r| radians about r), and its q̇ is (ṫ, ω in the body frame, γ̇): 6 + D numbers each, as
// `wobble simulate` takes them. `trans x y θ` places it at (x, y, 0), turned by θ about z.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"

namespace wobble::scene {

class FfdObject {
 public:
  // Reads the object file (formats::ParseError when it is bad): no modes, at rest at the
  // placement. A 3D file's `mesh` line is read by `read_mesh` (formats/object_file.h).
  void Load(const std::string& path, const formats::MeshReader& read_mesh = nullptr);
  bool loaded() const { return def_.has_value() || def3_.has_value(); }
  int dim() const { return def3_ ? 3 : 2; }
  const std::string& path() const { return path_; }                          // absolute
  const std::vector<std::string>& mode_paths() const { return mode_paths_; }  // absolute, in load order

  // Replaces the mode set by the modes of these files, in order (§4.10): the amplitude and
  // rate of a mode whose name was loaded before carry over, the others start at 0. Throws
  // std::invalid_argument when the modes do not fit the object's lattice.
  void LoadModes(const std::vector<std::string>& paths);
  // The modes as loaded and assigned, codamA not added: a 2D object's, a 3D object's (the other
  // is empty); the accessors below serve either.
  const std::vector<DeformationMode>& modes() const { return modes_; }
  const std::vector<DeformationMode3>& modes3() const { return modes3_; }
  int num_modes() const { return def3_ ? int(modes3_.size()) : int(modes_.size()); }
  const std::string& mode_name(int mode) const { return def3_ ? modes3_.at(mode).name : modes_.at(mode).name; }
  bool mode_active(int mode) const { return def3_ ? modes3_.at(mode).active : modes_.at(mode).active; }
  std::vector<std::string> mode_names() const;
  // The index of the mode of this name, or -1.
  int ModeIndex(const std::string& name) const;
  // V = K γ² and −c γ̇ of one mode (§4.7), and whether the pose graph drives it (chapter 5).
  void Assign(int mode, double stiffness, double damping);
  void SetActive(int mode, bool active);
  // codamA: extra damping of the active modes' PD controllers, D = c + codamA.
  void SetCodamActive(double damping);
  double codam_active() const { return codam_active_; }

  // The placement (x, y, θ) of `trans`: the state keeps its part relative to the placement.
  void SetPlacement(const Eigen::Vector3d& placement);
  const Eigen::Vector3d& placement() const { return placement_; }
  // q or q̇ relative to the placement (set_vec): t = (x, y) + R(θ) t_q, θ = θ_p + θ_q (3D: the
  // turn about z composed with the orientation).
  void SetRelativeQ(Eigen::VectorXd q);
  void SetRelativeQd(Eigen::VectorXd qd);
  // The state in world coordinates (tx ty θ γ1..γD; 3D: tx ty tz rx ry rz γ1..γD).
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }
  int num_q() const { return (def3_ ? Group<3>::kRigidDofs : kRigidDofs) + num_modes(); }
  void SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

  // The body the runs step: the modes with codamA in the active modes' damping. Built once
  // per change; nullptr before Load or for the other dimension.
  std::shared_ptr<const BodyModel> Body() const;
  std::shared_ptr<const BodyModel3> Body3() const;

 private:
  template <class Modes> void Remember(Modes modes, std::vector<std::string> paths);
  template <class F> void ForEachMode(F&& f);
  std::optional<BodyDef> def_;
  std::optional<BodyDef3> def3_;
  std::string path_;
  std::vector<std::string> mode_paths_;
  std::vector<DeformationMode> modes_;
  std::vector<DeformationMode3> modes3_;
  double codam_active_ = 0.0;
  Eigen::Vector3d placement_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd q_, qd_;
  mutable std::shared_ptr<const BodyModel> body_;  // Body()'s cache; reset by every change
  mutable std::shared_ptr<const BodyModel3> body3_;
};

}  // namespace wobble::scene
