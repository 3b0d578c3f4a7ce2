// The headless runtime's instance-level API, called in-process through the real OpenXR loader:
// negotiation, extensions, system and view configuration, paths, strings, unsupported functions.
#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "xr/xr_common.h"
#include "xr_test_support.h"

using namespace embody::test;

namespace {

struct ScopedXrInstance {
  XrInstance handle = XR_NULL_HANDLE;
  explicit ScopedXrInstance(std::vector<const char*> extensions = {}) {
    setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
    XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
    std::strcpy(ci.applicationInfo.applicationName, "embody-tests");
    ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
    ci.enabledExtensionCount = static_cast<uint32_t>(extensions.size());
    ci.enabledExtensionNames = extensions.data();
    REQUIRE(xrCreateInstance(&ci, &handle) == XR_SUCCESS);
  }
  ~ScopedXrInstance() {
    if (handle) xrDestroyInstance(handle);
  }
};

template <typename Fn>
Fn proc(XrInstance inst, const char* name) {
  PFN_xrVoidFunction f = nullptr;
  REQUIRE(xrGetInstanceProcAddr(inst, name, &f) == XR_SUCCESS);
  return reinterpret_cast<Fn>(f);
}

}  // namespace

TEST_CASE("the loader negotiates with the headless runtime and lists its extensions", "[xr]") {
  setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
  uint32_t n = 0;
  REQUIRE(xrEnumerateInstanceExtensionProperties(nullptr, 0, &n, nullptr) == XR_SUCCESS);
  std::vector<XrExtensionProperties> props(n, {XR_TYPE_EXTENSION_PROPERTIES});
  REQUIRE(xrEnumerateInstanceExtensionProperties(nullptr, n, &n, props.data()) == XR_SUCCESS);
  std::vector<std::string> names;
  for (const auto& p : props) names.push_back(p.extensionName);
  for (const char* want : {"XR_KHR_vulkan_enable2", "XR_KHR_vulkan_enable", "XR_EXT_hand_tracking",
                           "XR_KHR_composition_layer_depth"})
    CHECK(std::find(names.begin(), names.end(), want) != names.end());

  ScopedXrInstance inst;
  XrInstanceProperties ip{XR_TYPE_INSTANCE_PROPERTIES};
  REQUIRE(xrGetInstanceProperties(inst.handle, &ip) == XR_SUCCESS);
  CHECK(std::string(ip.runtimeName) == "Embody headless runtime");
}

TEST_CASE("an unknown extension fails instance creation cleanly", "[xr]") {
  setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "embody-tests");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  const char* ext = "XR_FB_passthrough";
  ci.enabledExtensionCount = 1;
  ci.enabledExtensionNames = &ext;
  XrInstance inst = XR_NULL_HANDLE;
  CHECK(xrCreateInstance(&ci, &inst) == XR_ERROR_EXTENSION_NOT_PRESENT);
}

