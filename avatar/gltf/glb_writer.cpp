#include "avatar/gltf/glb_writer.h"

#include <stb_image_write.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <functional>
#include <set>
#include <type_traits>
#include <glm/gtc/type_ptr.hpp>
#include <nlohmann/json.hpp>

#include "avatar/gltf/component_type.h"

namespace embody::avatar {
namespace {

using nlohmann::json;

using gltf::kFloat, gltf::kUShort, gltf::kUInt;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

class BinBuilder {
 public:
  // Appends raw bytes as a new bufferView (4-byte aligned) and returns its index.
  int view(const void* data, size_t bytes, int target, json& doc) {
    while (bin_.size() % 4) bin_.push_back(0);
    const size_t at = bin_.size();
    bin_.resize(at + bytes);
    if (bytes) std::memcpy(bin_.data() + at, data, bytes);
    json v = {{"buffer", 0}, {"byteOffset", at}, {"byteLength", bytes}};
    if (target) v["target"] = target;
    doc["bufferViews"].push_back(v);
    return static_cast<int>(doc["bufferViews"].size() - 1);
  }
  std::vector<uint8_t>& bytes() { return bin_; }

 private:
  std::vector<uint8_t> bin_;
};

int accessor(json& doc, int view, size_t byteOffset, int componentType, size_t count, const char* type) {
  json a = {{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}};
  if (byteOffset) a["byteOffset"] = byteOffset;
  doc["accessors"].push_back(a);
  return static_cast<int>(doc["accessors"].size() - 1);
}

void appendU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void pngSink(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<uint8_t>*>(context);
  const auto* p = static_cast<const uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

// The animation's samplers and channels: times, then per joint a rotation track and, where the
// translation moves, a translation track.
Status addAnimation(const Skeleton& sk, const GlbAnimation& anim, BinBuilder& bin, json& doc) {
  const size_t frames = anim.frames.size(), n = sk.joints.size();
  if (frames == 0) return Error{"the animation has no frames"};
  if (!(anim.frameTime > 0.0)) return Error{"the animation's frame time must be positive"};
  for (const auto& f : anim.frames)
    if (f.local.size() != n) return Error{"an animation frame does not match the skeleton"};
  std::vector<float> times(frames);
  for (size_t f = 0; f < frames; ++f) times[f] = float(double(f) * anim.frameTime);
  const int input = accessor(doc, bin.view(times.data(), times.size() * 4, 0, doc), 0, kFloat, frames, "SCALAR");
  doc["accessors"][size_t(input)]["min"] = {times.front()};
  doc["accessors"][size_t(input)]["max"] = {times.back()};
  json samplers = json::array(), channels = json::array();
  auto track = [&](size_t joint, const char* path, std::vector<float>& values, const char* type) {
    const int out = accessor(doc, bin.view(values.data(), values.size() * 4, 0, doc), 0, kFloat, frames, type);
    samplers.push_back({{"input", input}, {"output", out}, {"interpolation", "LINEAR"}});
    channels.push_back({{"sampler", samplers.size() - 1}, {"target", {{"node", joint}, {"path", path}}}});
  };
  std::vector<float> values;
  for (size_t j = 0; j < n; ++j) {
    values.clear();
    glm::quat previous(1.0f, 0.0f, 0.0f, 0.0f);
    for (const auto& f : anim.frames) {
      glm::quat q = glm::normalize(f.local[j].rotation);
      if (glm::dot(q, previous) < 0.0f) q = -q;  // the short way round between samples
      previous = q;
      values.insert(values.end(), {q.x, q.y, q.z, q.w});
    }
    track(j, "rotation", values, "VEC4");
    bool moves = false;
    for (const auto& f : anim.frames) moves |= glm::length(f.local[j].translation - sk.joints[j].rest.translation) > 1e-6f;
    if (!moves) continue;
    values.clear();
    for (const auto& f : anim.frames) values.insert(values.end(), {f.local[j].translation.x, f.local[j].translation.y, f.local[j].translation.z});
    track(j, "translation", values, "VEC3");
  }
  doc["animations"] = json::array({{{"name", anim.name}, {"samplers", samplers}, {"channels", channels}}});
  return {};
}

// A textureInfo for `image` with its KHR_texture_transform (written when it is not the identity
// or reads TEXCOORD_1).
json textureInfo(int image, const TextureTransform& t, std::set<std::string>& extensionsUsed) {
  json info = {{"index", image}};
  if (t.texCoord != 0) info["texCoord"] = t.texCoord;
  if (!t.isIdentity()) {
    json tt = json::object();
    if (t.offset != glm::vec2(0.0f)) tt["offset"] = {t.offset.x, t.offset.y};
    if (t.rotation != 0.0f) tt["rotation"] = t.rotation;
    if (t.scale != glm::vec2(1.0f)) tt["scale"] = {t.scale.x, t.scale.y};
    info["extensions"]["KHR_texture_transform"] = tt;
    extensionsUsed.insert("KHR_texture_transform");
  }
  return info;
}

// VRMC_materials_mtoon (every property written; textures where the image exists).
json mtoonJson(const MToon& t, const std::function<bool(int)>& hasImage, std::set<std::string>& extensionsUsed) {
  auto rgb = [](glm::vec3 c) { return json::array({c.r, c.g, c.b}); };
  static const char* const kModes[] = {"none", "worldCoordinates", "screenCoordinates"};
  json e = {{"specVersion", "1.0"},
            {"transparentWithZWrite", t.transparentWithZWrite},
            {"renderQueueOffsetNumber", t.renderQueueOffset},
            {"shadeColorFactor", rgb(t.shadeColor)},
            {"shadingShiftFactor", t.shadingShift},
            {"shadingToonyFactor", t.shadingToony},
            {"giEqualizationFactor", t.giEqualization},
            {"matcapFactor", rgb(t.matcapFactor)},
            {"parametricRimColorFactor", rgb(t.rimColor)},
            {"parametricRimFresnelPowerFactor", t.rimFresnelPower},
            {"parametricRimLiftFactor", t.rimLift},
            {"rimLightingMixFactor", t.rimLightingMix},
            {"outlineWidthMode", kModes[static_cast<int>(t.outlineMode)]},
            {"outlineWidthFactor", t.outlineWidth},
            {"outlineColorFactor", rgb(t.outlineColor)},
            {"outlineLightingMixFactor", t.outlineLightingMix},
            {"uvAnimationScrollXSpeedFactor", t.uvAnimationScroll.x},
            {"uvAnimationScrollYSpeedFactor", t.uvAnimationScroll.y},
            {"uvAnimationRotationSpeedFactor", t.uvAnimationRotation}};
  if (hasImage(t.shadeImage)) e["shadeMultiplyTexture"] = textureInfo(t.shadeImage, t.shadeTransform, extensionsUsed);
  if (hasImage(t.shadingShiftImage)) {
    e["shadingShiftTexture"] = textureInfo(t.shadingShiftImage, t.shadingShiftTransform, extensionsUsed);
    e["shadingShiftTexture"]["scale"] = t.shadingShiftScale;
  }
  if (hasImage(t.matcapImage)) e["matcapTexture"] = textureInfo(t.matcapImage, {}, extensionsUsed);
  if (hasImage(t.rimImage)) e["rimMultiplyTexture"] = textureInfo(t.rimImage, t.rimTransform, extensionsUsed);
  if (hasImage(t.outlineWidthImage))
    e["outlineWidthMultiplyTexture"] = textureInfo(t.outlineWidthImage, t.outlineWidthTransform, extensionsUsed);
  if (hasImage(t.uvAnimationMaskImage))
    e["uvAnimationMaskTexture"] = textureInfo(t.uvAnimationMaskImage, t.uvAnimationMaskTransform, extensionsUsed);
  extensionsUsed.insert("VRMC_materials_mtoon");
  return e;
}

json materialJson(const Material& m, const AvatarAsset& asset, std::set<std::string>& extensionsUsed) {
  auto hasImage = [&](int image) { return image >= 0 && static_cast<size_t>(image) < asset.images.size(); };
  json pbr = {{"baseColorFactor", {m.baseColorFactor.r, m.baseColorFactor.g, m.baseColorFactor.b, m.baseColorFactor.a}},
              {"metallicFactor", 0.0},
              {"roughnessFactor", 0.8}};
  if (hasImage(m.baseColorImage))
    pbr["baseColorTexture"] = textureInfo(m.baseColorImage, m.baseColorTransform, extensionsUsed);
  json mat = {{"name", m.name.empty() ? std::string("material") : m.name}, {"pbrMetallicRoughness", pbr}};
  if (m.emissiveFactor != glm::vec3(0.0f)) {
    mat["emissiveFactor"] = {m.emissiveFactor.r, m.emissiveFactor.g, m.emissiveFactor.b};
    if (hasImage(m.emissiveImage))
      mat["emissiveTexture"] = textureInfo(m.emissiveImage, m.emissiveTransform, extensionsUsed);
    if (m.emissiveStrength != 1.0f) {
      mat["extensions"]["KHR_materials_emissive_strength"] = {{"emissiveStrength", m.emissiveStrength}};
      extensionsUsed.insert("KHR_materials_emissive_strength");
    }
  }
  if (m.unlit) {
    mat["extensions"]["KHR_materials_unlit"] = json::object();
    extensionsUsed.insert("KHR_materials_unlit");
  }
  if (m.alphaMode == AlphaMode::Mask) {
    mat["alphaMode"] = "MASK";
    mat["alphaCutoff"] = m.alphaCutoff;
  } else if (m.alphaMode == AlphaMode::Blend) {
    mat["alphaMode"] = "BLEND";
  }
  if (m.doubleSided) mat["doubleSided"] = true;
  if (m.isMToon) mat["extensions"]["VRMC_materials_mtoon"] = mtoonJson(m.mtoon, hasImage, extensionsUsed);
  return mat;
}

// Why the skeleton cannot be written as one glTF skin, or "".
std::string skinProblem(const AvatarAsset& asset) {
  const Skeleton& sk = asset.skeleton;
  const size_t n = sk.joints.size();
  if (n == 0) return "cannot write a glTF without joints";
  if (auto why = sk.validate(); !why.empty()) return why;
  if (asset.mesh.inverseBind.size() != n) return "inverseBind must have one matrix per joint";
  if (n > 65535) return "too many joints for unsigned-short JOINTS";
  return "";
}

// One node per joint (rest TRS), children linked.
void addJointNodes(const Skeleton& sk, json& doc) {
  for (const Joint& j : sk.joints) {
    json node = {{"name", j.name}};
    if (j.rest.translation != glm::vec3(0.0f))
      node["translation"] = {j.rest.translation.x, j.rest.translation.y, j.rest.translation.z};
    if (j.rest.rotation != glm::quat(1.0f, 0.0f, 0.0f, 0.0f))
      node["rotation"] = {j.rest.rotation.x, j.rest.rotation.y, j.rest.rotation.z, j.rest.rotation.w};
    if (j.rest.scale != glm::vec3(1.0f)) node["scale"] = {j.rest.scale.x, j.rest.scale.y, j.rest.scale.z};
    doc["nodes"].push_back(node);
  }
  for (size_t i = 0; i < sk.joints.size(); ++i)
    if (sk.joints[i].parent >= 0) doc["nodes"][static_cast<size_t>(sk.joints[i].parent)]["children"].push_back(i);
}

// The mesh's vertex streams (one tightly packed bufferView each) as a primitive's "attributes".
json vertexAttributes(const AvatarAsset& asset, BinBuilder& bin, json& doc) {
  const SkinnedMesh& mesh = asset.mesh;
  const size_t vc = mesh.vertices.size();
  std::vector<float> positions, normals, uvs, uvs1, weights0, weights1;
  std::vector<uint16_t> joints0, joints1;
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  bool eight = false;
  for (const auto& v : mesh.vertices) eight |= v.weights1 != glm::vec4(0.0f);
  bool secondUv = false;  // TEXCOORD_1 is written when a material reads it or a vertex sets it
  for (const auto& v : mesh.vertices) secondUv |= v.uv1 != glm::vec2(0.0f);
  for (const auto& m : asset.materials)
    secondUv |= m.baseColorTransform.texCoord == 1 || m.emissiveTransform.texCoord == 1 ||
                (m.isMToon && (m.mtoon.shadeTransform.texCoord == 1 || m.mtoon.shadingShiftTransform.texCoord == 1 ||
                               m.mtoon.rimTransform.texCoord == 1 || m.mtoon.outlineWidthTransform.texCoord == 1 ||
                               m.mtoon.uvAnimationMaskTransform.texCoord == 1));
  for (const auto& v : mesh.vertices) {
    positions.insert(positions.end(), {v.position.x, v.position.y, v.position.z});
    lo = glm::min(lo, v.position);
    hi = glm::max(hi, v.position);
    const glm::vec3 nn = glm::length(v.normal) > 0.0f ? glm::normalize(v.normal) : glm::vec3(0, 1, 0);
    normals.insert(normals.end(), {nn.x, nn.y, nn.z});
    uvs.insert(uvs.end(), {v.uv.x, v.uv.y});
    if (secondUv) uvs1.insert(uvs1.end(), {v.uv1.x, v.uv1.y});
    for (int k = 0; k < 4; ++k) {
      // Unused influences are (joint 0, weight 0), as the specification asks.
      joints0.push_back(static_cast<uint16_t>(v.weights0[k] > 0.0f ? v.joints0[k] : 0u));
      weights0.push_back(v.weights0[k]);
      if (eight) {
        joints1.push_back(static_cast<uint16_t>(v.weights1[k] > 0.0f ? v.joints1[k] : 0u));
        weights1.push_back(v.weights1[k]);
      }
    }
  }
  json attributes;
  if (vc == 0) return attributes;
  auto stream = [&](const auto& values, int componentType, const char* type) {
    using T = typename std::decay_t<decltype(values)>::value_type;
    return accessor(doc, bin.view(values.data(), values.size() * sizeof(T), kArrayBuffer, doc), 0, componentType,
                    vc, type);
  };
  const int a = stream(positions, kFloat, "VEC3");
  doc["accessors"][static_cast<size_t>(a)]["min"] = {lo.x, lo.y, lo.z};
  doc["accessors"][static_cast<size_t>(a)]["max"] = {hi.x, hi.y, hi.z};
  attributes["POSITION"] = a;
  attributes["NORMAL"] = stream(normals, kFloat, "VEC3");
  attributes["TEXCOORD_0"] = stream(uvs, kFloat, "VEC2");
  if (secondUv) attributes["TEXCOORD_1"] = stream(uvs1, kFloat, "VEC2");
  attributes["JOINTS_0"] = stream(joints0, kUShort, "VEC4");
  attributes["WEIGHTS_0"] = stream(weights0, kFloat, "VEC4");
  if (eight) {
    attributes["JOINTS_1"] = stream(joints1, kUShort, "VEC4");
    attributes["WEIGHTS_1"] = stream(weights1, kFloat, "VEC4");
  }
  return attributes;
}

// Morph targets: one dense POSITION + NORMAL accessor pair per channel over the whole vertex
// array, shared by every primitive (they share the vertex attributes too).
json morphTargets(const SkinnedMesh& mesh, BinBuilder& bin, json& doc) {
  json targets = json::array();
  const size_t vc = mesh.vertices.size();
  if (vc == 0) return targets;
  for (size_t c = 0; c < mesh.morphChannels.size(); ++c) {
    std::vector<float> dp(vc * 3, 0.0f), dn(vc * 3, 0.0f);
    for (const MorphDelta& d : mesh.morphDeltas) {
      if (d.channel != c || d.vertex >= vc) continue;
      for (int k = 0; k < 3; ++k) dp[d.vertex * 3 + k] = d.position[k], dn[d.vertex * 3 + k] = d.normal[k];
    }
    glm::vec3 tlo(std::numeric_limits<float>::max()), thi(-std::numeric_limits<float>::max());
    for (size_t i = 0; i < vc; ++i) {
      tlo = glm::min(tlo, glm::vec3(dp[i * 3], dp[i * 3 + 1], dp[i * 3 + 2]));
      thi = glm::max(thi, glm::vec3(dp[i * 3], dp[i * 3 + 1], dp[i * 3 + 2]));
    }
    const int ap = accessor(doc, bin.view(dp.data(), dp.size() * 4, kArrayBuffer, doc), 0, kFloat, vc, "VEC3");
    doc["accessors"][static_cast<size_t>(ap)]["min"] = {tlo.x, tlo.y, tlo.z};
    doc["accessors"][static_cast<size_t>(ap)]["max"] = {thi.x, thi.y, thi.z};
    const int an = accessor(doc, bin.view(dn.data(), dn.size() * 4, kArrayBuffer, doc), 0, kFloat, vc, "VEC3");
    targets.push_back({{"POSITION", ap}, {"NORMAL", an}});
  }
  return targets;
}

// The mesh's primitives over one shared index bufferView.
Result<json> meshPrimitives(const AvatarAsset& asset, const json& attributes, const json& targets, BinBuilder& bin,
                            json& doc) {
  const SkinnedMesh& mesh = asset.mesh;
  const int indexView = bin.view(mesh.indices.data(), mesh.indices.size() * 4, kElementArrayBuffer, doc);
  json primitives = json::array();
  for (const Primitive& p : mesh.primitives) {
    if (p.indexCount == 0) continue;
    if (static_cast<size_t>(p.firstIndex) + p.indexCount > mesh.indices.size())
      return Error{"primitive runs past the index buffer"};
    json prim = {
        {"attributes", attributes},
        {"indices", accessor(doc, indexView, size_t{p.firstIndex} * 4, kUInt, p.indexCount, "SCALAR")},
        {"mode", 4}};
    if (p.material >= 0 && static_cast<size_t>(p.material) < asset.materials.size())
      prim["material"] = p.material;
    if (!targets.empty()) prim["targets"] = targets;
    primitives.push_back(prim);
  }
  return primitives;
}

// Images as PNG (one texture each), then the materials, then the caller's top-level extensions.
Status addImagesAndMaterials(const AvatarAsset& asset, std::string_view extensionsJson, BinBuilder& bin, json& doc) {
  for (size_t i = 0; i < asset.images.size(); ++i) {
    const Image& im = asset.images[i];
    std::vector<uint8_t> png;
    if (im.width > 0 && im.height > 0 && im.rgba.size() == size_t(im.width) * size_t(im.height) * 4)
      stbi_write_png_to_func(pngSink, &png, im.width, im.height, 4, im.rgba.data(), im.width * 4);
    if (png.empty()) {  // keep indices stable: a 1x1 white pixel stands in
      const uint8_t white[4] = {255, 255, 255, 255};
      stbi_write_png_to_func(pngSink, &png, 1, 1, 4, white, 4);
    }
    doc["images"].push_back(
        {{"bufferView", bin.view(png.data(), png.size(), 0, doc)}, {"mimeType", "image/png"}});
    doc["textures"].push_back({{"source", i}});
  }
  std::set<std::string> extensionsUsed;
  for (const Material& m : asset.materials) doc["materials"].push_back(materialJson(m, asset, extensionsUsed));
  if (!extensionsJson.empty()) {
    const json ext = json::parse(extensionsJson, nullptr, false);
    if (!ext.is_object()) return Error{"extensionsJson is not a JSON object"};
    for (const auto& [name, value] : ext.items()) {
      doc["extensions"][name] = value;
      extensionsUsed.insert(name);
    }
  }
  if (!extensionsUsed.empty()) doc["extensionsUsed"] = extensionsUsed;
  return {};
}

// The mesh's default morph weights and target names (extras.targetNames, as exporters write them).
void addMorphWeights(const SkinnedMesh& mesh, json& meshJson) {
  json weights = json::array(), names = json::array();
  for (const MorphChannel& c : mesh.morphChannels) {
    weights.push_back(c.defaultWeight);
    names.push_back(c.name.empty() ? "target" + std::to_string(names.size()) : c.name);
  }
  meshJson["weights"] = weights;
  meshJson["extras"] = {{"targetNames", names}};
}

// The GLB container: header, JSON chunk (space-padded), BIN chunk (zero-padded).
Result<std::vector<uint8_t>> glbContainer(json& doc, BinBuilder& bin) {
  while (bin.bytes().size() % 4) bin.bytes().push_back(0);
  doc["buffers"] = json::array({{{"byteLength", bin.bytes().size()}}});
  std::string text = doc.dump();
  while (text.size() % 4) text.push_back(' ');
  const uint64_t total = 12 + 8 + text.size() + 8 + bin.bytes().size();
  if (total > 0xFFFFFFFFull) return Error{"GLB larger than 4 GiB"};
  std::vector<uint8_t> out;
  out.reserve(total);
  for (char c : std::string("glTF")) out.push_back(static_cast<uint8_t>(c));
  appendU32(out, 2);
  appendU32(out, static_cast<uint32_t>(total));
  appendU32(out, static_cast<uint32_t>(text.size()));
  appendU32(out, 0x4E4F534Au);  // "JSON"
  for (char c : text) out.push_back(static_cast<uint8_t>(c));
  appendU32(out, static_cast<uint32_t>(bin.bytes().size()));
  appendU32(out, 0x004E4942u);  // "BIN\0"
  for (uint8_t b : bin.bytes()) out.push_back(b);
  return out;
}

}  // namespace

Result<std::vector<uint8_t>> encodeGlb(const AvatarAsset& asset, const GlbAnimation* animation,
                                       std::string_view extensionsJson) {
  if (auto why = skinProblem(asset); !why.empty()) return Error{why};
  const Skeleton& sk = asset.skeleton;
  const size_t n = sk.joints.size();
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "Embody"}}},
              {"scene", 0},
              {"nodes", json::array()},
              {"bufferViews", json::array()},
              {"accessors", json::array()}};
  BinBuilder bin;
  addJointNodes(sk, doc);
  const json attributes = vertexAttributes(asset, bin, doc);
  const json targets = morphTargets(asset.mesh, bin, doc);
  auto primitives = meshPrimitives(asset, attributes, targets, bin, doc);
  if (!primitives) return Error{primitives.error()};

  std::vector<float> ibm;
  for (const auto& m : asset.mesh.inverseBind) ibm.insert(ibm.end(), glm::value_ptr(m), glm::value_ptr(m) + 16);
  const int ibmAccessor = accessor(doc, bin.view(ibm.data(), ibm.size() * 4, 0, doc), 0, kFloat, n, "MAT4");
  json skinJoints = json::array();
  for (size_t i = 0; i < n; ++i) skinJoints.push_back(i);
  // The skin's joints need one common root node. A skeleton with several root joints (a loaded
  // file whose mesh node stood beside its armature at the scene root: the tool's own
  // `avatar export-default` output) gets a plain node above them, after the joint and mesh nodes so
  // that joint i stays node i (the animation's channels target those).
  std::vector<size_t> roots;
  for (size_t i = 0; i < n; ++i)
    if (sk.joints[i].parent < 0) roots.push_back(i);
  const size_t root = roots.size() > 1 ? n + (primitives->empty() ? 0 : 1) : roots.front();
  if (auto s = addImagesAndMaterials(asset, extensionsJson, bin, doc); !s) return Error{s.error()};

  json sceneNodes = json::array({root});
  if (!primitives->empty()) {
    doc["meshes"] = json::array({{{"name", "body"}, {"primitives", *primitives}}});
    if (!targets.empty()) addMorphWeights(asset.mesh, doc["meshes"][0]);
    doc["skins"] =
        json::array({{{"inverseBindMatrices", ibmAccessor}, {"joints", skinJoints}, {"skeleton", root}}});
    doc["nodes"].push_back({{"name", "body"}, {"mesh", 0}, {"skin", 0}});
    sceneNodes.push_back(n);
  }
  if (roots.size() > 1) doc["nodes"].push_back({{"name", "skeleton"}, {"children", roots}});
  doc["scenes"] = json::array({{{"nodes", sceneNodes}}});
  if (animation)
    if (auto s = addAnimation(sk, *animation, bin, doc); !s) return Error{s.error()};
  return glbContainer(doc, bin);
}

Status writeGlbFile(const AvatarAsset& asset, const std::string& path, const GlbAnimation* animation,
                    std::string_view extensionsJson) {
  auto bytes = encodeGlb(asset, animation, extensionsJson);
  if (!bytes.ok()) return Error{bytes.error()};
  std::ofstream f(path, std::ios::binary);
  if (!f) return Error{"cannot write '" + path + "'"};
  f.write(reinterpret_cast<const char*>(bytes->data()), static_cast<std::streamsize>(bytes->size()));
  if (!f) return Error{"cannot write '" + path + "'"};
  return {};
}

}  // namespace embody::avatar
