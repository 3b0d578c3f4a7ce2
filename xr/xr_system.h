#pragma once
// XrSystem: the OpenXR instance, the HMD system and the Vulkan instance/device that the runtime
// creates for us (XR_KHR_vulkan_enable2), owned together because they must die in one order:
// everything built on the VkDevice first, then the VkDevice, the VkInstance, the XrInstance.
#include <array>
#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include "core/result.h"
#include "xr/xr_common.h"

namespace embody::xr {

struct XrSystemOptions {
  std::string appName = "embody";
  // The Khronos validation layer on the Vulkan instance the runtime creates for us; messages are
  // counted (validationMessages()) and printed to stderr.
  bool vulkanValidation = false;
  bool handTracking = true;  // enable XR_EXT_hand_tracking when the runtime offers it
  std::vector<std::string> vulkanInstanceExtensions;  // e.g. surface extensions for a mirror window
  std::vector<std::string> vulkanDeviceExtensions;    // e.g. VK_KHR_swapchain for a mirror window
};

class XrSystem {
 public:
  static Result<std::unique_ptr<XrSystem>> create(const XrSystemOptions& options);
  ~XrSystem();
  XrSystem(const XrSystem&) = delete;
  XrSystem& operator=(const XrSystem&) = delete;

  XrInstance instance() const { return instance_; }
  XrSystemId systemId() const { return systemId_; }
  const std::string& runtimeName() const { return runtimeName_; }
  const std::string& systemName() const { return systemName_; }
  bool handTrackingEnabled() const { return handTracking_; }
  bool depthLayerEnabled() const { return depthLayer_; }
  // Recommended per-eye image sizes of the primary stereo configuration.
  const std::array<XrViewConfigurationView, 2>& views() const { return views_; }

  VkInstance vkInstance() const { return vkInstance_; }
  VkPhysicalDevice vkPhysicalDevice() const { return vkPhysical_; }
  VkDevice vkDevice() const { return vkDevice_; }
  uint32_t queueFamily() const { return queueFamily_; }
  uint32_t validationMessages() const { return messages_->load(); }
  // The counter itself, which outlives this object (messages come until vkDestroyInstance returns).
  std::shared_ptr<const std::atomic<uint32_t>> validationCounter() const { return messages_; }

  XrPath path(const char* s) const;  // XR_NULL_PATH on a malformed string
  std::string pathString(XrPath p) const;
  std::string result(XrResult r) const { return resultString(instance_, r); }
  // A function of an enabled extension (nullptr when the runtime does not provide it).
  PFN_xrVoidFunction proc(const char* name) const;
  // The runtime's current time (XR_KHR_convert_timespec_time on CLOCK_MONOTONIC); 0 when the
  // runtime does not offer the extension.
  XrTime now() const;

 private:
  XrSystem() = default;
  Status createInstance(const XrSystemOptions& o);
  // createVulkan's steps: the runtime's Vulkan version, the instance (with the validation
  // messenger), the device on the physical device the runtime names.
  Status createVulkan(const XrSystemOptions& o);
  Status checkVulkanVersion();
  Status createVulkanInstance(const XrSystemOptions& o);
  Status createVulkanDevice(const XrSystemOptions& o);

  XrInstance instance_ = XR_NULL_HANDLE;
  XrSystemId systemId_ = XR_NULL_SYSTEM_ID;
  std::string runtimeName_, systemName_;
  bool handTracking_ = false, depthLayer_ = false;
  PFN_xrConvertTimespecTimeToTimeKHR convertTimespec_ = nullptr;
  std::array<XrViewConfigurationView, 2> views_{};
  VkInstance vkInstance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  VkPhysicalDevice vkPhysical_ = VK_NULL_HANDLE;
  VkDevice vkDevice_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  std::shared_ptr<std::atomic<uint32_t>> messages_ = std::make_shared<std::atomic<uint32_t>>(0);
};

}  // namespace embody::xr
