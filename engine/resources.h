#pragma once
// Buffers and images with their memory (move-only), synchronization2 layout transitions, and a
// staging uploader that batches copies into device-local memory with one submit.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <span>
#include <vector>

#include "core/result.h"
#include "engine/device.h"
#include "engine/vk_handle.h"

namespace embody::engine {

enum class MemoryUse {
  DeviceLocal,  // filled through the staging Uploader
  HostUpload,   // mapped, written by the CPU every frame (uniforms, palettes, line vertices)
  HostReadback  // mapped, read by the CPU (readback, compute results)
};

class Buffer {
 public:
  static Result<Buffer> create(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use);
  Buffer() = default;
  Buffer(Buffer&&) noexcept = default;
  Buffer& operator=(Buffer&&) noexcept = default;

  VkBuffer handle() const { return buffer_.get(); }
  VkDeviceSize size() const { return size_; }
  void* mapped() const { return mapped_; }  // null unless host-visible
  // For host-visible memory that is not coherent (never on lavapipe): make writes visible / reads fresh.
  void flush() const;
  void invalidate() const;
  explicit operator bool() const { return static_cast<bool>(buffer_); }

 private:
  UniqueMemory memory_;  // destroyed after the buffer (members destruct in reverse order)
  UniqueBuffer buffer_;
  VkDeviceSize size_ = 0;
  void* mapped_ = nullptr;
  bool coherent_ = true;
};

struct ImageDesc {
  VkExtent2D extent{1, 1};
  VkFormat format = VK_FORMAT_R8G8B8A8_SRGB;
  VkImageUsageFlags usage = 0;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
  uint32_t layers = 1;
  uint32_t mipLevels = 1;  // Uploader::upload fills level 0 and blits the rest (needs TRANSFER_SRC usage)
};

class Image {
 public:
  static Result<Image> create(const Device& device, const ImageDesc& desc);
  Image() = default;
  Image(Image&&) noexcept = default;
  Image& operator=(Image&&) noexcept = default;

  VkImage handle() const { return image_.get(); }
  // A view of every layer (2D array when layers > 1).
  VkImageView view() const { return view_.get(); }
  const ImageDesc& desc() const { return desc_; }
  VkImageAspectFlags aspect() const;
  explicit operator bool() const { return static_cast<bool>(image_); }

 private:
  UniqueMemory memory_;
  UniqueImage image_;
  UniqueImageView view_;
  ImageDesc desc_;
};

bool isDepthFormat(VkFormat format);
VkImageAspectFlags aspectOf(VkFormat format);

// One image layout transition (synchronization2). Stage/access masks are derived from the layouts.
void transitionImage(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                     VkImageLayout to, uint32_t baseLayer = 0, uint32_t layerCount = VK_REMAINING_ARRAY_LAYERS,
                     uint32_t baseMip = 0, uint32_t mipCount = VK_REMAINING_MIP_LEVELS);

// Mip levels for a full chain down to 1x1.
uint32_t fullMipChain(VkExtent2D extent);

// A global memory barrier (synchronization2): make `srcAccess` writes at `srcStage` visible to
// `dstAccess` at `dstStage` (uploads -> vertex input, compute -> host readback, copy -> host).
void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess);

Result<UniqueShaderModule> createShaderModule(VkDevice device, const uint32_t* code, size_t bytes);
Result<VkDescriptorSet> allocateDescriptorSet(VkDevice device, VkDescriptorPool pool, VkDescriptorSetLayout layout);

// Batches uploads into device-local buffers/images through host-visible staging buffers and
// submits them together. Staging memory is freed once flush() has waited for the copies.
class Uploader {
 public:
  explicit Uploader(const Device& device) : device_(device) {}
  Status upload(const Buffer& dst, std::span<const std::byte> bytes, VkDeviceSize dstOffset = 0);
  // RGBA8 pixels, tightly packed, into level 0; levels below are filtered down from it by linear
  // blits (the format must support them: see Device::supportsLinearBlit). Leaves the image in
  // SHADER_READ_ONLY_OPTIMAL.
  Status upload(const Image& dst, std::span<const uint8_t> rgba);
  Status flush();

 private:
  struct BufferCopy {
    VkBuffer dst;
    VkDeviceSize dstOffset;
    size_t staging;
    VkDeviceSize size;
  };
  struct ImageCopy {
    VkImage dst;
    VkExtent2D extent;
    uint32_t mipLevels;
    size_t staging;
  };
  static void recordImageCopy(VkCommandBuffer cmd, VkBuffer staging, const ImageCopy& c);
  Result<size_t> stage(std::span<const std::byte> bytes);
  const Device& device_;
  std::vector<Buffer> staging_;
  std::vector<BufferCopy> bufferCopies_;
  std::vector<ImageCopy> imageCopies_;
};

template <class T>
std::span<const std::byte> asBytes(const std::vector<T>& v) {
  return std::as_bytes(std::span<const T>(v));
}

}  // namespace embody::engine
