#pragma once
// An in-process session on the headless runtime for API-level tests. The Vulkan instance comes
// from TestInstance (validation on) and is handed to the runtime through XR_KHR_vulkan_enable
// (the legacy extension lets the application create the instance itself).
#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "tests/support/vulkan_test_instance.h"

namespace embody::test {

class HeadlessSession {
 public:
  // `env` is set (setenv) before the instance is created, e.g. EMBODY_XR_POSES.
  explicit HeadlessSession(const std::map<std::string, std::string>& env = {});
  ~HeadlessSession();

  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  XrSession session = XR_NULL_HANDLE;
  XrSpace stage = XR_NULL_HANDLE;

  XrPath path(const char* s);
  template <typename Fn>
  Fn proc(const char* name) {
    PFN_xrVoidFunction f = nullptr;
    xrGetInstanceProcAddr(instance, name, &f);
    return reinterpret_cast<Fn>(f);
  }
  // Drains events; returns the session states seen, in order.
  std::vector<XrSessionState> poll();
  // Polls, begins the session on READY, and runs frames (no layers) until FOCUSED.
  void runUntilFocused();
  XrTime lastDisplayTime = 0;
  // One hand's joints in STAGE at `time`, through a hand tracker created for the call; returns
  // the locations' isActive.
  bool locateHand(XrHandEXT hand, XrTime time,
                  std::array<XrHandJointLocationEXT, XR_HAND_JOINT_COUNT_EXT>& joints);

 private:
  std::unique_ptr<TestInstance> vk_;
  VkDevice device_ = VK_NULL_HANDLE;
};

// A trace file with the given JSON lines, in the test output folder.
std::string writeTraceFile(const std::string& name, const std::vector<std::string>& lines);

}  // namespace embody::test
