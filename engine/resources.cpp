#include "engine/resources.h"

#include <cstring>
#include <string>

namespace embody::engine {

namespace {

Result<UniqueMemory> allocate(const Device& device, const VkMemoryRequirements& req, MemoryUse use, bool* coherent) {
  VkMemoryPropertyFlags required = 0, preferred = 0;
  switch (use) {
    case MemoryUse::DeviceLocal: required = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT; break;
    case MemoryUse::HostUpload:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
      preferred = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT | VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
      break;
    case MemoryUse::HostReadback:
      required = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT;
      preferred = VK_MEMORY_PROPERTY_HOST_CACHED_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
      break;
  }
  uint32_t type = device.memoryType(req.memoryTypeBits, required, preferred);
  if (type == UINT32_MAX && use == MemoryUse::DeviceLocal) type = device.memoryType(req.memoryTypeBits, 0);
  if (type == UINT32_MAX) return Error{"no suitable Vulkan memory type"};
  VkPhysicalDeviceMemoryProperties props;
  vkGetPhysicalDeviceMemoryProperties(device.physical(), &props);
  if (coherent) *coherent = props.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = type;
  VkDeviceMemory mem = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateMemory(device.handle(), &ai, nullptr, &mem); r != VK_SUCCESS)
    return Error{std::string("vkAllocateMemory(") + std::to_string(req.size) + " bytes): " + vkResultName(r)};
  return UniqueMemory(device.handle(), mem);
}

}  // namespace

Result<Buffer> Buffer::create(const Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use) {
  Buffer b;
  b.size_ = size;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = size > 0 ? size : 4;  // a zero-sized buffer is invalid; empty meshes still get a handle
  bci.usage = usage | (use == MemoryUse::DeviceLocal ? VK_BUFFER_USAGE_TRANSFER_DST_BIT : 0);
  bci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  VkBuffer raw = VK_NULL_HANDLE;
  if (VkResult r = vkCreateBuffer(device.handle(), &bci, nullptr, &raw); r != VK_SUCCESS)
    return Error{std::string("vkCreateBuffer: ") + vkResultName(r)};
  b.buffer_ = UniqueBuffer(device.handle(), raw);
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device.handle(), raw, &req);
  auto mem = allocate(device, req, use, &b.coherent_);
  if (!mem) return Error{mem.error()};
  b.memory_ = std::move(mem).value();
  vkBindBufferMemory(device.handle(), raw, b.memory_.get(), 0);
  if (use != MemoryUse::DeviceLocal) {
    if (VkResult r = vkMapMemory(device.handle(), b.memory_.get(), 0, VK_WHOLE_SIZE, 0, &b.mapped_); r != VK_SUCCESS)
      return Error{std::string("vkMapMemory: ") + vkResultName(r)};
  }
  return b;
}

void Buffer::flush() const {
  if (coherent_ || !mapped_) return;
  VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
  range.memory = memory_.get();
  range.size = VK_WHOLE_SIZE;
  vkFlushMappedMemoryRanges(memory_.device(), 1, &range);
}

void Buffer::invalidate() const {
  if (coherent_ || !mapped_) return;
  VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
  range.memory = memory_.get();
  range.size = VK_WHOLE_SIZE;
  vkInvalidateMappedMemoryRanges(memory_.device(), 1, &range);
}

bool isDepthFormat(VkFormat f) {
  return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D16_UNORM || f == VK_FORMAT_D24_UNORM_S8_UINT ||
         f == VK_FORMAT_D32_SFLOAT_S8_UINT || f == VK_FORMAT_X8_D24_UNORM_PACK32;
}

VkImageAspectFlags aspectOf(VkFormat f) {
  if (!isDepthFormat(f)) return VK_IMAGE_ASPECT_COLOR_BIT;
  if (f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT)
    return VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
  return VK_IMAGE_ASPECT_DEPTH_BIT;
}

VkImageAspectFlags Image::aspect() const { return aspectOf(desc_.format); }

