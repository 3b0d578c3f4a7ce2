#include "avatar/avatar_asset.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/quaternion.hpp>

namespace embody::avatar {
namespace {

glm::dmat4 restMatrixInDouble(const Transform& t) {
  glm::dmat4 m = glm::mat4_cast(glm::dquat(t.rotation));
  m[0] *= double(t.scale.x);
  m[1] *= double(t.scale.y);
  m[2] *= double(t.scale.z);
  m[3] = glm::dvec4(glm::dvec3(t.translation), 1.0);
  return m;
}

// The orthogonal factor of a non-singular matrix's polar decomposition: the closest rotation (a
// mirror stays a mirror). Newton's iteration with Higham's scaling, quadratic near the end.
glm::dmat3 polarRotationOf(glm::dmat3 m) {
  for (int k = 0; k < 100; ++k) {
    const glm::dmat3 inverseT = glm::transpose(glm::inverse(m));
    double nm = 0.0, ni = 0.0;
    for (int c = 0; c < 3; ++c) nm += glm::dot(m[c], m[c]), ni += glm::dot(inverseT[c], inverseT[c]);
    const double gamma = std::sqrt(std::sqrt(ni / nm));
    const glm::dmat3 next = 0.5 * (gamma * m + inverseT / gamma);
    double change = 0.0;
    for (int c = 0; c < 3; ++c) change = std::max(change, glm::length(next[c] - m[c]));
    m = next;
    if (change < 1e-15) break;
  }
  return m;
}

// A similarity matrix (rotation or mirror, uniform scale, translation) as TRS; a mirror goes into
// scale.x, as the loader stores a node matrix's. A scale within 1e-6 of 1 is 1.
Transform similarityToTrs(const glm::dmat4& m) {
  Transform t;
  t.translation = glm::vec3(m[3]);
  glm::dmat3 r(m);
  double s = std::cbrt(std::abs(glm::determinant(r)));
  r /= s;
  if (std::abs(s - 1.0) < 1e-6) s = 1.0;
  t.scale = glm::vec3(float(s));
  if (glm::determinant(r) < 0.0) {
    t.scale.x = -t.scale.x;
    r[0] = -r[0];
  }
  t.rotation = glm::normalize(glm::quat(glm::quat_cast(r)));
  return t;
}

bool isUniformScale(const glm::vec3& s) {
  const glm::vec3 a = glm::abs(s);
  const float big = std::max({a.x, a.y, a.z});
  return big - std::min({a.x, a.y, a.z}) <= 1e-6f * big;
}

}  // namespace

int foldBoneScaleIntoBind(AvatarAsset& asset) {
  Skeleton& sk = asset.skeleton;
  const size_t n = sk.joints.size();
  if (asset.mesh.inverseBind.size() != n) return 0;
  std::vector<glm::mat4> before;
  computeGlobals(sk, SkeletonPose::rest(sk), before);
  // kept: the joint and every joint above it have a uniform scale, so its global is a similarity
  // and it keeps its rest. invertible: its rigid global has an inverse (not hidden by a zero scale).
  std::vector<glm::dmat4> full(n), rigid(n);
  std::vector<char> kept(n), invertible(n);
  int changed = 0;
  for (size_t j = 0; j < n; ++j) {
    Joint& joint = sk.joints[j];
    const int p = joint.parent;
    const glm::dmat4 parentFull = p < 0 ? glm::dmat4(1.0) : full[size_t(p)];
    const glm::dmat4 parentRigid = p < 0 ? glm::dmat4(1.0) : rigid[size_t(p)];
    full[j] = parentFull * restMatrixInDouble(joint.rest);
    const glm::dmat3 m(full[j]);
    const double size = std::max({glm::length(m[0]), glm::length(m[1]), glm::length(m[2])});
    const bool degenerate = !(std::abs(glm::determinant(m)) > 1e-9 * size * size * size) ||
                            (p >= 0 && !invertible[size_t(p)]);
    invertible[j] = !degenerate;
    if ((p < 0 || kept[size_t(p)]) && isUniformScale(joint.rest.scale)) {
      kept[j] = 1;
      rigid[j] = full[j];
      continue;
    }
    if (degenerate) {
      // Hidden by a zero scale (here or above): keeps its rotation and scale, and its pivot.
      if (p >= 0 && invertible[size_t(p)])
        joint.rest.translation = glm::vec3(glm::inverse(parentRigid) * full[j][3]);
      rigid[j] = parentRigid * restMatrixInDouble(joint.rest);
    } else {
      rigid[j] = glm::dmat4(polarRotationOf(m) * std::cbrt(std::abs(glm::determinant(m))));
      rigid[j][3] = full[j][3];
      joint.rest = similarityToTrs(glm::inverse(parentRigid) * rigid[j]);
      rigid[j] = parentRigid * restMatrixInDouble(joint.rest);
    }
    ++changed;
  }
  if (changed == 0) return 0;
  // The binds, from the globals the renderer computes: the rest palette stays what it was.
  std::vector<glm::mat4> after;
  computeGlobals(sk, SkeletonPose::rest(sk), after);
  for (size_t j = 0; j < n; ++j) {
    if (kept[j] || !invertible[j]) continue;
    glm::dmat4 bind = glm::inverse(glm::dmat4(after[j])) * glm::dmat4(before[j]) * glm::dmat4(asset.mesh.inverseBind[j]);
    for (int c = 0; c < 4; ++c) bind[c][3] = c == 3 ? 1.0 : 0.0;  // affine, exactly
    asset.mesh.inverseBind[j] = glm::mat4(bind);
  }
  return changed;
}

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
