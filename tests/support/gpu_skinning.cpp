#include "tests/support/gpu_skinning.h"

#include <algorithm>
#include <cstring>

#include "shaders/skin_comp.spv.h"

namespace embody::test {
using namespace embody::engine;

Result<std::unique_ptr<GpuSkinner>> GpuSkinner::create(const Device& device) {
  std::unique_ptr<GpuSkinner> s(new GpuSkinner(device));
  const VkDevice dev = device.handle();
  // 0 vertices, 1 palette, 2 output, 3..5 morph ranges, deltas, weights (shaders/morphing.glsl).
  VkDescriptorSetLayoutBinding bindings[6];
  for (uint32_t i = 0; i < 6; ++i)
    bindings[i] = {i, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  VkDescriptorSetLayoutCreateInfo lci{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  lci.bindingCount = 6;
  lci.pBindings = bindings;
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  if (vkCreateDescriptorSetLayout(dev, &lci, nullptr, &layout) != VK_SUCCESS) return Error{"descriptor set layout"};
  s->layout_ = UniqueDescriptorSetLayout(dev, layout);
  VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t)};
  VkPipelineLayoutCreateInfo pli{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pli.setLayoutCount = 1;
  pli.pSetLayouts = &layout;
  pli.pushConstantRangeCount = 1;
  pli.pPushConstantRanges = &push;
  VkPipelineLayout pl = VK_NULL_HANDLE;
  if (vkCreatePipelineLayout(dev, &pli, nullptr, &pl) != VK_SUCCESS) return Error{"pipeline layout"};
  s->pipelineLayout_ = UniquePipelineLayout(dev, pl);

  auto module = createShaderModule(dev, skin_comp_spv, sizeof(skin_comp_spv));
  if (!module) return Error{module.error()};
  VkComputePipelineCreateInfo cci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
  cci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  cci.stage.module = module->get();
  cci.stage.pName = "main";
  cci.layout = pl;
  VkPipeline pipeline = VK_NULL_HANDLE;
  if (vkCreateComputePipelines(dev, VK_NULL_HANDLE, 1, &cci, nullptr, &pipeline) != VK_SUCCESS)
    return Error{"vkCreateComputePipelines failed"};
  s->pipeline_ = UniquePipeline(dev, pipeline);

  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 6};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = 1;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  if (vkCreateDescriptorPool(dev, &dpci, nullptr, &pool) != VK_SUCCESS) return Error{"descriptor pool"};
  s->pool_ = UniqueDescriptorPool(dev, pool);
  auto set = allocateDescriptorSet(dev, pool, layout);
  if (!set) return Error{set.error()};
  s->set_ = *set;
  return s;
}

Status GpuSkinner::run(const GpuAvatar& avatar, std::span<const glm::mat4> palette, std::vector<glm::vec3>& positions,
                       std::vector<glm::vec3>& normals, std::span<const float> morphWeights) {
  if (palette.size() < avatar.jointCount()) return Error{"palette smaller than the avatar's skeleton"};
  const uint32_t n = avatar.vertexCount();
  if (palette_.size() < palette.size_bytes()) {
    auto b = Buffer::create(device_, palette.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::HostUpload);
    if (!b) return Error{b.error()};
    palette_ = std::move(b).value();
  }
  const VkDeviceSize outBytes = VkDeviceSize(n) * 2 * sizeof(glm::vec4);
  if (output_.size() < outBytes) {
    auto b = Buffer::create(device_, outBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::HostReadback);
    if (!b) return Error{b.error()};
    output_ = std::move(b).value();
  }
  std::memcpy(palette_.mapped(), palette.data(), palette.size_bytes());
  palette_.flush();
  const VkDeviceSize weightBytes = std::max<VkDeviceSize>(morphWeights.size_bytes(), 16);
  if (weights_.size() < weightBytes) {
    auto b = Buffer::create(device_, weightBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::HostUpload);
    if (!b) return Error{b.error()};
    weights_ = std::move(b).value();
  }
  std::memset(weights_.mapped(), 0, weights_.size());
  if (!morphWeights.empty()) std::memcpy(weights_.mapped(), morphWeights.data(), morphWeights.size_bytes());
  weights_.flush();
  // Without morph targets a zeroed placeholder stands in: ranges (0, 0), no deltas.
  if (placeholder_.size() == 0) {
    auto b = Buffer::create(device_, 32, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUse::HostUpload);
    if (!b) return Error{b.error()};
    placeholder_ = std::move(b).value();
    std::memset(placeholder_.mapped(), 0, 32);
    placeholder_.flush();
  }
  const VkBuffer ranges = avatar.morphRanges() ? avatar.morphRanges() : placeholder_.handle();
  const VkBuffer deltas = avatar.morphDeltas() ? avatar.morphDeltas() : placeholder_.handle();

  VkDescriptorBufferInfo infos[6] = {{avatar.vertexBuffer(), 0, VK_WHOLE_SIZE}, {palette_.handle(), 0, VK_WHOLE_SIZE},
                                     {output_.handle(), 0, VK_WHOLE_SIZE},      {ranges, 0, VK_WHOLE_SIZE},
                                     {deltas, 0, VK_WHOLE_SIZE},                {weights_.handle(), 0, VK_WHOLE_SIZE}};
  VkWriteDescriptorSet w[6];
  for (uint32_t i = 0; i < 6; ++i) {
    w[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w[i].dstSet = set_;
    w[i].dstBinding = i;
    w[i].descriptorCount = 1;
    w[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    w[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(device_.handle(), 6, w, 0, nullptr);

  auto status = device_.submitAndWait([&](VkCommandBuffer cmd) {
    vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline_.get());
    vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, pipelineLayout_.get(), 0, 1, &set_, 0, nullptr);
    vkCmdPushConstants(cmd, pipelineLayout_.get(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(uint32_t), &n);
    vkCmdDispatch(cmd, (n + 63) / 64, 1, 1);
    memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                  VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  });
  if (!status) return status;
  output_.invalidate();
  const auto* out = static_cast<const glm::vec4*>(output_.mapped());
  positions.resize(n);
  normals.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    positions[i] = glm::vec3(out[2 * i]);
    normals[i] = glm::vec3(out[2 * i + 1]);
  }
  return {};
}

}  // namespace embody::test
