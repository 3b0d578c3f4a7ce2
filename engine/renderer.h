#pragma once
// The renderer: frames in flight, per-frame scene data (views, light, joint palette, lines), and
// passes that draw the scene into colour (+ depth) images with dynamic rendering. Targets are
// plain image references, so the same code draws into its own offscreen images and into images
// someone else owns (OpenXR swapchain images, a window's swapchain).
//
//   renderer.beginFrame();
//   renderer.setScene(scene);                    // palette, lines, light: once per frame
//   renderer.drawPass(cameras, target);          // any number of passes (mirror, left eye, ...)
//   renderer.endFrame();                         // submit; resources retire with this frame
#include <array>
#include <glm/glm.hpp>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <tuple>
#include <vector>

#include "avatar/avatar_asset.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "engine/gpu_avatar.h"
#include "engine/resources.h"

namespace embody::engine {

constexpr uint32_t kMaxViewsPerFrame = 8;  // matches kMaxViews in shaders/common.glsl

struct LineVertex {
  glm::vec3 position{0.0f};
  glm::vec4 color{1.0f};
};

struct Lighting {
  glm::vec3 directionToLight = glm::normalize(glm::vec3(0.35f, 0.8f, 0.5f));
  glm::vec3 lightColor{0.85f, 0.82f, 0.78f};
  glm::vec3 skyColor{0.42f, 0.45f, 0.52f};
  glm::vec3 groundColor{0.16f, 0.14f, 0.12f};
};

// What one frame shows. Spans must stay valid until setScene returns (they are copied).
struct SceneFrame {
  const GpuAvatar* avatar = nullptr;
  std::span<const glm::mat4> palette;  // skinning palette, one matrix per skeleton joint
  // Morph target weights, one per mesh.morphChannels (shaders/morphing.glsl); empty: all zero.
  std::span<const float> morphWeights;
  // One per avatar->boundMaterials() (avatar::SecondaryMotion::materialStates()): expression
  // material colour and texture-transform binds; empty: the materials as loaded.
  std::span<const avatar::MaterialBindState> materialStates;
  // The frame clock in seconds (MToon UV animation); float precision, so callers count from
  // their start (1 ms resolution lasts about 2 hours).
  double seconds = 0.0;
  bool firstPerson = false;            // draw the first-person list (the user's head hidden)
  bool grid = true;                    // the ground grid on y = 0
  std::span<const LineVertex> lines;          // line list, depth-tested (tracking-target gizmos)
  std::span<const LineVertex> overlayLines;   // line list, drawn on top (skeleton overlay)
  Lighting lighting;
};

// One image a pass draws into. For multiview, `view` is a 2D-array view of layerCount layers.
struct TargetImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{0, 0};
  uint32_t baseLayer = 0;   // first layer `view` covers (for barriers)
  uint32_t layerCount = 1;  // layers `view` covers
  // Layout the image is in when the pass starts (UNDEFINED: contents may be discarded) and the one
  // the pass leaves it in (OpenXR wants COLOR_ATTACHMENT_OPTIMAL at xrReleaseSwapchainImage).
  VkImageLayout initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  VkImageLayout finalLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
};

struct PassTarget {
  TargetImage color;                 // single-sampled; MSAA resolves into it
  std::optional<TargetImage> depth;  // none: the renderer uses its own transient depth buffer
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;  // 4: renders into internal MSAA images
  glm::vec4 clearColor{0.30f, 0.33f, 0.38f, 1.0f};        // linear
};

struct SubmitSync {
  std::vector<VkSemaphoreSubmitInfo> wait, signal;  // e.g. a window's acquire/present semaphores
  bool waitForCompletion = false;                   // block until the GPU has finished this frame
};

struct RendererStats {
  uint64_t frames = 0;
  uint64_t pipelinesCreated = 0;
  uint64_t drawCalls = 0;  // of the last frame
};

// Neither copyable nor movable (its RAII handle members and the Device reference see to that):
// created once, held by unique_ptr, and referenced by the GpuAvatars it uploads.
class Renderer {
 public:
  static Result<std::unique_ptr<Renderer>> create(const Device& device);
  ~Renderer();

  const Device& device() const { return device_; }

  // Uploads an avatar (validated first: bad indices give an error, never a GPU fault).
  Result<std::unique_ptr<GpuAvatar>> upload(const avatar::AvatarAsset& asset);

  // Waits until the frame slot is free (its previous use retired), releases what was retired
  // with it, and opens its command buffer.
  Status beginFrame();
  Status setScene(const SceneFrame& scene);
  // Draws into `target` with one camera, or two cameras into a 2-layer target with multiview
  // (gl_ViewIndex picks the camera). Two-pass stereo is two calls with one camera each.
  Status drawPass(std::span<const Camera> cameras, const PassTarget& target);
  Status endFrame(const SubmitSync& sync = {});
  // The open frame's command buffer, for commands around the passes (readback, transitions).
  VkCommandBuffer commandBuffer() const;
  // Keeps `object` alive until the current (or, outside a frame, the last submitted) frame has
  // finished on the GPU.
  template <class T>
  void retire(T&& object) {
    const uint32_t slot = frames_[current_].recording ? current_ : (current_ + kFramesInFlight - 1) % kFramesInFlight;
    frames_[slot].retired.retire(std::forward<T>(object));
  }
  void waitIdle();
  const RendererStats& stats() const { return stats_; }
  // Pipelines are built on first use for each target format; call to pay that before timing.
  Status prepare(VkFormat color, std::optional<VkFormat> depth, VkSampleCountFlagBits samples, uint32_t viewMask);

