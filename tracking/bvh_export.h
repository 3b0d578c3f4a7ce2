#pragma once
// Solved motion as BVH (`embody render --export FILE.bvh`, embody eval's solved.bvh): one frame
// per shown pose, on the avatar's hierarchy.
//
// - A BVH avatar (tracking/bvh_avatar.h): the SAME hierarchy, joint names, offsets, channels
//   (order included) and frame time as the input clip, in its units and axes, so any BVH tool
//   compares the two joint by joint.
// - Any other avatar: its skeleton, offsets = rest joint positions (centimetres, the avatar's
//   axes), root Xposition Yposition Zposition Zrotation Xrotation Yrotation, others ZXY.
// A joint's BVH rotation is its world rotation relative to rest (BVH rests have no rotations),
// made local to its parent's; position channels carry the joint's displacement from its offset.
#include <string>

#include "avatar/avatar_asset.h"
#include "avatar/bvh/bvh.h"
#include "core/result.h"
#include "tracking/bvh_avatar.h"

namespace embody::tracking {

class SolvedMotionBvh {
 public:
  static SolvedMotionBvh forBvhAvatar(const BvhAvatar& avatar);
  static SolvedMotionBvh forAvatar(const avatar::AvatarAsset& asset, double frameTime);

  void reserve(size_t frames);
  // Frames written at another rate than the clip's (e.g. render --fps 90 on a 120 Hz clip).
  void setFrameTime(double seconds) { clip_.frameTime = seconds; }
  void add(const avatar::SkeletonPose& pose);  // one frame (the pose shown)
  const avatar::BvhClip& clip() const { return clip_; }
  Status write(const std::string& path) const;

 private:
  SolvedMotionBvh(const avatar::Skeleton& skeleton) : skeleton_(&skeleton) {}
  const avatar::Skeleton* skeleton_;
  avatar::BvhClip clip_;  // hierarchy + frames so far
  std::vector<int> bvhOfJoint_;  // skeleton joint -> clip joint (-1 none)
  std::vector<glm::dquat> restRotation_;  // avatar world rest rotations
  glm::dmat3 toAvatar_{1.0};  // file axes -> avatar axes
  double scale_ = 0.01;       // metres per file unit
  glm::dvec3 shift_{0.0};     // avatar = toAvatar * file * scale + shift
  std::vector<glm::mat4> globals_;
  std::vector<glm::dquat> world_;
  std::vector<glm::dvec3> position_;
  std::vector<char> posed_;  // clip joints a skeleton joint wrote this frame
  void carryTranslationsToRoot();
};

}  // namespace embody::tracking
