#include "engine/gpu_avatar.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "engine/renderer.h"

namespace embody::engine {

namespace {

static_assert(sizeof(avatar::SkinnedVertex) == 26 * 4, "shaders/skin.comp reads the vertex as 26 words");

// std140 mirror of `Material` in shaders/material.glsl.
struct MaterialBlock {
  glm::vec4 baseColorFactor{1.0f};
  glm::vec4 emissive{0.0f};
  glm::vec4 baseColorUv[2];
  glm::vec4 emissiveUv[2];
  glm::vec4 params{0.5f, 0.0f, 0.0f, 0.0f};
  glm::vec4 shadeColor{0.0f}, shading{0.0f}, rimColor{0.0f}, mixes{0.0f}, matcapFactor{0.0f}, outlineColor{0.0f};
  glm::vec4 shadeUv[2], shadingShiftUv[2], rimUv[2], outlineWidthUv[2];
  glm::vec4 uvAnimation{0.0f};  // xy: scroll (UV/s), z: rotation (rad/s), w: 0 none, 1 VRM 1.0, 2 VRM 0.x order and mask
  glm::vec4 uvAnimationMaskUv[2];
};
static_assert(sizeof(MaterialBlock) == 24 * sizeof(glm::vec4), "std140: vec4 members only, no padding");

// KHR_texture_transform as the two rows of its 2x3 matrix (see avatar::TextureTransform); the
// first row's w carries the texture coordinate set.
void uvRows(const avatar::TextureTransform& t, glm::vec4 rows[2]) {
  const float c = std::cos(t.rotation), s = std::sin(t.rotation);
  rows[0] = glm::vec4(c * t.scale.x, s * t.scale.y, t.offset.x, float(t.texCoord));
  rows[1] = glm::vec4(-s * t.scale.x, c * t.scale.y, t.offset.y, 0.0f);
}

// The block of `m` as loaded, or under this frame's expression binds (`bind`, colours and texture
// transforms; the rest stays as loaded).
MaterialBlock materialBlock(const avatar::Material& m, const avatar::MaterialBindState* bind = nullptr) {
  using C = avatar::MaterialColorType;
  const avatar::MaterialBindState s = bind ? *bind : avatar::materialBindBase(m);
  MaterialBlock b;
  b.baseColorFactor = glm::vec4(s.color(C::Color), s.alpha);
  b.emissive = glm::vec4(s.color(C::EmissionColor) * m.emissiveStrength, 0.0f);
  uvRows(s.transform(m.baseColorTransform), b.baseColorUv);
  uvRows(s.transform(m.emissiveTransform), b.emissiveUv);
  const avatar::MToon& t = m.mtoon;
  const bool outline = m.isMToon && t.hasOutline();
  b.params = glm::vec4(m.alphaCutoff, m.unlit ? 1.0f : 0.0f, m.isMToon ? 1.0f : 0.0f,
                       outline ? float(static_cast<int>(t.outlineMode)) : 0.0f);
  b.shadeColor = glm::vec4(s.color(C::ShadeColor), t.shadingShift);
  // Without a shading-shift texture the white default would shift by its scale: scale 0 instead.
  b.shading = glm::vec4(t.shadingToony, t.giEqualization, t.shadingShiftImage >= 0 ? t.shadingShiftScale : 0.0f,
                        t.rimFresnelPower);
  b.rimColor = glm::vec4(s.color(C::RimColor), t.rimLift);
  b.mixes = glm::vec4(t.rimLightingMix, t.outlineWidth, t.outlineLightingMix, 0.0f);
  b.matcapFactor = glm::vec4(t.matcapImage >= 0 ? s.color(C::MatcapColor) : glm::vec3(0.0f), 0.0f);  // no texture: no matcap
  b.outlineColor = glm::vec4(s.color(C::OutlineColor), 1.0f);
  // Texture-transform binds move every texture but the matcap (which has no transform).
  uvRows(s.transform(t.shadeTransform), b.shadeUv);
  uvRows(s.transform(t.shadingShiftTransform), b.shadingShiftUv);
  uvRows(s.transform(t.rimTransform), b.rimUv);
  uvRows(s.transform(t.outlineWidthTransform), b.outlineWidthUv);
  if (m.isMToon && t.hasUvAnimation())
    b.uvAnimation = glm::vec4(t.uvAnimationScroll, t.uvAnimationRotation, t.uvAnimationVrm0 ? 2.0f : 1.0f);
  uvRows(t.uvAnimationMaskTransform, b.uvAnimationMaskUv);  // the mask reads the un-animated uv (binds do not move it)
  return b;
}

// A material's textures in binding order (set 1, bindings 1..8), and whether each holds linear
// data (shading shift, outline width, UV animation mask) rather than sRGB colour.
struct MaterialTextures {
  int image[kMaterialTextureCount];
  static constexpr bool kLinear[kMaterialTextureCount] = {false, false, false, true, false, false, true, true};
};

MaterialTextures materialTextures(const avatar::Material& m) {
  const avatar::MToon& t = m.mtoon;
  if (!m.isMToon) return {{m.baseColorImage, m.emissiveImage, -1, -1, -1, -1, -1, -1}};
  return {{m.baseColorImage, m.emissiveImage, t.shadeImage, t.shadingShiftImage, t.rimImage, t.matcapImage,
           t.outlineWidthImage, t.uvAnimationMaskImage}};
}

// Centroid (bind space) and the joint with the most skin weight over a draw's vertices.
void locateDraw(const avatar::SkinnedMesh& mesh, const std::vector<uint32_t>& indices, GpuDraw& d,
                std::vector<float>& weightPerJoint) {
  std::fill(weightPerJoint.begin(), weightPerJoint.end(), 0.0f);
  glm::vec3 sum(0.0f);
  for (uint32_t i = 0; i < d.indexCount; ++i) {
    const avatar::SkinnedVertex& v = mesh.vertices[indices[d.firstIndex + i]];
    sum += v.position;
    for (int k = 0; k < 4; ++k) {
      weightPerJoint[v.joints0[k]] += v.weights0[k];
      weightPerJoint[v.joints1[k]] += v.weights1[k];
    }
  }
  d.center = d.indexCount ? sum / float(d.indexCount) : glm::vec3(0.0f);
  d.joint = uint32_t(std::max_element(weightPerJoint.begin(), weightPerJoint.end()) - weightPerJoint.begin());
}

}  // namespace

std::string GpuAvatar::validate(const avatar::AvatarAsset& asset) {
  const auto& mesh = asset.mesh;
  const size_t joints = asset.skeleton.joints.size();
  if (auto s = asset.skeleton.validate(); !s.empty()) return s;
  if (!mesh.vertices.empty() && joints == 0) return "the mesh has vertices but the skeleton has no joints";
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const auto& v = mesh.vertices[i];
    for (int k = 0; k < 4; ++k) {
      // All eight indices, weighted or not: the shader fetches palette entries before weighting.
      if (v.joints0[k] >= joints || v.joints1[k] >= joints)
        return "vertex " + std::to_string(i) + " refers to joint outside the skeleton (" + std::to_string(joints) +
               " joints)";
      if (!std::isfinite(v.weights0[k]) || !std::isfinite(v.weights1[k]))
        return "vertex " + std::to_string(i) + " has a non-finite skin weight";
    }
    if (!std::isfinite(v.position.x) || !std::isfinite(v.position.y) || !std::isfinite(v.position.z))
      return "vertex " + std::to_string(i) + " has a non-finite position";
  }
  auto checkList = [&](const std::vector<uint32_t>& indices, const std::vector<avatar::Primitive>& prims,
                       const char* what) -> std::string {
    if (indices.size() % 3 != 0) return std::string(what) + " index count is not a multiple of 3";
    for (uint32_t idx : indices)
      if (idx >= mesh.vertices.size()) return std::string(what) + " index " + std::to_string(idx) + " is out of range";
    for (const auto& p : prims) {
      if (size_t(p.firstIndex) + p.indexCount > indices.size()) return std::string(what) + " primitive exceeds its index list";
      if (p.material >= int(asset.materials.size())) return std::string(what) + " primitive refers to a missing material";
    }
    return {};
  };
  for (size_t i = 0; i < mesh.morphDeltas.size(); ++i) {
    const auto& d = mesh.morphDeltas[i];
    if (d.vertex >= mesh.vertices.size() || d.channel >= mesh.morphChannels.size() ||
        (i > 0 && d.vertex < mesh.morphDeltas[i - 1].vertex))
      return "morph delta " + std::to_string(i) + " is out of range or out of vertex order";
  }
  if (auto s = checkList(mesh.indices, mesh.primitives, "third-person"); !s.empty()) return s;
  if (auto s = checkList(mesh.firstPersonIndices, mesh.firstPersonPrimitives, "first-person"); !s.empty()) return s;
  for (int m : asset.expressions.boundMaterials)
    if (m < 0 || static_cast<size_t>(m) >= asset.materials.size()) return "an expression binds a missing material";
  for (const auto& m : asset.materials) {
    const MaterialTextures textures = materialTextures(m);
    for (int image : textures.image) {
      if (image >= int(asset.images.size())) return "material '" + m.name + "' refers to a missing image";
      if (image < 0) continue;
      const auto& img = asset.images[image];
      if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * img.height * 4)
        return "image " + std::to_string(image) + " has inconsistent size/data";
    }
    for (const avatar::TextureTransform* t : {&m.baseColorTransform, &m.emissiveTransform, &m.mtoon.shadeTransform,
                                              &m.mtoon.shadingShiftTransform, &m.mtoon.rimTransform,
                                              &m.mtoon.outlineWidthTransform, &m.mtoon.uvAnimationMaskTransform})
      if (t->texCoord < 0 || t->texCoord > 1)
        return "material '" + m.name + "' reads a texture coordinate set other than 0 or 1";
  }
  return {};
}

