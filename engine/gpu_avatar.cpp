#include "engine/gpu_avatar.h"

#include <cmath>
#include <string>

#include "engine/renderer.h"

namespace embody::engine {

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
  if (auto s = checkList(mesh.indices, mesh.primitives, "third-person"); !s.empty()) return s;
  if (auto s = checkList(mesh.firstPersonIndices, mesh.firstPersonPrimitives, "first-person"); !s.empty()) return s;
  for (const auto& m : asset.materials) {
    if (m.baseColorImage >= int(asset.images.size())) return "material '" + m.name + "' refers to a missing image";
    if (m.baseColorImage >= 0) {
      const auto& img = asset.images[m.baseColorImage];
      if (img.width <= 0 || img.height <= 0 || img.rgba.size() != size_t(img.width) * img.height * 4)
        return "image " + std::to_string(m.baseColorImage) + " has inconsistent size/data";
    }
  }
  return {};
}

Result<std::unique_ptr<GpuAvatar>> Renderer::upload(const avatar::AvatarAsset& asset) {
  if (auto why = GpuAvatar::validate(asset); !why.empty()) return Error{"cannot draw this avatar: " + why};
  const VkDevice dev = device_.handle();
  std::unique_ptr<GpuAvatar> a(new GpuAvatar());
  const auto& mesh = asset.mesh;
  a->vertexCount_ = static_cast<uint32_t>(mesh.vertices.size());
  a->jointCount_ = static_cast<uint32_t>(asset.skeleton.joints.size());
  a->triangles_ = mesh.triangleCount();
  a->hasFirstPerson_ = !mesh.firstPersonPrimitives.empty();

  // Storage usage too: the compute skinner (GpuSkinner) reads the same vertex buffer.
  auto vb = Buffer::create(device_, mesh.vertices.size() * sizeof(avatar::SkinnedVertex),
                           VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  const size_t indexCount = mesh.indices.size() + mesh.firstPersonIndices.size();
  auto ib = Buffer::create(device_, indexCount * sizeof(uint32_t), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                           MemoryUse::DeviceLocal);
  if (!vb) return Error{vb.error()};
  if (!ib) return Error{ib.error()};
  a->vertices_ = std::move(vb).value();
  a->indices_ = std::move(ib).value();
  Uploader up(device_);
  if (auto s = up.upload(a->vertices_, asBytes(mesh.vertices)); !s) return Error{s.error()};
  if (auto s = up.upload(a->indices_, asBytes(mesh.indices)); !s) return Error{s.error()};
  if (auto s = up.upload(a->indices_, asBytes(mesh.firstPersonIndices), mesh.indices.size() * sizeof(uint32_t)); !s)
    return Error{s.error()};

  // Textures: every image a material uses, plus a 1x1 white one for untextured materials.
  std::vector<int> textureOf(asset.images.size(), -1);
  auto makeTexture = [&](const avatar::Image& img) -> Result<int> {
    ImageDesc d;
    d.extent = {uint32_t(img.width), uint32_t(img.height)};
    d.format = VK_FORMAT_R8G8B8A8_SRGB;  // glTF base colour is sRGB-encoded
    d.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    auto t = Image::create(device_, d);
    if (!t) return Error{t.error()};
    if (auto s = up.upload(*t, img.rgba); !s) return Error{s.error()};
    a->textures_.push_back(std::move(t).value());
    return int(a->textures_.size() - 1);
  };
  avatar::Image white;
  white.width = white.height = 1;
  white.rgba = {255, 255, 255, 255};
  auto whiteTex = makeTexture(white);
  if (!whiteTex) return Error{whiteTex.error()};
  for (const auto& m : asset.materials) {
    if (m.baseColorImage < 0 || textureOf[m.baseColorImage] >= 0) continue;
    auto t = makeTexture(asset.images[m.baseColorImage]);
    if (!t) return Error{t.error()};
    textureOf[m.baseColorImage] = *t;
  }
  if (auto s = up.flush(); !s) return Error{s.error()};

  VkSamplerCreateInfo sci{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  sci.magFilter = VK_FILTER_LINEAR;
  sci.minFilter = VK_FILTER_LINEAR;
  sci.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  sci.addressModeU = sci.addressModeV = sci.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  sci.maxLod = 0.0f;
  VkSampler sampler = VK_NULL_HANDLE;
  if (vkCreateSampler(dev, &sci, nullptr, &sampler) != VK_SUCCESS) return Error{"vkCreateSampler failed"};
  a->sampler_ = UniqueSampler(dev, sampler);

  // Materials: the asset's, then the glTF default material (white, opaque, single-sided) last.
  std::vector<avatar::Material> materials = asset.materials;
  materials.push_back(avatar::Material{});
  const uint32_t setCount = static_cast<uint32_t>(materials.size());
  VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, setCount};
  VkDescriptorPoolCreateInfo dpci{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  dpci.maxSets = setCount;
  dpci.poolSizeCount = 1;
  dpci.pPoolSizes = &size;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  if (vkCreateDescriptorPool(dev, &dpci, nullptr, &pool) != VK_SUCCESS) return Error{"vkCreateDescriptorPool failed"};
  a->pool_ = UniqueDescriptorPool(dev, pool);
  for (const auto& m : materials) {
    GpuMaterial g;
    g.baseColorFactor = m.baseColorFactor;
    g.alphaMode = m.alphaMode;
    g.alphaCutoff = m.alphaCutoff;
    g.doubleSided = m.doubleSided;
    auto set = allocateDescriptorSet(dev, pool, materialLayout_.get());
    if (!set) return Error{set.error()};
    g.descriptorSet = *set;
    const int tex = m.baseColorImage >= 0 ? textureOf[m.baseColorImage] : *whiteTex;
    VkDescriptorImageInfo ii{sampler, a->textures_[tex].view(), VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
    VkWriteDescriptorSet w{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstSet = g.descriptorSet;
    w.dstBinding = 0;
    w.descriptorCount = 1;
    w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
    w.pImageInfo = &ii;
    vkUpdateDescriptorSets(dev, 1, &w, 0, nullptr);
    a->materials_.push_back(g);
  }

  auto split = [&](const std::vector<avatar::Primitive>& prims, uint32_t indexBase, GpuDrawList& out) {
    for (const auto& p : prims) {
      if (p.indexCount == 0) continue;
      const uint32_t mat = p.material >= 0 ? uint32_t(p.material) : setCount - 1;
      const GpuDraw d{indexBase + p.firstIndex, p.indexCount, mat};
      switch (materials[mat].alphaMode) {
        case avatar::AlphaMode::Opaque: out.opaque.push_back(d); break;
        case avatar::AlphaMode::Mask: out.mask.push_back(d); break;
        case avatar::AlphaMode::Blend: out.blend.push_back(d); break;
      }
    }
  };
  split(mesh.primitives, 0, a->thirdPerson_);
  split(mesh.firstPersonPrimitives, static_cast<uint32_t>(mesh.indices.size()), a->firstPerson_);
  return a;
}

}  // namespace embody::engine
