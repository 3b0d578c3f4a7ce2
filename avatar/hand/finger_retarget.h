#pragma once
// Finger retargeting: the 26 joints of XR_EXT_hand_tracking (or any hand tracker with the same
// joint set) drive an avatar's 30 humanoid finger bones. Pure math on a Skeleton + SkeletonPose;
// no OpenXR header (the joint indices below are XrHandJointEXT's).
//
//   FingerRig rig = buildFingerRig(asset.skeleton, asset.humanoid);     // once per avatar
//   FingerRetargetState state;                                         // per avatar instance
//   each frame, after the body IK has posed the wrists:
//     FingerRetargetJob job;
//     job.skeleton = &asset.skeleton; job.rig = &rig; job.state = &state;
//     job.hands = {&leftJoints, &rightJoints}; job.deltaTime = dt; job.pose = &pose;
//     if (job.Validate()) job.Run();
//
// Method (direction-based, like FinalIK's and Unreal's OpenXR hand retargeting):
// - Hand frame. The same construction on both sides: wrist -> mean of the non-thumb knuckles
//   (the proximal joints) is the finger direction, little -> index knuckle the thumb side; the
//   frame has OpenXR's wrist axes (-Z towards the fingers, +Y out of the back of the hand). The
//   avatar's is measured once at rest and rides on its posed hand bone; the tracked one comes from
//   this frame's joints. Their difference maps tracked directions into the avatar's hand, so the
//   fingers are relative to the hand whatever the IK did to the wrist.
// - Segments. Each finger bone (VRM 1.0: thumb metacarpal/proximal/distal, index..little
//   proximal/intermediate/distal) points from its joint to the next; the tracked segment is the
//   matching pair of joints (thumb metacarpal -> thumb proximal, ..., index distal -> index tip).
//   Walking each finger from the hand outwards, the bone turns from its rest direction onto the
//   tracked direction with the smallest rotation (the avatar keeps its own bone lengths; only
//   rotations are written), flexion and spread are clamped to a human range per joint, and for
//   index..little the twist about the bone follows the tracked joint's +Y (the back of the
//   finger), clamped to a few degrees. The thumb gets no twist: an avatar's rest thumb roll is
//   unknown from its bones.
// - Validity. A finger is driven when the hand is active, the wrist and the frame's knuckles are
//   valid and every joint of its mapped segments is valid and finite; otherwise it blends back to
//   the input pose (the rest or animated fingers) over `blendTime`, and comes back the same way.
//   Output rotations are always finite.
// Rotations compose without the joints' scale: the rig assumes uniform scale above the hand (as
// glTF avatars and TrackedAvatarBody's root scale have).
#include <array>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

#include "avatar/humanoid/humanoid_map.h"
#include "avatar/skeleton.h"

