// The FFD object of a scene (Faloutsos 1995, §4.10.2): the object file, its deformation modes
// with their stiffness, damping and active flags, the extra damping `codamA` of the active
// modes, the placement `trans`, and the state q, q̇ in world coordinates. What the script's
// load_obj, load_def, assign, mode, trans and set_vec change; the runs step the BodyModel that
// Body() builds from it.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "wobble/body/body_model.h"

namespace wobble::scene {

class FfdObject {
 public:
  // Reads the object file (formats::ParseError when it is bad): no modes, at rest at the
  // placement.
  void Load(const std::string& path);
  bool loaded() const { return def_.has_value(); }
  const std::string& path() const { return path_; }                          // absolute
  const std::vector<std::string>& mode_paths() const { return mode_paths_; }  // absolute, in load order

  // Replaces the mode set by the modes of these files, in order (§4.10): the amplitude and
  // rate of a mode whose name was loaded before carry over, the others start at 0. Throws
  // std::invalid_argument when the modes do not fit the object's lattice.
  void LoadModes(const std::vector<std::string>& paths);
  const std::vector<DeformationMode>& modes() const { return modes_; }
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
  // q or q̇ relative to the placement (set_vec): t = (x, y) + R(θ) t_q, θ = θ_p + θ_q.
  void SetRelativeQ(Eigen::VectorXd q);
  void SetRelativeQd(Eigen::VectorXd qd);
  // The state in world coordinates (tx ty θ γ1..γD).
  const Eigen::VectorXd& q() const { return q_; }
  const Eigen::VectorXd& qd() const { return qd_; }
  void SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

  // The body the runs step: the modes with codamA in the active modes' damping. Built once
  // per change; nullptr before Load.
  std::shared_ptr<const BodyModel> Body() const;

 private:
  std::optional<BodyDef> def_;
  std::string path_;
  std::vector<std::string> mode_paths_;
  std::vector<DeformationMode> modes_;
  double codam_active_ = 0.0;
  Eigen::Vector3d placement_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd q_, qd_;
  mutable std::shared_ptr<const BodyModel> body_;  // Body()'s cache; reset by every change
};

}  // namespace wobble::scene