 private:
  struct FrameSlot {
    VkCommandBuffer cmd = VK_NULL_HANDLE;
    UniqueFence fence;
    Buffer sceneBlock, palette, lines, morphWeights;
    VkBuffer boundMorphRanges = VK_NULL_HANDLE;  // the avatar morph buffers the set points at
    VkDescriptorSet set = VK_NULL_HANDLE;
    RetireQueue retired;
    uint32_t viewsUsed = 0;
    uint32_t lineCount = 0, overlayCount = 0;
    const GpuAvatar* avatar = nullptr;
    bool firstPerson = false, grid = true;
    bool recording = false;
    std::vector<glm::vec3> blendCenters;  // world centre of each blended draw in this frame's pose
    std::vector<uint32_t> blendOrder;     // their back-to-front order for the current pass
  };
  struct PassAttachments {  // depth (the target's or transient) and, under MSAA, the transient colour
    VkImage depthImage = VK_NULL_HANDLE, msaaImage = VK_NULL_HANDLE;
    VkImageView depthView = VK_NULL_HANDLE, msaaView = VK_NULL_HANDLE;
    VkFormat depthFormat = VK_FORMAT_UNDEFINED;
    uint32_t depthBase = 0;
    bool ownDepth = true;
  };
  struct PipelineSet {
    UniquePipeline opaque, mask, blend, lines;
    UniquePipeline outlineOpaque, outlineMask, outlineBlend;  // MToon outline hulls
  };
  using PipelineKey = std::tuple<VkFormat, VkFormat, VkSampleCountFlagBits, uint32_t>;
  struct Transient {  // renderer-owned depth / MSAA colour for a given target shape
    VkFormat format;
    VkExtent2D extent;
    uint32_t layers;
    VkSampleCountFlagBits samples;
    Image image;
    uint64_t lastFrame;
  };

  explicit Renderer(const Device& device) : device_(device) {}
  Status init();
  Result<const PipelineSet*> pipelines(const PipelineKey& key);
  Result<const Image*> transient(VkFormat format, VkExtent2D extent, uint32_t layers, VkSampleCountFlagBits samples);
  Status ensureCapacity(Buffer& buffer, VkDeviceSize bytes, VkBufferUsageFlags usage, FrameSlot& slot);
  void writeFrameDescriptors(FrameSlot& slot);
  // Pieces of drawPass.
  Result<PassAttachments> passAttachments(const PassTarget& target);
  void beginRendering(VkCommandBuffer cmd, const PassTarget& target, const PassAttachments& att, uint32_t viewMask);
  void recordScene(VkCommandBuffer cmd, const PipelineSet& p, FrameSlot& f, glm::vec3 eye);
  void endRendering(VkCommandBuffer cmd, const PassTarget& target, const PassAttachments& att);
  // `order` lists the indices into `draws` to draw (empty: all, as listed).
  void drawAvatarList(VkCommandBuffer cmd, const GpuAvatar& a, const std::vector<GpuDraw>& draws,
                      std::span<const uint32_t> order, VkPipeline pipeline);
  // The outline hulls of the draws whose material has one (front faces culled).
  void drawOutlines(VkCommandBuffer cmd, const GpuAvatar& a, std::span<const GpuDraw> draws, VkPipeline pipeline);
  // Blended draws in `order`, each followed by its outline; depth writes per material.
  void drawBlended(VkCommandBuffer cmd, const GpuAvatar& a, const std::vector<GpuDraw>& draws,
                   std::span<const uint32_t> order, const PipelineSet& p);
  void drawLines(VkCommandBuffer cmd, const PipelineSet& p, VkBuffer buffer, VkDeviceSize offset, uint32_t count);
  // MToon's render order: transparentWithZWrite before plain blending, then by
  // renderQueueOffsetNumber, then back to front.
  static void sortBlendBackToFront(FrameSlot& f, const GpuAvatar& a, const std::vector<GpuDraw>& draws, glm::vec3 eye);

  const Device& device_;
  UniqueDescriptorSetLayout sceneLayout_, materialLayout_;
  UniquePipelineLayout pipelineLayout_;
  UniqueShaderModule skinnedVert_, skinnedFrag_, linesVert_, linesFrag_;
  UniqueDescriptorPool framePool_;
  UniqueCommandPool commandPool_;
  Buffer grid_;
  Buffer morphPlaceholder_;  // bound for avatars without morph targets (reads as "no deltas")
  uint32_t gridVertexCount_ = 0;
  std::map<PipelineKey, PipelineSet> pipelines_;
  std::vector<Transient> transients_;
  std::array<FrameSlot, kFramesInFlight> frames_;
  uint32_t current_ = 0;
  RendererStats stats_;
};

}  // namespace embody::engine
