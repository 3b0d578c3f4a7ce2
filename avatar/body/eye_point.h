#pragma once
// The avatar's eye point: the point between the eyes that a headset's pose stands for. The
// renderer's first-person camera (engine/avatar_renderer.cpp) and the body solver's head target
// (runtime/avatar_body_solver.cpp) both take it from here, so the user sees from where the solver
// puts the eyes.
#include <glm/glm.hpp>

#include "avatar/avatar_asset.h"

namespace embody::avatar {

// The rest pose's floor and standing height along `up` (metres): from the skinned rest mesh (the
// skeleton alone misses the skull and soles); without a usable mesh (under 30 cm tall), the
// skeleton: 7 cm below the lower foot joint to 15 cm above the head joint.
struct RestStature {
  double floor = 0.0;
  double height = 0.0;
};
RestStature restStature(const AvatarAsset& asset, const glm::dvec3& up);

struct EyePoint {
  glm::dvec3 position{0.0};  // rest pose, model space (metres)
  double aboveFloor = 0.0;   // its height over the stature's floor along humanoid.up
  bool fromMesh = false;     // false: the proportion rule
  RestStature stature;       // restStature(asset, humanoid.up), measured on the way
};

// The eye point at the rest pose of head joint `head`, the avatar facing `forward` (unit):
// - with skinned geometry on the head (vertices whose strongest joint is `head` or below it): over
//   the head geometry's rest bounds, halfway up (the eyes halve the head, the artists' canon) and
//   a quarter of their depth ahead of their centre;
// - otherwise (no mesh, a BVH skeleton): the proportion rule, kEyeHeightRatio x stature above the
//   floor and kEyeForwardRatio x stature ahead of the head joint.
// `head` < 0 gives the rule's point over the origin.
EyePoint restEyePoint(const AvatarAsset& asset, int head, const glm::vec3& forward);

}  // namespace embody::avatar
