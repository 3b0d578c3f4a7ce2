#include "runtime/body_seed.h"

#include <algorithm>
#include <cmath>

#include "ik/expmap.h"
#include "runtime/foot_planner.h"

namespace embody::runtime {

namespace {
constexpr double kPi = 3.14159265358979323846;
}  // namespace

double seedYaw(const SeedInputs& in) {
  if (!in.leftHand || !in.rightHand) return in.headYaw;
  const Eigen::Vector3d up = in.up.normalized();
  Eigen::Vector3d across = *in.leftHand - *in.rightHand;
  across -= up * up.dot(across);
  if (across.norm() < 0.3 * in.scale) return in.headYaw;
  // Facing: perpendicular to the line between the hands, on the side the avatar's left is left.
  const Eigen::Vector3d facing = across.cross(up);
  const Eigen::Vector3d fwd = (in.forward - up * up.dot(in.forward)).normalized();
  const Eigen::Vector3d side = up.cross(fwd);
  const double handsYaw = std::atan2(facing.dot(side), facing.dot(fwd));
  const double diff = wrapAngle(handsYaw - in.headYaw);
  if (std::abs(diff) > 0.5 * kPi) return in.headYaw;
  return wrapAngle(in.headYaw + 0.5 * diff);
}

Eigen::Vector3d seedPelvis(const SeedInputs& in, double yaw) {
  const Eigen::Vector3d up = in.up.normalized();
  const Eigen::Vector3d p = in.headPivot + Eigen::AngleAxisd(yaw, up) * in.restHeadToHips;
  const double underHead = up.dot(p) - in.floor;
  const double height = std::clamp(underHead, 0.5 * in.restHipsHeight, in.restHipsHeight);
  return p + up * (height - underHead);
}

Eigen::VectorXd placeRoot(const ik::Model& model, ik::JointId root, const Eigen::VectorXd& base,
                          const Eigen::Vector3d& pelvis, double yaw, const Eigen::Vector3d& up) {
  Eigen::VectorXd q = base;
  if (root < 0 || size_t(root) >= model.joints.size()) return q;
  const ik::Model::Joint& joint = model.joints[size_t(root)];
  if (joint.desc.type != ik::JointType::Free || joint.desc.parent != ik::kNoParent) return q;
  // World frame = rest * translate(t) * rotate(v): t in the rest frame, v the rest-frame rotation.
  const Eigen::Matrix3d restR = joint.desc.rest.linear();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(yaw, up.normalized()).toRotationMatrix();
  q.segment<3>(joint.first_dof) = restR.transpose() * (pelvis - joint.desc.rest.translation());
  q.segment<3>(joint.first_dof + 3) = ik::rotationLog(restR.transpose() * turn * restR);
  return q;
}

}  // namespace embody::runtime
