#include "xr/xr_common.h"

#include <cmath>
#include <openxr/openxr_reflection.h>

namespace embody::xr {

std::string resultString(XrInstance instance, XrResult r) {
  char buf[XR_MAX_RESULT_STRING_SIZE] = {};
  if (instance != XR_NULL_HANDLE && XR_SUCCEEDED(xrResultToString(instance, r, buf))) return buf;
  // Without an instance (xrCreateInstance itself failed) the registry's names, from the SDK's
  // reflection header: "XR_ERROR_API_LAYER_NOT_PRESENT" says what "-36" did not.
  switch (r) {
#define EMBODY_XR_RESULT_NAME(name, value) \
  case name:                               \
    return #name;
    XR_LIST_ENUM_XrResult(EMBODY_XR_RESULT_NAME)
#undef EMBODY_XR_RESULT_NAME
    default:
      return "XrResult " + std::to_string(static_cast<int>(r));
  }
}

TrackedPose fromSpaceLocation(const XrSpaceLocation& loc) {
  TrackedPose t;
  const bool orientationValid = loc.locationFlags & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  const bool positionValid = loc.locationFlags & XR_SPACE_LOCATION_POSITION_VALID_BIT;
  t.valid = orientationValid && positionValid;
  t.tracked = t.valid && (loc.locationFlags & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT) &&
              (loc.locationFlags & XR_SPACE_LOCATION_POSITION_TRACKED_BIT);
  if (t.valid) t.pose = fromXr(loc.pose);
  return t;
}

}  // namespace embody::xr
