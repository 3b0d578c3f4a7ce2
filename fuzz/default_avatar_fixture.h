#pragma once
// The default mannequin, built once per fuzzing process: the skeleton the VRM-extension and
// bone-map targets map onto (a glTF node per joint, in joint order).
#include <numeric>

#include "avatar/procedural/default_avatar.h"

namespace embody::fuzz {

inline const avatar::AvatarAsset& defaultAvatarFixture() {
  static const avatar::AvatarAsset asset = [] {
    avatar::AvatarAsset a = avatar::buildDefaultAvatar();
    a.gltfNodeToJoint.resize(a.skeleton.joints.size());
    std::iota(a.gltfNodeToJoint.begin(), a.gltfNodeToJoint.end(), 0);
    return a;
  }();
  return asset;
}

}  // namespace embody::fuzz
