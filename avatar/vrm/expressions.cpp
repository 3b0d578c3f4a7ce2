// Parsing and evaluating VRM expressions (1.0) and blend shape groups (0.x).
#include "avatar/vrm/vrm_parsers.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "avatar/avatar_asset.h"
#include "avatar/gltf/mtoon_json.h"

namespace embody::avatar {

namespace {

using vrm::Json;
using vrm::member;

constexpr std::array<std::string_view, kExpressionPresetCount + 1> kPresetNames = {
    "happy",  "angry",     "sad",        "relaxed", "surprised", "aa",       "ih",        "ou",       "ee",  "oh",
    "blink",  "blinkLeft", "blinkRight", "lookUp",  "lookDown",  "lookLeft", "lookRight", "neutral", "custom"};

ExpressionPreset presetFromVrm1(std::string_view name) {
  for (size_t i = 0; i < kExpressionPresetCount; ++i)
    if (kPresetNames[i] == name) return static_cast<ExpressionPreset>(i);
  return ExpressionPreset::Custom;
}

ExpressionPreset presetFromVrm0(std::string name) {
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  static const std::pair<const char*, ExpressionPreset> table[] = {
      {"joy", ExpressionPreset::Happy},          {"angry", ExpressionPreset::Angry},
      {"sorrow", ExpressionPreset::Sad},         {"fun", ExpressionPreset::Relaxed},
      {"a", ExpressionPreset::Aa},               {"i", ExpressionPreset::Ih},
      {"u", ExpressionPreset::Ou},               {"e", ExpressionPreset::Ee},
      {"o", ExpressionPreset::Oh},               {"blink", ExpressionPreset::Blink},
      {"blink_l", ExpressionPreset::BlinkLeft},  {"blink_r", ExpressionPreset::BlinkRight},
      {"lookup", ExpressionPreset::LookUp},      {"lookdown", ExpressionPreset::LookDown},
      {"lookleft", ExpressionPreset::LookLeft},  {"lookright", ExpressionPreset::LookRight},
      {"neutral", ExpressionPreset::Neutral},    {"surprised", ExpressionPreset::Surprised}};
  for (const auto& [n, p] : table)
    if (name == n) return p;
  return ExpressionPreset::Custom;
}

constexpr std::array<std::string_view, kMaterialColorTypeCount> kColorTypeNames = {"color",      "emissionColor", "shadeColor",
                                                             "matcapColor", "rimColor",      "outlineColor"};

std::optional<MaterialColorType> colorTypeFromVrm1(std::string_view name) {
  for (size_t i = 0; i < kColorTypeNames.size(); ++i)
    if (kColorTypeNames[i] == name) return static_cast<MaterialColorType>(i);
  return std::nullopt;
}

// 0.x property names (three-vrm's v0ExpressionMaterialColorMap; 0.x has no matcap colour).
std::optional<MaterialColorType> colorTypeFromVrm0(std::string_view name) {
  using T = MaterialColorType;
  static const std::pair<const char*, T> table[] = {{"_Color", T::Color},           {"_EmissionColor", T::EmissionColor},
                                                    {"_ShadeColor", T::ShadeColor}, {"_RimColor", T::RimColor},
                                                    {"_OutlineColor", T::OutlineColor}};
  for (const auto& [n, t] : table)
    if (name == n) return t;
  return std::nullopt;
}

// An array of minCount..maxCount finite numbers, or none.
std::optional<std::vector<float>> finiteNumbers(const Json& v, size_t minCount, size_t maxCount) {
  if (!v.is_array() || v.size() < minCount || v.size() > maxCount) return std::nullopt;
  std::vector<float> out;
  for (const Json& x : v) {
    if (!x.is_number() || !std::isfinite(x.get<double>()) || std::abs(x.get<double>()) > 1e6) return std::nullopt;
    out.push_back(x.get<float>());
  }
  return out;
}

// One 0.x materialValue: a colour property (sRGB-decoded like the 0.x base colours; alpha linear)
// or `_MainTex_ST` (Unity's [scale.x, scale.y, offset.x, offset.y], v from the bottom). Other
// properties (floats such as _OutlineWidth) are not supported: dropped with a warning.
void readVrm0MaterialValue(const Json& mv, const Json& materials, size_t materialCount, const std::string& what,
                           Expression& e, std::vector<std::string>& w) {
  const std::string mname = vrm::stringOr(member(mv, "materialName"), "");
  const std::string prop = vrm::stringOr(member(mv, "propertyName"), "");
  int material = -1;
  for (size_t m = 0; m < std::min(materials.size(), materialCount) && material < 0; ++m)
    if (vrm::stringOr(member(materials[m], "name"), "") == mname) material = static_cast<int>(m);
  const auto v = finiteNumbers(member(mv, "targetValue"), 4, 4);
  const auto type = colorTypeFromVrm0(prop);
  if (material < 0 || !v || (!type && prop != "_MainTex_ST")) {
    w.push_back(what + ": materialValue '" + prop.substr(0, 30) + "' of '" + mname.substr(0, 40) +
                "' names no material, has no 4 finite numbers or is not a supported property; dropped");
    return;
  }
  if (type) {
    glm::vec4 c((*v)[0], (*v)[1], (*v)[2], (*v)[3]);
    for (int k = 0; k < 3; ++k) c[k] = srgbToLinear(std::max(c[k], 0.0f));
    e.colorBinds.push_back({material, *type, c});
    return;
  }
  TextureTransformBind t;
  t.material = material;
  t.scale = {(*v)[0], (*v)[1]};
  t.offset = {(*v)[2], 1.0f - (*v)[3] - (*v)[1]};
  e.textureTransformBinds.push_back(t);
}

ExpressionOverride overrideOf(const Json& v, const std::string& what, std::vector<std::string>& w) {
  if (v.is_null()) return ExpressionOverride::None;
  const std::string s = vrm::stringOr(v, "?");
  if (s == "none") return ExpressionOverride::None;
  if (s == "block") return ExpressionOverride::Block;
  if (s == "blend") return ExpressionOverride::Blend;
  w.push_back(what + ": '" + s.substr(0, 20) + "' is not none/block/blend; none used");
  return ExpressionOverride::None;
}

// The morph channel of (node, target) for VRM 1.0, (mesh, target) for 0.x (every node using it).
void addMorphBinds(const AvatarAsset& asset, int node, int mesh, int target, float weight, Expression& e) {
  const auto& ch = asset.mesh.morphChannels;
  for (size_t c = 0; c < ch.size(); ++c)
    if (ch[c].targetIndex == target && (node >= 0 ? ch[c].sourceNode == node : ch[c].sourceMesh == mesh))
      e.morphBinds.push_back({static_cast<uint32_t>(c), weight});
}

Expression readVrm1(const Json& x, const std::string& name, ExpressionPreset preset, const AvatarAsset& asset,
                    size_t materialCount, std::vector<std::string>& w) {
  const std::string what = "expression '" + name + "'";
  Expression e;
  e.name = name;
  e.preset = preset;
  e.isBinary = member(x, "isBinary").is_boolean() && member(x, "isBinary").get<bool>();
  e.overrideBlink = overrideOf(member(x, "overrideBlink"), what + " overrideBlink", w);
  e.overrideLookAt = overrideOf(member(x, "overrideLookAt"), what + " overrideLookAt", w);
  e.overrideMouth = overrideOf(member(x, "overrideMouth"), what + " overrideMouth", w);
  for (const Json& b : vrm::arrayOf(member(x, "morphTargetBinds"))) {
    const int node = vrm::indexBelow(member(b, "node"), asset.gltfNodeToJoint.size(), what + " morph bind node", w);
    const int index = vrm::indexBelow(member(b, "index"), 1u << 16, what + " morph bind index", w);
    const float weight = vrm::numberIn(member(b, "weight"), 0.0f, 0.0f, 1.0f, what + " morph bind weight", w);
    const size_t before = e.morphBinds.size();
    if (node >= 0 && index >= 0) addMorphBinds(asset, node, -1, index, weight, e);
    if (e.morphBinds.size() == before) w.push_back(what + ": a morph bind names no morph target of the file; dropped");
  }
  for (const Json& b : vrm::arrayOf(member(x, "materialColorBinds"))) {
    MaterialColorBind c;
    c.material = vrm::indexBelow(member(b, "material"), materialCount, what + " material", w);
    const std::string type = vrm::stringOr(member(b, "type"), "?");
    const auto t = colorTypeFromVrm1(type);
    const auto v = finiteNumbers(member(b, "targetValue"), 3, 4);
    if (c.material < 0 || !t || !v) {
      w.push_back(what + ": a materialColorBind (type '" + type.substr(0, 20) +
                  "') lacks a material, a known type or a targetValue of 3-4 finite numbers; dropped");
      continue;
    }
    c.type = *t;
    c.target = glm::vec4((*v)[0], (*v)[1], (*v)[2], v->size() > 3 ? (*v)[3] : 1.0f);
    e.colorBinds.push_back(c);
  }
  for (const Json& b : vrm::arrayOf(member(x, "textureTransformBinds"))) {
    TextureTransformBind t;
    t.material = vrm::indexBelow(member(b, "material"), materialCount, what + " material", w);
    const Json& sc = member(b, "scale");
    const Json& of = member(b, "offset");
    const auto scale = finiteNumbers(sc, 2, 2), offset = finiteNumbers(of, 2, 2);
    if (t.material < 0 || (!sc.is_null() && !scale) || (!of.is_null() && !offset)) {
      w.push_back(what + ": a textureTransformBind lacks a material or has a scale/offset that is not 2 finite numbers; dropped");
      continue;
    }
    if (scale) t.scale = {(*scale)[0], (*scale)[1]};
    if (offset) t.offset = {(*offset)[0], (*offset)[1]};
    e.textureTransformBinds.push_back(t);
  }
  return e;
}

void parseVrm1(const Json& ex, const AvatarAsset& asset, size_t materialCount, ExpressionSet& set,
               std::vector<std::string>& w) {
  const Json& preset = member(ex, "preset");
  if (preset.is_object())
    for (const auto& [name, x] : preset.items()) {
      const ExpressionPreset p = presetFromVrm1(name);
      if (p == ExpressionPreset::Custom)
        w.push_back("expression preset '" + name.substr(0, 40) + "' is not a VRM 1.0 preset; read as custom");
      set.expressions.push_back(readVrm1(x, name, p, asset, materialCount, w));
    }
  const Json& custom = member(ex, "custom");
  if (custom.is_object())
    for (const auto& [name, x] : custom.items())
      set.expressions.push_back(readVrm1(x, name, ExpressionPreset::Custom, asset, materialCount, w));
}

void parseVrm0(const Json& master, const Json& doc, const AvatarAsset& asset, ExpressionSet& set,
               std::vector<std::string>& w) {
  const Json& materials = vrm::arrayOf(member(doc, "materials"));
  const size_t meshCount = vrm::arrayOf(member(doc, "meshes")).size();
  size_t gi = 0;
  for (const Json& g : vrm::arrayOf(member(master, "blendShapeGroups"))) {
    const std::string what = "blendShapeGroup " + std::to_string(gi++);
    Expression e;
    e.name = vrm::stringOr(member(g, "name"), what);
    e.preset = presetFromVrm0(vrm::stringOr(member(g, "presetName"), "unknown"));
    e.isBinary = member(g, "isBinary").is_boolean() && member(g, "isBinary").get<bool>();
    for (const Json& b : vrm::arrayOf(member(g, "binds"))) {
      const int mesh = vrm::indexBelow(member(b, "mesh"), meshCount, what + " bind mesh", w);
      const int index = vrm::indexBelow(member(b, "index"), 1u << 16, what + " bind index", w);
      const float weight = vrm::numberIn(member(b, "weight"), 100.0f, 0.0f, 100.0f, what + " bind weight", w) / 100.0f;
      const size_t before = e.morphBinds.size();
      if (mesh >= 0 && index >= 0) addMorphBinds(asset, -1, mesh, index, weight, e);
      if (e.morphBinds.size() == before) w.push_back(what + ": a bind names no morph target of the file; dropped");
    }
    for (const Json& mv : vrm::arrayOf(member(g, "materialValues"))) readVrm0MaterialValue(mv, materials, asset.materials.size(), what, e, w);
    // 0.x has no override flags: every override stays none.
    set.expressions.push_back(std::move(e));
  }
}

bool inCategory(ExpressionPreset p, int category) {  // 0 blink, 1 lookAt, 2 mouth
  using P = ExpressionPreset;
  switch (category) {
    case 0: return p == P::Blink || p == P::BlinkLeft || p == P::BlinkRight;
    case 1: return p == P::LookUp || p == P::LookDown || p == P::LookLeft || p == P::LookRight;
    default: return p == P::Aa || p == P::Ih || p == P::Ou || p == P::Ee || p == P::Oh;
  }
}

}  // namespace

std::string_view expressionPresetName(ExpressionPreset p) { return kPresetNames[static_cast<size_t>(p)]; }

std::string_view materialColorTypeName(MaterialColorType t) { return kColorTypeNames[static_cast<size_t>(t)]; }

int ExpressionSet::find(std::string_view name) const {
  for (size_t i = 0; i < expressions.size(); ++i)
    if (expressions[i].name == name) return static_cast<int>(i);
  for (size_t i = 0; i < kExpressionPresetCount; ++i)
    if (kPresetNames[i] == name) return byPreset[i];
  return -1;
}

ExpressionSet parseExpressions(const Json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings) {
  ExpressionSet set;
  const Json& ext = member(doc, "extensions");
  const size_t materialCount = asset.materials.size();
  if (const Json& ex = member(member(ext, "VRMC_vrm"), "expressions"); ex.is_object())
    parseVrm1(ex, asset, materialCount, set, warnings);
  else if (const Json& master = member(member(ext, "VRM"), "blendShapeMaster"); master.is_object())
    parseVrm0(master, doc, asset, set, warnings);
  for (const Expression& e : set.expressions) {
    for (const MaterialColorBind& c : e.colorBinds) set.boundMaterials.push_back(c.material);
    for (const TextureTransformBind& t : e.textureTransformBinds) set.boundMaterials.push_back(t.material);
  }
  std::sort(set.boundMaterials.begin(), set.boundMaterials.end());
  set.boundMaterials.erase(std::unique(set.boundMaterials.begin(), set.boundMaterials.end()), set.boundMaterials.end());
  for (size_t i = 0; i < set.expressions.size(); ++i) {
    const ExpressionPreset p = set.expressions[i].preset;
    if (p != ExpressionPreset::Custom && set.byPreset[static_cast<size_t>(p)] < 0)
      set.byPreset[static_cast<size_t>(p)] = static_cast<int>(i);
  }
  return set;
}

bool ExpressionEvaluateJob::Validate() const {
  if (!set) return false;
  const size_t n = set->expressions.size(), c = defaultMorphWeights.size();
  if (weights.size() != n || effectiveWeights.size() != n || morphWeights.size() != c) return false;
  for (const Expression& e : set->expressions)
    for (const MorphBind& b : e.morphBinds)
      if (b.channel >= c) return false;
  return true;
}

bool ExpressionEvaluateJob::Run() {
  if (!Validate()) return false;
  const auto& ex = set->expressions;
  for (size_t i = 0; i < ex.size(); ++i) {
    float w = std::isfinite(weights[i]) ? std::clamp(weights[i], 0.0f, 1.0f) : 0.0f;
    if (ex[i].isBinary) w = w > 0.5f ? 1.0f : 0.0f;
    effectiveWeights[i] = w;
  }
  // Overrides: how much of each category the other expressions leave.
  float keep[3] = {1.0f, 1.0f, 1.0f};
  for (size_t i = 0; i < ex.size(); ++i) {
    const float w = effectiveWeights[i];
    if (w <= 0.0f) continue;
    const ExpressionOverride o[3] = {ex[i].overrideBlink, ex[i].overrideLookAt, ex[i].overrideMouth};
    for (int c = 0; c < 3; ++c) {
      if (inCategory(ex[i].preset, c)) continue;  // a blink does not block blinking
      if (o[c] == ExpressionOverride::Block) keep[c] = 0.0f;
      if (o[c] == ExpressionOverride::Blend) keep[c] *= 1.0f - w;
    }
  }
  for (size_t i = 0; i < ex.size(); ++i)
    for (int c = 0; c < 3; ++c)
      if (inCategory(ex[i].preset, c)) effectiveWeights[i] *= keep[c];
  std::copy(defaultMorphWeights.begin(), defaultMorphWeights.end(), morphWeights.begin());
  for (size_t i = 0; i < ex.size(); ++i) {
    if (effectiveWeights[i] <= 0.0f) continue;
    for (const MorphBind& b : ex[i].morphBinds) morphWeights[b.channel] += effectiveWeights[i] * b.weight;
  }
  for (float& m : morphWeights) m = std::clamp(m, 0.0f, 1.0f);
  return true;
}

}  // namespace embody::avatar
