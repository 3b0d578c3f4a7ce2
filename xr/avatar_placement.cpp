#include "xr/avatar_placement.h"

#include <cmath>

#include "tracking/space_transform.h"

namespace embody::xr {

float headingOf(const Pose& p) {
  const glm::quat h = tracking::headingOf(p.orientation);  // a rotation about +Y by the heading
  return 2.0f * std::atan2(h.y, h.w);
}

AvatarPlacement::AvatarPlacement(const glm::vec3& avatarEye, const glm::vec3& avatarForward,
                                 const PlacementOptions& o)
    : eye_(avatarEye), forward_(avatarForward), options_(o) {
  if (o.userEyeHeight > 0.0f && eye_.y > 1e-3f) {
    scale_ = o.userEyeHeight / eye_.y;
    calibrated_ = true;
  }
}

bool AvatarPlacement::calibrate(const Pose& head) {
  if (options_.seated || options_.userEyeHeight > 0.0f) return false;
  const float h = head.position.y;
  if (!std::isfinite(h) || h < 0.8f || h > 2.5f || eye_.y <= 1e-3f) return false;
  scale_ = h / eye_.y;
  calibrated_ = true;
  return true;
}

void AvatarPlacement::recenter(const Pose& head) {
  // The one recenter rule (tracking/space_transform.h): the head over the origin, facing -Z.
  const tracking::SpaceTransform move = tracking::recenterOn({head.position, head.orientation, true});
  recenter_ = Pose{move.translation, move.rotation};
}

glm::mat4 AvatarPlacement::root(const Pose& head) const {
  // Turn the avatar's forward onto the head's heading.
  const float avatarYaw = std::atan2(-forward_.x, -forward_.z);  // heading of the avatar's rest forward
  const glm::quat turn = glm::angleAxis(headingOf(head) - avatarYaw, glm::vec3(0, 1, 0));
  const glm::vec3 eyeWorldOffset = turn * (eye_ * scale_);
  glm::vec3 t{head.position.x - eyeWorldOffset.x, 0.0f, head.position.z - eyeWorldOffset.z};
  if (options_.seated) t.y = head.position.y - eyeWorldOffset.y;
  glm::mat4 m = glm::mat4_cast(turn) * glm::mat4(glm::mat3(scale_));
  m[3] = glm::vec4(t, 1.0f);
  return m;
}

void AvatarPlacement::place(const avatar::Skeleton& skeleton, const Pose& head,
                            avatar::SkeletonPose& pose) const {
  const glm::mat4 m = root(head);
  const glm::quat r = glm::quat_cast(glm::mat3(m) / scale_);
  for (size_t j = 0; j < skeleton.joints.size(); ++j) {
    if (skeleton.joints[j].parent >= 0) continue;
    auto& t = pose.local[j];
    t.translation = glm::vec3(m * glm::vec4(t.translation, 1.0f));
    t.rotation = r * t.rotation;
    t.scale *= scale_;
  }
}

}  // namespace embody::xr
