#pragma once
// The inferred body's heading in three-point mode: where the pelvis and the feet face, from the
// head's heading (faceHeadingOf). Upright, the body faces where the head does: a user who turns turns
// the body at once (a spinning jump lagged by a fixed band dragged the hands and knees round,
// cmu_131_03). Bent over, a head that looks at one leg and then the other turns on the neck while
// the body stays: the body follows the head only as far as `neckTurn` leaves between them. Before,
// each look turned the bent body and swung its pelvis, 0.6 m behind the head, from side to side.
//
// The body follows the head's yaw through a One Euro filter of its own (the tracker filter's
// tuned orientation cutoffs: 1 Hz at rest, +3 Hz per rad/s). The head tracker's filter smooths a
// clean source (motion capture, a runtime's own filtered poses) only as much as its noise needs,
// so the head meets a fast turn from its first frame; a body turned as abruptly stepped its feet
// round one at a time behind it and crossed its legs (half a turn in 0.6 s), so the body's turn is
// eased in where the head's need not be. Stateful: one per body; reset() with the warm start.
//
// Walking, people face where they go and look about: over the three moving clips in shared/ the
// pelvis faced the travel within 1 degree on average (sd 6-8), where the head looked 2-15 degrees
// off it (cmu_12_01_walk: the pelvis 1.2 from the travel, the head -14.7). So a walking body
// turns from the head's heading to the travel's (`facingTravel`), fully from `fullSpeed` on and
// while the travel is within `fullWithin` of the head's heading; stepping sideways or backwards
// (the travel past `noneBeyond`) the body keeps the head's heading.
#include <Eigen/Core>

#include "tracking/one_euro_filter.h"

namespace embody::runtime {

struct BodyHeadingConfig {
  bool smoothed = true;  // false: the body takes the head's yaw as it comes (tests)
  // The tracker filter's tuned orientation cutoffs (its referenceNoise is not read here: the yaw
  // is smoothed as a 0.3 deg tracker's would be, whatever the source's noise).
  tracking::OneEuroParams smoothing = tracking::TrackerFilterParams{}.orientation;
  // Facing the travel while walking: from none at `noSpeed` to all at `fullSpeed` (m/s at a
  // 1.75 m avatar's scale), while the travel is within `fullWithin` of the heading, none past
  // `noneBeyond` (radians).
  double noSpeed = 0.3, fullSpeed = 0.7;
  double fullWithin = 0.436, noneBeyond = 0.785;  // 25 and 45 degrees
};

class BodyHeading {
 public:
  explicit BodyHeading(const BodyHeadingConfig& config = {}) : config_(config) {}
  void reset() { initialised_ = false; }
  // The body's heading (radians about up) for the head's heading at `time` (seconds), at most
  // `neckTurn` radians from the smoothed head heading (0: that heading itself). The first call
  // after a reset, or after a gap over half a second, takes the head's as it is.
  double update(double headYaw, double neckTurn, double time);
  // `yaw` turned towards the body's travel (its mean ground velocity, avatar space) as far as
  // the body walks (`walking`, 0 standing .. 1 walking: the foot planner's) and the travel's
  // speed and direction say. `scale`: the avatar's height / 1.75 m.
  double facingTravel(double yaw, const Eigen::Vector3d& travel, double walking, const Eigen::Vector3d& up,
                      const Eigen::Vector3d& forward, double scale) const;

 private:
  // The head's yaw through the One Euro filter (radians, wrapped).
  double smoothedHeadYaw(double headYaw, double time);

  BodyHeadingConfig config_;
  double yaw_ = 0.0;
  double rawYaw_ = 0.0, smoothYaw_ = 0.0, rate_ = 0.0, lastTime_ = 0.0;
  bool initialised_ = false;
};

}  // namespace embody::runtime
