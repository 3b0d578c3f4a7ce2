#include "tests/support/mtoon_test_avatar.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/procedural/default_avatar.h"

namespace embody::test {

namespace {

using nlohmann::json;
using avatar::HumanBone;

uint32_t readU32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }
void appendU32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// A lit sphere's white highlight towards the upper left on black, sRGB-encoded (64 x 64).
avatar::Image matcapImage() {
  avatar::Image img{64, 64, std::vector<uint8_t>(64 * 64 * 4, 0)};
  const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.6f, 0.7f));
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      const float u = (float(x) + 0.5f) / 32.0f - 1.0f, v = 1.0f - (float(y) + 0.5f) / 32.0f;  // v up
      const float r2 = u * u + v * v;
      const float shine = r2 < 1.0f ? std::pow(std::max(glm::dot(glm::vec3(u, v, std::sqrt(1.0f - r2)), light), 0.0f), 6.0f) : 0.0f;
      uint8_t* px = &img.rgba[size_t(y * 64 + x) * 4];
      px[0] = px[1] = px[2] = uint8_t(std::lround(255.0f * std::pow(shine, 1.0f / 2.2f)));
      px[3] = 255;
    }
  return img;
}

// Joints whose skin counts as "skin": the neck (with the head) and the hands, and their descendants.
std::vector<bool> skinJoints(const avatar::AvatarAsset& a) {
  std::vector<bool> skin(a.skeleton.joints.size(), false);
  for (HumanBone b : {HumanBone::neck, HumanBone::head, HumanBone::leftHand, HumanBone::rightHand})
    if (a.humanoid.has(b)) skin[size_t(a.humanoid.joint(b))] = true;
  for (size_t j = 0; j < skin.size(); ++j)  // parents come before children
    if (const int p = a.skeleton.joints[j].parent; p >= 0 && skin[size_t(p)]) skin[j] = true;
  return skin;
}

avatar::Material clothMaterial() {
  avatar::Material m;
  m.name = "cloth";
  m.baseColorFactor = glm::vec4(0.10f, 0.20f, 0.55f, 1.0f);
  m.isMToon = true;
  auto& t = m.mtoon;
  t.shadeColor = glm::vec3(0.02f, 0.04f, 0.16f);
  t.shadingShift = -0.1f;
  t.shadingToony = 0.9f;
  t.rimColor = glm::vec3(1.0f, 0.55f, 0.2f);
  t.rimFresnelPower = 3.0f;
  t.rimLift = 0.1f;
  t.rimLightingMix = 0.3f;
  t.outlineMode = avatar::OutlineWidthMode::WorldCoordinates;
  t.outlineWidth = 0.012f;
  t.outlineColor = glm::vec3(0.02f, 0.02f, 0.06f);
  t.outlineLightingMix = 0.0f;
  return m;
}

avatar::Material skinMaterial(int matcap) {
  avatar::Material m;
  m.name = "skin";
  m.baseColorFactor = glm::vec4(0.95f, 0.72f, 0.60f, 1.0f);
  m.isMToon = true;
  auto& t = m.mtoon;
  t.shadeColor = glm::vec3(0.75f, 0.40f, 0.38f);
  t.shadingToony = 0.95f;
  t.matcapImage = matcap;
  t.matcapFactor = glm::vec3(0.3f);
  t.outlineMode = avatar::OutlineWidthMode::ScreenCoordinates;
  t.outlineWidth = 0.006f;
  t.outlineColor = glm::vec3(0.30f, 0.10f, 0.08f);
  t.outlineLightingMix = 1.0f;
  return m;
}

json vrm1Extension(const avatar::AvatarAsset& a) {
  json bones = json::object();
  for (int b = 0; b < avatar::kHumanBoneCount; ++b)
    if (a.humanoid.bones[size_t(b)] >= 0)
      bones[std::string(avatar::humanBoneName(HumanBone(b)))] = {{"node", a.humanoid.bones[size_t(b)]}};
  return {{"specVersion", "1.0"},
          {"meta",
           {{"name", "Embody MToon test mannequin"},
            {"version", "1"},
            {"authors", {"Embody tests"}},
            {"licenseUrl", "https://vrm.dev/licenses/1.0/"},
            {"avatarPermission", "everyone"},
            {"commercialUsage", "corporation"}}},
          {"humanoid", {{"humanBones", bones}}}};
}