Status GpuAvatar::uploadMesh(const Device& device, Uploader& up, const avatar::SkinnedMesh& mesh) {
  // Storage usage too: the compute skinner (GpuSkinner) reads the same vertex buffer.
  auto vb = Buffer::create(device, mesh.vertices.size() * sizeof(avatar::SkinnedVertex),
                           VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  const size_t indexCount = mesh.indices.size() + mesh.firstPersonIndices.size();
  auto ib = Buffer::create(device, indexCount * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  if (!vb) return Error{vb.error()};
  if (!ib) return Error{ib.error()};
  vertices_ = std::move(vb).value();
  indices_ = std::move(ib).value();
  if (auto s = up.upload(vertices_, asBytes(mesh.vertices)); !s) return s;
  if (auto s = up.upload(indices_, asBytes(mesh.indices)); !s) return s;
  if (auto s = up.upload(indices_, asBytes(mesh.firstPersonIndices), mesh.indices.size() * sizeof(uint32_t)); !s)
    return s;
  return uploadMorphTargets(device, up, mesh);
}

// shaders/morphing.glsl: a (first, count) range per vertex into the sparse deltas, each delta two
// vec4s with the channel's index in position.w. Nothing is uploaded for a mesh without morphs.
Status GpuAvatar::uploadMorphTargets(const Device& device, Uploader& up, const avatar::SkinnedMesh& mesh) {
  morphChannelCount_ = static_cast<uint32_t>(mesh.morphChannels.size());
  if (mesh.morphDeltas.empty()) return {};
  std::vector<glm::uvec2> ranges(mesh.vertices.size(), glm::uvec2(0));
  std::vector<glm::vec4> deltas;
  deltas.reserve(mesh.morphDeltas.size() * 2);
  for (size_t i = 0; i < mesh.morphDeltas.size(); ++i) {
    const avatar::MorphDelta& d = mesh.morphDeltas[i];
    glm::uvec2& r = ranges[d.vertex];
    if (r.y == 0) r.x = static_cast<uint32_t>(i);
    ++r.y;
    uint32_t channelBits = d.channel;
    float channel;
    std::memcpy(&channel, &channelBits, sizeof channel);
    deltas.emplace_back(d.position, channel);
    deltas.emplace_back(d.normal, 0.0f);
  }
  auto rb = Buffer::create(device, ranges.size() * sizeof(glm::uvec2), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  auto db = Buffer::create(device, deltas.size() * sizeof(glm::vec4), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  if (!rb) return Error{rb.error()};
  if (!db) return Error{db.error()};
  morphRanges_ = std::move(rb).value();
  morphDeltas_ = std::move(db).value();
  if (auto s = up.upload(morphRanges_, asBytes(ranges)); !s) return s;
  return up.upload(morphDeltas_, asBytes(deltas));
}

// Every image a material uses, mipmapped (when the device can blit the format linearly), after a
// 1x1 white texture (index 0) for untextured slots. Colour images are sRGB; an image a material
// reads as data (shading shift, outline width) gets a UNORM copy. Returns the texture index of
// each asset image in each encoding (0 where unused).
Result<GpuAvatar::TextureIndex> GpuAvatar::uploadTextures(const Device& device, Uploader& up,
                                                          const std::vector<avatar::Material>& materials,
                                                          const std::vector<avatar::Image>& images) {
  auto makeTexture = [&](const avatar::Image& img, VkFormat format) -> Status {
    ImageDesc d;
    d.extent = {uint32_t(img.width), uint32_t(img.height)};
    d.format = format;
    d.mipLevels = device.supportsLinearBlit(format) ? fullMipChain(d.extent) : 1;
    d.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    auto t = Image::create(device, d);
    if (!t) return Error{t.error()};
    if (auto s = up.upload(*t, img.rgba); !s) return s;
    textures_.push_back(std::move(t).value());
    return {};
  };
  avatar::Image white;
  white.width = white.height = 1;
  white.rgba = {255, 255, 255, 255};
  if (auto s = makeTexture(white, VK_FORMAT_R8G8B8A8_SRGB); !s) return Error{s.error()};
  TextureIndex index{std::vector<int>(images.size(), 0), std::vector<int>(images.size(), 0)};
  for (const auto& m : materials) {
    const MaterialTextures mt = materialTextures(m);
    for (int k = 0; k < kMaterialTextureCount; ++k) {
      const int image = mt.image[k];
      auto& slot = MaterialTextures::kLinear[k] ? index.linear : index.srgb;
      if (image < 0 || slot[image] > 0) continue;
      const VkFormat format = MaterialTextures::kLinear[k] ? VK_FORMAT_R8G8B8A8_UNORM : VK_FORMAT_R8G8B8A8_SRGB;
      if (auto s = makeTexture(images[image], format); !s) return Error{s.error()};
      slot[image] = int(textures_.size() - 1);
    }
  }
  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = VK_FILTER_LINEAR;
  sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_LINEAR;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.maxLod = VK_LOD_CLAMP_NONE;
  VkSampler sampler = VK_NULL_HANDLE;
  if (vkCreateSampler(device.handle(), &sci, nullptr, &sampler) != VK_SUCCESS) return Error{"vkCreateSampler failed"};
  sampler_ = UniqueSampler(device.handle(), sampler);
  return index;
}

namespace {

// Points `set` at a material's uniform block and its textures (set 1, bindings 0..7).
void writeMaterialSet(VkDevice dev, VkDescriptorSet set, const VkDescriptorBufferInfo& block,
                      const VkDescriptorImageInfo (&images)[kMaterialTextureCount]) {
  VkWriteDescriptorSet w[2] = {{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}, {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}};
  w[0].dstSet = w[1].dstSet = set;
  w[0].dstBinding = 0;
  w[0].descriptorCount = 1;
  w[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  w[0].pBufferInfo = &block;
  w[1].dstBinding = 1;  // bindings 1..8 are consecutive, one descriptor each
  w[1].descriptorCount = kMaterialTextureCount;
  w[1].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w[1].pImageInfo = images;
  vkUpdateDescriptorSets(dev, 2, w, 0, nullptr);
}

}  // namespace

void GpuAvatar::writeBoundMaterials(uint32_t slot, std::span<const avatar::MaterialBindState> states) const {
  if (boundBase_.empty()) return;
  auto* base = static_cast<std::byte*>(boundBlocks_.mapped()) + slot * boundBase_.size() * blockStride_;
  for (size_t k = 0; k < boundBase_.size(); ++k) {
    const MaterialBlock b = materialBlock(boundBase_[k], states.empty() ? nullptr : &states[k]);
    std::memcpy(base + k * blockStride_, &b, sizeof(b));
  }
  boundBlocks_.flush();
}

// Device-local blocks for every material; the bound ones (boundMaterials_) also get a host-visible
// block and a descriptor set per frame slot.
Status GpuAvatar::createMaterials(const Device& device, Uploader& up, VkDescriptorSetLayout layout,
                                  const std::vector<avatar::Material>& materials, const TextureIndex& textureOf) {
  const VkDevice dev = device.handle();
  const VkDeviceSize align = std::max<VkDeviceSize>(device.limits().minUniformBufferOffsetAlignment, 16);
  const VkDeviceSize stride = (sizeof(MaterialBlock) + align - 1) / align * align;
  blockStride_ = stride;
  std::vector<std::byte> blocks(stride * materials.size());
  for (size_t i = 0; i < materials.size(); ++i) {
    const MaterialBlock b = materialBlock(materials[i]);
    std::memcpy(blocks.data() + i * stride, &b, sizeof(b));
  }
  auto buffer = Buffer::create(device, blocks.size(), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, MemoryUse::DeviceLocal);
  if (!buffer) return Error{buffer.error()};
  materialBlocks_ = std::move(buffer).value();
  if (auto s = up.upload(materialBlocks_, blocks); !s) return s;
  const size_t bound = boundMaterials_.size();
  for (int m : boundMaterials_) boundBase_.push_back(materials[static_cast<size_t>(m)]);
  if (bound > 0) {
    auto hb = Buffer::create(device, stride * bound * kFramesInFlight, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT,
                             MemoryUse::HostUpload);
    if (!hb) return Error{hb.error()};
    boundBlocks_ = std::move(hb).value();
    for (uint32_t slot = 0; slot < kFramesInFlight; ++slot) writeBoundMaterials(slot, {});
  }

  const uint32_t setCount = static_cast<uint32_t>(materials.size() + bound * (kFramesInFlight - 1));
  const VkDescriptorPoolSize sizes[2] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, setCount},
                                         {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, kMaterialTextureCount * setCount}};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = setCount;
  dpci.poolSizeCount = 2;
  dpci.pPoolSizes = sizes;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  if (vkCreateDescriptorPool(dev, &dpci, nullptr, &pool) != VK_SUCCESS) return Error{"vkCreateDescriptorPool failed"};
  pool_ = UniqueDescriptorPool(dev, pool);
  for (size_t i = 0; i < materials.size(); ++i) {
    const avatar::Material& m = materials[i];
    const MaterialTextures mt = materialTextures(m);
    VkDescriptorImageInfo images[kMaterialTextureCount];
    for (int k = 0; k < kMaterialTextureCount; ++k) {
      const int image = mt.image[k];
      const int texture = image < 0 ? 0 : (MaterialTextures::kLinear[k] ? textureOf.linear : textureOf.srgb)[image];
      images[k] = {sampler_.get(), textures_[texture].view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    }
    const auto b = std::find(boundMaterials_.begin(), boundMaterials_.end(), static_cast<int>(i));
    const size_t k = static_cast<size_t>(b - boundMaterials_.begin());
    GpuMaterial g;
    for (uint32_t slot = 0; slot < (k < bound ? kFramesInFlight : 1); ++slot) {
      auto set = allocateDescriptorSet(dev, pool, layout);
      if (!set) return Error{set.error()};
      const VkDescriptorBufferInfo block = k < bound ? VkDescriptorBufferInfo{boundBlocks_.handle(), (slot * bound + k) * stride, sizeof(MaterialBlock)}
                                                     : VkDescriptorBufferInfo{materialBlocks_.handle(), i * stride, sizeof(MaterialBlock)};
      writeMaterialSet(dev, *set, block, images);
      g.descriptorSets[slot] = *set;
    }
    if (k >= bound) g.descriptorSets.fill(g.descriptorSets[0]);
    g.alphaMode = m.alphaMode;
    g.doubleSided = m.doubleSided;
    g.outline = m.isMToon && m.mtoon.hasOutline();
    g.zwrite = m.alphaMode != avatar::AlphaMode::Blend || (m.isMToon && m.mtoon.transparentWithZWrite);
    g.queueOffset = m.isMToon && m.alphaMode == avatar::AlphaMode::Blend ? m.mtoon.renderQueueOffset : 0;
    materials_.push_back(g);
  }
  return {};
}

void GpuAvatar::buildDrawLists(const avatar::AvatarAsset& asset, const std::vector<avatar::Material>& materials) {
  const auto& mesh = asset.mesh;
  std::vector<float> weightPerJoint(asset.skeleton.joints.size());
  auto split = [&](const std::vector<avatar::Primitive>& prims, const std::vector<uint32_t>& indices,
                   uint32_t indexBase, GpuDrawList& out) {
    for (const auto& p : prims) {
      if (p.indexCount == 0) continue;
      const uint32_t mat = p.material >= 0 ? uint32_t(p.material) : uint32_t(materials.size() - 1);
      GpuDraw d{p.firstIndex, p.indexCount, mat};
      switch (materials[mat].alphaMode) {
        case avatar::AlphaMode::Opaque: out.opaque.push_back(d); break;
        case avatar::AlphaMode::Mask: out.mask.push_back(d); break;
        case avatar::AlphaMode::Blend:
          locateDraw(mesh, indices, d, weightPerJoint);
          out.blend.push_back(d);
          break;
      }
    }
    for (auto* list : {&out.opaque, &out.mask, &out.blend})
      for (GpuDraw& d : *list) d.firstIndex += indexBase;
  };
  split(mesh.primitives, mesh.indices, 0, thirdPerson_);
  split(mesh.firstPersonPrimitives, mesh.firstPersonIndices, static_cast<uint32_t>(mesh.indices.size()), firstPerson_);
}

Result<std::unique_ptr<GpuAvatar>> Renderer::upload(const avatar::AvatarAsset& asset) {
  if (auto why = GpuAvatar::validate(asset); !why.empty()) return Error{"cannot draw this avatar: " + why};
  std::unique_ptr<GpuAvatar> a(new GpuAvatar());
  const auto& mesh = asset.mesh;
  a->vertexCount_ = static_cast<uint32_t>(mesh.vertices.size());
  a->jointCount_ = static_cast<uint32_t>(asset.skeleton.joints.size());
  a->triangles_ = mesh.triangleCount();
  a->hasFirstPerson_ = !mesh.firstPersonPrimitives.empty();
  // Materials: the asset's, then the glTF default material (white, opaque, single-sided) last.
  std::vector<avatar::Material> materials = asset.materials;
  materials.push_back(avatar::Material{});
  a->boundMaterials_ = asset.expressions.boundMaterials;
  Uploader up(device_);
  if (auto s = a->uploadMesh(device_, up, mesh); !s) return Error{s.error()};
  auto textureOf = a->uploadTextures(device_, up, materials, asset.images);
  if (!textureOf) return Error{textureOf.error()};
  if (auto s = a->createMaterials(device_, up, materialLayout_.get(), materials, *textureOf); !s)
    return Error{s.error()};
  if (auto s = up.flush(); !s) return Error{s.error()};
  a->buildDrawLists(asset, materials);
  return a;
}

}  // namespace embody::engine
