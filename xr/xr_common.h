#pragma once
// Shared includes and small helpers of the OpenXR application side (embody_xr). The Vulkan
// platform types must be visible before openxr_platform.h.
#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#include <ctime>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>

#include "tracking/tracker.h"
#include "xr/xr_pose.h"

namespace embody::xr {

// "XR_ERROR_SESSION_LOST" (through the runtime when an instance exists, else the number).
std::string resultString(XrInstance instance, XrResult r);

// The project's one rigid pose (tracking/tracker.h: OpenXR conventions, metres, +Y up, -Z
// forward); fromXr / toXr convert it from and to OpenXR's XrPosef (xr_pose.h).
using Pose = tracking::Pose;

// A pose with the tracking state OpenXR reported for it. valid: the pose can be used (maybe
// inferred); tracked: it is actively tracked now. Consumers treat !valid as "tracking lost".
struct TrackedPose {
  Pose pose;
  bool valid = false;
  bool tracked = false;
};
TrackedPose fromSpaceLocation(const XrSpaceLocation& loc);

}  // namespace embody::xr