json vrm0Extension(const avatar::AvatarAsset& a) {
  json bones = json::array();
  for (int b = 0; b < avatar::kHumanBoneCount; ++b)
    if (a.humanoid.bones[size_t(b)] >= 0)
      bones.push_back({{"bone", std::string(avatar::humanBoneName(HumanBone(b)))}, {"node", a.humanoid.bones[size_t(b)]}});
  return {{"exporterVersion", "Embody tests"},
          {"specVersion", "0.0"},
          {"meta", {{"title", "Embody MToon 0.x test mannequin"}, {"version", "1"}, {"author", "Embody tests"},
                    {"allowedUserName", "Everyone"}, {"licenseName", "CC0"}}},
          {"humanoid", {{"humanBones", bones}}},
          {"firstPerson", {{"firstPersonBone", a.humanoid.joint(HumanBone::head)}, {"meshAnnotations", json::array()}}},
          {"materialProperties", mtoonVrm0MaterialProperties()}};
}

void addExtension(json& doc, const char* name, json extension) {
  doc["extensionsUsed"].push_back(name);
  doc["extensions"][name] = std::move(extension);
}

}  // namespace

avatar::AvatarAsset mtoonMannequin() {
  avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  auto& mesh = a.mesh;
  const std::vector<bool> skin = skinJoints(a);
  // Triangles mostly weighted to skin joints form the second primitive.
  std::vector<uint32_t> cloth, skinTris;
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    float weight = 0.0f;
    for (size_t k = 0; k < 3; ++k) {
      const auto& v = mesh.vertices[mesh.indices[t + k]];
      for (int i = 0; i < 4; ++i) weight += skin[v.joints0[i]] ? v.weights0[i] : 0.0f;
      for (int i = 0; i < 4; ++i) weight += skin[v.joints1[i]] ? v.weights1[i] : 0.0f;
    }
    auto& out = weight > 1.5f ? skinTris : cloth;
    out.insert(out.end(), mesh.indices.begin() + long(t), mesh.indices.begin() + long(t) + 3);
  }
  mesh.indices = cloth;
  mesh.indices.insert(mesh.indices.end(), skinTris.begin(), skinTris.end());
  mesh.primitives = {{0, uint32_t(cloth.size()), 0}, {uint32_t(cloth.size()), uint32_t(skinTris.size()), 1}};
  a.images = {matcapImage()};
  a.materials = {clothMaterial(), skinMaterial(0)};
  if (auto s = avatar::prepareAvatar(a, ""); !s.ok()) a.humanoid = {};  // cannot fail without a bone map
  return a;
}

Result<std::vector<uint8_t>> editGlbJson(const std::vector<uint8_t>& glb, const std::function<void(json&)>& edit) {
  if (glb.size() < 20 || readU32(glb.data()) != 0x46546C67u) return Error{"not a GLB"};
  const uint32_t jsonLength = readU32(glb.data() + 12);
  if (20 + size_t(jsonLength) > glb.size()) return Error{"truncated GLB"};
  json doc = json::parse(glb.begin() + 20, glb.begin() + 20 + jsonLength, nullptr, false);
  if (doc.is_discarded()) return Error{"GLB JSON does not parse"};
  edit(doc);
  std::string text = doc.dump();
  while (text.size() % 4) text.push_back(' ');
  const std::vector<uint8_t> rest(glb.begin() + 20 + jsonLength, glb.end());  // the BIN chunk, as is
  std::vector<uint8_t> out;
  for (char c : std::string("glTF")) out.push_back(uint8_t(c));
  appendU32(out, 2);
  appendU32(out, uint32_t(12 + 8 + text.size() + rest.size()));
  appendU32(out, uint32_t(text.size()));
  appendU32(out, 0x4E4F534Au);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  out.insert(out.end(), rest.begin(), rest.end());
  return out;
}

