// The FFD object of a scene (Faloutsos 1995, §4.10.2): the object file, its deformation modes
// with their stiffness, damping and active flags, the extra damping `codamA` of the active
// modes, the placement `trans`, and the state q, q̇ in world coordinates. What the script's
// load_obj, load_def, assign, mode, trans and set_vec change; the runs step the body model that
// Body<Dim>() builds from it.
//
// 2D or 3D: an object file that starts with 'dimension 3' gives a 3D FFD body (issue 15),
// built by Body<3>(). Its q is (t, r, γ), r the rotation vector of the orientation (the turn by
// |r| radians about r), and its q̇ is (ṫ, ω in the body frame, γ̇): 6 + D numbers each, as
// `wobble simulate` takes them. `trans x y θ` places it at (x, y, 0), turned by θ about z.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "wobble/body/body_model.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"

namespace wobble::scene {

class FfdObject {
  // (first: the accessors below deduce their types from OnParts)
  // What the object file and mode files of one dimension give; only the loaded dimension's
  // part is filled, so one object has one set of modes.
  template <int Dim> struct Part {
    std::optional<BodyDefN<Dim>> def;
    std::vector<DeformationModeN<Dim>> modes;
    mutable std::shared_ptr<const BodyModelN<Dim>> body;  // Body()'s cache; reset by every change
  };
  template <int Dim> Part<Dim>& part() { return std::get<Part<Dim>>(parts_); }
  template <int Dim> const Part<Dim>& part() const { return std::get<Part<Dim>>(parts_); }
  // f(part) on the loaded dimension's part (the 2D one before Load).
  template <class F> decltype(auto) OnParts(F&& f) const { return dim() == 3 ? f(part<3>()) : f(part<2>()); }

 public:
  // Reads the object file (formats::ParseError when it is bad): no modes, at rest at the
  // placement. A 3D file's `mesh` line is read by `read_mesh` (formats/object_file.h).
  void Load(const std::string& path, const formats::MeshReader& read_mesh = nullptr);
  bool loaded() const { return part<2>().def.has_value() || part<3>().def.has_value(); }
  int dim() const { return part<3>().def ? 3 : 2; }
  const std::string& path() const { return path_; }                          // absolute
  const std::vector<std::string>& mode_paths() const { return mode_paths_; }  // absolute, in load order

  // Replaces the mode set by the modes of these files, in order (§4.10): the amplitude and
  // rate of a mode whose name was loaded before carry over, the others start at 0. Throws
  // std::invalid_argument when the modes do not fit the object's lattice.
  void LoadModes(const std::vector<std::string>& paths);
  // The modes as loaded and assigned, codamA not added, of the object's dimension (those of the
  // other dimension are empty); the accessors below serve either.
  template <int Dim> const std::vector<DeformationModeN<Dim>>& modes() const { return part<Dim>().modes; }
  int num_modes() const { return OnParts([](const auto& p) { return int(p.modes.size()); }); }
  const std::string& mode_name(int mode) const {
    return OnParts([mode](const auto& p) -> const std::string& { return p.modes.at(size_t(mode)).name; });
  }
  bool mode_active(int mode) const {
    return OnParts([mode](const auto& p) { return p.modes.at(size_t(mode)).active; });
  }
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
  int num_q() const { return (dim() == 3 ? Group<3>::kRigidDofs : Group<2>::kRigidDofs) + num_modes(); }
  void SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd);

  // The body the runs step: the modes with codamA in the active modes' damping. Built once
  // per change; nullptr before Load or for the other dimension.
  template <int Dim> std::shared_ptr<const BodyModelN<Dim>> Body() const;

 private:
  template <class F> void ForEachMode(F&& f);  // f(mode) on every mode, then the caches reset
  template <int Dim> void LoadModesOf(const std::vector<std::string>& paths, std::vector<std::string> absolute);
  void ResetBodies();
  std::tuple<Part<2>, Part<3>> parts_;
  std::string path_;
  std::vector<std::string> mode_paths_;
  double codam_active_ = 0.0;
  Eigen::Vector3d placement_ = Eigen::Vector3d::Zero();
  Eigen::VectorXd q_, qd_;
};

}  // namespace wobble::scene
