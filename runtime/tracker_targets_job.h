#pragma once
// Trackers -> targets: a guarded sample (tracking space) to every tracker's target in the avatar's
// model space, as its joint's pose, with its weight. Pure math, no allocation.
//
//   TrackerTargetsJob job;
//   job.rig = &rig; job.calibration = &calibration; job.sample = &guarded; job.targets = &targets;
//   if (job.Run()) ...  // Run() validates first
//
// point    = rig.toAvatar(scale, p) + up * heightOffset[tracker]
// rotation = (rig.fromTracking * q) * rig.jointFromTracker[tracker]
// weight   = statusWeight(status) for a valid pose, else 0 (the hips' 0 too without pelvisRow)
//
// Arm length (armScale != 1, from a profile's arm span: the user's arm over the avatar's, scaled
// to the user's height): before the mapping a hand is moved towards or away from the user's shoulder,
// estimated from the head (tracking::BodyDimensions::shoulderFromHead), by 1 / armScale, so a
// user with longer arms than the avatar's proportions reaches the avatar's full reach with a
// straight arm, not beyond it, and a shorter-armed user's straight arm straightens the avatar's.
#include "runtime/body_calibration.h"
#include "runtime/body_rig.h"
#include "runtime/body_targets.h"

namespace embody::runtime {

struct TrackerTargetsJob {
  const BodyRig* rig = nullptr;
  const BodyCalibration* calibration = nullptr;  // scaled()
  const tracking::GuardedSample* sample = nullptr;
  bool pelvisRow = true;  // AvatarBodyOptions::pelvisRow: a tracked pelvis pulls
  double armScale = 1.0;  // AvatarBodyOptions::armScale (avatar::plausibleArmScale)
  BodyTargets* targets = nullptr;  // out

  // Every pointer set, the calibration scaled with finite values, the sample's poses finite.
  bool Validate() const;
  bool Run() const;

 private:
  glm::vec3 userHand(tracking::TrackerId id, const glm::vec3& position) const;
};

}  // namespace embody::runtime
