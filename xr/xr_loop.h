#pragma once
// The headset loop behind `embody xr`: OpenXR system + session + input, the avatar rendered in
// first person into the runtime's swapchains (one pass per eye), gizmos at the tracked hands.
//
// Per frame: xrWaitFrame -> xrBeginFrame -> trackers located at the predicted display time ->
// submitted to the IK thread (runtime::IkThread running `solveBody`) -> the render thread acquires
// the swapchain images and starts the renderer's frame while it solves -> the join takes the
// newest solved body, never waiting past submit + ikBudgetSeconds -> the hands are late-latched
// (controllers located again, hand joints moved rigidly onto them, xr/hand_late_latch.h) -> the
// fingers (XR_EXT_hand_tracking on humanoid finger bones, avatar::FingerRetargetJob) -> skinning,
// one pass per eye -> xrEndFrame. Without `solveBody` (or before its first body) the avatar
// stands in its rest pose under the head (scaled by the HMD-height calibration).
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"
#include "runtime/frame_stats.h"
#include "runtime/ik_stage.h"
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
  // The body, run on the IK thread: given a frame's tracker sample (world space, recentered: head,
  // wrists) fill `out` (out.pose: the posed skeleton in the world; out.targets: what it was solved
  // for; out.stats.sequence 0 while there is no body yet). Unset: the rest pose under the head.
  std::function<void(const tracking::PoseSample& sample, runtime::SolvedFrame& out)> solveBody;
  // The join: the render thread takes the newest solved body at submit + this, never later.
  double ikBudgetSeconds = 0.001;
  bool lateLatch = true;  // move the solved hands onto the controllers located again before skinning
  // Called on the render thread with each frame's body as it is shown (after the late latch and
  // the fingers, just before skinning; world space) and the frame's predicted display time in
  // seconds: `embody xr --export` records it.
  std::function<void(const avatar::SkeletonPose& shown, double displaySeconds)> onBodyShown;
  // Called on the IK thread before the next solve after each recenter (the world moved under the
  // user): e.g. a seated body places its seat again (runtime::TrackedAvatarBody::reset).
  std::function<void()> onRecenter;
  // Set (e.g. by a SIGINT handler) to end the session the OpenXR way: xrRequestExitSession ->
  // STOPPING -> xrEndSession -> EXITING.
  const std::atomic<bool>* stopRequested = nullptr;
};

// The IK thread as the render thread saw it.
struct IkJoinReport {
  uint64_t submitted = 0;     // samples handed to the IK thread
  uint64_t joins = 0;         // frames that joined (rendered with a body hook)
  uint64_t lateJoins = 0;     // joins that reached the deadline before this frame's solve ended
  const char* priority = "normal";  // the IK thread's scheduling: "realtime", "nice -10" or "normal"
  std::vector<double> waitMs;       // time blocked at each join
  std::vector<double> bodyAgeMs;    // tracker-to-photon age of the body shown (locate -> display)
  std::vector<double> handAgeMs;    // the same for the late-latched hands
};

struct LateLatchReport {
  uint64_t frames = 0;  // hands latched (per hand and frame)
  float maxErrorM = 0.0f;  // hand joint to the located wrist afterwards, worst
  std::vector<double> correctionMm;  // how far each latch moved the hand
};

struct XrLoopReport {
  std::string runtime, system, interactionProfile;
  bool usedStage = false, handTracking = false, depthSubmitted = false;
  std::vector<std::string> states;  // session states in the order they came
  bool reachedFocused = false;
  bool endedCleanly = false;  // EXITING reached after xrEndSession
  bool sessionLost = false;
  bool stoppedBySignal = false;  // options.stopRequested ended it
  uint64_t framesWaited = 0, framesSubmitted = 0;
  // OpenXR's bits, per frame: valid (usable, maybe inferred) and tracked (actively tracked now).
  uint64_t headValidFrames = 0, headTrackedFrames = 0;
  uint64_t handValidFrames[2] = {0, 0};    // frames whose grip pose was valid, per hand
  uint64_t handTrackedFrames[2] = {0, 0};  // ... and tracked
  uint64_t handLostFrames[2] = {0, 0};     // frames (while focused) with the hand's pose not valid
  float calibratedScale = 1.0f;
  bool calibrated = false;
  uint64_t recenters = 0, runtimeRecenters = 0;  // all recenters; those from REFERENCE_SPACE_CHANGE_PENDING
  uint32_t vulkanValidationMessages = 0;
  uint64_t mirrorFrames = 0;    // frames the mirror window presented
  uint64_t bodyPoseFrames = 0;  // frames whose pose came from options.solveBody
  runtime::StatsRecorder ikFrames;  // each solved body shown, with its render time
  IkJoinReport ik;
  LateLatchReport lateLatch;
  FingerReport fingers;
  double meanFrameMs = 0.0;  // wall time per loop iteration while rendering
  std::string error;         // "" when the run ended normally
};

// Runs until the session ends. Setup failures, failing calls and a lost session (sessionLost)
// set report.error; whatever was measured until then is reported too.
XrLoopReport runXrLoop(const XrLoopOptions& options);

}  // namespace embody::xr
