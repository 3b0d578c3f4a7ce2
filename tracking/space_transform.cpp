#include "tracking/space_transform.h"

namespace embody::tracking {

void SpaceTransform::apply(TrackerPose& pose) const {
  pose.position = apply(pose.position);
  pose.orientation = rotation * pose.orientation;
}

void SpaceTransform::apply(PoseSample& sample) const {
  for (TrackerPose& pose : sample.trackers) apply(pose);
}

SpaceTransform SpaceTransform::after(const SpaceTransform& first) const {
  return {rotation * first.rotation, rotation * first.translation + translation};
}

SpaceTransform SpaceTransform::inverse() const {
  const glm::quat back = glm::conjugate(rotation);
  return {back, -(back * translation)};
}

SpaceTransform recenterOn(const TrackerPose& head) {
  if (!head.valid || !isUsable(head)) return {};
  // Undo the head's heading about the vertical through the head: turn by its inverse, then shift
  // the head's (turned) horizontal position onto the origin.
  const glm::quat unturn = glm::conjugate(headingOf(glm::normalize(head.orientation)));
  const glm::vec3 turned = unturn * head.position;
  return {unturn, glm::vec3(-turned.x, 0.0f, -turned.z)};
}

}  // namespace embody::tracking
