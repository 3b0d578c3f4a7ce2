#pragma once
// What a VRM avatar does on its own each frame, after IK and before skinning:
//   look-at (eye bones or look expressions, towards a target) -> automatic blinking ->
//   expressions (weights, overrides) -> morph weights and material bind states; spring bones
//   (hair, skirts).
// One per avatar instance; update() is allocation-free after construction. For a glTF without VRM
// data it only hands out the file's default morph weights.
#include <optional>
#include <span>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/vrm/blink.h"
#include "avatar/vrm/look_at.h"
#include "avatar/vrm/material_binds.h"
#include "avatar/vrm/spring_bone.h"

namespace embody::avatar {

struct SecondaryMotionOptions {
  bool springBones = true;
  bool blink = true;
  bool lookAt = true;
  uint64_t blinkSeed = 1;
  double springStepSeconds = 1.0 / 120.0;
};

class SecondaryMotion {
 public:
  explicit SecondaryMotion(const AvatarAsset& asset, const SecondaryMotionOptions& options = {});

  // One frame: `pose` is the solved pose (in/out: spring and eye joints change); dt the seconds
  // since the last update; lookTarget where the avatar looks (the space of the pose's globals),
  // none to look straight ahead.
  void update(SkeletonPose& pose, double dt, const std::optional<glm::vec3>& lookTarget);
  // Forget the springs' motion (teleport, recenter): they restart at rest on the next update.
  void reset() { resetSprings_ = true; }

  // Expression weights set by the application (0..1 per asset.expressions entry); blink and
  // look-at write theirs on top each update.
  std::span<float> expressionWeights() { return manual_; }
  std::span<const float> morphWeights() const { return morph_; }  // one per mesh.morphChannels
  std::span<const float> effectiveExpressionWeights() const { return effective_; }
  // One per asset.expressions.boundMaterials: the colours and texture transforms the
  // expressions' material binds give this frame (engine::SceneFrame::materialStates).
  std::span<const MaterialBindState> materialStates() const { return materialStates_; }
  // Seconds of motion so far (the sum of update()'s dt): the frame clock of MToon UV animation.
  double seconds() const { return seconds_; }
  const SpringBoneJob& lastSpringJob() const { return job_; }
  float blinkWeight() const { return blink_; }
  Gaze lastGaze() const { return gaze_; }

 private:
  const AvatarAsset& asset_;
  SecondaryMotionOptions options_;
  BlinkSchedule blinkSchedule_;
  SpringBoneState springState_;
  SpringBoneJob job_;
  std::vector<glm::mat4> globals_;
  std::vector<float> manual_, weights_, effective_, defaults_, morph_;
  std::vector<MaterialBindState> materialStates_;
  float blink_ = 0.0f;
  double seconds_ = 0.0;
  Gaze gaze_;
  bool resetSprings_ = false;
};

}  // namespace embody::avatar
