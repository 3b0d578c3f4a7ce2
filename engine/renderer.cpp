#include "engine/renderer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

namespace embody::engine {

namespace {

// std140 mirror of `Scene` in shaders/common.glsl.
struct SceneBlock {
  struct View {
    glm::mat4 viewProj;
    glm::vec4 eye;
  } views[kMaxViewsPerFrame];
  glm::vec4 lightDirection, lightColor, skyColor, groundColor;
  glm::vec4 clock;  // x: SceneFrame::seconds
};

// Mirror of `Push` in shaders/common.glsl.
struct PushBlock {
  uint32_t viewBase = 0;
  float aspect = 1.0f;  // target width / height
};
constexpr VkShaderStageFlags kPushStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;

// A 10 m x 10 m grid on y = 0, a line every 0.5 m, the X (red) and Z (blue) axes through the origin.
std::vector<LineVertex> makeGrid() {
  std::vector<LineVertex> v;
  const float half = 5.0f, step = 0.5f;
  const glm::vec4 minor(0.42f, 0.44f, 0.48f, 1.0f), major(0.60f, 0.62f, 0.66f, 1.0f);
  for (int i = -10; i <= 10; ++i) {
    const float t = float(i) * step;
    const glm::vec4 cx = i == 0 ? glm::vec4(0.75f, 0.2f, 0.2f, 1.0f) : (i % 2 == 0 ? major : minor);
    const glm::vec4 cz = i == 0 ? glm::vec4(0.2f, 0.3f, 0.8f, 1.0f) : (i % 2 == 0 ? major : minor);
    v.push_back({{-half, 0.0f, t}, cx});  // lines parallel to X
    v.push_back({{half, 0.0f, t}, cx});
    v.push_back({{t, 0.0f, -half}, cz});  // lines parallel to Z
    v.push_back({{t, 0.0f, half}, cz});
  }
  return v;
}

}  // namespace

Result<std::unique_ptr<Renderer>> Renderer::create(const Device& device) {
  std::unique_ptr<Renderer> r(new Renderer(device));
  if (auto s = r->init(); !s) return Error{s.error()};
  const VkDevice dev = device.handle();

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = device.queueFamily();
  VkCommandPool pool = VK_NULL_HANDLE;
  if (vkCreateCommandPool(dev, &pci, nullptr, &pool) != VK_SUCCESS) return Error{"vkCreateCommandPool failed"};
  r->commandPool_ = UniqueCommandPool(dev, pool);

  VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, kFramesInFlight},
                                   {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 4 * kFramesInFlight}};  // palette + 3 morph
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = kFramesInFlight;
  dpci.poolSizeCount = 2;
  dpci.pPoolSizes = sizes;
  VkDescriptorPool dpool = VK_NULL_HANDLE;
  if (vkCreateDescriptorPool(dev, &dpci, nullptr, &dpool) != VK_SUCCESS) return Error{"vkCreateDescriptorPool failed"};
  r->framePool_ = UniqueDescriptorPool(dev, dpool);

  auto placeholder = Buffer::create(device, 32, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::HostUpload);
  if (!placeholder) return Error{placeholder.error()};
  r->morphPlaceholder_ = std::move(placeholder).value();
  std::memset(r->morphPlaceholder_.mapped(), 0, 32);
  r->morphPlaceholder_.flush();

  for (auto& f : r->frames_) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    if (vkAllocateCommandBuffers(dev, &ai, &f.cmd) != VK_SUCCESS) return Error{"vkAllocateCommandBuffers failed"};
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    fci.flags = VK_FENCE_CREATE_SIGNALED_BIT;
    VkFence fence = VK_NULL_HANDLE;
    vkCreateFence(dev, &fci, nullptr, &fence);
    f.fence = UniqueFence(dev, fence);
    auto set = allocateDescriptorSet(dev, dpool, r->sceneLayout_.get());
    if (!set) return Error{set.error()};
    f.set = *set;
    auto block = Buffer::create(device, sizeof(SceneBlock), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, MemoryUse::HostUpload);
    auto palette = Buffer::create(device, sizeof(glm::mat4) * 64, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                  MemoryUse::HostUpload);
    auto lines = Buffer::create(device, sizeof(LineVertex) * 256, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                                MemoryUse::HostUpload);
    auto morphWeights = Buffer::create(device, sizeof(float) * 64, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                                       MemoryUse::HostUpload);
    if (!block || !palette || !lines || !morphWeights) return Error{"could not allocate per-frame buffers"};
    f.sceneBlock = std::move(block).value();
    f.palette = std::move(palette).value();
    f.lines = std::move(lines).value();
    f.morphWeights = std::move(morphWeights).value();
    r->writeFrameDescriptors(f);
  }

  const auto grid = makeGrid();
  auto gridBuffer = Buffer::create(device, grid.size() * sizeof(LineVertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                                   MemoryUse::DeviceLocal);
  if (!gridBuffer) return Error{gridBuffer.error()};
  r->grid_ = std::move(gridBuffer).value();
  r->gridVertexCount_ = static_cast<uint32_t>(grid.size());
  Uploader up(device);
  if (auto s = up.upload(r->grid_, asBytes(grid)); !s) return Error{s.error()};
  if (auto s = up.flush(); !s) return Error{s.error()};
  return r;
}

