#include "wobble/scene/ffd_object.h"

#include <filesystem>
#include <stdexcept>

#include "wobble/core/rotation3.h"
#include "wobble/core/types.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"
#include "wobble/world/world.h"

namespace wobble::scene {

namespace {

// Rigid placement (x, y, θ) composed with a body-relative q: world = placement ∘ q. In 3D the
// placement is the translation (x, y, 0) and the turn by θ about z.
void Place(int dim, const Eigen::Vector3d& placement, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  if (dim == 2) {
    const Eigen::Matrix2d R = Rotation(placement[2]);
    if (q) {
      q->head<2>() = placement.head<2>() + R * q->head<2>();
      (*q)[2] += placement[2];
    }
    if (qd) qd->head<2>() = R * qd->head<2>();
    return;
  }
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(placement[2], Eigen::Vector3d::UnitZ()));
  if (q) {
    q->head<3>() = Eigen::Vector3d(placement[0], placement[1], 0.0) + turn * q->head<3>();
    q->segment<3>(3) = LogRotation<double>(turn * ExpRotation<double>(q->segment<3>(3)));
  }
  if (qd) qd->head<3>() = turn * qd->head<3>();  // ω is in the body frame: unchanged
}

}  // namespace

void FfdObject::Load(const std::string& path, const formats::MeshReader& read_mesh) {
  part<2>().def.reset();
  part<3>().def.reset();
  if (formats::ObjectFileDimension(path) == 3) part<3>().def = formats::ReadObjectFile<3>(path, read_mesh);
  else part<2>().def = formats::ReadObjectFile(path);
  path_ = std::filesystem::absolute(path).string();
  part<2>().modes.clear();
  part<3>().modes.clear();
  mode_paths_.clear();
  const int rigid = dim() == 3 ? Group<3>::kRigidDofs : Group<2>::kRigidDofs;
  q_.setZero(rigid);
  qd_.setZero(rigid);
  Place(dim(), placement_, &q_, &qd_);  // at rest where `trans` put it
  ResetBodies();
}

void FfdObject::ResetBodies() {
  part<2>().body.reset();
  part<3>().body.reset();
}

// A new mode set (§4.10): amplitudes of modes with the same name carry over, others start at 0.
template <int Dim> void FfdObject::LoadModesOf(const std::vector<std::string>& paths, std::vector<std::string> absolute) {
  const BodyDefN<Dim>& def = *part<Dim>().def;
  std::vector<DeformationModeN<Dim>> modes;
  for (const std::string& path : paths) {
    const std::vector<DeformationModeN<Dim>> more = formats::ReadDeformationFile(path, def.lattice);
    modes.insert(modes.end(), more.begin(), more.end());
  }
  BodyModelN<Dim> check(def, modes);  // throws when the modes do not fit the object
  const int rigid = Group<Dim>::kRigidDofs, n = rigid + int(modes.size());
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), qd = Eigen::VectorXd::Zero(n);
  q.head(rigid) = q_.head(rigid);
  qd.head(rigid) = qd_.head(rigid);
  for (size_t d = 0; d < modes.size(); ++d)
    for (int old = 0; old < num_modes(); ++old)
      if (mode_name(old) == modes[d].name) {
        q[rigid + int(d)] = q_[rigid + old];
        qd[rigid + int(d)] = qd_[rigid + old];
      }
  part<Dim>().modes = std::move(modes);
  mode_paths_ = std::move(absolute);
  q_ = q;
  qd_ = qd;
  ResetBodies();
}

void FfdObject::LoadModes(const std::vector<std::string>& paths) {
  std::vector<std::string> absolute;
  for (const std::string& path : paths) absolute.push_back(std::filesystem::absolute(path).string());
  if (dim() == 3) LoadModesOf<3>(paths, std::move(absolute));
  else LoadModesOf<2>(paths, std::move(absolute));
}

std::vector<std::string> FfdObject::mode_names() const {
  std::vector<std::string> names;
  for (int d = 0; d < num_modes(); ++d) names.push_back(mode_name(d));
  return names;
}

int FfdObject::ModeIndex(const std::string& name) const {
  for (int d = 0; d < num_modes(); ++d)
    if (mode_name(d) == name) return d;
  return -1;
}

template <class F> void FfdObject::ForEachMode(F&& f) {
  for (DeformationMode& m : part<2>().modes) f(m);
  for (DeformationModeN<3>& m : part<3>().modes) f(m);
  ResetBodies();
}

void FfdObject::Assign(int mode, double stiffness, double damping) {
  int d = 0;
  ForEachMode([&](auto& m) {
    if (d++ == mode) m.stiffness = stiffness, m.damping = damping;
  });
}

void FfdObject::SetActive(int mode, bool active) {
  int d = 0;
  ForEachMode([&](auto& m) {
    if (d++ == mode) m.active = active;
  });
}

void FfdObject::SetCodamActive(double damping) {
  codam_active_ = damping;
  ResetBodies();
}

void FfdObject::SetPlacement(const Eigen::Vector3d& placement) {
  if (loaded()) {  // re-place the state: its body-relative part is kept
    Eigen::VectorXd q = q_, qd = qd_;
    const Eigen::Vector3d undo(0.0, 0.0, -placement_[2]);
    // back to the body-relative state: translate back, then turn back
    if (dim() == 2) {
      q.head<2>() -= placement_.head<2>();
    } else {
      q[0] -= placement_[0];
      q[1] -= placement_[1];
    }
    Place(dim(), undo, &q, &qd);
    Place(dim(), placement, &q, &qd);
    q_ = q;
    qd_ = qd;
  }
  placement_ = placement;
}

void FfdObject::SetRelativeQ(Eigen::VectorXd q) {
  Place(dim(), placement_, &q, nullptr);
  q_ = std::move(q);
}

void FfdObject::SetRelativeQd(Eigen::VectorXd qd) {
  Place(dim(), placement_, nullptr, &qd);
  qd_ = std::move(qd);
}

void FfdObject::SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  q_ = q;
  qd_ = qd;
}

template <int Dim> std::shared_ptr<const BodyModelN<Dim>> FfdObject::Body() const {
  const Part<Dim>& p = part<Dim>();
  if (p.body || !p.def) return p.body;
  std::vector<DeformationModeN<Dim>> modes = p.modes;
  for (DeformationModeN<Dim>& m : modes)
    if (m.active) m.damping += codam_active_;
  p.body = std::make_shared<const BodyModelN<Dim>>(*p.def, std::move(modes));
  return p.body;
}

template std::shared_ptr<const BodyModel> FfdObject::Body<2>() const;
template std::shared_ptr<const BodyModelN<3>> FfdObject::Body<3>() const;

}  // namespace wobble::scene
