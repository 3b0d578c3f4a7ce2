#pragma once
// The late latch of the hands (embody xr): the body was solved on the IK thread from trackers
// located right after xrWaitFrame; just before skinning the controllers are located again and
// each hand joint is moved rigidly (with its fingers) onto the newest wrist pose, so the hand
// the user sees is not a solve behind the controller. The arm up to the wrist keeps the solved
// pose; the correction is a few millimetres per frame of hand motion, which the skin of the wrist
// absorbs.
//
//   HandLatch latch[2] = {...};                     // joint, solved-for target, newest pose
//   latchHands(skeleton, latch, pose, scratch, out);  // pose: world-space (its roots placed)
#include <array>
#include <vector>

#include "avatar/skeleton.h"
#include "xr/xr_common.h"

namespace embody::xr {

struct HandLatch {
  int joint = -1;   // the avatar's hand joint (humanoid leftHand/rightHand); < 0: skip
  Pose solvedFor;   // the wrist target the shown body was solved for (world, tracker axes)
  Pose newest;      // the wrist located again (world, the same axes)
  bool apply = false;  // both poses are live (valid and tracked by the guard)
};

struct LatchResult {
  std::array<bool, 2> applied{false, false};
  std::array<float, 2> correction{0.0f, 0.0f};  // metres the hand joint moved
  std::array<float, 2> error{0.0f, 0.0f};       // metres from the hand joint to `newest` afterwards
};

// Corrections larger than this are not latched (a tracking jump, a recenter): the solver's next
// frame takes them, the arm is never torn apart.
constexpr float kMaxLatchMetres = 0.10f;

// Rigidly moves each applied hand joint: its world position becomes newest.position, its world
// rotation turns by newest * solvedFor^-1. `globals` is scratch (no allocation once sized).
void latchHands(const avatar::Skeleton& skeleton, const std::array<HandLatch, 2>& latch,
                avatar::SkeletonPose& pose, std::vector<glm::mat4>& globals, LatchResult& out);

}  // namespace embody::xr