TEST_CASE("the system is an HMD with a primary stereo view configuration of two views", "[xr]") {
  ScopedXrInstance inst({"XR_EXT_hand_tracking"});
  XrSystemGetInfo gi{XR_TYPE_SYSTEM_GET_INFO};
  gi.formFactor = XR_FORM_FACTOR_HANDHELD_DISPLAY;
  XrSystemId sys = XR_NULL_SYSTEM_ID;
  CHECK(xrGetSystem(inst.handle, &gi, &sys) == XR_ERROR_FORM_FACTOR_UNSUPPORTED);
  gi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  REQUIRE(xrGetSystem(inst.handle, &gi, &sys) == XR_SUCCESS);

  XrSystemHandTrackingPropertiesEXT hand{XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT};
  XrSystemProperties sp{XR_TYPE_SYSTEM_PROPERTIES, &hand};
  REQUIRE(xrGetSystemProperties(inst.handle, sys, &sp) == XR_SUCCESS);
  CHECK(sp.trackingProperties.positionTracking == XR_TRUE);
  CHECK(hand.supportsHandTracking == XR_TRUE);

  uint32_t n = 0;
  REQUIRE(xrEnumerateViewConfigurations(inst.handle, sys, 0, &n, nullptr) == XR_SUCCESS);
  std::vector<XrViewConfigurationType> types(n);
  REQUIRE(xrEnumerateViewConfigurations(inst.handle, sys, n, &n, types.data()) == XR_SUCCESS);
  REQUIRE(types == std::vector<XrViewConfigurationType>{XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO});

  REQUIRE(xrEnumerateViewConfigurationViews(inst.handle, sys, types[0], 0, &n, nullptr) == XR_SUCCESS);
  REQUIRE(n == 2);
  std::vector<XrViewConfigurationView> views(n, {XR_TYPE_VIEW_CONFIGURATION_VIEW});
  // The two-call idiom: too small a buffer is an error, the count is still reported.
  CHECK(xrEnumerateViewConfigurationViews(inst.handle, sys, types[0], 1, &n, views.data()) ==
        XR_ERROR_SIZE_INSUFFICIENT);
  CHECK(n == 2);
  REQUIRE(xrEnumerateViewConfigurationViews(inst.handle, sys, types[0], n, &n, views.data()) == XR_SUCCESS);
  for (const auto& v : views) {
    CHECK(v.recommendedImageRectWidth >= 64);
    CHECK(v.recommendedImageRectHeight >= 64);
    CHECK(v.recommendedImageRectWidth <= v.maxImageRectWidth);
  }
  REQUIRE(xrEnumerateEnvironmentBlendModes(inst.handle, sys, types[0], 0, &n, nullptr) == XR_SUCCESS);
  CHECK(n == 1);
}

TEST_CASE("paths round-trip and malformed paths are rejected", "[xr]") {
  ScopedXrInstance inst;
  XrPath a = XR_NULL_PATH, b = XR_NULL_PATH;
  REQUIRE(xrStringToPath(inst.handle, "/user/hand/left/input/grip/pose", &a) == XR_SUCCESS);
  REQUIRE(xrStringToPath(inst.handle, "/user/hand/left/input/grip/pose", &b) == XR_SUCCESS);
  CHECK(a == b);
  CHECK(a != XR_NULL_PATH);
  char buf[XR_MAX_PATH_LENGTH];
  uint32_t n = 0;
  REQUIRE(xrPathToString(inst.handle, a, sizeof(buf), &n, buf) == XR_SUCCESS);
  CHECK(std::string(buf) == "/user/hand/left/input/grip/pose");
  CHECK(n == std::strlen(buf) + 1);
  for (const char* bad :
       {"user/hand", "/user/hand/", "/user//hand", "/User/hand", "/user/./hand", "/user/hand left"})
    CHECK(xrStringToPath(inst.handle, bad, &a) == XR_ERROR_PATH_FORMAT_INVALID);
  CHECK(xrPathToString(inst.handle, 999999, sizeof(buf), &n, buf) == XR_ERROR_PATH_INVALID);
}

TEST_CASE("result and structure type strings come from the registry", "[xr]") {
  ScopedXrInstance inst;
  char buf[XR_MAX_RESULT_STRING_SIZE];
  REQUIRE(xrResultToString(inst.handle, XR_ERROR_SESSION_LOST, buf) == XR_SUCCESS);
  CHECK(std::string(buf) == "XR_ERROR_SESSION_LOST");
  REQUIRE(xrResultToString(inst.handle, static_cast<XrResult>(-999999), buf) == XR_SUCCESS);
  CHECK(std::string(buf).find("UNKNOWN_FAILURE") != std::string::npos);
  char sbuf[XR_MAX_STRUCTURE_NAME_SIZE];
  REQUIRE(xrStructureTypeToString(inst.handle, XR_TYPE_HAND_JOINT_LOCATIONS_EXT, sbuf) == XR_SUCCESS);
  CHECK(std::string(sbuf) == "XR_TYPE_HAND_JOINT_LOCATIONS_EXT");
  // Without an instance (xrCreateInstance failed) embody's messages name the code from the SDK's
  // reflection header: "XrResult -36" said nothing (OpenXR probe, session 20).
  CHECK(embody::xr::resultString(XR_NULL_HANDLE, XR_ERROR_API_LAYER_NOT_PRESENT) == "XR_ERROR_API_LAYER_NOT_PRESENT");
  CHECK(embody::xr::resultString(inst.handle, XR_ERROR_SESSION_LOST) == "XR_ERROR_SESSION_LOST");
  CHECK(embody::xr::resultString(XR_NULL_HANDLE, static_cast<XrResult>(-999999)) == "XrResult -999999");
}

