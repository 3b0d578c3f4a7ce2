#pragma once
// Solved body -> skeleton pose: the retarget step (avatar::retarget). Every IK joint sits on an
// avatar bone's pivot, so each driven bone takes its IK joint's world rotation relative to its
// rest and the hips their translation (body_model.h). Writes every joint's local transform; no
// allocation.
//
//   SkeletonPoseJob job{&rig.body, &avatar, &data, &pose};
//   if (job.Run()) ... pose skins the avatar
#include "avatar/avatar_asset.h"
#include "avatar/body/body_model.h"
#include "ik/solver.h"

namespace embody::runtime {

struct SkeletonPoseJob {
  const avatar::BodyModel* body = nullptr;
  const avatar::AvatarAsset* avatar = nullptr;  // the asset `body` was built from
  const ik::Data* data = nullptr;               // solved, kinematics current
  avatar::SkeletonPose* pose = nullptr;         // out: sized for the avatar's skeleton

  // Every pointer set, the data sized for the body's model, the pose one transform per joint and
  // the body's avatar-joint maps sized for the skeleton.
  bool Validate() const;
  bool Run() const;
};

}  // namespace embody::runtime