Renderer::~Renderer() {
  device_.waitIdle();
  for (auto& f : frames_) f.retired.releaseAll();
}

void Renderer::writeFrameDescriptors(FrameSlot& f) {
  // 0: scene block, 1: palette, 3..5: morph ranges, deltas (the avatar's, or the placeholder) and weights.
  const VkBuffer ranges = f.avatar && f.avatar->morphRanges() ? f.avatar->morphRanges() : morphPlaceholder_.handle();
  const VkBuffer deltas = f.avatar && f.avatar->morphDeltas() ? f.avatar->morphDeltas() : morphPlaceholder_.handle();
  const VkDescriptorBufferInfo infos[5] = {{f.sceneBlock.handle(), 0, VK_WHOLE_SIZE},
                                           {f.palette.handle(), 0, VK_WHOLE_SIZE},
                                           {ranges, 0, VK_WHOLE_SIZE},
                                           {deltas, 0, VK_WHOLE_SIZE},
                                           {f.morphWeights.handle(), 0, VK_WHOLE_SIZE}};
  const uint32_t bindings[5] = {0, 1, 3, 4, 5};
  VkWriteDescriptorSet w[5];
  for (int i = 0; i < 5; ++i) {
    w[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w[i].dstSet = f.set;
    w[i].dstBinding = bindings[i];
    w[i].descriptorCount = 1;
    w[i].descriptorType = i == 0 ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    w[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(device_.handle(), 5, w, 0, nullptr);
  f.boundMorphRanges = ranges;
}

Status Renderer::ensureCapacity(Buffer& buffer, VkDeviceSize bytes, VkBufferUsageFlags usage, FrameSlot& slot) {
  if (buffer.size() >= bytes) return {};
  auto grown = Buffer::create(device_, std::max<VkDeviceSize>(bytes, buffer.size() * 2), usage, MemoryUse::HostUpload);
  if (!grown) return Error{grown.error()};
  // This slot's previous frame has retired (beginFrame waited), so the old buffer is free; it
  // still goes through the retire queue so that the rule has one path.
  slot.retired.retire(std::move(buffer));
  buffer = std::move(grown).value();
  return {};
}

Status Renderer::beginFrame() {
  FrameSlot& f = frames_[current_];
  if (f.recording) return Error{"beginFrame called twice without endFrame"};
  VkFence fence = f.fence.get();
  if (VkResult r = vkWaitForFences(device_.handle(), 1, &fence, VK_TRUE, UINT64_MAX); r != VK_SUCCESS)
    return Error{std::string("waiting for a frame in flight: ") + vkResultName(r)};
  f.retired.releaseAll();
  vkResetCommandBuffer(f.cmd, 0);
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(f.cmd, &bi);
  f.recording = true;
  f.viewsUsed = 0;
  f.lineCount = f.overlayCount = 0;
  f.avatar = nullptr;
  stats_.drawCalls = 0;
  return {};
}

Status Renderer::setScene(const SceneFrame& scene) {
  FrameSlot& f = frames_[current_];
  if (!f.recording) return Error{"setScene outside beginFrame/endFrame"};
  if (scene.avatar && scene.palette.size() < scene.avatar->jointCount())
    return Error{"the palette has " + std::to_string(scene.palette.size()) + " matrices; the avatar needs " +
                 std::to_string(scene.avatar->jointCount())};
  if (scene.avatar && !scene.morphWeights.empty() && scene.morphWeights.size() < scene.avatar->morphChannelCount())
    return Error{"the frame has " + std::to_string(scene.morphWeights.size()) + " morph weights; the avatar has " +
                 std::to_string(scene.avatar->morphChannelCount()) + " morph channels"};
  if (scene.avatar && !scene.materialStates.empty() && scene.materialStates.size() != scene.avatar->boundMaterials().size())
    return Error{"the frame has " + std::to_string(scene.materialStates.size()) + " material bind states; the avatar binds " +
                 std::to_string(scene.avatar->boundMaterials().size()) + " materials"};
  const bool paletteGrows = f.palette.size() < scene.palette.size_bytes();
  if (auto s = ensureCapacity(f.palette, scene.palette.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, f); !s)
    return s;
  const bool weightsGrow = f.morphWeights.size() < scene.morphWeights.size_bytes();
  if (auto s = ensureCapacity(f.morphWeights, scene.morphWeights.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, f); !s)
    return s;
  f.avatar = scene.avatar;
  // This slot's copy of the expression-bound material blocks (its previous frame has finished).
  if (f.avatar) f.avatar->writeBoundMaterials(current_, scene.materialStates);
  const VkBuffer ranges = f.avatar && f.avatar->morphRanges() ? f.avatar->morphRanges() : morphPlaceholder_.handle();
  if (paletteGrows || weightsGrow || ranges != f.boundMorphRanges) writeFrameDescriptors(f);
  if (!scene.palette.empty()) std::memcpy(f.palette.mapped(), scene.palette.data(), scene.palette.size_bytes());
  // Weights beyond this frame's (a larger buffer from another avatar) read as zero.
  std::memset(f.morphWeights.mapped(), 0, f.morphWeights.size());
  if (!scene.morphWeights.empty())
    std::memcpy(f.morphWeights.mapped(), scene.morphWeights.data(), scene.morphWeights.size_bytes());
  f.morphWeights.flush();
  const size_t lineBytes = (scene.lines.size() + scene.overlayLines.size()) * sizeof(LineVertex);
  if (auto s = ensureCapacity(f.lines, lineBytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, f); !s) return s;
  auto* dst = static_cast<LineVertex*>(f.lines.mapped());
  std::copy(scene.lines.begin(), scene.lines.end(), dst);
  std::copy(scene.overlayLines.begin(), scene.overlayLines.end(), dst + scene.lines.size());
  f.lineCount = static_cast<uint32_t>(scene.lines.size());
  f.overlayCount = static_cast<uint32_t>(scene.overlayLines.size());
  f.palette.flush();
  f.lines.flush();

  auto* block = static_cast<SceneBlock*>(f.sceneBlock.mapped());
  block->lightDirection = glm::vec4(glm::normalize(scene.lighting.directionToLight), 0.0f);
  block->lightColor = glm::vec4(scene.lighting.lightColor, 1.0f);
  block->skyColor = glm::vec4(scene.lighting.skyColor, 1.0f);
  block->groundColor = glm::vec4(scene.lighting.groundColor, 1.0f);
  block->clock = glm::vec4(std::isfinite(scene.seconds) ? float(scene.seconds) : 0.0f, 0.0f, 0.0f, 0.0f);
  f.firstPerson = scene.firstPerson;
  f.grid = scene.grid;
  // Blended draws' centres in this pose, for sorting them per pass (vectors grow once, then reuse).
  f.blendCenters.clear();
  if (scene.avatar) {
    const GpuDrawList& list = scene.firstPerson ? scene.avatar->firstPerson() : scene.avatar->thirdPerson();
    for (const GpuDraw& d : list.blend)
      f.blendCenters.push_back(glm::vec3(scene.palette[d.joint] * glm::vec4(d.center, 1.0f)));
  }
  return {};
}

Result<const Image*> Renderer::transient(VkFormat format, VkExtent2D extent, uint32_t layers,
                                         VkSampleCountFlagBits samples) {
  for (auto& t : transients_) {
    if (t.format == format && t.extent.width == extent.width && t.extent.height == extent.height &&
        t.layers == layers && t.samples == samples) {
      t.lastFrame = stats_.frames;
      return &t.image;
    }
  }
  // Drop shapes unused for a few frames (a resized window, a changed MSAA setting): they may
  // still be in use by frames in flight, so they retire with the current frame.
  for (size_t i = 0; i < transients_.size();) {
    if (transients_[i].lastFrame + kFramesInFlight < stats_.frames) {
      retire(std::move(transients_[i].image));
      transients_.erase(transients_.begin() + long(i));
    } else {
      ++i;
    }
  }
  ImageDesc d;
  d.extent = extent;
  d.format = format;
  d.layers = layers;
  d.samples = samples;
  d.usage = isDepthFormat(format) ? VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT : VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  d.usage |= VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT;
  auto img = Image::create(device_, d);
  if (!img) return Error{img.error()};
  transients_.push_back({format, extent, layers, samples, std::move(img).value(), stats_.frames});
  return &transients_.back().image;
}

Status Renderer::prepare(VkFormat color, std::optional<VkFormat> depth, VkSampleCountFlagBits samples,
                         uint32_t viewMask) {
  auto p = pipelines({color, depth.value_or(kDepthFormat), samples, viewMask});
  if (!p) return Error{p.error()};
  return {};
}

void Renderer::drawAvatarList(VkCommandBuffer cmd, const GpuAvatar& a, const std::vector<GpuDraw>& draws,
                              std::span<const uint32_t> order, VkPipeline pipeline) {
  if (draws.empty()) return;
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
  const size_t count = order.empty() ? draws.size() : order.size();
  for (size_t i = 0; i < count; ++i) {
    const GpuDraw& d = draws[order.empty() ? i : order[i]];
    const GpuMaterial& m = a.materials()[d.material];
    vkCmdSetCullMode(cmd, m.doubleSided ? VK_CULL_MODE_NONE : VK_CULL_MODE_BACK_BIT);
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout_.get(), 1, 1, &m.descriptorSets[current_], 0,
                            nullptr);
    vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, 0, 0);
    ++stats_.drawCalls;
  }
}

void Renderer::drawOutlines(VkCommandBuffer cmd, const GpuAvatar& a, std::span<const GpuDraw> draws,
                            VkPipeline pipeline) {
  bool bound = false;
  for (const GpuDraw& d : draws) {
    const GpuMaterial& m = a.materials()[d.material];
    if (!m.outline) continue;
    if (!bound) {
      vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
      vkCmdSetCullMode(cmd, VK_CULL_MODE_FRONT_BIT);  // the hull's inside: always, whatever doubleSided says
      bound = true;
    }
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout_.get(), 1, 1, &m.descriptorSets[current_], 0,
                            nullptr);
    vkCmdDrawIndexed(cmd, d.indexCount, 1, d.firstIndex, 0, 0);
    ++stats_.drawCalls;
  }
}

