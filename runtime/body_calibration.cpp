#include "runtime/body_calibration.h"

#include <algorithm>

#include "avatar/body/anthropometry.h"
#include "tracking/body_dimensions.h"

namespace embody::runtime {

using tracking::TrackerId;
using tracking::TrackerStatus;

BodyCalibration BodyCalibration::fromUserHeight(const BodyRig& rig, float userHeight) {
  const auto dims = tracking::BodyDimensions::fromHeight(userHeight);
  BodyCalibration c;
  c.scale = rig.avatarEyeHeight / double(dims.eyeHeight);
  return c;
}

BodyCalibration BodyCalibration::sameBody() {
  BodyCalibration c;
  c.scale = 1.0;
  return c;
}

BodyCalibration BodyCalibration::fromFirstSample(const BodyRig& rig, const tracking::GuardedSample& targets) {
  // Calibrate from the first live head sample: its height is a standing eye height.
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  const tracking::TrackerPose& head = targets.pose[TrackerId::Head];
  const float eye = head.position.y;
  const bool live = targets.status[headIndex] == TrackerStatus::Tracked && head.valid && eye > 0.4f && eye < 2.4f;
  // Seated, the head's height says nothing about the user's stature: 1.75 m unless given.
  const bool standing = live && !rig.layout.seated;
  BodyCalibration c = fromUserHeight(rig, standing ? eye / float(avatar::kEyeHeightRatio) : 1.75f);
  c.fromHead = standing;
  return c;
}

// On the first sample with a tracked head: the vertical offsets that stand the user's ankles and
// pelvis at the avatar's rest heights, and the stride scaling (avatar leg / user leg).
BodyCalibration BodyCalibration::withHeights(const BodyRig& rig, const tracking::GuardedSample& targets) const {
  BodyCalibration c = withoutHeights();
  c.heightsCalibrated = true;
  const auto& lf = targets.pose[TrackerId::LeftFoot];
  const auto& rf = targets.pose[TrackerId::RightFoot];
  if (targets[TrackerId::LeftFoot] == TrackerStatus::Tracked && targets[TrackerId::RightFoot] == TrackerStatus::Tracked) {
    const double lowest = scale * std::min(lf.position.y, rf.position.y);
    for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot})
      c.heightOffset[size_t(tracking::index(id))] = rig.restHeight[size_t(tracking::index(id))] - lowest;
  }
  if (targets[TrackerId::Hips] == TrackerStatus::Tracked) {
    const size_t h = size_t(tracking::index(TrackerId::Hips));
    c.heightOffset[h] = rig.restHeight[h] - scale * targets.pose[TrackerId::Hips].position.y;
    // Stride scaling: the user's leg (pelvis to ankle) against the avatar's.
    const double userLeg = scale * (targets.pose[TrackerId::Hips].position.y - std::min(lf.position.y, rf.position.y));
    const double avatarLeg = rig.restHeight[h] - rig.restHeight[size_t(tracking::index(TrackerId::LeftFoot))];
    if (userLeg > 0.2 && avatarLeg > 0.2) c.legRatio = std::clamp(avatarLeg / userLeg, 0.5, 2.0);
  }
  return c;
}

BodyCalibration BodyCalibration::withoutHeights() const {
  BodyCalibration c;
  c.scale = scale;
  c.fromHead = fromHead;
  return c;
}

}  // namespace embody::runtime
