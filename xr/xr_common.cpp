#include "xr/xr_common.h"

#include <cmath>

namespace embody::xr {

std::string resultString(XrInstance instance, XrResult r) {
  char buf[XR_MAX_RESULT_STRING_SIZE] = {};
  if (instance != XR_NULL_HANDLE && XR_SUCCEEDED(xrResultToString(instance, r, buf))) return buf;
  return "XrResult " + std::to_string(static_cast<int>(r));
}

glm::mat4 Pose::matrix() const {
  glm::mat4 m = glm::mat4_cast(orientation);
  m[3] = glm::vec4(position, 1.0f);
  return m;
}

Pose Pose::operator*(const Pose& b) const {
  return {position + orientation * b.position, glm::normalize(orientation * b.orientation)};
}

Pose Pose::inverse() const {
  const glm::quat qi = glm::conjugate(orientation);
  return {qi * -position, qi};
}

Pose Pose::fromXr(const XrPosef& p) {
  Pose r{{p.position.x, p.position.y, p.position.z},
         glm::quat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)};
  const float n = glm::length(r.orientation);
  if (!(n > 1e-6f) || !std::isfinite(n) || !std::isfinite(r.position.x) || !std::isfinite(r.position.y) ||
      !std::isfinite(r.position.z))
    return {};  // never propagate NaN from a misbehaving runtime
  r.orientation /= n;
  return r;
}

XrPosef Pose::toXr() const {
  XrPosef p;
  p.position = {position.x, position.y, position.z};
  p.orientation = {orientation.x, orientation.y, orientation.z, orientation.w};
  return p;
}

TrackedPose fromSpaceLocation(const XrSpaceLocation& loc) {
  TrackedPose t;
  const bool orientationValid = loc.locationFlags & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  const bool positionValid = loc.locationFlags & XR_SPACE_LOCATION_POSITION_VALID_BIT;
  t.valid = orientationValid && positionValid;
  t.tracked = t.valid && (loc.locationFlags & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT) &&
              (loc.locationFlags & XR_SPACE_LOCATION_POSITION_TRACKED_BIT);
  if (t.valid) t.pose = Pose::fromXr(loc.pose);
  return t;
}

}  // namespace embody::xr
