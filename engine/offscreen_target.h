#pragma once
// Offscreen colour target (sRGB by default; one layer, or two for a stereo pair) with a
// host-visible readback buffer. Readback rows are padded to 256 bytes, the way many drivers
// want optimal copies, and pixels() walks that row pitch back into a tight image.
#include <vector>

#include "avatar/avatar_asset.h"
#include "engine/renderer.h"
#include "engine/resources.h"

namespace embody::engine {

struct OffscreenDesc {
  uint32_t width = 256, height = 256;
  uint32_t layers = 1;  // 2 for a stereo pair (multiview or one pass per layer)
  VkFormat format = VK_FORMAT_R8G8B8A8_SRGB;
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;
};

class OffscreenTarget {
 public:
  static Result<OffscreenTarget> create(const Device& device, const OffscreenDesc& desc);
  OffscreenTarget() = default;
  OffscreenTarget(OffscreenTarget&&) noexcept = default;
  OffscreenTarget& operator=(OffscreenTarget&&) noexcept = default;

  const OffscreenDesc& desc() const { return desc_; }
  // A pass into every layer (multiview when layers == 2) or into one layer. The pass leaves the
  // image ready for recordReadback (TRANSFER_SRC_OPTIMAL).
  PassTarget allLayers() const;
  PassTarget layer(uint32_t layer) const;
  // Copies layers [firstLayer, firstLayer + layerCount) into the readback buffer (after the
  // passes that drew them, in the same frame). Layers not drawn this frame must be left out.
  void recordReadback(VkCommandBuffer cmd, uint32_t firstLayer = 0, uint32_t layerCount = UINT32_MAX) const;
  // Tight RGBA8 pixels of one layer; valid once the frame with recordReadback has completed.
  avatar::Image pixels(uint32_t layer = 0) const;
  uint32_t rowPitchBytes() const { return rowPitch_; }
  VkImage image() const { return color_.handle(); }

 private:
  OffscreenDesc desc_;
  Image color_;
  std::vector<UniqueImageView> layerViews_;
  Buffer readback_;
  uint32_t rowPitch_ = 0;
};

}  // namespace embody::engine
