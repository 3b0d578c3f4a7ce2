#pragma once
// Body proportions from the user's height (segment lengths as fractions of stature after
// Drillis & Contini 1966, the table Winter's "Biomechanics and Motor Control of Human Movement"
// reprints). Used where a source or a fallback needs a plausible body without an avatar:
// synthetic motions, the neutral pose of a lost hand, arm-reach limits.
#include "avatar/body/anthropometry.h"
#include "tracking/tracker.h"

namespace embody::tracking {

// Eye height over body height (avatar/body/anthropometry.h): the one ratio, so a synthetic or
// BVH head target and a calibrated avatar's eyes agree.
using avatar::kEyeHeightRatio;

struct BodyDimensions {
  float height = 1.75f;
  float eyeHeight = 0.0f;          // floor to the point between the eyes (head tracker), standing
  float eyeForward = 0.0f;         // eyes ahead of the neck pivot, head upright
  float eyeAboveNeck = 0.0f;       // eyes above the neck pivot (top of the cervical spine)
  float neckAboveShoulders = 0.0f; // neck pivot above the shoulder line
  float shoulderHeight = 0.0f;     // floor to the shoulder joints
  float shoulderHalfWidth = 0.0f;  // midline to a shoulder joint centre
  float upperArm = 0.0f, forearm = 0.0f;
  float armReach = 0.0f;           // shoulder joint to wrist, arm straight
  float hipHeight = 0.0f;          // floor to the pelvis centre (hips tracker)
  float hipHalfWidth = 0.0f;       // midline to a hip joint centre
  float thigh = 0.0f, shin = 0.0f;
  float ankleHeight = 0.0f;

  static BodyDimensions fromHeight(float height);

  // Where the shoulders are, estimated from the head pose alone: the neck pivot follows the head
  // (so nodding does not move the shoulders), the shoulders hang below it in the heading frame.
  glm::vec3 neckFromHead(const TrackerPose& head) const;
  glm::vec3 shoulderFromHead(const TrackerPose& head, Side side) const;
  // A relaxed hand hanging at the side, wrist position and grip orientation, for a head pose.
  TrackerPose neutralHand(const TrackerPose& head, Side side) const;
};

}  // namespace embody::tracking