TEST_CASE("unimplemented and not-enabled functions are XR_ERROR_FUNCTION_UNSUPPORTED, never a crash",
          "[xr]") {
  PFN_xrVoidFunction f = reinterpret_cast<PFN_xrVoidFunction>(&xrDestroyInstance);
  {
    ScopedXrInstance inst;  // no extensions enabled (the 1.0.20 loader allows one instance at a time)
    CHECK(xrGetInstanceProcAddr(inst.handle, "xrCreateSpatialAnchorMSFT", &f) ==
          XR_ERROR_FUNCTION_UNSUPPORTED);
    CHECK(f == nullptr);
    CHECK(xrGetInstanceProcAddr(inst.handle, "xrCreateHandTrackerEXT", &f) == XR_ERROR_FUNCTION_UNSUPPORTED);
    CHECK(xrGetInstanceProcAddr(inst.handle, "xrNotAFunctionAtAll", &f) == XR_ERROR_FUNCTION_UNSUPPORTED);
  }

  ScopedXrInstance withHands({"XR_EXT_hand_tracking", "XR_KHR_vulkan_enable2"});
  CHECK(xrGetInstanceProcAddr(withHands.handle, "xrCreateHandTrackerEXT", &f) == XR_SUCCESS);
  CHECK(f != nullptr);
  auto requirements =
      proc<PFN_xrGetVulkanGraphicsRequirements2KHR>(withHands.handle, "xrGetVulkanGraphicsRequirements2KHR");
  XrGraphicsRequirementsVulkan2KHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
  CHECK(requirements(withHands.handle, 12345, &req) == XR_ERROR_SYSTEM_INVALID);
}

TEST_CASE("a malformed runtime setting fails instance creation instead of reading as its default", "[xr]") {
  // EMBODY_XR_FRAMES=30x was read as "no frame limit": hello_xr ran until its job's timeout
  // (OpenXR robustness probe, session 20); a bad view size or IPD quietly became the default.
  setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "embody-tests");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  struct Case {
    const char *name, *value;
    bool ok;
  };
  for (const Case& c : {Case{"EMBODY_XR_FRAMES", "30x", false}, Case{"EMBODY_XR_FRAMES", "-3", false},
                        Case{"EMBODY_XR_FRAMES", "30", true}, Case{"EMBODY_XR_LOSS_FRAMES", "ten", false},
                        Case{"EMBODY_XR_VIEW_SIZE", "garbage", false}, Case{"EMBODY_XR_VIEW_SIZE", "15x15", false},
                        Case{"EMBODY_XR_VIEW_SIZE", "64x64", true}, Case{"EMBODY_XR_IPD", "0.5", false},
                        Case{"EMBODY_XR_IPD", "0.063", true}}) {
    INFO(c.name << "=" << c.value);
    setenv(c.name, c.value, 1);
    XrInstance inst = XR_NULL_HANDLE;
    const XrResult r = xrCreateInstance(&ci, &inst);
    unsetenv(c.name);
    CHECK((r == XR_SUCCESS) == c.ok);
    if (!c.ok) CHECK(r == XR_ERROR_INITIALIZATION_FAILED);
    if (r == XR_SUCCESS) CHECK(xrDestroyInstance(inst) == XR_SUCCESS);
  }
}
