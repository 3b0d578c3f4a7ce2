#include "avatar/avatar_asset.h"

#include <cmath>

namespace embody::avatar {

glm::vec2 TextureTransform::apply(glm::vec2 uv) const {
  const glm::vec2 s = scale * uv;
  const float c = std::cos(rotation), n = std::sin(rotation);
  return offset + glm::vec2(c * s.x + n * s.y, -n * s.x + c * s.y);
}

std::string_view avatarFormatName(AvatarFormat f) {
  switch (f) {
    case AvatarFormat::Vrm0:
      return "vrm0";
    case AvatarFormat::Vrm1:
      return "vrm1";
    case AvatarFormat::Procedural:
      return "procedural";
    default:
      return "gltf";
  }
}

void computeSkinningPalette(const AvatarAsset& asset, const std::vector<glm::mat4>& globals,
                            std::vector<glm::mat4>& palette) {
  palette.resize(globals.size());
  for (size_t j = 0; j < globals.size(); ++j)
    palette[j] = j < asset.mesh.inverseBind.size() ? globals[j] * asset.mesh.inverseBind[j] : globals[j];
}

std::vector<float> defaultMorphWeights(const SkinnedMesh& mesh) {
  std::vector<float> w(mesh.morphChannels.size());
  for (size_t c = 0; c < w.size(); ++c) w[c] = mesh.morphChannels[c].defaultWeight;
  return w;
}

void skinOnCpu(const SkinnedMesh& mesh, const std::vector<glm::mat4>& palette,
               std::vector<glm::vec3>& positions, std::vector<glm::vec3>& normals,
               std::span<const float> morphWeights) {
  positions.resize(mesh.vertices.size());
  normals.resize(mesh.vertices.size());
  size_t d = 0;  // morph deltas are sorted by vertex
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    SkinnedVertex v = mesh.vertices[i];
    for (; d < mesh.morphDeltas.size() && mesh.morphDeltas[d].vertex <= i; ++d) {
      const MorphDelta& md = mesh.morphDeltas[d];
      if (md.vertex != i || md.channel >= morphWeights.size()) continue;
      v.position += morphWeights[md.channel] * md.position;
      v.normal += morphWeights[md.channel] * md.normal;
    }
    glm::mat4 m(0.0f);
    for (int k = 0; k < 4; ++k) {
      if (v.weights0[k] != 0.0f) m += v.weights0[k] * palette[v.joints0[k]];
      if (v.weights1[k] != 0.0f) m += v.weights1[k] * palette[v.joints1[k]];
    }
    positions[i] = glm::vec3(m * glm::vec4(v.position, 1.0f));
    const glm::vec3 n = glm::mat3(m) * v.normal;
    const float len = glm::length(n);
    normals[i] = len > 0.0f ? n / len : v.normal;
  }
}

}  // namespace embody::avatar
