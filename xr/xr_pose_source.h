#pragma once
// The OpenXR session as a tracking::PoseSource ("openxr"): the headset loop publishes each
// frame's head (the VIEW pose between the eyes) and wrists (hand tracking, else grip * the
// profile's grip-to-wrist offset) at the predicted display time; consumers (the tracking guard,
// the IK stage) sample the newest one. Validity is OpenXR's: a pose without both VALID bits is
// an invalid tracker, which the tracking-loss rules then handle.
#include <mutex>

#include "xr/xr_common.h"
#include "tracking/pose_source.h"

namespace embody::xr {

class XrPoseSource : public tracking::PoseSource {
 public:
  std::string name() const override { return "openxr"; }
  tracking::TrackerMask trackers() const override { return tracking::TrackerMask::threePoint(); }
  double duration() const override { return 0.0; }  // live: no clip length
  // The newest published sample (a live source has nothing older to interpolate); `time` is
  // ignored. Before the first publish every tracker is invalid.
  tracking::PoseSample sample(double time) override;

  // `time`: seconds since the session began (the predicted display time of the frame).
  void publish(double time, const TrackedPose& head, const TrackedPose& leftWrist,
               const TrackedPose& rightWrist);
  uint64_t published() const;

 private:
  mutable std::mutex mutex_;
  tracking::PoseSample latest_;
  uint64_t count_ = 0;
};

}  // namespace embody::xr
