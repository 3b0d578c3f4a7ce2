#pragma once
// Vulkan instance with optional Khronos validation and a debug-utils messenger that counts (and
// forwards) every validation message. Move-only RAII owner of VkInstance and the messenger.
#include <vulkan/vulkan.h>

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/result.h"

namespace embody::engine {

struct ValidationMessage {
  VkDebugUtilsMessageSeverityFlagBitsEXT severity;
  VkDebugUtilsMessageTypeFlagsEXT type;
  std::string idName;
  std::string text;
};

enum class Validation {
  Off,       // no layer
  IfPresent, // enable the layer when it is installed (debug builds, the CLI's --validate)
  Required,  // fail instance creation when it cannot load (every test)
};

struct InstanceOptions {
  std::string appName = "embody";
  Validation validation = Validation::Off;
  std::vector<std::string> extensions;  // beyond debug-utils (added when validating)
  // Called for every message the messenger counts (after the allow-list). May be called from
  // any thread the driver uses.
  std::function<void(const ValidationMessage&)> onMessage;
  // Print counted messages to stderr.
  bool printMessages = true;
};

struct PhysicalDeviceInfo {
  VkPhysicalDevice handle = VK_NULL_HANDLE;
  std::string name;
  std::string driverName;
  std::string driverInfo;
  VkPhysicalDeviceType type = VK_PHYSICAL_DEVICE_TYPE_OTHER;
  uint32_t apiVersion = 0;
  std::string typeName() const;
  std::string apiVersionString() const;
};

// Name, driver and type of one physical device.
PhysicalDeviceInfo describePhysicalDevice(VkPhysicalDevice device);

class Instance {
 public:
  static Result<Instance> create(const InstanceOptions& options);
  // Wraps an instance created by someone else (the OpenXR runtime via XR_KHR_vulkan_enable2);
  // does not destroy it.
  static Instance borrow(VkInstance instance);

  Instance();
  Instance(Instance&&) noexcept;
  Instance& operator=(Instance&&) noexcept;
  Instance(const Instance&) = delete;
  Instance& operator=(const Instance&) = delete;
  ~Instance();

  VkInstance handle() const { return instance_; }
  bool validationEnabled() const { return messenger_ != VK_NULL_HANDLE; }
  // Messages counted so far (validation warnings and errors; loader notices are not counted).
  uint32_t messageCount() const;
  std::vector<PhysicalDeviceInfo> physicalDevices() const;

  // Whether the Khronos validation layer is installed (without creating an instance).
  static bool validationLayerAvailable();
  static uint32_t loaderApiVersion();

  struct Shared;  // state the messenger callback points at; stable across moves

 private:
  void reset();
  VkInstance instance_ = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
  std::unique_ptr<Shared> shared_;
  bool owned_ = false;
};

}  // namespace embody::engine
