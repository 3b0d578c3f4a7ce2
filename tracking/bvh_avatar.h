#pragma once
// Any BVH clip as an avatar (`--avatar CLIP.bvh`, `embody eval`): the skeleton is the clip's
// hierarchy (End Sites included, named "<parent>_End"; skeleton joint i = clip joint i), the
// rest pose its offsets with every channel zero, in tracking space as the clip's trackers are
// (tracking/bvh_source.h: metres, +Y up, facing -Z; the rest pose stands over the origin with its
// ankles as high above the floor, y = 0, as the clip's stand: `restLift`), mapped to the humanoid
// like any avatar (names, else topology), with a generated mesh: one capsule per bone, skinned to
// the bone's joint, so it renders.
//
// Because the avatar and the trackers share one space and one scale, the clip's own joints can
// be set beside the solved body joint by joint (bvhJointsAt), and a solved pose can be written
// back onto the clip's hierarchy (avatar/bvh/bvh_writer.h).
#include <span>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/bvh/bvh.h"
#include "tracking/bvh_source.h"

namespace embody::tracking {

struct BvhAvatar {
  avatar::BvhClip clip;
  BvhMapping mapping;  // file -> tracking space, trackers, rest references
  Trace trace;         // the clip's trackers, as `--motion CLIP.bvh` replays them
  avatar::AvatarAsset asset;
  // The skeleton's rest pose is the clip's first frame: its zero-channel pose is not a standing
  // body (CC_Base exports). mapping.reference and eyeOffset are then at that frame too.
  bool restFromFirstFrame = false;
  // The turn that stood the zero-channel pose upright in tracking space, when neither it nor the
  // first frame stood (a Y-up skeleton turned into a Z-up world by its root's channels); the
  // identity otherwise. mapping.reference and eyeOffset are turned with it.
  glm::dquat restTurn{1.0, 0.0, 0.0, 0.0};
  // Metres the rest pose stands above (negative: below) its lowest joint on the floor, so that its
  // ankles are as high as the clip's standing ankles (bvh_avatar.cpp: restLift).
  double restLift = 0.0;
};

// Fails (one line) when the clip has no frames, or neither its zero-channel pose, its first frame
// nor its zero-channel pose turned upright is a standing humanoid the mapper can read (head above
// the hips and within 30 degrees of straight over the feet, feet below the hips, two arms).
Result<BvhAvatar> buildBvhAvatar(avatar::BvhClip clip, const BvhTrackerOptions& options);
Result<BvhAvatar> loadBvhAvatar(const std::string& path, const BvhTrackerOptions& options);

// The clip's joints at time t (seconds from the trace's first sample, as the BVH pose source
// replays it: linear positions, slerped rotations between frames) in tracking space: world
// positions (metres) and world rotations (identity in the rest pose). `out` is resized.
void bvhJointsAt(const avatar::BvhClip& clip, const BvhMapping& mapping, double t, std::vector<avatar::BvhGlobal>& out);

// The avatar's local pose for the clip's joints (rest rotations are identity, so a local
// rotation is the clip's, turned into tracking axes).
void bvhPoseAt(const BvhAvatar& avatar, double t, avatar::SkeletonPose& pose);

}  // namespace embody::tracking
