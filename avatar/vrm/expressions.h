#pragma once
// VRM expressions: VRM 1.0 `VRMC_vrm.expressions` (preset and custom) and VRM 0.x
// `VRM.blendShapeMaster.blendShapeGroups`, read into one ExpressionSet, and their evaluation:
// expression weights (0..1) -> override rules -> morph channel weights and material binds.
#include <array>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace embody::avatar {

// VRM 1.0 preset names (0.x names are translated: a->aa, joy->happy, blink_l->blinkLeft ...).
enum class ExpressionPreset {
  Happy, Angry, Sad, Relaxed, Surprised,
  Aa, Ih, Ou, Ee, Oh,
  Blink, BlinkLeft, BlinkRight,
  LookUp, LookDown, LookLeft, LookRight,
  Neutral, Custom
};
constexpr size_t kExpressionPresetCount = static_cast<size_t>(ExpressionPreset::Custom);
std::string_view expressionPresetName(ExpressionPreset p);  // "happy", ..., "custom"

enum class ExpressionOverride { None, Block, Blend };

struct MorphBind {
  uint32_t channel = 0;  // into SkinnedMesh::morphChannels
  float weight = 1.0f;   // 0..1 (VRM 0.x's 0..100 divided by 100)
};

// What a material colour bind moves: VRM 1.0 `materialColorBinds[].type`; VRM 0.x
// `materialValues[].propertyName` _Color, _EmissionColor, _ShadeColor, _RimColor, _OutlineColor
// (0.x has no matcap colour).
enum class MaterialColorType { Color, EmissionColor, ShadeColor, MatcapColor, RimColor, OutlineColor };
constexpr size_t kMaterialColorTypeCount = 6;
std::string_view materialColorTypeName(MaterialColorType t);  // "color", ..., "outlineColor"

// materialColorBinds (1.0) / materialValues (0.x): a material colour moved towards a target.
struct MaterialColorBind {
  int material = -1;  // into AvatarAsset::materials
  MaterialColorType type = MaterialColorType::Color;
  glm::vec4 target{0.0f};  // linear rgb (0.x values sRGB-decoded, as its base colours are); a: alpha, `color` only
};

// textureTransformBinds (1.0) / materialValues `_MainTex_ST` (0.x, converted from Unity's
// bottom-up v: offset.y = 1 - offset.y - scale.y): KHR_texture_transform scale and offset.
struct TextureTransformBind {
  int material = -1;
  glm::vec2 scale{1.0f}, offset{0.0f};
};

struct Expression {
  std::string name;
  ExpressionPreset preset = ExpressionPreset::Custom;
  bool isBinary = false;  // weights above 0.5 count as 1, the rest as 0
  ExpressionOverride overrideBlink = ExpressionOverride::None;
  ExpressionOverride overrideLookAt = ExpressionOverride::None;
  ExpressionOverride overrideMouth = ExpressionOverride::None;
  std::vector<MorphBind> morphBinds;
  std::vector<MaterialColorBind> colorBinds;
  std::vector<TextureTransformBind> textureTransformBinds;
};

struct ExpressionSet {
  std::vector<Expression> expressions;
  std::array<int, kExpressionPresetCount> byPreset{};  // preset -> expression index, -1 when absent
  // The materials some colour or texture-transform bind moves, ascending (MaterialBindEvaluateJob
  // writes one state per entry).
  std::vector<int> boundMaterials;
  ExpressionSet() { byPreset.fill(-1); }
  int find(ExpressionPreset p) const { return p == ExpressionPreset::Custom ? -1 : byPreset[static_cast<size_t>(p)]; }
  int find(std::string_view name) const;  // by expression name (custom) or preset name
  bool empty() const { return expressions.empty(); }
};

// One frame's evaluation, allocation-free once the output spans are sized:
//   1. binary expressions snap to 0/1;
//   2. override: every expression with weight w > 0 that blocks a category (blink, lookAt,
//      mouth) zeroes the presets of that category, one that blends scales them by (1 - w);
//   3. morph weight = the channel's glTF default + sum of w x bind weight, clamped to [0, 1].
// effectiveWeights (after steps 1 and 2) drive the material colour and texture transform binds
// (MaterialBindEvaluateJob, avatar/vrm/material_binds.h).
struct ExpressionEvaluateJob {
  const ExpressionSet* set = nullptr;
  std::span<const float> defaultMorphWeights;  // one per morph channel
  std::span<const float> weights;              // in: one per expression (0..1)
  std::span<float> effectiveWeights;           // out: one per expression, after binary and overrides
  std::span<float> morphWeights;               // out: one per morph channel
  bool Validate() const;
  bool Run();
};

}  // namespace embody::avatar