void Renderer::drawBlended(VkCommandBuffer cmd, const GpuAvatar& a, const std::vector<GpuDraw>& draws,
                           std::span<const uint32_t> order, const PipelineSet& p) {
  for (uint32_t i : order) {
    const GpuDraw& d = draws[i];
    const GpuMaterial& m = a.materials()[d.material];
    // Blended surfaces test against depth but do not occlude, unless transparentWithZWrite.
    vkCmdSetDepthWriteEnable(cmd, m.zwrite ? VK_TRUE : VK_FALSE);
    drawAvatarList(cmd, a, draws, std::span<const uint32_t>(&i, 1), p.blend.get());
    if (m.outline) drawOutlines(cmd, a, std::span<const GpuDraw>(&d, 1), p.outlineBlend.get());
  }
  vkCmdSetDepthWriteEnable(cmd, VK_TRUE);
}

void Renderer::sortBlendBackToFront(FrameSlot& f, const GpuAvatar& a, const std::vector<GpuDraw>& draws,
                                    glm::vec3 eye) {
  f.blendOrder.resize(f.blendCenters.size());
  for (uint32_t i = 0; i < f.blendOrder.size(); ++i) f.blendOrder[i] = i;
  auto key = [&](uint32_t i) {
    const GpuMaterial& m = a.materials()[draws[i].material];
    return std::pair<int, int>(m.zwrite ? 0 : 1, m.queueOffset);
  };
  // std::sort (stable_sort may allocate); equal distances keep file order.
  std::sort(f.blendOrder.begin(), f.blendOrder.end(), [&](uint32_t x, uint32_t y) {
    if (key(x) != key(y)) return key(x) < key(y);
    const float dx = glm::dot(f.blendCenters[x] - eye, f.blendCenters[x] - eye);
    const float dy = glm::dot(f.blendCenters[y] - eye, f.blendCenters[y] - eye);
    return dx != dy ? dx > dy : x < y;
  });
}

