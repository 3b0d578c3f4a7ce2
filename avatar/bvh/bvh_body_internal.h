#pragma once
// Shared between the parts of analyseBvhBody (bvh_body.cpp, bvh_body_joints.cpp).
#include <vector>

#include "avatar/bvh/bvh_body.h"

namespace embody::avatar {

// The bones a BVH clip's trackers stand on: hips, head, hands, feet.
const std::vector<HumanBone>& bvhBodyBones();

// Names, then topology on the skeleton as posed in `frame` where names leave body bones
// unmapped, then the user's bone map (JSON, "" for none).
Result<HumanoidMap> mapBvhJoints(const BvhClip& clip, const Skeleton& skeleton, size_t frame,
                                 const std::string& boneMapJson);

}  // namespace embody::avatar
