#pragma once
// Invariants every loaded avatar keeps, whatever file it came from (checked by the avatar fuzz
// targets after a load is accepted).
#include <cmath>

#include "avatar/avatar_asset.h"
#include "avatar/vrm/secondary_motion.h"
#include "fuzz/fuzz_target.h"

namespace embody::fuzz {

inline bool finite(const glm::vec3& v) { return std::isfinite(v.x + v.y + v.z); }

inline void checkIndexRange(const std::vector<uint32_t>& indices, const std::vector<avatar::Primitive>& prims,
                            size_t vertexCount) {
  for (uint32_t i : indices) EMBODY_FUZZ_CHECK(i < vertexCount);
  for (const auto& p : prims)
    EMBODY_FUZZ_CHECK(static_cast<size_t>(p.firstIndex) + p.indexCount <= indices.size());
}

inline void checkAvatar(const avatar::AvatarAsset& a) {
  const size_t joints = a.skeleton.joints.size();
  for (size_t j = 0; j < joints; ++j) EMBODY_FUZZ_CHECK(a.skeleton.joints[j].parent < static_cast<int>(j));
  for (int j : a.gltfNodeToJoint) EMBODY_FUZZ_CHECK(j < static_cast<int>(joints));
  const auto& m = a.mesh;
  checkIndexRange(m.indices, m.primitives, m.vertices.size());
  checkIndexRange(m.firstPersonIndices, m.firstPersonPrimitives, m.vertices.size());
  for (const auto& v : m.vertices) {
    EMBODY_FUZZ_CHECK(finite(v.position) && finite(v.normal));
    for (int k = 0; k < 4; ++k) {
      EMBODY_FUZZ_CHECK(std::isfinite(v.weights0[k]) && std::isfinite(v.weights1[k]));
      if (v.weights0[k] > 0.0f) EMBODY_FUZZ_CHECK(v.joints0[k] < joints);
      if (v.weights1[k] > 0.0f) EMBODY_FUZZ_CHECK(v.joints1[k] < joints);
    }
  }
  for (const auto& p : m.primitives)
    EMBODY_FUZZ_CHECK(p.material < static_cast<int>(a.materials.size()));
  for (size_t i = 0; i < m.morphDeltas.size(); ++i) {
    const auto& d = m.morphDeltas[i];
    EMBODY_FUZZ_CHECK(d.vertex < m.vertices.size() && d.channel < m.morphChannels.size());
    EMBODY_FUZZ_CHECK(i == 0 || m.morphDeltas[i - 1].vertex <= d.vertex);
    EMBODY_FUZZ_CHECK(finite(d.position) && finite(d.normal));
  }
  for (const auto& mat : a.materials) {
    EMBODY_FUZZ_CHECK(mat.baseColorImage < static_cast<int>(a.images.size()));
    EMBODY_FUZZ_CHECK(mat.emissiveImage < static_cast<int>(a.images.size()));
    EMBODY_FUZZ_CHECK(std::isfinite(mat.baseColorFactor.r + mat.baseColorFactor.g + mat.baseColorFactor.b +
                                    mat.baseColorFactor.a + mat.emissiveStrength + mat.alphaCutoff));
  }
  for (const auto& mat : a.materials) {  // MToon: finite, in the specification's ranges, images that exist
    const auto& t = mat.mtoon;
    for (int image : {t.shadeImage, t.shadingShiftImage, t.matcapImage, t.rimImage, t.outlineWidthImage, t.uvAnimationMaskImage})
      EMBODY_FUZZ_CHECK(image < static_cast<int>(a.images.size()));
    EMBODY_FUZZ_CHECK(finite(t.shadeColor) && finite(t.matcapFactor) && finite(t.rimColor) && finite(t.outlineColor) &&
                      finite(mat.emissiveFactor));
    EMBODY_FUZZ_CHECK(std::isfinite(t.shadingShift + t.shadingShiftScale + t.rimLift));
    EMBODY_FUZZ_CHECK(t.shadingToony >= 0.0f && t.shadingToony <= 1.0f && t.giEqualization >= 0.0f &&
                      t.giEqualization <= 1.0f && t.rimLightingMix >= 0.0f && t.rimLightingMix <= 1.0f &&
                      t.outlineLightingMix >= 0.0f && t.outlineLightingMix <= 1.0f);
    EMBODY_FUZZ_CHECK(t.rimFresnelPower >= 0.0f && t.rimFresnelPower <= 100.0f && t.outlineWidth >= 0.0f &&
                      t.outlineWidth <= 1.0f && t.renderQueueOffset >= -9 && t.renderQueueOffset <= 9);
    EMBODY_FUZZ_CHECK(std::abs(t.uvAnimationScroll.x) <= 1000.0f && std::abs(t.uvAnimationScroll.y) <= 1000.0f &&
                      std::abs(t.uvAnimationRotation) <= 2000.0f * 3.1416f);  // 0.x: turns x 2 pi
    for (const auto* tt : {&t.shadeTransform, &t.shadingShiftTransform, &t.rimTransform, &t.outlineWidthTransform,
                           &t.uvAnimationMaskTransform})
      EMBODY_FUZZ_CHECK(tt->texCoord == 0 || tt->texCoord == 1);
  }
  for (const auto& img : a.images)
    EMBODY_FUZZ_CHECK(img.rgba.size() == static_cast<size_t>(img.width) * static_cast<size_t>(img.height) * 4);
  for (int j : a.humanoid.bones) EMBODY_FUZZ_CHECK(j < static_cast<int>(joints));
  for (const auto& s : a.humanoid.spine) EMBODY_FUZZ_CHECK(s.joint < static_cast<int>(joints));
  EMBODY_FUZZ_CHECK(a.firstPerson.headJoint < static_cast<int>(joints));
}

// Spring bones, expressions and look-at of a loaded avatar: valid references, and a few frames
// of motion (a head turn, a teleport of the root, a look target, every expression half on) leave
// the pose, the morph weights and the material bind states finite.
inline void checkSecondaryMotion(const avatar::AvatarAsset& a) {
  const int joints = static_cast<int>(a.skeleton.joints.size());
  for (const auto& c : a.springBones.chains)
    for (const auto& j : c.joints) EMBODY_FUZZ_CHECK(j.joint >= 0 && j.joint < joints && j.child < joints);
  for (const auto& e : a.expressions.expressions)
    for (const auto& b : e.morphBinds) EMBODY_FUZZ_CHECK(b.channel < a.mesh.morphChannels.size());
  for (int m : a.expressions.boundMaterials) EMBODY_FUZZ_CHECK(m >= 0 && static_cast<size_t>(m) < a.materials.size());
  avatar::SecondaryMotion motion(a);
  for (float& w : motion.expressionWeights()) w = 0.5f;
  const int head = a.humanoid.joint(avatar::HumanBone::head);
  for (int frame = 0; frame < 4; ++frame) {
    avatar::SkeletonPose pose = avatar::SkeletonPose::rest(a.skeleton);
    if (head >= 0) pose.local[static_cast<size_t>(head)].rotation = glm::angleAxis(0.4f * float(frame), glm::vec3(0, 1, 0));
    if (frame == 2 && !pose.local.empty()) pose.local[0].translation += glm::vec3(30.0f, 0.0f, 0.0f);
    motion.update(pose, frame == 3 ? 5.0 : 1.0 / 90.0, glm::vec3(0.5f, 1.6f, 1.0f));
    for (const auto& t : pose.local) EMBODY_FUZZ_CHECK(std::isfinite(t.rotation.w + t.rotation.x + t.rotation.y + t.rotation.z));
    for (float w : motion.morphWeights()) EMBODY_FUZZ_CHECK(std::isfinite(w) && w >= 0.0f && w <= 1.0f);
    EMBODY_FUZZ_CHECK(motion.materialStates().size() == a.expressions.boundMaterials.size());
    for (const auto& s : motion.materialStates()) {
      for (const glm::vec3& c : s.colors) EMBODY_FUZZ_CHECK(std::isfinite(c.x + c.y + c.z) && glm::all(glm::greaterThanEqual(c, glm::vec3(0.0f))));
      EMBODY_FUZZ_CHECK(std::isfinite(s.alpha + s.uvWeight + s.uvScale.x + s.uvScale.y + s.uvOffset.x + s.uvOffset.y));
    }
  }
}

}  // namespace embody::fuzz