void Renderer::drawLines(VkCommandBuffer cmd, const PipelineSet& p, VkBuffer buffer, VkDeviceSize offset,
                         uint32_t count) {
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.lines.get());
  vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
  vkCmdBindVertexBuffers(cmd, 0, 1, &buffer, &offset);
  vkCmdDraw(cmd, count, 1, 0, 0);
  ++stats_.drawCalls;
}

// The pass's contents: opaque and alpha-tested avatar first (it occludes most of what follows, so
// the grid and gizmos behind it are rejected by the depth test before shading) and their MToon
// outlines, then the grid and gizmos, then blended avatar surfaces (MToon render queue order, back
// to front, each with its outline), then the skeleton overlay on top.
void Renderer::recordScene(VkCommandBuffer cmd, const PipelineSet& p, FrameSlot& f, glm::vec3 eye) {
  const GpuAvatar* a = f.avatar;
  const GpuDrawList* list = a ? (f.firstPerson ? &a->firstPerson() : &a->thirdPerson()) : nullptr;
  auto bindAvatar = [&] {
    const VkDeviceSize zero = 0;
    const VkBuffer vb = a->vertexBuffer();
    vkCmdBindVertexBuffers(cmd, 0, 1, &vb, &zero);
  };
  if (a) {
    bindAvatar();
    vkCmdBindIndexBuffer(cmd, a->indexBuffer(), 0, VK_INDEX_TYPE_UINT32);
    drawAvatarList(cmd, *a, list->opaque, {}, p.opaque.get());
    drawAvatarList(cmd, *a, list->mask, {}, p.mask.get());
    drawOutlines(cmd, *a, list->opaque, p.outlineOpaque.get());
    drawOutlines(cmd, *a, list->mask, p.outlineMask.get());
  }
  if (f.grid) drawLines(cmd, p, grid_.handle(), 0, gridVertexCount_);
  if (f.lineCount > 0) drawLines(cmd, p, f.lines.handle(), 0, f.lineCount);
  if (a && !list->blend.empty()) {
    sortBlendBackToFront(f, *a, list->blend, eye);
    bindAvatar();
    drawBlended(cmd, *a, list->blend, f.blendOrder, p);
  }
  if (f.overlayCount > 0) {
    vkCmdSetDepthTestEnable(cmd, VK_FALSE);
    drawLines(cmd, p, f.lines.handle(), VkDeviceSize(f.lineCount) * sizeof(LineVertex), f.overlayCount);
  }
}

