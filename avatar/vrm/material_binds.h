#pragma once
// VRM expression material binds, evaluated per frame: VRM 1.0 `materialColorBinds` and
// `textureTransformBinds`, VRM 0.x `materialValues` (parsed in avatar/vrm/expressions.cpp).
// As three-vrm and UniVRM do, every bound value is its material's value plus the weighted
// differences towards each expression's target:
//
//   value = base + sum_e w_e (target_e - base)      (w_e: the expression's effective weight)
//
// so one expression at weight 1 reaches its target and two that move the same property add
// their deltas. Colours are clamped to >= 0 and alpha to [0, 1] afterwards (three-vrm does not
// clamp; a negative colour has no meaning to the shader).
#include <array>
#include <span>

#include "avatar/avatar_asset.h"

namespace embody::avatar {

// One bound material's expression-driven values in one frame.
struct MaterialBindState {
  // By MaterialColorType: baseColorFactor rgb, emissiveFactor (KHR_materials_emissive_strength
  // still multiplies it), MToon's shadeColorFactor, matcapFactor, parametricRimColorFactor,
  // outlineColorFactor.
  std::array<glm::vec3, kMaterialColorTypeCount> colors{};
  float alpha = 1.0f;  // baseColorFactor.a
  glm::vec3 color(MaterialColorType t) const { return colors[static_cast<size_t>(t)]; }
  // Texture transform binds, kept as sum w and sum w x target so that each texture of the
  // material (its own base transform) moves by w (target - its base):
  //   scale = (1 - uvWeight) base.scale + uvScale, offset likewise (rotation and set unchanged).
  float uvWeight = 0.0f;
  glm::vec2 uvScale{0.0f}, uvOffset{0.0f};
  // A texture's transform under these binds: every texture of the material but the matcap.
  TextureTransform transform(const TextureTransform& base) const;
};

// The values of `m` with no expression on.
MaterialBindState materialBindBase(const Material& m);

// Allocation-free: states[k] belongs to set->boundMaterials[k].
struct MaterialBindEvaluateJob {
  const ExpressionSet* set = nullptr;
  std::span<const Material> materials;      // the asset's
  std::span<const float> effectiveWeights;  // one per expression (ExpressionEvaluateJob's output)
  std::span<MaterialBindState> states;      // out: one per set->boundMaterials
  bool Validate() const;
  bool Run();
};

}  // namespace embody::avatar
