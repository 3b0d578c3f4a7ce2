#pragma once
// A cross-fade between two skeleton poses: after the solver restarts from a new configuration
// (a recovery from a collapse, collapse_guard.h) the published pose moves from the last one shown
// to the new solution over a fraction of a second instead of jumping.
#include "avatar/skeleton.h"

namespace embody::runtime {

// out = from at t = 0, to at t = 1 (per joint: translations and scales lerped, rotations slerped
// along the shorter arc). `out` may alias `to`. All three have the same joint count; nothing is
// allocated when `out` already has it.
void blendPoses(const avatar::SkeletonPose& from, const avatar::SkeletonPose& to, float t, avatar::SkeletonPose& out);

// Holds the pose to fade from and how far the fade has gone.
class PoseFade {
 public:
  // Starts a fade from `shown` (copied; allocation only when the joint count grows) lasting
  // `seconds`, from `time`.
  void start(const avatar::SkeletonPose& shown, double time, double seconds);
  // Blends `pose` (the new solution) in place while the fade runs; smoothstep weights.
  void apply(double time, avatar::SkeletonPose& pose);
  bool active() const { return active_; }

 private:
  avatar::SkeletonPose from_;
  double start_ = 0.0, seconds_ = 0.2;
  bool active_ = false;
};

}  // namespace embody::runtime