Result<Renderer::PassAttachments> Renderer::passAttachments(const PassTarget& target) {
  PassAttachments att;
  const uint32_t layers = target.color.layerCount;
  const bool msaa = target.samples != VK_SAMPLE_COUNT_1_BIT;
  att.ownDepth = !target.depth || msaa;
  att.depthFormat = att.ownDepth ? kDepthFormat : target.depth->format;
  if (att.ownDepth) {
    auto d = transient(kDepthFormat, target.color.extent, layers, target.samples);
    if (!d) return Error{d.error()};
    att.depthImage = (*d)->handle();
    att.depthView = (*d)->view();
  } else {
    att.depthImage = target.depth->image;
    att.depthView = target.depth->view;
    att.depthBase = target.depth->baseLayer;
  }
  if (msaa) {
    auto c = transient(target.color.format, target.color.extent, layers, target.samples);
    if (!c) return Error{c.error()};
    att.msaaImage = (*c)->handle();
    att.msaaView = (*c)->view();
  }
  return att;
}

void Renderer::beginRendering(VkCommandBuffer cmd, const PassTarget& target, const PassAttachments& att,
                              uint32_t viewMask) {
  const TargetImage& color = target.color;
  const uint32_t layers = color.layerCount;
  const bool msaa = att.msaaImage != VK_NULL_HANDLE;
  // Always a barrier, even without a layout change: an earlier pass of this frame may have
  // written the same image (a mirror view after the eyes), and that write must come first.
  transitionImage(cmd, color.image, VK_IMAGE_ASPECT_COLOR_BIT, color.initialLayout,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, color.baseLayer, layers);
  // Depth is cleared every pass, so its previous contents never matter: start from UNDEFINED.
  transitionImage(cmd, att.depthImage, aspectOf(att.depthFormat), VK_IMAGE_LAYOUT_UNDEFINED,
                  VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL, att.depthBase, layers);
  if (msaa)
    transitionImage(cmd, att.msaaImage, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_UNDEFINED,
                    VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, 0, layers);

  VkRenderingAttachmentInfo colorAtt{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  colorAtt.imageView = msaa ? att.msaaView : color.view;
  colorAtt.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colorAtt.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  colorAtt.storeOp = msaa ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
  colorAtt.clearValue.color = {{target.clearColor.r, target.clearColor.g, target.clearColor.b, target.clearColor.a}};
  if (msaa) {
    colorAtt.resolveMode = VK_RESOLVE_MODE_AVERAGE_BIT;
    colorAtt.resolveImageView = color.view;
    colorAtt.resolveImageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  }
  VkRenderingAttachmentInfo depthAtt{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  depthAtt.imageView = att.depthView;
  depthAtt.imageLayout = VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL;
  depthAtt.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
  depthAtt.storeOp = att.ownDepth ? VK_ATTACHMENT_STORE_OP_DONT_CARE : VK_ATTACHMENT_STORE_OP_STORE;
  depthAtt.clearValue.depthStencil = {1.0f, 0};
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, color.extent};
  ri.layerCount = 1;  // under multiview the view mask picks the layers
  ri.viewMask = viewMask;
  ri.colorAttachmentCount = 1;
  ri.pColorAttachments = &colorAtt;
  ri.pDepthAttachment = &depthAtt;
  vkCmdBeginRendering(cmd, &ri);

  const VkViewport viewport{0.0f, 0.0f, float(color.extent.width), float(color.extent.height), 0.0f, 1.0f};
  const VkRect2D scissor{{0, 0}, color.extent};
  vkCmdSetViewport(cmd, 0, 1, &viewport);
  vkCmdSetScissor(cmd, 0, 1, &scissor);
  vkCmdSetDepthTestEnable(cmd, VK_TRUE);
  vkCmdSetDepthWriteEnable(cmd, VK_TRUE);
  vkCmdSetCullMode(cmd, VK_CULL_MODE_NONE);
}

void Renderer::endRendering(VkCommandBuffer cmd, const PassTarget& target, const PassAttachments& att) {
  vkCmdEndRendering(cmd);
  const TargetImage& color = target.color;
  if (color.finalLayout != VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL)
    transitionImage(cmd, color.image, VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                    color.finalLayout, color.baseLayer, color.layerCount);
  if (!att.ownDepth && target.depth->finalLayout != VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL)
    transitionImage(cmd, att.depthImage, aspectOf(att.depthFormat), VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL,
                    target.depth->finalLayout, att.depthBase, color.layerCount);
}

Status Renderer::drawPass(std::span<const Camera> cameras, const PassTarget& target) {
  FrameSlot& f = frames_[current_];
  if (!f.recording) return Error{"drawPass outside beginFrame/endFrame"};
  const uint32_t layers = target.color.layerCount;
  const bool multiview = cameras.size() == 2 && layers == 2;
  if (cameras.empty() || (cameras.size() != 1 && !multiview))
    return Error{"drawPass takes one camera, or two cameras with a 2-layer target (multiview)"};
  if (f.viewsUsed + cameras.size() > kMaxViewsPerFrame) return Error{"too many views in one frame"};
  if (target.samples != VK_SAMPLE_COUNT_1_BIT && !device_.supportsSamples(target.samples))
    return Error{"the device does not support this MSAA sample count"};
  if (target.color.extent.width == 0 || target.color.extent.height == 0) return Error{"empty colour target"};
  const uint32_t viewMask = multiview ? 0b11u : 0u;
  auto att = passAttachments(target);
  if (!att) return Error{att.error()};
  auto pset = pipelines({target.color.format, att->depthFormat, target.samples, viewMask});
  if (!pset) return Error{pset.error()};

  const uint32_t viewBase = f.viewsUsed;
  auto* block = static_cast<SceneBlock*>(f.sceneBlock.mapped());
  glm::vec3 eye(0.0f);  // blended draws sort by distance from the cameras' midpoint
  for (size_t i = 0; i < cameras.size(); ++i) {
    block->views[viewBase + i] = {cameras[i].viewProjection(), glm::vec4(cameras[i].position(), 1.0f)};
    eye += cameras[i].position() / float(cameras.size());
  }
  f.viewsUsed += static_cast<uint32_t>(cameras.size());
  f.sceneBlock.flush();

  const VkCommandBuffer cmd = f.cmd;
  beginRendering(cmd, target, *att, viewMask);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipelineLayout_.get(), 0, 1, &f.set, 0, nullptr);
  const PushBlock push{viewBase, float(target.color.extent.width) / float(target.color.extent.height)};
  vkCmdPushConstants(cmd, pipelineLayout_.get(), kPushStages, 0, sizeof(push), &push);
  recordScene(cmd, **pset, f, eye);
  endRendering(cmd, target, *att);
  return {};
}

