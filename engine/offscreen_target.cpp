#include "engine/offscreen_target.h"

#include <algorithm>
#include <cstring>

namespace embody::engine {

Result<OffscreenTarget> OffscreenTarget::create(const Device& device, const OffscreenDesc& desc) {
  if (desc.width == 0 || desc.height == 0 || desc.layers == 0 || desc.layers > 2)
    return Error{"offscreen target needs a non-empty size and 1 or 2 layers"};
  if (desc.samples != VK_SAMPLE_COUNT_1_BIT && !device.supportsSamples(desc.samples))
    return Error{"the device does not support the requested MSAA sample count"};
  OffscreenTarget t;
  t.desc_ = desc;
  ImageDesc d;
  d.extent = {desc.width, desc.height};
  d.format = desc.format;
  d.layers = desc.layers;
  d.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  auto img = Image::create(device, d);
  if (!img) return Error{img.error()};
  t.color_ = std::move(img).value();
  for (uint32_t l = 0; l < desc.layers; ++l) {
    VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vci.image = t.color_.handle();
    vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vci.format = desc.format;
    vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, l, 1};
    VkImageView v = VK_NULL_HANDLE;
    if (vkCreateImageView(device.handle(), &vci, nullptr, &v) != VK_SUCCESS) return Error{"vkCreateImageView failed"};
    t.layerViews_.emplace_back(device.handle(), v);
  }
  constexpr uint32_t kPitchAlign = 256;
  t.rowPitch_ = (desc.width * 4 + kPitchAlign - 1) / kPitchAlign * kPitchAlign;
  auto rb = Buffer::create(device, VkDeviceSize(t.rowPitch_) * desc.height * desc.layers,
                           VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::HostReadback);
  if (!rb) return Error{rb.error()};
  t.readback_ = std::move(rb).value();
  return t;
}

PassTarget OffscreenTarget::allLayers() const {
  PassTarget p;
  p.color = {color_.handle(), color_.view(), desc_.format, {desc_.width, desc_.height}, 0, desc_.layers,
             VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
  p.samples = desc_.samples;
  return p;
}

PassTarget OffscreenTarget::layer(uint32_t layer) const {
  PassTarget p;
  p.color = {color_.handle(), layerViews_.at(layer).get(), desc_.format, {desc_.width, desc_.height}, layer, 1,
             VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL};
  p.samples = desc_.samples;
  return p;
}

void OffscreenTarget::recordReadback(VkCommandBuffer cmd, uint32_t firstLayer, uint32_t layerCount) const {
  std::vector<VkBufferImageCopy> regions;
  const uint32_t end = layerCount > desc_.layers ? desc_.layers : std::min(desc_.layers, firstLayer + layerCount);
  for (uint32_t l = firstLayer; l < end; ++l) {
    VkBufferImageCopy r{};
    r.bufferOffset = VkDeviceSize(rowPitch_) * desc_.height * l;
    r.bufferRowLength = rowPitch_ / 4;  // in texels
    r.bufferImageHeight = desc_.height;
    r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, l, 1};
    r.imageExtent = {desc_.width, desc_.height, 1};
    regions.push_back(r);
  }
  vkCmdCopyImageToBuffer(cmd, color_.handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.handle(),
                         static_cast<uint32_t>(regions.size()), regions.data());
  memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_2_HOST_BIT,
                VK_ACCESS_2_HOST_READ_BIT);
}

avatar::Image OffscreenTarget::pixels(uint32_t layer) const {
  readback_.invalidate();
  avatar::Image img;
  img.width = int(desc_.width);
  img.height = int(desc_.height);
  img.rgba.resize(size_t(desc_.width) * desc_.height * 4);
  const auto* src = static_cast<const uint8_t*>(readback_.mapped()) + size_t(rowPitch_) * desc_.height * layer;
  for (uint32_t y = 0; y < desc_.height; ++y)
    std::memcpy(img.rgba.data() + size_t(y) * desc_.width * 4, src + size_t(y) * rowPitch_, size_t(desc_.width) * 4);
  // B8G8R8A8 targets (window/XR-like formats) come back as BGRA: swap to RGBA.
  if (desc_.format == VK_FORMAT_B8G8R8A8_SRGB || desc_.format == VK_FORMAT_B8G8R8A8_UNORM)
    for (size_t i = 0; i < img.rgba.size(); i += 4) std::swap(img.rgba[i], img.rgba[i + 2]);
  return img;
}

}  // namespace embody::engine
