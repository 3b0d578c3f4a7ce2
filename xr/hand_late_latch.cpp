#include "xr/hand_late_latch.h"

#include <cmath>

namespace embody::xr {

namespace {

glm::quat rotationOf(const glm::mat4& m) {
  const float s = glm::length(glm::vec3(m[0]));
  return glm::normalize(glm::quat_cast(glm::mat3(m) / (s > 0.0f ? s : 1.0f)));
}

}  // namespace

void latchHands(const avatar::Skeleton& skeleton, const std::array<HandLatch, 2>& latch,
                avatar::SkeletonPose& pose, std::vector<glm::mat4>& globals, LatchResult& out) {
  out = LatchResult{};
  avatar::computeGlobals(skeleton, pose, globals);
  for (size_t h = 0; h < 2; ++h) {
    const HandLatch& l = latch[h];
    if (!l.apply || l.joint < 0 || size_t(l.joint) >= globals.size()) continue;
    const int parent = skeleton.joints[size_t(l.joint)].parent;
    const glm::mat4& hand = globals[size_t(l.joint)];
    const glm::vec3 from(hand[3]);
    const float moved = glm::distance(from, l.newest.position);
    if (!std::isfinite(moved) || moved > kMaxLatchMetres) continue;
    const glm::quat turn = l.newest.orientation * glm::inverse(l.solvedFor.orientation);
    const glm::quat worldRot = glm::normalize(turn * rotationOf(hand));
    const glm::mat4 parentGlobal = parent >= 0 ? globals[size_t(parent)] : glm::mat4(1.0f);
    avatar::Transform& local = pose.local[size_t(l.joint)];
    local.translation = glm::vec3(glm::inverse(parentGlobal) * glm::vec4(l.newest.position, 1.0f));
    local.rotation = glm::normalize(glm::inverse(rotationOf(parentGlobal)) * worldRot);
    const glm::vec3 now(parentGlobal * glm::vec4(local.translation, 1.0f));
    out.applied[h] = true;
    out.correction[h] = moved;
    out.error[h] = glm::distance(now, l.newest.position);
  }
}

}  // namespace embody::xr