VkCommandBuffer Renderer::commandBuffer() const { return frames_[current_].cmd; }

Status Renderer::endFrame(const SubmitSync& sync) {
  FrameSlot& f = frames_[current_];
  if (!f.recording) return Error{"endFrame without beginFrame"};
  vkEndCommandBuffer(f.cmd);
  f.recording = false;
  VkFence fence = f.fence.get();
  vkResetFences(device_.handle(), 1, &fence);
  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = f.cmd;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.waitSemaphoreInfoCount = static_cast<uint32_t>(sync.wait.size());
  si.pWaitSemaphoreInfos = sync.wait.data();
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbi;
  si.signalSemaphoreInfoCount = static_cast<uint32_t>(sync.signal.size());
  si.pSignalSemaphoreInfos = sync.signal.data();
  if (VkResult r = vkQueueSubmit2(device_.queue(), 1, &si, fence); r != VK_SUCCESS)
    return Error{std::string("vkQueueSubmit2: ") + vkResultName(r)};
  ++stats_.frames;
  if (sync.waitForCompletion) {
    if (VkResult r = vkWaitForFences(device_.handle(), 1, &fence, VK_TRUE, UINT64_MAX); r != VK_SUCCESS)
      return Error{std::string("waiting for the frame: ") + vkResultName(r)};
  }
  current_ = (current_ + 1) % kFramesInFlight;
  return {};
}

void Renderer::waitIdle() {
  device_.waitIdle();
  for (auto& f : frames_) f.retired.releaseAll();
}

}  // namespace embody::engine
