#pragma once
// A skinned mesh for a bare skeleton: one capsule per bone (a joint to each of its children),
// weighted fully to the joint the bone hangs from, so any skeleton renders and its bones show
// (BVH clips as avatars, tracking/bvh_avatar.h). One material.
#include "avatar/avatar_asset.h"

namespace embody::avatar {

// Bones shorter than 1 mm are skipped. Radius: a quarter of the bone's length, between 0.6 % and
// 3.5 % of `stature` (metres). `bodyRoot` (the pelvis joint, -1 none): bones hanging from its
// ancestors get no capsule. Those are root-motion and helper bones above the body (CC_Base's
// RL_BoneRoot on the floor, Unreal's root and IK bones); nothing drives them, so their capsules
// would stand where the clip began like a pole.
void buildCapsuleMesh(AvatarAsset& asset, float stature, int bodyRoot = -1);

}  // namespace embody::avatar
