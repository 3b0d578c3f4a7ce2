#pragma once
// A skinned mesh for a bare skeleton: one capsule per bone (a joint to each of its children),
// weighted fully to the joint the bone hangs from, so any skeleton renders and its bones show
// (BVH clips as avatars, tracking/bvh_avatar.h). One material.
#include "avatar/avatar_asset.h"

namespace embody::avatar {

// Bones shorter than 1 mm are skipped. Radius: a quarter of the bone's length, between 0.6 % and
// 3.5 % of `stature` (metres).
void buildCapsuleMesh(AvatarAsset& asset, float stature);

}  // namespace embody::avatar
