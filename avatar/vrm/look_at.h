#pragma once
// VRM look-at: where the eyes point. VRM 1.0 `VRMC_vrm.lookAt` (type bone or expression,
// offsetFromHeadBone, range maps) and VRM 0.x `VRM.firstPerson` (lookAtTypeName Bone/BlendShape,
// firstPersonBoneOffset, lookAtHorizontalInner/Outer, lookAtVerticalDown/Up: xRange -> yRange
// through the curve's shape). The gaze is yaw (+ towards the avatar's left) and pitch (+ up) in
// degrees, measured in the head's frame against the avatar's facing direction.
#include <span>
#include <string>
#include <vector>

#include "avatar/skeleton.h"

namespace embody::avatar {

struct ExpressionSet;

// output = outputScale * f(min(input, inputMaxValue) / inputMaxValue), input in degrees (>= 0):
// f(x) = x for VRM 1.0 range maps; for VRM 0.x, f is the curve (UniVRM's CurveMapper: 0.x
// `xRange`, `yRange` and `curve`).
struct LookAtRangeMap {
  float inputMaxValue = 90.0f;
  float outputScale = 10.0f;
  // VRM 0.x: Unity AnimationCurve keyframes flattened as [time, value, inTangent, outTangent] x n,
  // times strictly increasing (checked at load); empty: linear.
  std::vector<float> curve;
  float map(float degrees) const;
};

// A Unity AnimationCurve at x: cubic Hermite between the two keys around x (tangents are slopes
// dvalue/dtime, scaled by the key interval as Unity does), the end values outside the keys
// (Unity's clamp). `keys` as LookAtRangeMap::curve, at least one key.
float evaluateUnityCurve(std::span<const float> keys, float x);

struct LookAtSetup {
  enum class Type { None, Bone, Expression };
  Type type = Type::None;
  int head = -1, leftEye = -1, rightEye = -1;  // joints (eyes only for Bone)
  glm::vec3 offsetFromHead{0.0f};              // gaze origin in the head's frame
  glm::vec3 forward{0.0f, 0.0f, 1.0f};         // the avatar's facing direction at rest (model space)
  glm::quat headRest{1, 0, 0, 0}, leftEyeRest{1, 0, 0, 0}, rightEyeRest{1, 0, 0, 0};  // rest global rotations
  LookAtRangeMap horizontalInner, horizontalOuter, verticalDown, verticalUp;
};

struct Gaze {
  float yawDegrees = 0.0f;    // + towards the avatar's left
  float pitchDegrees = 0.0f;  // + up
};

// The gaze that looks from the look-at origin (head global x offset) at `target` (same space as
// the globals), relative to the head's rest orientation.
Gaze gazeTowards(const LookAtSetup& setup, const Skeleton& skeleton, std::span<const glm::mat4> globals,
                 glm::vec3 target);

// Applies a gaze: Bone type turns the eye joints' local rotations in `pose` (the range maps give
// degrees); Expression type writes the lookUp/Down/Left/Right weights into expressionWeights
// (one per expression of `expressions`). Allocation-free.
void applyGaze(const LookAtSetup& setup, const Skeleton& skeleton, std::span<const glm::mat4> globals, Gaze gaze,
               SkeletonPose& pose, const ExpressionSet& expressions, std::span<float> expressionWeights);

}  // namespace embody::avatar
