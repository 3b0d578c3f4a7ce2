#include "runtime/tracker_targets_job.h"

#include <cmath>

#include "avatar/body/calibration.h"
#include "avatar/glm_eigen.h"
#include "tracking/body_dimensions.h"

namespace embody::runtime {

using tracking::TrackerId;

namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::quat& q) { return std::isfinite(q.w) && finite(glm::vec3(q.x, q.y, q.z)); }

}  // namespace

bool TrackerTargetsJob::Validate() const {
  if (!rig || !calibration || !sample || !targets) return false;
  if (!calibration->scaled() || !std::isfinite(calibration->scale) || !std::isfinite(calibration->legRatio)) return false;
  if (!avatar::plausibleArmScale(armScale)) return false;
  for (double h : calibration->heightOffset)
    if (!std::isfinite(h)) return false;
  for (auto id : tracking::kAllTrackers)
    if (!finite(sample->pose[id].position) || !finite(sample->pose[id].orientation)) return false;
  return true;
}

// A hand's position with the user's arm scaled to the avatar's proportions (the header): the
// offset from the shoulder the head implies, divided by armScale. Other trackers, a hand without
// a live head or armScale 1: unchanged.
glm::vec3 TrackerTargetsJob::userHand(tracking::TrackerId id, const glm::vec3& position) const {
  const bool hand = id == TrackerId::LeftHand || id == TrackerId::RightHand;
  const tracking::TrackerPose& head = sample->pose[TrackerId::Head];
  if (!hand || armScale == 1.0 || !head.valid) return position;
  const auto dims = tracking::BodyDimensions::fromHeight(float(rig->avatarHeight / calibration->scale));
  const glm::vec3 shoulder = dims.shoulderFromHead(head, id == TrackerId::LeftHand ? tracking::Side::Left : tracking::Side::Right);
  return shoulder + (position - shoulder) / float(armScale);
}

bool TrackerTargetsJob::Run() const {
  if (!Validate()) return false;
  const BodyRig& r = *rig;
  // Every tracker's target, in avatar space, as its joint's pose.
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    const tracking::TrackerPose& tp = sample->pose[id];
    double w = tp.valid ? statusWeight(sample->status[i]) : 0.0;
    if (id == TrackerId::Hips && !pelvisRow) w = 0.0;
    targets->weight[i] = w;
    targets->point[i] = r.toAvatar(calibration->scale, avatar::toEigen(userHand(id, tp.position))) + r.up * calibration->heightOffset[i];
    targets->rotation[i] = (r.fromTracking * avatar::toEigen(tp.orientation)).normalized() * r.jointFromTracker[i];
  }
  return true;
}

}  // namespace embody::runtime