Result<Image> Image::create(const Device& device, const ImageDesc& desc) {
  Image img;
  img.desc_ = desc;
  VkImageCreateInfo ici{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ici.imageType = VK_IMAGE_TYPE_2D;
  ici.format = desc.format;
  ici.extent = {desc.extent.width, desc.extent.height, 1};
  ici.mipLevels = std::max(desc.mipLevels, 1u);
  ici.arrayLayers = desc.layers;
  ici.samples = desc.samples;
  ici.tiling = VK_IMAGE_TILING_OPTIMAL;
  ici.usage = desc.usage;
  ici.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImage raw = VK_NULL_HANDLE;
  if (VkResult r = vkCreateImage(device.handle(), &ici, nullptr, &raw); r != VK_SUCCESS)
    return Error{std::string("vkCreateImage: ") + vkResultName(r)};
  img.image_ = UniqueImage(device.handle(), raw);
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device.handle(), raw, &req);
  auto mem = allocate(device, req, MemoryUse::DeviceLocal, nullptr);
  if (!mem) return Error{mem.error()};
  img.memory_ = std::move(mem).value();
  vkBindImageMemory(device.handle(), raw, img.memory_.get(), 0);

  VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vci.image = raw;
  vci.viewType = desc.layers > 1 ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
  vci.format = desc.format;
  vci.subresourceRange = {aspectOf(desc.format), 0, ici.mipLevels, 0, desc.layers};
  VkImageView view = VK_NULL_HANDLE;
  if (VkResult r = vkCreateImageView(device.handle(), &vci, nullptr, &view); r != VK_SUCCESS)
    return Error{std::string("vkCreateImageView: ") + vkResultName(r)};
  img.view_ = UniqueImageView(device.handle(), view);
  return img;
}

namespace {

struct LayoutUse {
  VkPipelineStageFlags2 stage;
  VkAccessFlags2 access;
};

LayoutUse useOf(VkImageLayout layout, bool source) {
  switch (layout) {
    case VK_IMAGE_LAYOUT_UNDEFINED: return {VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE};
    case VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL:
      return {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT,
              VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT | (source ? 0 : VK_ACCESS_2_COLOR_ATTACHMENT_READ_BIT)};
    case VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL:
    case VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL:
      return {VK_PIPELINE_STAGE_2_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
              VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT | VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_READ_BIT};
    // All transfers (copies, and the blits that fill mip levels).
    case VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL:
      return {VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_READ_BIT};
    case VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL:
      return {VK_PIPELINE_STAGE_2_ALL_TRANSFER_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT};
    case VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL:
      return {VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT, VK_ACCESS_2_SHADER_SAMPLED_READ_BIT};
    default: return {VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_MEMORY_READ_BIT | VK_ACCESS_2_MEMORY_WRITE_BIT};
  }
}

}  // namespace

void transitionImage(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from,
                     VkImageLayout to, uint32_t baseLayer, uint32_t layerCount, uint32_t baseMip,
                     uint32_t mipCount) {
  const LayoutUse src = useOf(from, true), dst = useOf(to, false);
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = src.stage;
  b.srcAccessMask = src.access;
  b.dstStageMask = dst.stage;
  b.dstAccessMask = dst.access;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, baseMip, mipCount, baseLayer, layerCount};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}

uint32_t fullMipChain(VkExtent2D extent) {
  uint32_t levels = 1;
  for (uint32_t size = std::max(extent.width, extent.height); size > 1; size /= 2) ++levels;
  return levels;
}

void memoryBarrier(VkCommandBuffer cmd, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                   VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
  VkMemoryBarrier2 mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
  mb.srcStageMask = srcStage;
  mb.srcAccessMask = srcAccess;
  mb.dstStageMask = dstStage;
  mb.dstAccessMask = dstAccess;
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.memoryBarrierCount = 1;
  dep.pMemoryBarriers = &mb;
  vkCmdPipelineBarrier2(cmd, &dep);
}

Result<UniqueShaderModule> createShaderModule(VkDevice device, const uint32_t* code, size_t bytes) {
  VkShaderModuleCreateInfo ci{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  ci.codeSize = bytes;
  ci.pCode = code;
  VkShaderModule m = VK_NULL_HANDLE;
  if (VkResult r = vkCreateShaderModule(device, &ci, nullptr, &m); r != VK_SUCCESS)
    return Error{std::string("vkCreateShaderModule: ") + vkResultName(r)};
  return UniqueShaderModule(device, m);
}

Result<VkDescriptorSet> allocateDescriptorSet(VkDevice device, VkDescriptorPool pool, VkDescriptorSetLayout layout) {
  VkDescriptorSetAllocateInfo dai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  dai.descriptorPool = pool;
  dai.descriptorSetCount = 1;
  dai.pSetLayouts = &layout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateDescriptorSets(device, &dai, &set); r != VK_SUCCESS)
    return Error{std::string("vkAllocateDescriptorSets: ") + vkResultName(r)};
  return set;
}