namespace embody::avatar {

// XR_EXT_hand_tracking's joint set, same indices as XrHandJointEXT.
enum class HandJoint : int {
  Palm,
  Wrist,
  ThumbMetacarpal,
  ThumbProximal,
  ThumbDistal,
  ThumbTip,
  IndexMetacarpal,
  IndexProximal,
  IndexIntermediate,
  IndexDistal,
  IndexTip,
  MiddleMetacarpal,
  MiddleProximal,
  MiddleIntermediate,
  MiddleDistal,
  MiddleTip,
  RingMetacarpal,
  RingProximal,
  RingIntermediate,
  RingDistal,
  RingTip,
  LittleMetacarpal,
  LittleProximal,
  LittleIntermediate,
  LittleDistal,
  LittleTip,
  count
};
constexpr int kTrackedHandJointCount = static_cast<int>(HandJoint::count);  // 26
constexpr int kFingerCount = 5;  // thumb, index, middle, ring, little
constexpr int kFingerSegments = 3;
constexpr int kFingerBonesPerHand = kFingerCount * kFingerSegments;  // 15

// One hand's tracked joints in any one rigid frame (world, stage, ...): only their relative
// placement matters. Orientations follow XR_EXT_hand_tracking (-Z along the bone towards the
// fingertip, +Y out of the back of the finger).
struct TrackedHandJoints {
  bool active = false;  // the tracker reports this hand at all (XrHandJointLocationsEXT::isActive)
  std::array<glm::vec3, kTrackedHandJointCount> position{};
  std::array<glm::quat, kTrackedHandJointCount> orientation{};
  std::array<bool, kTrackedHandJointCount> valid{};  // position and orientation valid
};

// Joint limits of one finger bone relative to its parent, radians. Flexion turns the bone
// towards the palm (negative: hyperextension), spread towards the thumb or little finger side.
struct FingerLimits {
  float minFlexion = 0.0f, maxFlexion = 0.0f;
  float maxSpread = 0.0f;
  float maxTwist = 0.0f;
};

// The default human ranges per VRM finger bone (segment 0..2 of finger 0..4).
FingerLimits defaultFingerLimits(int finger, int segment);

struct FingerBone {
  int joint = -1;  // skeleton joint, -1 when the avatar lacks this bone
  HandJoint trackedFrom = HandJoint::Wrist, trackedTo = HandJoint::Wrist;  // the tracked segment
  // In the bone's own rest frame (constant): the direction to the next finger joint, the back of
  // the finger (perpendicular to it) and the flexion axis lateral = cross(axis, dorsal).
  glm::vec3 axis{0.0f, 1.0f, 0.0f}, dorsal{0.0f, 0.0f, 1.0f}, lateral{1.0f, 0.0f, 0.0f};
  FingerLimits limits;
};

struct FingerRigHand {
  int hand = -1;  // the avatar's hand joint; -1 when this hand has no usable fingers
  bool left = true;
  glm::quat handFrame{1.0f, 0.0f, 0.0f, 0.0f};   // hand frame (OpenXR wrist axes) in the hand joint's frame
  std::array<bool, kFingerCount> frameFinger{};  // the knuckles the hand frame is built from (index..little)
  std::array<FingerBone, kFingerBonesPerHand> bones;  // [finger * 3 + segment]
  int mappedBones = 0;
};

// Const model: which joints are finger bones and their rest geometry.
struct FingerRig {
  std::array<FingerRigHand, 2> hands;  // 0 left, 1 right
  std::vector<std::string> notes;      // why a hand or bone is not driven
  int mappedBones() const { return hands[0].mappedBones + hands[1].mappedBones; }
};

// The VRM 1.0 bone of finger f (0 thumb .. 4 little), segment s (0..2), on one side.
HumanBone fingerHumanBone(bool left, int finger, int segment);
// Mapped finger bones of a humanoid map (0..30).
int countFingerBones(const HumanoidMap& map);

// Builds the rig from the rest pose. A hand is driven when its hand bone and at least two of the
// index..little proximal bones are mapped (they define the hand frame); every mapped finger bone
// below it is retargeted.
FingerRig buildFingerRig(const Skeleton& skeleton, const HumanoidMap& map);

// The hand frame (OpenXR wrist axes) from a wrist and its knuckles (proximal joints of index,
// middle, ring, little; `use` picks which). False when degenerate (coincident points).
bool handFrameFromKnuckles(const glm::vec3& wrist, const std::array<glm::vec3, 4>& knuckles,
                           const std::array<bool, 4>& use, bool left, glm::quat& frame);

// Mutable state carried from frame to frame: each finger's blend weight (0: input pose, 1: tracked)
// and each bone's last retargeted local rotation (held while a lost finger blends out).
struct FingerRetargetState {
  std::array<std::array<float, kFingerCount>, 2> weight{};
  std::array<std::array<glm::quat, kFingerBonesPerHand>, 2> last{};  // zero quaternion: none yet
};

// Per-frame output for statistics and tests: each bone's angle between its input-pose direction
// and its retargeted direction (radians, after blending), and each finger's weight.
struct FingerRetargetOutput {
  std::array<std::array<float, kFingerBonesPerHand>, 2> bend{};
  std::array<std::array<float, kFingerCount>, 2> weight{};
  std::array<bool, 2> handTracked{};  // the tracked hand frame was usable this frame
};

struct FingerRetargetJob {
  const Skeleton* skeleton = nullptr;
  const FingerRig* rig = nullptr;
  std::array<const TrackedHandJoints*, 2> hands{};  // left, right; nullptr = no hand tracking
  float deltaTime = 0.0f;                           // seconds since the last Run (>= 0)
  float blendTime = 0.15f;                          // seconds to blend fully in or out (> 0)
  FingerRetargetState* state = nullptr;
  SkeletonPose* pose = nullptr;            // in: the posed skeleton (IK, animation); out: fingers set
  FingerRetargetOutput* output = nullptr;  // optional

  // True when every pointer is set, the pose has one transform per joint, the rig's joints exist
  // and the times are finite and in range.
  bool Validate() const;
  // Validate() must hold. Writes only the rotations of the rig's finger bones.
  bool Run() const;
};

}  // namespace embody::avatar
