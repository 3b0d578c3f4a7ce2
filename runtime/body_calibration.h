#pragma once
// What the body knows about the user: the scale from tracking metres to avatar metres (from the
// user's height, else from the first live head sample, taken as a standing eye height), and the
// vertical offsets and stride ratio fixed on the first sample with a tracked head. Immutable
// values: the solver replaces its calibration whole (fromUserHeight / fromFirstSample at the
// first solve, withHeights on the first tracked head, withoutHeights on resetWarmStart, which
// calibrates the heights again from the next tracked head; the scale stays).
//
// Spaces: a tracking point p maps to rig.toAvatar(scale, p) + up * heightOffset[tracker]
// (tracker_targets_job.h): scaled about the floor and turned so the user's forward is the avatar's.
#include <array>

#include "runtime/body_rig.h"
#include "tracking/tracking_guard.h"

namespace embody::runtime {

struct BodyCalibration {
  double scale = 0.0;       // tracking metres -> avatar metres; 0 = not calibrated yet
  bool fromHead = false;    // the scale came from the first live head sample
  // Vertical offsets (avatar metres) added to the hips and feet targets, fixed on the first sample
  // with a tracked head: the user's (or performer's) pelvis and ankles stand at the avatar's rest
  // heights then, whatever the proportions. 0 for the other trackers and until then.
  bool heightsCalibrated = false;
  std::array<double, tracking::kTrackerCount> heightOffset{};
  double legRatio = 1.0;  // avatar leg / user leg, for tracked feet (1 until calibrated)

  bool scaled() const { return scale > 0.0; }

  // From the user's height in metres (a standing eye height of kEyeHeightRatio of it).
  static BodyCalibration fromUserHeight(const BodyRig& rig, float userHeight);
  // The tracked person is the avatar (AvatarBodyOptions::sameBody): scale 1, no height offsets.
  static BodyCalibration sameBody();
  // From the first sample the solver sees: a live head's height is a standing eye height; seated
  // (the head says nothing of the stature) or without a live head, a 1.75 m user.
  static BodyCalibration fromFirstSample(const BodyRig& rig, const tracking::GuardedSample& sample);
  // This calibration plus the height offsets and stride ratio measured on `sample` (its first
  // sample with a tracked head): tracked feet's lowest ankle and a tracked pelvis stand at the
  // avatar's rest heights.
  BodyCalibration withHeights(const BodyRig& rig, const tracking::GuardedSample& sample) const;
  BodyCalibration withoutHeights() const;
};

}  // namespace embody::runtime
