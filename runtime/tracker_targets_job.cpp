#include "runtime/tracker_targets_job.h"

#include <cmath>

#include "avatar/glm_eigen.h"

namespace embody::runtime {

using tracking::TrackerId;

namespace {

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite(const glm::quat& q) { return std::isfinite(q.w) && finite(glm::vec3(q.x, q.y, q.z)); }

}  // namespace

bool TrackerTargetsJob::Validate() const {
  if (!rig || !calibration || !sample || !targets) return false;
  if (!calibration->scaled() || !std::isfinite(calibration->scale) || !std::isfinite(calibration->legRatio)) return false;
  for (double h : calibration->heightOffset)
    if (!std::isfinite(h)) return false;
  for (auto id : tracking::kAllTrackers)
    if (!finite(sample->pose[id].position) || !finite(sample->pose[id].orientation)) return false;
  return true;
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
    targets->point[i] = r.toAvatar(calibration->scale, avatar::toEigen(tp.position)) + r.up * calibration->heightOffset[i];
    targets->rotation[i] = (r.fromTracking * avatar::toEigen(tp.orientation)).normalized() * r.jointFromTracker[i];
  }
  return true;
}

}  // namespace embody::runtime
