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

namespace embody::xr {

// "XR_ERROR_SESSION_LOST" (through the runtime when an instance exists, else the number).
std::string resultString(XrInstance instance, XrResult r);

// A rigid pose in OpenXR conventions (metres, right-handed, +Y up, -Z forward).
struct Pose {
  glm::vec3 position{0.0f};
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::mat4 matrix() const;
  Pose operator*(const Pose& b) const;  // this * b
  Pose inverse() const;
  static Pose fromXr(const XrPosef& p);
  XrPosef toXr() const;
};

// A pose with the tracking state OpenXR reported for it. valid: the pose can be used (maybe
// inferred); tracked: it is actively tracked now. Consumers treat !valid as "tracking lost".
struct TrackedPose {
  Pose pose;
  bool valid = false;
  bool tracked = false;
};
TrackedPose fromSpaceLocation(const XrSpaceLocation& loc);

}  // namespace embody::xr
