#pragma once
// GPU skinning into a buffer (compute shader shaders/skin.comp, which shares skinning.glsl with
// the vertex shader), read back for comparison with avatar::skinOnCpu. Not on the frame path:
// frames skin in the vertex shader; this exists so tests can check the GPU formula exactly.
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <vector>

#include "engine/gpu_avatar.h"
#include "engine/resources.h"

namespace embody::test {

class GpuSkinner {
 public:
  static Result<std::unique_ptr<GpuSkinner>> create(const engine::Device& device);
  // Morphs (weights: one per morph channel, empty: none) and skins every vertex of `avatar` with
  // `palette`, and returns positions and normals (blocking).
  Status run(const engine::GpuAvatar& avatar, std::span<const glm::mat4> palette, std::vector<glm::vec3>& positions,
             std::vector<glm::vec3>& normals, std::span<const float> morphWeights = {});

 private:
  explicit GpuSkinner(const engine::Device& device) : device_(device) {}
  const engine::Device& device_;
  engine::UniqueDescriptorSetLayout layout_;
  engine::UniquePipelineLayout pipelineLayout_;
  engine::UniquePipeline pipeline_;
  engine::UniqueDescriptorPool pool_;
  VkDescriptorSet set_ = VK_NULL_HANDLE;
  engine::Buffer palette_, output_, weights_, placeholder_;
};

}  // namespace embody::test
