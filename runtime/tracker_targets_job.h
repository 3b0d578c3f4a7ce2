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
#include "runtime/body_calibration.h"
#include "runtime/body_rig.h"
#include "runtime/body_targets.h"

namespace embody::runtime {

struct TrackerTargetsJob {
  const BodyRig* rig = nullptr;
  const BodyCalibration* calibration = nullptr;  // scaled()
  const tracking::GuardedSample* sample = nullptr;
  bool pelvisRow = true;  // AvatarBodyOptions::pelvisRow: a tracked pelvis pulls
  BodyTargets* targets = nullptr;  // out

  // Every pointer set, the calibration scaled with finite values, the sample's poses finite.
  bool Validate() const;
  bool Run() const;
};

}  // namespace embody::runtime
