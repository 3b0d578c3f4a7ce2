#pragma once
// The project's one rigid pose (tracking::Pose) from and to OpenXR's XrPosef: header-only, so the
// application side (embody_xr) and the headless OpenXR runtime (tools/xr_runtime) convert alike.
// Include after <openxr/openxr.h> has been configured (xr_common.h, tools/xr_runtime/runtime.h).
#include <openxr/openxr.h>

#include <cmath>

#include "tracking/tracker.h"

namespace embody::xr {

// A non-finite position or an unusable quaternion gives the identity pose: never NaN from a
// misbehaving runtime or application.
inline tracking::Pose fromXr(const XrPosef& p) {
  tracking::Pose r{{p.position.x, p.position.y, p.position.z},
                   glm::quat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z)};
  const float n = glm::length(r.orientation);
  if (!(n > 1e-6f) || !std::isfinite(n) || !std::isfinite(r.position.x) || !std::isfinite(r.position.y) ||
      !std::isfinite(r.position.z))
    return {};
  r.orientation /= n;
  return r;
}

inline XrPosef toXr(const tracking::Pose& pose) {
  XrPosef p;
  p.position = {pose.position.x, pose.position.y, pose.position.z};
  p.orientation = {pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w};
  return p;
}

}  // namespace embody::xr
