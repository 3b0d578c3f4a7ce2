#include "headless_session.h"

#include <catch2/catch.hpp>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "xr_test_support.h"

namespace embody::test {

HeadlessSession::HeadlessSession(const std::map<std::string, std::string>& env) {
  setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
  unsetenv("EMBODY_XR_POSES");
  unsetenv("EMBODY_XR_FRAMES");
  for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
  const char* exts[] = {XR_KHR_VULKAN_ENABLE_EXTENSION_NAME, XR_EXT_HAND_TRACKING_EXTENSION_NAME};
  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::strcpy(ci.applicationInfo.applicationName, "embody-tests");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  ci.enabledExtensionCount = 2;
  ci.enabledExtensionNames = exts;
  REQUIRE(xrCreateInstance(&ci, &instance) == XR_SUCCESS);
  XrSystemGetInfo gi{XR_TYPE_SYSTEM_GET_INFO};
  gi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  REQUIRE(xrGetSystem(instance, &gi, &system) == XR_SUCCESS);

  vk_ = std::make_unique<TestInstance>();
  XrGraphicsRequirementsVulkanKHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN_KHR};
  REQUIRE(proc<PFN_xrGetVulkanGraphicsRequirementsKHR>("xrGetVulkanGraphicsRequirementsKHR")(
              instance, system, &req) == XR_SUCCESS);
  VkPhysicalDevice pd = VK_NULL_HANDLE;
  REQUIRE(proc<PFN_xrGetVulkanGraphicsDeviceKHR>("xrGetVulkanGraphicsDeviceKHR")(
              instance, system, vk_->handle(), &pd) == XR_SUCCESS);
  const float prio = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = 0;  // lavapipe: one graphics+compute+transfer family
  qci.queueCount = 1;
  qci.pQueuePriorities = &prio;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  REQUIRE(vkCreateDevice(pd, &dci, nullptr, &device_) == VK_SUCCESS);

  XrGraphicsBindingVulkanKHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN_KHR};
  binding.instance = vk_->handle();
  binding.physicalDevice = pd;
  binding.device = device_;
  XrSessionCreateInfo sci{XR_TYPE_SESSION_CREATE_INFO, &binding};
  sci.systemId = system;
  REQUIRE(xrCreateSession(instance, &sci, &session) == XR_SUCCESS);
  XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
  rci.poseInReferenceSpace.orientation.w = 1.0f;
  REQUIRE(xrCreateReferenceSpace(session, &rci, &stage) == XR_SUCCESS);
}

HeadlessSession::~HeadlessSession() {
  if (instance) xrDestroyInstance(instance);  // destroys the session and what it created
  if (device_) vkDestroyDevice(device_, nullptr);
  vk_.reset();  // reports any validation message
}

XrPath HeadlessSession::path(const char* s) {
  XrPath p = XR_NULL_PATH;
  REQUIRE(xrStringToPath(instance, s, &p) == XR_SUCCESS);
  return p;
}

std::vector<XrSessionState> HeadlessSession::poll() {
  std::vector<XrSessionState> states;
  for (;;) {
    XrEventDataBuffer ev{XR_TYPE_EVENT_DATA_BUFFER};
    if (xrPollEvent(instance, &ev) != XR_SUCCESS) break;
    if (ev.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED)
      states.push_back(reinterpret_cast<XrEventDataSessionStateChanged&>(ev).state);
  }
  return states;
}

void HeadlessSession::runUntilFocused() {
  bool focused = false;
  for (int i = 0; i < 10 && !focused; ++i) {
    for (XrSessionState s : poll()) {
      if (s == XR_SESSION_STATE_READY) {
        XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
        bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
        REQUIRE(xrBeginSession(session, &bi) == XR_SUCCESS);
      }
      focused = focused || s == XR_SESSION_STATE_FOCUSED;
    }
    if (focused) break;
    XrFrameState fs{XR_TYPE_FRAME_STATE};
    REQUIRE(xrWaitFrame(session, nullptr, &fs) == XR_SUCCESS);
    REQUIRE(xrBeginFrame(session, nullptr) == XR_SUCCESS);
    XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
    ei.displayTime = fs.predictedDisplayTime;
    ei.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    REQUIRE(xrEndFrame(session, &ei) == XR_SUCCESS);
    lastDisplayTime = fs.predictedDisplayTime;
  }
  REQUIRE(focused);
}

std::string writeTraceFile(const std::string& name, const std::vector<std::string>& lines) {
  const std::string path = freshTestDir(name) + "/trace.jsonl";
  std::ofstream out(path);
  for (const auto& l : lines) out << l << "\n";
  return path;
}

bool HeadlessSession::locateHand(XrHandEXT hand, XrTime time,
                                 std::array<XrHandJointLocationEXT, XR_HAND_JOINT_COUNT_EXT>& joints) {
  auto create = proc<PFN_xrCreateHandTrackerEXT>("xrCreateHandTrackerEXT");
  auto locate = proc<PFN_xrLocateHandJointsEXT>("xrLocateHandJointsEXT");
  auto destroy = proc<PFN_xrDestroyHandTrackerEXT>("xrDestroyHandTrackerEXT");
  REQUIRE(create);
  REQUIRE(locate);
  REQUIRE(destroy);
  XrHandTrackerCreateInfoEXT ci{XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT};
  ci.hand = hand;
  ci.handJointSet = XR_HAND_JOINT_SET_DEFAULT_EXT;
  XrHandTrackerEXT tracker = XR_NULL_HANDLE;
  REQUIRE(create(session, &ci, &tracker) == XR_SUCCESS);
  XrHandJointLocationsEXT locs{XR_TYPE_HAND_JOINT_LOCATIONS_EXT};
  locs.jointCount = XR_HAND_JOINT_COUNT_EXT;
  locs.jointLocations = joints.data();
  XrHandJointsLocateInfoEXT li{XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT};
  li.baseSpace = stage;
  li.time = time;
  REQUIRE(locate(tracker, &li, &locs) == XR_SUCCESS);
  REQUIRE(destroy(tracker) == XR_SUCCESS);
  return locs.isActive == XR_TRUE;
}

}  // namespace embody::test
