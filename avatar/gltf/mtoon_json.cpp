// VRMC_materials_mtoon (VRM 1.0) and VRM 0.x MToon materialProperties -> avatar::MToon.
#include "avatar/gltf/mtoon_json.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

namespace embody::avatar {

float srgbToLinear(float c) {
  return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

namespace {

using nlohmann::json;
constexpr float kInf = std::numeric_limits<float>::infinity();

const json* member(const json& object, const char* key) {
  if (!object.is_object()) return nullptr;
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

// Reads one material's properties; everything it cannot use becomes a warning and a default.
class PropertyReader {
 public:
  PropertyReader(const json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings, std::string where)
      : doc_(doc), asset_(asset), warnings_(warnings), where_(std::move(where)) {}

  void warn(const std::string& key, const std::string& why) const { warnings_.push_back(where_ + key + ": " + why); }

  // A finite number in [lo, hi]: missing gives `def`; wrong type or non-finite warns and gives
  // `def`; out of range warns and is clamped.
  float number(const json& object, const char* key, float def, float lo = -kInf, float hi = kInf) const {
    const json* v = member(object, key);
    if (!v) return def;
    if (!v->is_number() || !std::isfinite(v->get<double>())) {
      warn(key, "not a finite number; " + std::to_string(def) + " used");
      return def;
    }
    const double x = v->get<double>();
    if (x < lo || x > hi) {
      const float c = float(std::clamp(x, double(lo), double(hi)));
      warn(key, std::to_string(x) + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]; " +
                    std::to_string(c) + " used");
      return c;
    }
    return float(x);
  }

  bool boolean(const json& object, const char* key, bool def) const {
    const json* v = member(object, key);
    if (!v) return def;
    if (!v->is_boolean()) {
      warn(key, std::string("not a boolean; ") + (def ? "true" : "false") + " used");
      return def;
    }
    return v->get<bool>();
  }

  // The first three numbers of an array (VRM 0.x vectors have four) clamped to [0, 1]; sRGB-decoded
  // when `srgb`.
  glm::vec3 color(const json& object, const char* key, glm::vec3 def, bool srgb = false) const {
    const json* v = member(object, key);
    if (!v) return def;
    if (!v->is_array() || v->size() < 3 ||
        !std::all_of(v->begin(), v->begin() + 3, [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()); })) {
      warn(key, "not an array of 3 finite numbers; default used");
      return def;
    }
    glm::vec3 c;
    bool clamped = false;
    for (int i = 0; i < 3; ++i) {
      const double x = (*v)[size_t(i)].get<double>();
      clamped |= x < 0.0 || x > 1.0;
      c[i] = float(std::clamp(x, 0.0, 1.0));
      if (srgb) c[i] = srgbToLinear(c[i]);
    }
    if (clamped) warn(key, "components outside [0, 1] clamped");
    return c;
  }

  // A glTF texture index -> the index of its decoded image, or -1 (with a warning when broken).
  int imageOfTexture(const json& index, const std::string& key) const {
    if (!index.is_number_integer()) {
      warn(key, "texture index is not an integer; untextured");
      return -1;
    }
    const int64_t t = index.get<int64_t>();
    const json* textures = member(doc_, "textures");
    const json* source = textures && textures->is_array() && t >= 0 && uint64_t(t) < textures->size()
                             ? member((*textures)[size_t(t)], "source")
                             : nullptr;
    if (!source || !source->is_number_integer() || source->get<int64_t>() < 0 ||
        uint64_t(source->get<int64_t>()) >= asset_.images.size()) {
      warn(key, "texture " + std::to_string(t) + " or its image is out of range; untextured");
      return -1;
    }
    const int image = int(source->get<int64_t>());
    return asset_.images[size_t(image)].rgba.empty() ? -1 : image;  // undecodable: the loader warned
  }

  // A VRM 1.0 textureInfo ({index, texCoord, extensions.KHR_texture_transform}) -> image.
  int texture(const json& object, const char* key, TextureTransform& t) const {
    t = {};
    const json* info = member(object, key);
    if (!info) return -1;
    const json* index = member(*info, "index");
    if (!index) {
      warn(key, "textureInfo without an index; untextured");
      return -1;
    }
    float texCoord = number(*info, "texCoord", 0.0f, 0.0f, 65535.0f);
    const json* extensions = member(*info, "extensions");
    if (const json* tt = extensions ? member(*extensions, "KHR_texture_transform") : nullptr) {
      t.offset = vec2(*tt, "offset", glm::vec2(0.0f));
      t.scale = vec2(*tt, "scale", glm::vec2(1.0f));
      t.rotation = number(*tt, "rotation", 0.0f);
      texCoord = number(*tt, "texCoord", texCoord, 0.0f, 65535.0f);
    }
    t.texCoord = int(texCoord);
    if (t.texCoord > 1) {  // as for glTF textures (gltf_loader.cpp)
      warn(key, "TEXCOORD_" + std::to_string(t.texCoord) + " is not read; TEXCOORD_0 used");
      t.texCoord = 0;
    }
    return imageOfTexture(*index, key);
  }

  glm::vec2 vec2(const json& object, const char* key, glm::vec2 def) const {
    const json* v = member(object, key);
    if (!v) return def;
    if (!v->is_array() || v->size() != 2 ||
        !std::all_of(v->begin(), v->end(), [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()); })) {
      warn(key, "not an array of 2 finite numbers; default used");
      return def;
    }
    return {float((*v)[0].get<double>()), float((*v)[1].get<double>())};
  }

 private:
  const json& doc_;
  const AvatarAsset& asset_;
  std::vector<std::string>& warnings_;
  std::string where_;
};

OutlineWidthMode outlineMode(const json& ext, const PropertyReader& r) {
  const json* v = member(ext, "outlineWidthMode");
  if (!v) return OutlineWidthMode::None;
  if (v->is_string()) {
    const auto s = v->get<std::string>();
    if (s == "none") return OutlineWidthMode::None;
    if (s == "worldCoordinates") return OutlineWidthMode::WorldCoordinates;
    if (s == "screenCoordinates") return OutlineWidthMode::ScreenCoordinates;
  }
  r.warn("outlineWidthMode", "not one of none, worldCoordinates, screenCoordinates; no outline");
  return OutlineWidthMode::None;
}

// renderQueueOffsetNumber's range depends on the alpha mode (specification, Render Queue).
int clampQueueOffset(float offset, const Material& m, const PropertyReader& r) {
  const int lo = m.alphaMode == AlphaMode::Blend && !m.mtoon.transparentWithZWrite ? -9 : 0;
  const int hi = m.alphaMode == AlphaMode::Blend && m.mtoon.transparentWithZWrite ? 9 : 0;
  const int n = int(std::lround(offset));
  if (n < lo || n > hi)
    r.warn("renderQueueOffsetNumber", std::to_string(n) + " is outside [" + std::to_string(lo) + ", " +
                                          std::to_string(hi) + "] for this alpha mode; clamped");
  return std::clamp(n, lo, hi);
}

// UV animation speeds are clamped to this (UV or radians per second; 0.x: turns per second).
constexpr float kMaxUvSpeed = 1000.0f;

void readMToon1(const json& ext, Material& mat, const PropertyReader& r) {
  if (!ext.is_object()) {
    r.warn("", "not an object; drawn as its glTF material");
    return;
  }
  MToon& t = mat.mtoon;
  mat.isMToon = true;
  mat.unlit = false;  // MToon takes precedence over KHR_materials_unlit
  if (const json* v = member(ext, "specVersion"); !v || !v->is_string())
    r.warn("specVersion", "missing or not a string (required); read as 1.0");
  t.transparentWithZWrite = r.boolean(ext, "transparentWithZWrite", false);
  t.renderQueueOffset = clampQueueOffset(r.number(ext, "renderQueueOffsetNumber", 0.0f), mat, r);
  t.shadeColor = r.color(ext, "shadeColorFactor", glm::vec3(0.0f));
  t.shadeImage = r.texture(ext, "shadeMultiplyTexture", t.shadeTransform);
  t.shadingShift = r.number(ext, "shadingShiftFactor", 0.0f);
  t.shadingShiftImage = r.texture(ext, "shadingShiftTexture", t.shadingShiftTransform);
  if (const json* info = member(ext, "shadingShiftTexture")) t.shadingShiftScale = r.number(*info, "scale", 1.0f);
  t.shadingToony = r.number(ext, "shadingToonyFactor", 0.9f, 0.0f, 1.0f);
  t.giEqualization = r.number(ext, "giEqualizationFactor", 0.9f, 0.0f, 1.0f);
  t.matcapFactor = r.color(ext, "matcapFactor", glm::vec3(1.0f));
  TextureTransform matcapTransform;  // the matcap is addressed by the normal, not by a texture coordinate
  t.matcapImage = r.texture(ext, "matcapTexture", matcapTransform);
  t.rimColor = r.color(ext, "parametricRimColorFactor", glm::vec3(0.0f));
  t.rimFresnelPower = r.number(ext, "parametricRimFresnelPowerFactor", 5.0f, 0.0f, 100.0f);
  t.rimLift = r.number(ext, "parametricRimLiftFactor", 0.0f);
  t.rimImage = r.texture(ext, "rimMultiplyTexture", t.rimTransform);
  t.rimLightingMix = r.number(ext, "rimLightingMixFactor", 1.0f, 0.0f, 1.0f);
  t.outlineMode = outlineMode(ext, r);
  t.outlineWidth = r.number(ext, "outlineWidthFactor", 0.0f, 0.0f, 1.0f);
  t.outlineWidthImage = r.texture(ext, "outlineWidthMultiplyTexture", t.outlineWidthTransform);
  t.outlineColor = r.color(ext, "outlineColorFactor", glm::vec3(0.0f));
  t.outlineLightingMix = r.number(ext, "outlineLightingMixFactor", 1.0f, 0.0f, 1.0f);
  t.uvAnimationMaskImage = r.texture(ext, "uvAnimationMaskTexture", t.uvAnimationMaskTransform);
  t.uvAnimationScroll = {r.number(ext, "uvAnimationScrollXSpeedFactor", 0.0f, -kMaxUvSpeed, kMaxUvSpeed),
                         r.number(ext, "uvAnimationScrollYSpeedFactor", 0.0f, -kMaxUvSpeed, kMaxUvSpeed)};
  t.uvAnimationRotation = r.number(ext, "uvAnimationRotationSpeedFactor", 0.0f, -kMaxUvSpeed, kMaxUvSpeed);
}

// VRM 0.x: render queues of transparent materials become 1.0 offsets in the same order (as
// three-vrm does): with z-write 0, 1, 2 ... up to +9; without, ... -2, -1, 0 down to -9.
struct QueueMap {
  std::vector<int> zwrite, plain;  // sorted distinct renderQueue values
  int offset(int queue, bool withZWrite) const {
    const auto& v = withZWrite ? zwrite : plain;
    const int i = int(std::lower_bound(v.begin(), v.end(), queue) - v.begin());
    return withZWrite ? std::min(i, 9) : std::max(i - int(v.size()) + 1, -9);
  }
};

// What a VRM 0.x material's shader and properties say about blending.
struct Vrm0Blend {
  AlphaMode mode = AlphaMode::Opaque;
  bool zwrite = false;
  bool known = false;  // the shader is one we read
};

Vrm0Blend vrm0Blend(const json& props) {
  const json* shader = member(props, "shader");
  const std::string name = shader && shader->is_string() ? shader->get<std::string>() : "";
  Vrm0Blend b;
  if (name == "VRM/MToon") {
    b.known = true;
    const json* floats = member(props, "floatProperties");
    const json* mode = floats ? member(*floats, "_BlendMode") : nullptr;
    const double m = mode && mode->is_number() ? mode->get<double>() : 0.0;
    const json* zwrite = floats ? member(*floats, "_ZWrite") : nullptr;
    b.mode = m == 1.0 ? AlphaMode::Mask : (m == 2.0 || m == 3.0) ? AlphaMode::Blend : AlphaMode::Opaque;
    b.zwrite = b.mode == AlphaMode::Blend && (m == 3.0 || (zwrite && zwrite->is_number() && zwrite->get<double>() == 1.0));
  } else if (name.rfind("VRM/Unlit", 0) == 0) {
    b.known = true;
    b.mode = name == "VRM/UnlitCutout" ? AlphaMode::Mask
             : (name == "VRM/UnlitTransparent" || name == "VRM/UnlitTransparentZWrite") ? AlphaMode::Blend
                                                                                         : AlphaMode::Opaque;
    b.zwrite = name == "VRM/UnlitTransparentZWrite";
  }
  return b;
}

QueueMap vrm0QueueMap(const json& list) {
  std::set<int> zwrite, plain;
  for (const json& props : list) {
    const Vrm0Blend b = vrm0Blend(props);
    const json* q = member(props, "renderQueue");
    if (b.mode != AlphaMode::Blend || !q || !q->is_number_integer()) continue;
    (b.zwrite ? zwrite : plain).insert(int(std::clamp<int64_t>(q->get<int64_t>(), -100000, 100000)));
  }
  return {{zwrite.begin(), zwrite.end()}, {plain.begin(), plain.end()}};
}

// The shared texture transform of a VRM 0.x material (Unity's _MainTex_ST: offset and scale,
// with v measured from the bottom).
TextureTransform vrm0Transform(const json& vectors, const PropertyReader& r) {
  TextureTransform t;
  const json* st = member(vectors, "_MainTex");
  if (!st) return t;
  if (!st->is_array() || st->size() < 4 ||
      !std::all_of(st->begin(), st->begin() + 4, [](const json& x) { return x.is_number() && std::isfinite(x.get<double>()); })) {
    r.warn("_MainTex", "texture offset/scale is not 4 finite numbers; ignored");
    return t;
  }
  t.scale = {float((*st)[2].get<double>()), float((*st)[3].get<double>())};
  t.offset = {float((*st)[0].get<double>()), 1.0f - t.scale.y - float((*st)[1].get<double>())};
  return t;
}

// A VRM 0.x property group ("floatProperties", ...): an object, else empty (with a warning when
// present but of another type).
const json& group(const json& props, const char* key, const PropertyReader& r, bool warn = true) {
  static const json empty = json::object();
  const json* g = member(props, key);
  if (g && g->is_object()) return *g;
  if (g && warn) r.warn(key, "not an object; its properties take their defaults");
  return empty;
}

void readVrm0Common(const json& props, Material& mat, const PropertyReader& r, const Vrm0Blend& blend,
                    const TextureTransform& st) {
  const json& f = group(props, "floatProperties", r, false);  // readMToon0 warns once
  const json& v = group(props, "vectorProperties", r, false);
  const json& tex = group(props, "textureProperties", r, false);
  mat.alphaMode = blend.mode;
  if (blend.mode == AlphaMode::Mask) mat.alphaCutoff = r.number(f, "_Cutoff", 0.5f, 0.0f, 1.0f);
  if (member(v, "_Color")) {
    const glm::vec3 c = r.color(v, "_Color", glm::vec3(1.0f), true);
    const json& a = (*member(v, "_Color"));
    const float alpha = a.is_array() && a.size() >= 4 && a[3].is_number() && std::isfinite(a[3].get<double>())
                            ? float(std::clamp(a[3].get<double>(), 0.0, 1.0))
                            : 1.0f;
    mat.baseColorFactor = glm::vec4(c, alpha);
  }
  if (const json* t = member(tex, "_MainTex")) {
    mat.baseColorImage = r.imageOfTexture(*t, "_MainTex");
    mat.baseColorTransform = st;
  }
}

void readMToon0(const json& props, Material& mat, const PropertyReader& r, const Vrm0Blend& blend, const QueueMap& queues) {
  const json& f = group(props, "floatProperties", r);
  const json& v = group(props, "vectorProperties", r);
  const json& tex = group(props, "textureProperties", r);
  const TextureTransform st = vrm0Transform(v, r);
  readVrm0Common(props, mat, r, blend, st);
  mat.isMToon = true;
  mat.unlit = false;
  MToon& t = mat.mtoon;
  auto image = [&](const char* key, TextureTransform* transform) {
    const json* index = member(tex, key);
    if (!index) return -1;
    if (transform) *transform = st;
    return r.imageOfTexture(*index, key);
  };
  if (member(f, "_CullMode")) {
    const float cull = r.number(f, "_CullMode", 2.0f, 0.0f, 2.0f);
    if (cull == 1.0f) r.warn("_CullMode", "front-face culling is not supported; back faces culled");
    mat.doubleSided = cull == 0.0f;
  }
  t.transparentWithZWrite = blend.zwrite;
  if (blend.mode == AlphaMode::Blend) {
    const json* q = member(props, "renderQueue");
    if (q && q->is_number_integer()) t.renderQueueOffset = queues.offset(int(std::clamp<int64_t>(q->get<int64_t>(), -100000, 100000)), blend.zwrite);
  }
  t.shadeColor = r.color(v, "_ShadeColor", glm::vec3(srgbToLinear(0.97f), srgbToLinear(0.81f), srgbToLinear(0.86f)), true);
  t.shadeImage = image("_ShadeTexture", &t.shadeTransform);
  // UniVRM's MToon10Migrator: 0.x maps d = dot(N, L) through linearstep(shift, lerp(1, shift, toony), d);
  // 1.0 through linearstep(-1 + toony' - shift', 1 - toony' - shift', d). Equal when shift' is
  // minus the range's centre and toony' one minus its half width (exact until the clamps).
  const float toony0 = r.number(f, "_ShadeToony", 0.9f, 0.0f, 1.0f), shift0 = r.number(f, "_ShadeShift", 0.0f, -1.0f, 1.0f);
  const float lo = shift0, hi = 1.0f + (shift0 - 1.0f) * toony0;
  t.shadingToony = std::clamp((2.0f - (hi - lo)) * 0.5f, 0.0f, 1.0f);
  t.shadingShift = std::clamp(-(hi + lo) * 0.5f, -1.0f, 1.0f);
  t.giEqualization = std::clamp(1.0f - r.number(f, "_IndirectLightIntensity", 0.1f, 0.0f, 1.0f), 0.0f, 1.0f);
  t.matcapImage = image("_SphereAdd", nullptr);
  t.matcapFactor = glm::vec3(1.0f);
  t.rimColor = r.color(v, "_RimColor", glm::vec3(0.0f), true);
  t.rimFresnelPower = r.number(f, "_RimFresnelPower", 1.0f, 0.0f, 100.0f);
  t.rimLift = r.number(f, "_RimLift", 0.0f, 0.0f, 1.0f);
  t.rimLightingMix = r.number(f, "_RimLightingMix", 0.0f, 0.0f, 1.0f);
  t.rimImage = image("_RimTexture", &t.rimTransform);
  mat.emissiveFactor = r.color(v, "_EmissionColor", glm::vec3(0.0f), true);
  mat.emissiveImage = image("_EmissionMap", &mat.emissiveTransform);
  const float mode = r.number(f, "_OutlineWidthMode", 0.0f, 0.0f, 2.0f);
  t.outlineMode = mode == 1.0f ? OutlineWidthMode::WorldCoordinates
                  : mode == 2.0f ? OutlineWidthMode::ScreenCoordinates
                                 : OutlineWidthMode::None;
  // 0.x widths are centimetres in world mode; in screen mode 0.01 * width is an NDC offset, i.e.
  // half of that as a share of the screen height.
  const float width = r.number(f, "_OutlineWidth", 0.0f, 0.0f, 100.0f);
  t.outlineWidth = width * (t.outlineMode == OutlineWidthMode::ScreenCoordinates ? 0.005f : 0.01f);
  t.outlineWidthImage = image("_OutlineWidthTexture", &t.outlineWidthTransform);
  t.outlineColor = r.color(v, "_OutlineColor", glm::vec3(0.0f), true);
  const bool mixed = r.number(f, "_OutlineColorMode", 0.0f, 0.0f, 1.0f) == 1.0f;
  t.outlineLightingMix = mixed ? r.number(f, "_OutlineLightingMix", 1.0f, 0.0f, 1.0f) : 0.0f;
  // 0.x's shader works in Unity's bottom-up v: its scroll y is negated; its rotation (turns per
  // second, counter-clockwise there) is the same turn in glTF's top-down v with the 1.0 matrix.
  t.uvAnimationVrm0 = true;
  t.uvAnimationMaskImage = image("_UvAnimMaskTexture", &t.uvAnimationMaskTransform);
  t.uvAnimationScroll = {r.number(f, "_UvAnimScrollX", 0.0f, -kMaxUvSpeed, kMaxUvSpeed),
                         -r.number(f, "_UvAnimScrollY", 0.0f, -kMaxUvSpeed, kMaxUvSpeed)};
  t.uvAnimationRotation = 2.0f * glm::pi<float>() * r.number(f, "_UvAnimRotation", 0.0f, -kMaxUvSpeed, kMaxUvSpeed);
}

void readVrm0Materials(const json& doc, const json& list, AvatarAsset& asset, std::vector<std::string>& warnings) {
  if (!list.is_array()) {
    warnings.push_back("VRM.materialProperties: not an array; materials drawn as glTF");
    return;
  }
  const QueueMap queues = vrm0QueueMap(list);
  for (size_t i = 0; i < list.size(); ++i) {
    const json& props = list[i];
    const std::string where = "VRM.materialProperties[" + std::to_string(i) + "].";
    if (i >= asset.materials.size()) {
      warnings.push_back(where + " has no glTF material " + std::to_string(i) + "; ignored");
      continue;
    }
    const PropertyReader r(doc, asset, warnings, where);
    const Vrm0Blend blend = vrm0Blend(props);
    const json* shader = member(props, "shader");
    const std::string name = shader && shader->is_string() ? shader->get<std::string>() : "";
    Material& mat = asset.materials[i];
    if (name == "VRM/MToon") {
      readMToon0(props, mat, r, blend, queues);
    } else if (blend.known) {  // VRM/Unlit*: unlit base colour
      readVrm0Common(props, mat, r, blend, vrm0Transform(group(props, "vectorProperties", r), r));
      mat.unlit = true;
    } else if (name != "VRM_USE_GLTFSHADER") {
      r.warn("shader", "'" + name + "' is not read; drawn as its glTF material");
    }
  }
}

}  // namespace

void readMToonMaterials(AvatarAsset& asset, std::vector<std::string>& warnings) {
  if (asset.rawJson.empty()) return;
  const json doc = json::parse(asset.rawJson, nullptr, false);
  if (!doc.is_object()) return;  // the loader has parsed it; a fuzzed document may not be JSON
  if (const json* materials = member(doc, "materials"); materials && materials->is_array()) {
    for (size_t i = 0; i < materials->size() && i < asset.materials.size(); ++i) {
      const json* ext = member((*materials)[i], "extensions");
      const json* mtoon = ext ? member(*ext, "VRMC_materials_mtoon") : nullptr;
      if (!mtoon) continue;
      const PropertyReader r(doc, asset, warnings, "material " + std::to_string(i) + " VRMC_materials_mtoon.");
      readMToon1(*mtoon, asset.materials[i], r);
    }
  }
  const json* ext = member(doc, "extensions");
  const json* vrm0 = ext ? member(*ext, "VRM") : nullptr;
  if (const json* props = vrm0 ? member(*vrm0, "materialProperties") : nullptr)
    readVrm0Materials(doc, *props, asset, warnings);
}

}  // namespace embody::avatar
