#include "xr/xr_pose_source.h"

namespace embody::xr {

namespace {
tracking::TrackerPose toTracker(const TrackedPose& p) {
  return {p.pose.position, p.pose.orientation, p.valid};
}
}  // namespace

tracking::PoseSample XrPoseSource::sample(double) {
  std::lock_guard lock(mutex_);
  return latest_;
}

void XrPoseSource::publish(double time, const TrackedPose& head, const TrackedPose& leftWrist,
                           const TrackedPose& rightWrist) {
  tracking::PoseSample s;
  s.time = time;
  s[tracking::TrackerId::Head] = toTracker(head);
  s[tracking::TrackerId::LeftHand] = toTracker(leftWrist);
  s[tracking::TrackerId::RightHand] = toTracker(rightWrist);
  tracking::sanitize(s);  // a misbehaving runtime never puts NaN into a valid tracker
  std::lock_guard lock(mutex_);
  latest_ = s;
  ++count_;
}

uint64_t XrPoseSource::published() const {
  std::lock_guard lock(mutex_);
  return count_;
}

}  // namespace embody::xr
