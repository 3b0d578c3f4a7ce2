// Expression material colour and texture-transform binds: base + sum of weighted deltas.
#include "avatar/vrm/material_binds.h"

#include <algorithm>
#include <cmath>

namespace embody::avatar {

namespace {

// The bound-material slot of a material index (set->boundMaterials is ascending).
size_t slotOf(const ExpressionSet& set, int material) {
  return static_cast<size_t>(std::lower_bound(set.boundMaterials.begin(), set.boundMaterials.end(), material) -
                             set.boundMaterials.begin());
}

}  // namespace

TextureTransform MaterialBindState::transform(const TextureTransform& base) const {
  TextureTransform t = base;
  t.scale = (1.0f - uvWeight) * base.scale + uvScale;
  t.offset = (1.0f - uvWeight) * base.offset + uvOffset;
  return t;
}

MaterialBindState materialBindBase(const Material& m) {
  MaterialBindState s;
  s.colors = {glm::vec3(m.baseColorFactor), m.emissiveFactor,    m.mtoon.shadeColor,
              m.mtoon.matcapFactor,         m.mtoon.rimColor,    m.mtoon.outlineColor};
  s.alpha = m.baseColorFactor.a;
  return s;
}

bool MaterialBindEvaluateJob::Validate() const {
  if (!set || effectiveWeights.size() != set->expressions.size() || states.size() != set->boundMaterials.size())
    return false;
  for (int m : set->boundMaterials)
    if (m < 0 || static_cast<size_t>(m) >= materials.size()) return false;
  for (const Expression& e : set->expressions) {
    for (const MaterialColorBind& c : e.colorBinds)
      if (!std::binary_search(set->boundMaterials.begin(), set->boundMaterials.end(), c.material)) return false;
    for (const TextureTransformBind& t : e.textureTransformBinds)
      if (!std::binary_search(set->boundMaterials.begin(), set->boundMaterials.end(), t.material)) return false;
  }
  return true;
}

bool MaterialBindEvaluateJob::Run() {
  if (!Validate()) return false;
  for (size_t k = 0; k < states.size(); ++k)
    states[k] = materialBindBase(materials[static_cast<size_t>(set->boundMaterials[k])]);
  for (size_t i = 0; i < set->expressions.size(); ++i) {
    const float w = effectiveWeights[i];
    if (!(w > 0.0f) || !std::isfinite(w)) continue;
    const Expression& e = set->expressions[i];
    for (const MaterialColorBind& c : e.colorBinds) {
      const MaterialBindState base = materialBindBase(materials[static_cast<size_t>(c.material)]);
      MaterialBindState& s = states[slotOf(*set, c.material)];
      const size_t t = static_cast<size_t>(c.type);
      s.colors[t] += w * (glm::vec3(c.target) - base.colors[t]);
      if (c.type == MaterialColorType::Color) s.alpha += w * (c.target.a - base.alpha);
    }
    for (const TextureTransformBind& t : e.textureTransformBinds) {
      MaterialBindState& s = states[slotOf(*set, t.material)];
      s.uvWeight += w;
      s.uvScale += w * t.scale;
      s.uvOffset += w * t.offset;
    }
  }
  for (MaterialBindState& s : states) {
    for (glm::vec3& c : s.colors) c = glm::max(c, glm::vec3(0.0f));
    s.alpha = std::clamp(s.alpha, 0.0f, 1.0f);
  }
  return true;
}

}  // namespace embody::avatar
