#pragma once
// First-person draw list: what the user sees of their own avatar from inside its head.
//
// VRM files: firstPerson.meshAnnotations decide per mesh (VRM 1.0: per node, types auto, both,
// thirdPersonOnly, firstPersonOnly; VRM 0.x: per mesh, firstPersonFlag Auto, Both,
// ThirdPersonOnly, FirstPersonOnly). thirdPersonOnly meshes are left out of the first-person
// list, firstPersonOnly meshes out of the third-person list.
// `auto` and every non-VRM avatar: triangles with any vertex weighted (> 0) to the head joint or
// one of its descendants are dropped from the first-person list, so the inside of the head never
// covers the view while hands, arms and body stay. Built once, at load time.
#include "avatar/avatar_asset.h"

namespace embody::avatar {

// Rewrites mesh.primitives (third person) and mesh.firstPersonIndices/firstPersonPrimitives from
// the full primitive list the loader produced, and fills asset.firstPerson. Uses
// asset.humanoid's head (or VRM 0.x firstPersonBone) and asset.rawJson's annotations.
void buildFirstPerson(AvatarAsset& asset);

// True when any vertex of triangle t (index into mesh.indices / 3 of `indices`) has weight on a
// joint flagged in `hidden`. Exposed for tests.
bool triangleTouches(const SkinnedMesh& mesh, const std::vector<uint32_t>& indices, size_t triangle,
                     const std::vector<bool>& hidden);

}  // namespace embody::avatar
