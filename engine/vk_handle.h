#pragma once
// Move-only RAII owners for device-level Vulkan handles, plus the per-frame retire queue that
// keeps a resource alive until the frame that last used it has finished on the GPU.
#include <vulkan/vulkan.h>

#include <memory>
#include <utility>
#include <vector>

namespace embody::engine {

// Owns one handle created from `device`; destroys it with Destroy (vkDestroyX / vkFreeMemory all
// share the (VkDevice, T, const VkAllocationCallbacks*) signature).
template <class T, void (*Destroy)(VkDevice, T, const VkAllocationCallbacks*)>
class DeviceHandle {
 public:
  DeviceHandle() = default;
  DeviceHandle(VkDevice device, T handle) : device_(device), handle_(handle) {}
  DeviceHandle(DeviceHandle&& o) noexcept
      : device_(std::exchange(o.device_, VK_NULL_HANDLE)), handle_(std::exchange(o.handle_, T(VK_NULL_HANDLE))) {}
  DeviceHandle& operator=(DeviceHandle&& o) noexcept {
    if (this != &o) {
      reset();
      device_ = std::exchange(o.device_, VK_NULL_HANDLE);
      handle_ = std::exchange(o.handle_, T(VK_NULL_HANDLE));
    }
    return *this;
  }
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;
  ~DeviceHandle() { reset(); }

  void reset() {
    if (handle_ != T(VK_NULL_HANDLE)) Destroy(device_, handle_, nullptr);
    handle_ = T(VK_NULL_HANDLE);
  }
  T get() const { return handle_; }
  VkDevice device() const { return device_; }
  explicit operator bool() const { return handle_ != T(VK_NULL_HANDLE); }

 private:
  VkDevice device_ = VK_NULL_HANDLE;
  T handle_ = T(VK_NULL_HANDLE);
};

using UniqueBuffer = DeviceHandle<VkBuffer, vkDestroyBuffer>;
using UniqueImage = DeviceHandle<VkImage, vkDestroyImage>;
using UniqueImageView = DeviceHandle<VkImageView, vkDestroyImageView>;
using UniqueMemory = DeviceHandle<VkDeviceMemory, vkFreeMemory>;
using UniqueSampler = DeviceHandle<VkSampler, vkDestroySampler>;
using UniqueFence = DeviceHandle<VkFence, vkDestroyFence>;
using UniqueSemaphore = DeviceHandle<VkSemaphore, vkDestroySemaphore>;
using UniqueCommandPool = DeviceHandle<VkCommandPool, vkDestroyCommandPool>;
using UniqueDescriptorPool = DeviceHandle<VkDescriptorPool, vkDestroyDescriptorPool>;
using UniqueDescriptorSetLayout = DeviceHandle<VkDescriptorSetLayout, vkDestroyDescriptorSetLayout>;
using UniquePipelineLayout = DeviceHandle<VkPipelineLayout, vkDestroyPipelineLayout>;
using UniquePipeline = DeviceHandle<VkPipeline, vkDestroyPipeline>;
using UniqueShaderModule = DeviceHandle<VkShaderModule, vkDestroyShaderModule>;

// Things handed to a frame to be destroyed once that frame's fence has signalled.
class RetireQueue {
 public:
  template <class T>
  void retire(T&& object) {
    items_.push_back(std::make_unique<Holder<std::decay_t<T>>>(std::forward<T>(object)));
  }
  void releaseAll() { items_.clear(); }
  size_t size() const { return items_.size(); }

 private:
  struct Item {
    virtual ~Item() = default;
  };
  template <class T>
  struct Holder final : Item {
    explicit Holder(T&& o) : object(std::move(o)) {}
    T object;
  };
  std::vector<std::unique_ptr<Item>> items_;
};

// Throws nothing: turns a VkResult into a readable message for Error{}.
const char* vkResultName(VkResult r);

}  // namespace embody::engine
