#include "wobble/scene/ffd_object.h"

#include <filesystem>
#include <stdexcept>

#include "wobble/core/types.h"
#include "wobble/formats/deformation_file.h"
#include "wobble/formats/object_file.h"

namespace wobble::scene {

namespace {

// Rigid placement (x, y, θ) composed with a body-relative q: world = placement ∘ q.
void Place(const Eigen::Vector3d& placement, Eigen::VectorXd* q, Eigen::VectorXd* qd) {
  const Eigen::Matrix2d R = Rotation(placement[2]);
  if (q) {
    q->head<2>() = placement.head<2>() + R * q->head<2>();
    (*q)[2] += placement[2];
  }
  if (qd) qd->head<2>() = R * qd->head<2>();
}

}  // namespace

void FfdObject::Load(const std::string& path) {
  def_ = formats::ReadObjectFile(path);
  path_ = std::filesystem::absolute(path).string();
  modes_.clear();
  mode_paths_.clear();
  q_.setZero(kRigidDofs);
  qd_.setZero(kRigidDofs);
  Place(placement_, &q_, &qd_);  // at rest where `trans` put it
  body_.reset();
}

void FfdObject::LoadModes(const std::vector<std::string>& paths) {
  std::vector<DeformationMode> modes;
  std::vector<std::string> absolute;
  for (const std::string& path : paths) {
    std::vector<DeformationMode> more = formats::ReadDeformationFile(path);
    modes.insert(modes.end(), more.begin(), more.end());
    absolute.push_back(std::filesystem::absolute(path).string());
  }
  BodyModel check(*def_, modes);  // throws when the modes do not fit the object
  // a new mode set (§4.10): amplitudes of modes with the same name carry over, others start at 0
  const int n = kRigidDofs + int(modes.size());
  Eigen::VectorXd q = Eigen::VectorXd::Zero(n), qd = Eigen::VectorXd::Zero(n);
  q.head<kRigidDofs>() = q_.head<kRigidDofs>();
  qd.head<kRigidDofs>() = qd_.head<kRigidDofs>();
  for (size_t d = 0; d < modes.size(); ++d)
    for (size_t old = 0; old < modes_.size(); ++old)
      if (modes_[old].name == modes[d].name) {
        q[kRigidDofs + d] = q_[kRigidDofs + old];
        qd[kRigidDofs + d] = qd_[kRigidDofs + old];
      }
  modes_ = std::move(modes);
  mode_paths_ = std::move(absolute);
  q_ = q;
  qd_ = qd;
  body_.reset();
}

int FfdObject::ModeIndex(const std::string& name) const {
  for (int d = 0; d < int(modes_.size()); ++d)
    if (modes_[d].name == name) return d;
  return -1;
}

void FfdObject::Assign(int mode, double stiffness, double damping) {
  modes_.at(mode).stiffness = stiffness;
  modes_[mode].damping = damping;
  body_.reset();
}

void FfdObject::SetActive(int mode, bool active) {
  modes_.at(mode).active = active;
  body_.reset();
}

void FfdObject::SetCodamActive(double damping) {
  codam_active_ = damping;
  body_.reset();
}

void FfdObject::SetPlacement(const Eigen::Vector3d& placement) {
  if (q_.size() >= kRigidDofs) {  // re-place the state: its body-relative part is kept
    const Eigen::Matrix2d Rinv = Rotation(-placement_[2]);
    q_.head<2>() = Rinv * (q_.head<2>() - placement_.head<2>());
    q_[2] -= placement_[2];
    qd_.head<2>() = Rinv * qd_.head<2>();
    Place(placement, &q_, &qd_);
  }
  placement_ = placement;
}

void FfdObject::SetRelativeQ(Eigen::VectorXd q) {
  Place(placement_, &q, nullptr);
  q_ = std::move(q);
}

void FfdObject::SetRelativeQd(Eigen::VectorXd qd) {
  Place(placement_, nullptr, &qd);
  qd_ = std::move(qd);
}

void FfdObject::SetState(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  q_ = q;
  qd_ = qd;
}

std::shared_ptr<const BodyModel> FfdObject::Body() const {
  if (body_ || !def_) return body_;
  std::vector<DeformationMode> modes = modes_;
  for (DeformationMode& m : modes)
    if (m.active) m.damping += codam_active_;
  body_ = std::make_shared<const BodyModel>(*def_, std::move(modes));
  return body_;
}

}  // namespace wobble::scene
