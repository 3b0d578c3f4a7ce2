#pragma once
// The headset loop behind `embody xr`: OpenXR system + session + input, the avatar rendered in
// first person into the runtime's swapchains (one pass per eye), gizmos at the tracked hands.
//
// The body comes from `bodyPose` (embody xr: runtime::TrackedAvatarBody, three-point PIK); without
// it the avatar stands in its rest pose under the head (scaled by the HMD-height calibration,
// turned with the head's heading). After the body, when XR_EXT_hand_tracking is active and the
// avatar has humanoid finger bones, the 26 tracked joints of each hand drive its fingers
// (avatar::FingerRetargetJob, relative to the posed hands) before skinning.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"
#include "xr/avatar_placement.h"
#include "tracking/tracker.h"

namespace embody::xr {

// What the fingers did over the run (all zero without hand tracking or finger bones).
struct FingerReport {
  int drivenBones = 0;      // finger bones of the avatar that hand tracking drives (of 30)
  uint64_t frames = 0;      // frames with at least one finger following the tracked hand
  uint64_t fullFrames = 0;  // frames with every driven finger fully on the tracked hand
  // Curl: the mean bend of the driven index..little bones against the input pose (degrees),
  // over frames whose fingers were fully blended in.
  float curlMinDeg = 0.0f, curlMaxDeg = 0.0f, curlLastDeg = 0.0f;
};

struct XrLoopOptions {
  const avatar::AvatarAsset* avatar = nullptr;  // required; must outlive the loop
  uint64_t frames = 0;  // request exit after this many submitted frames (0: until the runtime ends it)
  bool vulkanValidation = false;
  PlacementOptions placement;
  bool recenterAtStart = false;
  bool verbose = false;  // print every session state change
  bool mirror = false;   // a desktop window (engine::DesktopWindow) showing the left eye (V: third person)
  bool fingers = true;   // drive the avatar's finger bones from hand tracking when both exist
  // The body: given each frame's tracker sample (world space, recentered: head, wrists), fill
  // `pose` (starts at the rest pose) and return true; false or unset = the rest pose placed under
  // the head. Called on the render thread with the trackers predicted for this frame's display.
  std::function<bool(const tracking::PoseSample& sample, avatar::SkeletonPose& pose)> bodyPose;
  // Called after each recenter (the world moved under the user): e.g. a seated body places its
  // seat again (runtime::TrackedAvatarBody::reset).
  std::function<void()> onRecenter;
};

struct XrLoopReport {
  std::string runtime, system, interactionProfile;
  bool usedStage = false, handTracking = false, depthSubmitted = false;
  std::vector<std::string> states;  // session states in the order they came
  bool reachedFocused = false;
  bool endedCleanly = false;  // EXITING reached after xrEndSession
  bool sessionLost = false;
  uint64_t framesWaited = 0, framesSubmitted = 0;
  uint64_t headTrackedFrames = 0;
  uint64_t handValidFrames[2] = {0, 0};  // frames whose grip pose was valid, per hand
  uint64_t handLostFrames[2] = {0, 0};   // frames (while focused) with the hand's pose not valid
  float calibratedScale = 1.0f;
  bool calibrated = false;
  uint32_t vulkanValidationMessages = 0;
  uint64_t mirrorFrames = 0;    // frames the mirror window presented
  uint64_t bodyPoseFrames = 0;  // frames whose pose came from options.bodyPose
  FingerReport fingers;
  double meanFrameMs = 0.0;  // wall time per loop iteration while rendering
  std::string error;         // "" when the run ended normally
};

// Runs until the session ends. Setup failures, failing calls and a lost session (sessionLost)
// set report.error; whatever was measured until then is reported too.
XrLoopReport runXrLoop(const XrLoopOptions& options);

}  // namespace embody::xr
