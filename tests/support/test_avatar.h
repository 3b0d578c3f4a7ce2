#pragma once
// A procedurally generated skinned avatar for the renderer's tests and benchmarks: a bendable textured tube
// (a chain of five spine joints, every vertex weighted to up to six of them, so both JOINTS_0 and
// JOINTS_1 are used) with a head sphere on a "head" joint, two hand blocks on "leftHand" /
// "rightHand", a half-transparent fin (BLEND) and a cut-out flag (MASK, double-sided).
// The first-person draw list leaves the head out.
#include "avatar/avatar_asset.h"

namespace embody::test {

struct TestAvatarOptions {
  int rings = 40;     // tube rings along the height
  int segments = 24;  // vertices around each ring
};

avatar::AvatarAsset makeTestAvatar(const TestAvatarOptions& options = {});

// The test avatar bent sideways by `bend` radians per spine joint, the head nodding and turned.
avatar::SkeletonPose bentTestPose(const avatar::Skeleton& skeleton, float bend = 0.3f);

}  // namespace embody::test
