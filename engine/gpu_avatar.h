#pragma once
// An AvatarAsset uploaded to the GPU: one vertex buffer (avatar::SkinnedVertex as is), one index
// buffer holding the third-person and first-person lists back to back, mipmapped textures, a
// uniform block + descriptor set per material, and the draw lists split by alpha mode. Created by
// Renderer::upload.
//
// Materials that VRM expressions move (material colour and texture-transform binds:
// asset.expressions.boundMaterials) keep their uniform blocks in a host-visible buffer, one copy
// per frame in flight, each with its own descriptor set; the renderer rewrites the copy of the
// frame it records (setScene), after beginFrame has waited for that frame's previous use.
#include <array>
#include <glm/glm.hpp>
#include <span>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/vrm/material_binds.h"
#include "engine/resources.h"

namespace embody::engine {

constexpr uint32_t kFramesInFlight = 2;  // the renderer's frame slots

// Textures a material binds (set 1, bindings 1..8): base colour, emissive, then MToon's shade,
// shading shift, rim, matcap, outline width and UV animation mask (the white texture where a
// material has none).
constexpr int kMaterialTextureCount = 8;

struct GpuMaterial {
  avatar::AlphaMode alphaMode = avatar::AlphaMode::Opaque;
  bool doubleSided = false;
  bool outline = false;  // MToon outline: an inverted-hull pass after the surface
  bool zwrite = true;    // BLEND writes depth only with MToon's transparentWithZWrite
  int queueOffset = 0;   // MToon renderQueueOffsetNumber (BLEND): later draws have higher offsets
  // set 1 per frame slot: the material's uniform block (shaders/material.glsl) and its textures;
  // the same set in every slot unless expressions bind the material (then each slot's own block).
  std::array<VkDescriptorSet, kFramesInFlight> descriptorSets{};
};

struct GpuDraw {
  uint32_t firstIndex = 0;  // into the shared index buffer
  uint32_t indexCount = 0;
  uint32_t material = 0;  // into GpuAvatar::materials() (the default material is appended last)
  // Where the triangles are, for sorting blended draws back to front: the centroid of their
  // vertices in bind space and the joint that moves it (the one with the most skin weight).
  glm::vec3 center{0.0f};
  uint32_t joint = 0;
};

// Draws of one view kind (third- or first-person), grouped by pipeline.
struct GpuDrawList {
  std::vector<GpuDraw> opaque, mask, blend;
};

class GpuAvatar {
 public:
  GpuAvatar(GpuAvatar&&) noexcept = default;
  GpuAvatar& operator=(GpuAvatar&&) noexcept = default;

  VkBuffer vertexBuffer() const { return vertices_.handle(); }
  VkBuffer indexBuffer() const { return indices_.handle(); }
  uint32_t vertexCount() const { return vertexCount_; }
  uint32_t jointCount() const { return jointCount_; }
  const std::vector<GpuMaterial>& materials() const { return materials_; }
  const GpuDrawList& thirdPerson() const { return thirdPerson_; }
  // The head-less list, or the full mesh when the asset has no first-person list.
  const GpuDrawList& firstPerson() const { return hasFirstPerson_ ? firstPerson_ : thirdPerson_; }
  size_t triangleCount() const { return triangles_; }
  // Morph targets (shaders/morphing.glsl); null handles when the mesh has none.
  VkBuffer morphRanges() const { return morphRanges_.handle(); }
  VkBuffer morphDeltas() const { return morphDeltas_.handle(); }
  uint32_t morphChannelCount() const { return morphChannelCount_; }
  // The materials with per-frame blocks (asset.expressions.boundMaterials).
  const std::vector<int>& boundMaterials() const { return boundMaterials_; }

  // Checks what the GPU would otherwise read out of bounds: joint indices against the skeleton,
  // vertex indices against the vertex count, primitive ranges, material and image indices.
  static std::string validate(const avatar::AvatarAsset& asset);

 private:
  friend class Renderer;
  GpuAvatar() = default;
  // Steps of Renderer::upload.
  Status uploadMesh(const Device& device, Uploader& up, const avatar::SkinnedMesh& mesh);
  Status uploadMorphTargets(const Device& device, Uploader& up, const avatar::SkinnedMesh& mesh);
  struct TextureIndex {  // per asset image: its texture as sRGB colour and as linear data (0: none)
    std::vector<int> srgb, linear;
  };
  Result<TextureIndex> uploadTextures(const Device& device, Uploader& up, const std::vector<avatar::Material>& materials,
                                      const std::vector<avatar::Image>& images);
  Status createMaterials(const Device& device, Uploader& up, VkDescriptorSetLayout layout,
                         const std::vector<avatar::Material>& materials, const TextureIndex& textureOf);
  void buildDrawLists(const avatar::AvatarAsset& asset, const std::vector<avatar::Material>& materials);
  // Writes frame slot `slot`'s blocks of the bound materials: the states (one per bound material)
  // or, when empty, the materials as loaded. Only the renderer calls it, for the slot it records.
  void writeBoundMaterials(uint32_t slot, std::span<const avatar::MaterialBindState> states) const;
  Buffer vertices_, indices_, materialBlocks_;
  Buffer boundBlocks_;  // host-visible: kFramesInFlight x boundMaterials_ blocks
  VkDeviceSize blockStride_ = 0;
  std::vector<int> boundMaterials_;
  std::vector<avatar::Material> boundBase_;  // the bound materials as loaded
  Buffer morphRanges_, morphDeltas_;
  uint32_t morphChannelCount_ = 0;
  std::vector<Image> textures_;
  UniqueSampler sampler_;
  UniqueDescriptorPool pool_;
  std::vector<GpuMaterial> materials_;
  GpuDrawList thirdPerson_, firstPerson_;
  bool hasFirstPerson_ = false;
  uint32_t vertexCount_ = 0, jointCount_ = 0;
  size_t triangles_ = 0;
};

}  // namespace embody::engine
