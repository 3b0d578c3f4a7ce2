#pragma once
// XrSessionRunner: one OpenXR session with its state machine handled completely, the world space
// (STAGE, LOCAL when the runtime has no STAGE), the view space, the per-eye swapchains (colour,
// and depth when XR_KHR_composition_layer_depth is on) and the frame calls.
//
//   runner.pollEvents();                      // READY -> xrBeginSession, STOPPING -> xrEndSession
//   if (runner.running()) {
//     auto frame = runner.waitFrame();        // predicted display time, shouldRender
//     runner.beginFrame();
//     auto views = runner.locateViews(frame->predictedDisplayTime);
//     ... acquire images, render, release ...
//     runner.endFrame(frame, views or nothing);
//   }
//   until runner.finished()                   // EXITING or LOSS_PENDING: tear down
#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "core/result.h"
#include "xr/xr_system.h"

namespace embody::xr {

struct FrameTiming {
  XrTime predictedDisplayTime = 0;
  XrDuration predictedDisplayPeriod = 0;
  bool shouldRender = false;
};

struct EyeView {
  Pose pose;  // in the world space
  XrFovf fov{};
};
struct Views {
  std::array<EyeView, 2> eyes;
  bool valid = false, tracked = false;
};

struct SwapchainImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
};

struct EyeSwapchain {
  XrSwapchain handle = XR_NULL_HANDLE;
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent2D extent{0, 0};
  std::vector<SwapchainImage> images;
};

class XrSessionRunner {
 public:
  static Result<std::unique_ptr<XrSessionRunner>> create(XrSystem& system);
  ~XrSessionRunner();
  XrSessionRunner(const XrSessionRunner&) = delete;
  XrSessionRunner& operator=(const XrSessionRunner&) = delete;

  // Drains the event queue and reacts: READY begins the session, STOPPING ends it, EXITING and
  // LOSS_PENDING finish it. Errors only for calls that fail unexpectedly.
  Status pollEvents();
  bool running() const { return running_; }    // between xrBeginSession and xrEndSession
  bool finished() const { return finished_; }  // EXITING or LOSS_PENDING (or instance loss)
  bool lost() const { return lost_; }
  XrSessionState state() const { return state_; }
  const std::vector<XrSessionState>& stateHistory() const { return history_; }
  bool focused() const { return state_ == XR_SESSION_STATE_FOCUSED; }
  // Asks the runtime to end the session (STOPPING follows); safe in any state.
  void requestExit();
  // True when the runtime's profile changed since the last call (the input re-reads it).
  bool takeInteractionProfileChanged();
  // XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING for the world space (the user recentered
  // in the runtime's own UI): the change time, once; 0 when none is pending.
  XrTime takeWorldSpaceChange();

  Result<FrameTiming> waitFrame();
  Status beginFrame();
  Views locateViews(XrTime time);
  // Submits a frame: with `views` (and images released), one projection layer; without, none.
  Status endFrame(const FrameTiming& timing, const Views* views, float nearZ = 0.05f, float farZ = 100.0f);

  // Colour (and depth) image for each eye: acquire + wait; release after the GPU work that
  // renders into them has been submitted.
  Result<uint32_t> acquire(XrSwapchain swapchain);
  Status release(XrSwapchain swapchain);

  XrSession handle() const { return session_; }
  XrSpace worldSpace() const { return world_; }
  XrSpace viewSpace() const { return view_; }
  bool usingStage() const { return usingStage_; }
  const std::array<EyeSwapchain, 2>& color() const { return color_; }
  const std::array<EyeSwapchain, 2>& depth() const { return depth_; }
  bool submitsDepth() const { return depth_[0].handle != XR_NULL_HANDLE; }
  uint64_t framesSubmitted() const { return framesSubmitted_; }
  XrSystem& system() { return system_; }

 private:
  explicit XrSessionRunner(XrSystem& s) : system_(s) {}
  Status init();
  Status createSwapchain(uint32_t eye, bool depth, int64_t format, EyeSwapchain& out);
  void setState(XrSessionState s);
  void noteLoss(XrResult r);  // XR_ERROR_SESSION_LOST / _INSTANCE_LOST: the session is over

  XrSystem& system_;
  XrSession session_ = XR_NULL_HANDLE;
  XrSpace world_ = XR_NULL_HANDLE, view_ = XR_NULL_HANDLE;
  bool usingStage_ = false;
  std::array<EyeSwapchain, 2> color_{}, depth_{};
  XrSessionState state_ = XR_SESSION_STATE_UNKNOWN;
  std::vector<XrSessionState> history_;
  bool running_ = false, finished_ = false, lost_ = false, exitRequested_ = false;
  bool profileChanged_ = false;
  XrTime worldSpaceChange_ = 0;
  uint64_t framesSubmitted_ = 0;
};

const char* sessionStateName(XrSessionState s);

}  // namespace embody::xr
