#include "tracking/body_dimensions.h"

namespace embody::tracking {

BodyDimensions BodyDimensions::fromHeight(float h) {
  BodyDimensions d;
  d.height = h;
  d.eyeHeight = float(kEyeHeightRatio) * h;
  d.eyeForward = float(avatar::kEyeForwardRatio) * h;
  d.eyeAboveNeck = 0.062f * h;
  d.shoulderHeight = 0.818f * h;
  d.neckAboveShoulders = d.eyeHeight - d.eyeAboveNeck - d.shoulderHeight;
  d.shoulderHalfWidth = 0.1f * h;
  d.upperArm = 0.186f * h;
  d.forearm = 0.146f * h;
  d.armReach = d.upperArm + d.forearm;
  d.hipHeight = 0.53f * h;
  d.hipHalfWidth = 0.05f * h;
  d.thigh = 0.245f * h;
  d.shin = 0.246f * h;
  d.ankleHeight = float(avatar::kAnkleHeightRatio) * h;
  return d;
}

glm::vec3 BodyDimensions::neckFromHead(const TrackerPose& head) const {
  return head.position + head.orientation * glm::vec3(0.0f, -eyeAboveNeck, eyeForward);
}

glm::vec3 BodyDimensions::shoulderFromHead(const TrackerPose& head, Side side) const {
  const glm::quat heading = headingOf(head.orientation);
  const float x = side == Side::Left ? -shoulderHalfWidth : shoulderHalfWidth;
  return neckFromHead(head) + heading * glm::vec3(x, -neckAboveShoulders, 0.0f);
}

TrackerPose BodyDimensions::neutralHand(const TrackerPose& head, Side side) const {
  const glm::quat heading = headingOf(head.orientation);
  const float out = side == Side::Left ? -1.0f : 1.0f;
  TrackerPose p;
  // Arm hanging almost straight, slightly away from the thigh and a little forward.
  const glm::vec3 local(out * 0.02f * height, -0.96f * armReach, -0.02f * height);
  p.position = shoulderFromHead(head, side) + heading * local;
  p.orientation = heading * gripOrientation(side, glm::vec3(0, -1, 0), glm::vec3(-out, 0, 0));
  p.valid = true;
  return p;
}

}  // namespace embody::tracking