Result<std::vector<uint8_t>> mtoonVrm1File() {
  const avatar::AvatarAsset a = mtoonMannequin();
  auto glb = avatar::encodeGlb(a);
  if (!glb.ok()) return Error{glb.error()};
  return editGlbJson(*glb, [&](json& doc) { addExtension(doc, "VRMC_vrm", vrm1Extension(a)); });
}

Result<std::vector<uint8_t>> mtoonVrm0File() {
  avatar::AvatarAsset a = mtoonMannequin();
  for (auto& m : a.materials) {  // the glTF fallback UniVRM writes: unlit, lit colour
    m.isMToon = false;
    m.unlit = true;
  }
  auto glb = avatar::encodeGlb(a);
  if (!glb.ok()) return Error{glb.error()};
  return editGlbJson(*glb, [&](json& doc) { addExtension(doc, "VRM", vrm0Extension(a)); });
}

json mtoonVrm0MaterialProperties() {
  // Unity colours, gamma-encoded as VRM 0.x stores them.
  auto srgb = [](float r, float g, float b, float alpha = 1.0f) {
    auto enc = [](float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; };
    return json::array({enc(r), enc(g), enc(b), alpha});
  };
  json cloth = {{"name", "cloth"},
                {"shader", "VRM/MToon"},
                {"renderQueue", 2000},
                {"floatProperties",
                 {{"_BlendMode", 0}, {"_CullMode", 2}, {"_ZWrite", 1}, {"_ShadeShift", -0.2}, {"_ShadeToony", 0.8},
                  {"_IndirectLightIntensity", 0.1}, {"_RimFresnelPower", 3.0}, {"_RimLift", 0.1},
                  {"_RimLightingMix", 0.3}, {"_OutlineWidthMode", 1}, {"_OutlineWidth", 1.2},
                  {"_OutlineColorMode", 1}, {"_OutlineLightingMix", 0.5}}},
                {"vectorProperties",
                 {{"_Color", srgb(0.50f, 0.08f, 0.06f)}, {"_ShadeColor", srgb(0.14f, 0.02f, 0.04f)},
                  {"_RimColor", srgb(1.0f, 0.85f, 0.3f)}, {"_OutlineColor", srgb(0.05f, 0.01f, 0.01f)},
                  {"_EmissionColor", srgb(0.0f, 0.0f, 0.0f)}, {"_MainTex", {0, 0, 1, 1}}}},
                {"textureProperties", json::object()},
                {"keywordMap", {{"MTOON_OUTLINE_WIDTH_WORLD", true}, {"MTOON_OUTLINE_COLOR_MIXED", true}}},
                {"tagMap", {{"RenderType", "Opaque"}}}};
  json skin = {{"name", "skin"},
               {"shader", "VRM/MToon"},
               {"renderQueue", 2000},
               {"floatProperties",
                {{"_BlendMode", 0}, {"_CullMode", 2}, {"_ZWrite", 1}, {"_ShadeShift", 0.0}, {"_ShadeToony", 0.9},
                 {"_IndirectLightIntensity", 0.1}, {"_RimFresnelPower", 1.0}, {"_RimLift", 0.0}, {"_RimLightingMix", 0.0},
                 {"_OutlineWidthMode", 2}, {"_OutlineWidth", 1.2}, {"_OutlineColorMode", 0}}},
               {"vectorProperties",
                {{"_Color", srgb(0.95f, 0.72f, 0.60f)}, {"_ShadeColor", srgb(0.75f, 0.40f, 0.38f)},
                 {"_RimColor", srgb(0.0f, 0.0f, 0.0f)}, {"_OutlineColor", srgb(0.30f, 0.10f, 0.08f)},
                 {"_MainTex", {0, 0, 1, 1}}}},
               {"textureProperties", {{"_SphereAdd", 0}}},
               {"keywordMap", {{"MTOON_OUTLINE_WIDTH_SCREEN", true}}},
               {"tagMap", {{"RenderType", "Opaque"}}}};
  return json::array({cloth, skin});
}

}  // namespace embody::test
