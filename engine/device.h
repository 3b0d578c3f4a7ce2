#pragma once
// Logical device: physical-device selection (discrete > integrated > virtual > CPU/lavapipe, or
// what --device names), one graphics+compute queue, Vulkan 1.3 core features (dynamic rendering,
// synchronization2) and multiview. Can also adopt a device someone else created (the OpenXR
// runtime through XR_KHR_vulkan_enable2), in which case nothing of it is destroyed here.
#include <vulkan/vulkan.h>

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.h"
#include "engine/instance.h"
#include "engine/vk_handle.h"

namespace embody::engine {

// Picks a physical device from `devices`. selector: "" or "auto" = best by type (discrete,
// integrated, virtual, CPU) among devices with Vulkan >= 1.3; a decimal number = that index;
// "cpu"/"lavapipe"/"llvmpipe" = the first CPU device; anything else = first device whose name
// contains it (case-insensitive). Returns the index, or an error listing the devices.
Result<size_t> choosePhysicalDevice(const std::vector<PhysicalDeviceInfo>& devices, std::string_view selector);

// The device features the renderer needs, reported for a physical device ("" = all present).
std::string missingRequiredFeatures(VkPhysicalDevice physical);

// Device extensions/feature structs a caller creating the VkDevice itself must enable (for
// xrCreateVulkanDeviceKHR): fill `features13`, `features11` and chain them into `features2`.
struct RequiredDeviceFeatures {
  VkPhysicalDeviceFeatures2 features2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan11Features features11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceVulkan13Features features13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  RequiredDeviceFeatures();
  RequiredDeviceFeatures(const RequiredDeviceFeatures&) = delete;  // self-referential pNext chain
  RequiredDeviceFeatures& operator=(const RequiredDeviceFeatures&) = delete;
};

struct AdoptedDevice {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  uint32_t queueFamily = 0;
  uint32_t queueIndex = 0;
};

class Device {
 public:
  // Creates a device on the physical device `selector` picks (see choosePhysicalDevice).
  static Result<std::unique_ptr<Device>> create(const Instance& instance, std::string_view selector = "");
  static Result<std::unique_ptr<Device>> create(const Instance& instance, VkPhysicalDevice physical);
  // Wraps a device created elsewhere (it must have the features RequiredDeviceFeatures lists);
  // the caller keeps ownership of the VkInstance/VkDevice and destroys them after this object.
  static Result<std::unique_ptr<Device>> adopt(const AdoptedDevice& external);

  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  ~Device();

  VkInstance instance() const { return instance_; }
  VkPhysicalDevice physical() const { return physical_; }
  VkDevice handle() const { return device_; }
  VkQueue queue() const { return queue_; }
  uint32_t queueFamily() const { return queueFamily_; }
  const PhysicalDeviceInfo& info() const { return info_; }
  // "llvmpipe (LLVM 15.0.6, 256 bits) / llvmpipe Mesa 22.3.6": what goldens and benchmarks record.
  std::string driverString() const { return info_.name + " / " + info_.driverName + " " + info_.driverInfo; }
  bool owned() const { return owned_; }
  const VkPhysicalDeviceLimits& limits() const { return limits_; }

  // A memory type index with all of `required` among `typeBits`; prefers also having `preferred`.
  // UINT32_MAX when none.
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred = 0) const;
  bool supportsSamples(VkSampleCountFlagBits samples) const;
  // Whether optimal-tiling images of `format` can be blit sources and destinations with linear
  // filtering and sampled linearly (what generating mip levels at upload needs).
  bool supportsLinearBlit(VkFormat format) const;

  // Records `record` into a one-shot command buffer, submits it and waits (uploads, readback,
  // compute tests). Not for per-frame work.
  Status submitAndWait(const std::function<void(VkCommandBuffer)>& record) const;
  void waitIdle() const;

 private:
  Device() = default;
  Status finishSetup();

  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  uint32_t queueFamily_ = 0;
  bool owned_ = false;
  PhysicalDeviceInfo info_;
  VkPhysicalDeviceMemoryProperties memory_{};
  VkPhysicalDeviceLimits limits_{};
  UniqueCommandPool oneShotPool_;
};

}  // namespace embody::engine
