#pragma once
// Writing BVH: a BvhClip (hierarchy, channels, frame time, values) back to text that the parser
// (avatar/bvh/bvh.h), Blender and other BVH tools read. Numbers are written in their shortest
// round-trip form, so a parsed clip written again keeps its offsets and frame time to the bit.
#include <string>

#include "avatar/bvh/bvh.h"
#include "core/result.h"

namespace embody::avatar {

std::string formatBvh(const BvhClip& clip);
Status writeBvh(const BvhClip& clip, const std::string& path);

// Euler angles (degrees) for a rotation, in a joint's channel order: the inverse of the parser's
// R(c1) * R(c2) * R(c3). `rotationChannels` are the joint's three rotation channels in file
// order (fewer than three: the missing axes are taken as zero, best effort).
void eulerForChannels(const glm::dquat& rotation, const BvhChannel rotationChannels[3], double degrees[3]);

}  // namespace embody::avatar
