#pragma once
// The skinned vertex positions of an avatar in a pose, through the renderer's contract (globals,
// palette = global * inverseBind, the reference CPU skinner): what a test compares two avatars by.
#include <vector>

#include "avatar/avatar_asset.h"

namespace embody::test {

inline std::vector<glm::vec3> skinnedPositions(const avatar::AvatarAsset& asset, const avatar::SkeletonPose& pose) {
  std::vector<glm::mat4> globals, palette;
  avatar::computeGlobals(asset.skeleton, pose, globals);
  avatar::computeSkinningPalette(asset, globals, palette);
  std::vector<glm::vec3> positions, normals;
  avatar::skinOnCpu(asset.mesh, palette, positions, normals);
  return positions;
}

}  // namespace embody::test
