#pragma once
// XrInput: the user's hands. Grip and aim poses and a trigger from the controllers (suggested
// bindings for khr/simple, oculus/touch, valve/index, htc/vive and microsoft/motion controllers),
// converted to the wrist with a per-profile grip-to-wrist offset; XR_EXT_hand_tracking joints
// when the runtime offers them (the tracked wrist then wins over the controller estimate).
// Validity follows OpenXR's location flags: a hand whose pose is not valid is "lost".
#include <array>
#include <memory>
#include <string>

#include "core/result.h"
#include "xr/xr_common.h"

namespace embody::xr {

class XrSystem;
class XrSessionRunner;

constexpr int kHandJointCount = 26;  // XR_HAND_JOINT_COUNT_EXT

struct HandState {
  bool active = false;    // the pose action is bound and the session focused
  TrackedPose grip, aim;  // controller poses in the world space
  TrackedPose wrist;      // where the user's wrist is (hand tracking, else grip * offset)
  bool wristFromHandTracking = false;
  float trigger = 0.0f;
  bool jointsValid = false;  // XR_EXT_hand_tracking joints (world space)
  std::array<TrackedPose, kHandJointCount> joints;
};

// The wrist in the grip frame of a controller profile, for the right hand (the left mirrors it).
// Measured from the controllers' geometry: the grip origin sits in the palm, about a palm's
// length ahead of the wrist and turned by the handle's angle.
Pose gripToWrist(const std::string& interactionProfile, bool leftHand);
// The wrists XrInput reports (hand-tracking wrist joints, or grips moved to the wrist) have
// OpenXR's hand-joint axes: -Z from the wrist towards the fingers, +Y out of the back of the hand.
// The pose sources and the body solver (tracking/tracker.h) use the grip convention instead:
// +Y along the fingers, +X = -palm normal (left) / +palm normal (right). This turns one into the
// other (a fixed rotation per hand).
glm::quat trackerHandOrientation(const glm::quat& xrWrist, bool leftHand);

class XrInput {
 public:
  static Result<std::unique_ptr<XrInput>> create(XrSystem& system, XrSessionRunner& session);
  ~XrInput();
  XrInput(const XrInput&) = delete;
  XrInput& operator=(const XrInput&) = delete;

  // xrSyncActions and locate everything at `time` (the predicted display time) in the world space.
  Status update(XrTime time);
  // The late latch: locates the grips (and tracked hands) again at `time`, without a new
  // xrSyncActions, just before skinning; the runtime answers with its newest prediction.
  void relocateWrists(XrTime time);
  const HandState& hand(int i) const { return hands_[i]; }            // 0 left, 1 right
  const std::string& interactionProfile() const { return profile_; }  // "" until one is bound
  bool recenterPressed() const { return recenterPressed_; }           // rising edge this update
  bool handTracking() const { return trackers_[0] != XR_NULL_HANDLE; }

 private:
  XrInput(XrSystem& s, XrSessionRunner& r) : system_(s), session_(r) {}
  // init's steps: the action set and its actions, the bindings per controller profile, the hand
  // spaces (and attaching the set), XR_EXT_hand_tracking's trackers when the runtime has them.
  Status init();
  Status createActions();
  Status suggestBindings();
  Status createHandSpaces();
  void createHandTrackers();
  void refreshProfile();
  void locateHand(int hand, XrTime time);  // grip, aim, wrist and joints of hands_[hand]

  XrSystem& system_;
  XrSessionRunner& session_;
  XrActionSet set_ = XR_NULL_HANDLE;
  XrAction grip_ = XR_NULL_HANDLE, aim_ = XR_NULL_HANDLE, trigger_ = XR_NULL_HANDLE,
           recenter_ = XR_NULL_HANDLE;
  std::array<XrPath, 2> handPaths_{};
  std::array<XrSpace, 2> gripSpaces_{}, aimSpaces_{};
  std::array<XrHandTrackerEXT, 2> trackers_{};
  PFN_xrLocateHandJointsEXT locateJoints_ = nullptr;
  PFN_xrDestroyHandTrackerEXT destroyTracker_ = nullptr;
  std::array<HandState, 2> hands_;
  std::string profile_;
  bool recenterPressed_ = false;
};

}  // namespace embody::xr