Result<size_t> Uploader::stage(std::span<const std::byte> bytes) {
  auto staging = Buffer::create(device_, bytes.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUse::HostUpload);
  if (!staging) return Error{staging.error()};
  std::memcpy(staging->mapped(), bytes.data(), bytes.size());
  staging->flush();
  staging_.push_back(std::move(staging).value());
  return staging_.size() - 1;
}

Status Uploader::upload(const Buffer& dst, std::span<const std::byte> bytes, VkDeviceSize dstOffset) {
  if (bytes.empty()) return {};
  if (dstOffset + bytes.size() > dst.size()) return Error{"upload larger than its destination buffer"};
  auto s = stage(bytes);
  if (!s) return Error{s.error()};
  bufferCopies_.push_back({dst.handle(), dstOffset, *s, bytes.size()});
  return {};
}

Status Uploader::upload(const Image& dst, std::span<const uint8_t> rgba) {
  const auto& e = dst.desc().extent;
  if (rgba.size() != size_t(e.width) * e.height * 4) return Error{"texture data does not match the image size"};
  auto s = stage(std::as_bytes(rgba));
  if (!s) return Error{s.error()};
  imageCopies_.push_back({dst.handle(), e, std::max(dst.desc().mipLevels, 1u), *s});
  return {};
}

void Uploader::recordImageCopy(VkCommandBuffer cmd, VkBuffer staging, const ImageCopy& c) {
  constexpr VkImageAspectFlags kColor = VK_IMAGE_ASPECT_COLOR_BIT;
  transitionImage(cmd, c.dst, kColor, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
  VkBufferImageCopy region{};
  region.imageSubresource = {kColor, 0, 0, 1};
  region.imageExtent = {c.extent.width, c.extent.height, 1};
  vkCmdCopyBufferToImage(cmd, staging, c.dst, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
  // Each level is a linear 2x2 box of the one above: level i-1 becomes a blit source, level i
  // (still TRANSFER_DST) its destination.
  int32_t w = int32_t(c.extent.width), h = int32_t(c.extent.height);
  for (uint32_t level = 1; level < c.mipLevels; ++level) {
    transitionImage(cmd, c.dst, kColor, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, 0,
                    1, level - 1, 1);
    const int32_t nw = std::max(w / 2, 1), nh = std::max(h / 2, 1);
    VkImageBlit blit{};
    blit.srcSubresource = {kColor, level - 1, 0, 1};
    blit.srcOffsets[1] = {w, h, 1};
    blit.dstSubresource = {kColor, level, 0, 1};
    blit.dstOffsets[1] = {nw, nh, 1};
    vkCmdBlitImage(cmd, c.dst, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, c.dst, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1,
                   &blit, VK_FILTER_LINEAR);
    w = nw;
    h = nh;
  }
  if (c.mipLevels > 1)
    transitionImage(cmd, c.dst, kColor, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                    0, 1, 0, c.mipLevels - 1);
  transitionImage(cmd, c.dst, kColor, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
                  0, 1, c.mipLevels - 1, 1);
}

Status Uploader::flush() {
  if (bufferCopies_.empty() && imageCopies_.empty()) return {};
  auto status = device_.submitAndWait([&](VkCommandBuffer cmd) {
    for (const auto& c : bufferCopies_) {
      VkBufferCopy region{0, c.dstOffset, c.size};
      vkCmdCopyBuffer(cmd, staging_[c.staging].handle(), c.dst, 1, &region);
    }
    for (const auto& c : imageCopies_) recordImageCopy(cmd, staging_[c.staging].handle(), c);
    // Make buffer copies visible to every later read (vertex input, index, shader storage).
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT,
                  VK_ACCESS_2_MEMORY_READ_BIT);
  });
  bufferCopies_.clear();
  imageCopies_.clear();
  staging_.clear();
  return status;
}

}  // namespace embody::engine
