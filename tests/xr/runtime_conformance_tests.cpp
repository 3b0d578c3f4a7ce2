// Conformance-style checks of the headless runtime against the OpenXR 1.0 specification's
// "must" rules for the frame loop, the session state calls, swapchain image order and handles:
// applications are tested against this runtime in CI, so it must not accept what real runtimes
// (Monado, SteamVR) reject, nor reject what they accept. Each check names the rule it follows.
#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <thread>
#include <vector>

#include "headless_session.h"

using namespace embody::test;
using Clock = std::chrono::steady_clock;

namespace {

XrSwapchain makeSwapchain(HeadlessSession& h) {
  uint32_t n = 0;
  REQUIRE(xrEnumerateSwapchainFormats(h.session, 0, &n, nullptr) == XR_SUCCESS);
  std::vector<int64_t> formats(n);
  REQUIRE(xrEnumerateSwapchainFormats(h.session, n, &n, formats.data()) == XR_SUCCESS);
  REQUIRE(!formats.empty());
  XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
  ci.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT;
  ci.format = formats[0];
  ci.sampleCount = 1;
  ci.width = ci.height = 32;
  ci.faceCount = ci.arraySize = ci.mipCount = 1;
  XrSwapchain sc = XR_NULL_HANDLE;
  REQUIRE(xrCreateSwapchain(h.session, &ci, &sc) == XR_SUCCESS);
  return sc;
}

XrResult waitFrame(XrSession s, XrFrameState& fs) {
  fs = {XR_TYPE_FRAME_STATE};
  return xrWaitFrame(s, nullptr, &fs);
}

XrResult endFrame(XrSession s, XrTime displayTime) {
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = displayTime;
  ei.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  return xrEndFrame(s, &ei);
}

}  // namespace

TEST_CASE("conformance: a second xrWaitFrame blocks until the previous frame is begun, not until it ends",
          "[xr]") {
  // xrWaitFrame: "A subsequent xrWaitFrame call must block until the previous frame has been
  // begun with xrBeginFrame and must unblock independently of the corresponding call to
  // xrEndFrame." It must be callable from any thread.
  HeadlessSession h;
  h.runUntilFocused();
  XrFrameState first{};
  REQUIRE(waitFrame(h.session, first) == XR_SUCCESS);
  std::atomic<bool> returned{false};
  Clock::time_point returnedAt{};
  XrFrameState second{};
  XrResult secondResult = XR_ERROR_RUNTIME_FAILURE;
  std::thread waiter([&] {
    secondResult = waitFrame(h.session, second);
    returnedAt = Clock::now();
    returned = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(150));  // > 10 display periods
  const bool blocked = !returned.load();
  const auto begunAt = Clock::now();
  REQUIRE(xrBeginFrame(h.session, nullptr) == XR_SUCCESS);
  waiter.join();  // returns without the first frame having ended
  CHECK(blocked);
  CHECK(secondResult == XR_SUCCESS);
  CHECK(returnedAt >= begunAt);
  CHECK(second.predictedDisplayTime > first.predictedDisplayTime);
  REQUIRE(endFrame(h.session, first.predictedDisplayTime) == XR_SUCCESS);
  // xrBeginFrame: XR_FRAME_DISCARDED "if a prior xrBeginFrame has been called without an
  // intervening call to xrEndFrame".
  REQUIRE(xrBeginFrame(h.session, nullptr) == XR_SUCCESS);
  XrFrameState third{};
  REQUIRE(waitFrame(h.session, third) == XR_SUCCESS);
  CHECK(xrBeginFrame(h.session, nullptr) == XR_FRAME_DISCARDED);
  CHECK(endFrame(h.session, third.predictedDisplayTime) == XR_SUCCESS);
}

TEST_CASE("conformance: xrEndSession wakes a blocked xrWaitFrame with XR_ERROR_SESSION_NOT_RUNNING", "[xr]") {
  HeadlessSession h;
  h.runUntilFocused();
  XrFrameState fs{};
  REQUIRE(waitFrame(h.session, fs) == XR_SUCCESS);
  XrResult blockedResult = XR_SUCCESS;
  std::thread waiter([&] {
    XrFrameState s2{};
    blockedResult = waitFrame(h.session, s2);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  REQUIRE(xrRequestExitSession(h.session) == XR_SUCCESS);
  h.poll();  // ... STOPPING
  REQUIRE(xrEndSession(h.session) == XR_SUCCESS);
  waiter.join();
  CHECK(blockedResult == XR_ERROR_SESSION_NOT_RUNNING);
}

TEST_CASE("conformance: frame and session calls out of order get the codes the spec names", "[xr]") {
  HeadlessSession h;
  XrFrameState fs{};
  // Not running yet: xrWaitFrame, xrBeginFrame, xrEndFrame, xrEndSession, xrRequestExitSession.
  CHECK(waitFrame(h.session, fs) == XR_ERROR_SESSION_NOT_RUNNING);
  CHECK(xrBeginFrame(h.session, nullptr) == XR_ERROR_SESSION_NOT_RUNNING);
  CHECK(endFrame(h.session, 1) == XR_ERROR_SESSION_NOT_RUNNING);
  CHECK(xrEndSession(h.session) == XR_ERROR_SESSION_NOT_RUNNING);
  CHECK(xrRequestExitSession(h.session) == XR_ERROR_SESSION_NOT_RUNNING);
  h.runUntilFocused();
  // xrBeginFrame without xrWaitFrame: XR_ERROR_CALL_ORDER_INVALID; xrEndFrame without
  // xrBeginFrame: XR_ERROR_CALL_ORDER_INVALID.
  CHECK(xrBeginFrame(h.session, nullptr) == XR_ERROR_CALL_ORDER_INVALID);
  CHECK(endFrame(h.session, h.lastDisplayTime + 11111111) == XR_ERROR_CALL_ORDER_INVALID);
  REQUIRE(waitFrame(h.session, fs) == XR_SUCCESS);
  REQUIRE(xrBeginFrame(h.session, nullptr) == XR_SUCCESS);
  CHECK(endFrame(h.session, 0) == XR_ERROR_TIME_INVALID);  // displayTime must be > 0
  XrFrameEndInfo additive{XR_TYPE_FRAME_END_INFO};
  additive.displayTime = fs.predictedDisplayTime;
  additive.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_ADDITIVE;  // not offered by this HMD
  CHECK(xrEndFrame(h.session, &additive) == XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED);
  CHECK(endFrame(h.session, fs.predictedDisplayTime) == XR_SUCCESS);
  // xrEndSession before STOPPING: XR_ERROR_SESSION_NOT_STOPPING; xrBeginSession while running:
  // XR_ERROR_SESSION_RUNNING.
  CHECK(xrEndSession(h.session) == XR_ERROR_SESSION_NOT_STOPPING);
  XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
  bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  CHECK(xrBeginSession(h.session, &bi) == XR_ERROR_SESSION_RUNNING);
  REQUIRE(xrRequestExitSession(h.session) == XR_SUCCESS);
  h.poll();
  REQUIRE(xrEndSession(h.session) == XR_SUCCESS);
  // Ended and EXITING: not READY, so xrBeginSession is XR_ERROR_SESSION_NOT_READY.
  CHECK(xrBeginSession(h.session, &bi) == XR_ERROR_SESSION_NOT_READY);
}

TEST_CASE("conformance: swapchain images are acquired, waited on and released in order", "[xr]") {
  HeadlessSession h;
  h.runUntilFocused();
  const XrSwapchain sc = makeSwapchain(h);
  uint32_t imageCount = 0;
  REQUIRE(xrEnumerateSwapchainImages(sc, 0, &imageCount, nullptr) == XR_SUCCESS);
  REQUIRE(imageCount >= 2);
  XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wi.timeout = XR_INFINITE_DURATION;
  // xrWaitSwapchainImage: XR_ERROR_CALL_ORDER_INVALID "if no image has been acquired";
  // xrReleaseSwapchainImage: "if no image has been waited on".
  CHECK(xrWaitSwapchainImage(sc, &wi) == XR_ERROR_CALL_ORDER_INVALID);
  CHECK(xrReleaseSwapchainImage(sc, nullptr) == XR_ERROR_CALL_ORDER_INVALID);
  std::vector<uint32_t> acquired;
  for (uint32_t i = 0; i < imageCount; ++i) {
    uint32_t index = 99;
    REQUIRE(xrAcquireSwapchainImage(sc, nullptr, &index) == XR_SUCCESS);
    acquired.push_back(index);
  }
  CHECK(acquired[0] != acquired[1]);
  uint32_t index = 0;
  // Acquire: XR_ERROR_CALL_ORDER_INVALID "if the next available index has already been acquired
  // and not yet released".
  CHECK(xrAcquireSwapchainImage(sc, nullptr, &index) == XR_ERROR_CALL_ORDER_INVALID);
  CHECK(xrReleaseSwapchainImage(sc, nullptr) == XR_ERROR_CALL_ORDER_INVALID);  // acquired, not waited
  REQUIRE(xrWaitSwapchainImage(sc, &wi) == XR_SUCCESS);
  // "Once a swapchain image has been successfully waited on, it must be released before waiting
  // on the next acquired swapchain image."
  CHECK(xrWaitSwapchainImage(sc, &wi) == XR_ERROR_CALL_ORDER_INVALID);
  REQUIRE(xrReleaseSwapchainImage(sc, nullptr) == XR_SUCCESS);
  REQUIRE(xrAcquireSwapchainImage(sc, nullptr, &index) == XR_SUCCESS);
  CHECK(index == acquired[0]);  // the released image comes round again
  for (uint32_t i = 0; i < imageCount; ++i) {
    REQUIRE(xrWaitSwapchainImage(sc, &wi) == XR_SUCCESS);
    REQUIRE(xrReleaseSwapchainImage(sc, nullptr) == XR_SUCCESS);
  }
  REQUIRE(xrDestroySwapchain(sc) == XR_SUCCESS);
}

TEST_CASE("conformance: destroyed handles are XR_ERROR_HANDLE_INVALID, never a crash", "[xr]") {
  HeadlessSession h;
  h.runUntilFocused();
  const XrSwapchain sc = makeSwapchain(h);
  REQUIRE(xrDestroySwapchain(sc) == XR_SUCCESS);
  uint32_t index = 0;
  CHECK(xrAcquireSwapchainImage(sc, nullptr, &index) == XR_ERROR_HANDLE_INVALID);
  XrReferenceSpaceCreateInfo si{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  si.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
  si.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace local = XR_NULL_HANDLE;
  REQUIRE(xrCreateReferenceSpace(h.session, &si, &local) == XR_SUCCESS);
  REQUIRE(xrDestroySpace(local) == XR_SUCCESS);
  XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
  CHECK(xrLocateSpace(local, h.stage, h.lastDisplayTime, &loc) == XR_ERROR_HANDLE_INVALID);
  CHECK(xrDestroySpace(local) == XR_ERROR_HANDLE_INVALID);
}

TEST_CASE("conformance: a swapchain the device cannot create is refused, never passed to Vulkan", "[xr]") {
  // xrCreateSwapchain returns XR_ERROR_FEATURE_UNSUPPORTED / XR_ERROR_VALIDATION_FAILURE for what
  // the runtime cannot honour. The OpenXR robustness probe (session 20) asked 64 mip levels of a
  // 64 x 64 image: the runtime passed them to vkCreateImage, which corrupted lavapipe's heap
  // (abort), and 100000 layers or storage on an sRGB format came back XR_SUCCESS against
  // Vulkan's valid usage (the validation layer of this suite's instance reports those).
  HeadlessSession h;
  uint32_t n = 0;
  REQUIRE(xrEnumerateSwapchainFormats(h.session, 0, &n, nullptr) == XR_SUCCESS);
  std::vector<int64_t> formats(n);
  REQUIRE(xrEnumerateSwapchainFormats(h.session, n, &n, formats.data()) == XR_SUCCESS);
  const bool srgb = std::find(formats.begin(), formats.end(), int64_t(VK_FORMAT_R8G8B8A8_SRGB)) != formats.end();
  REQUIRE(srgb);
  auto create = [&](auto&& edit) {
    XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
    ci.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT;
    ci.format = VK_FORMAT_R8G8B8A8_SRGB;
    ci.sampleCount = 1;
    ci.width = ci.height = 64;
    ci.faceCount = ci.arraySize = ci.mipCount = 1;
    edit(ci);
    XrSwapchain sc = XR_NULL_HANDLE;
    const XrResult r = xrCreateSwapchain(h.session, &ci, &sc);
    if (XR_SUCCEEDED(r)) CHECK(xrDestroySwapchain(sc) == XR_SUCCESS);
    else CHECK(sc == XR_NULL_HANDLE);
    return r;
  };
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.mipCount = 7; }) == XR_SUCCESS);  // the full chain of 64 x 64
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.mipCount = 8; }) == XR_ERROR_VALIDATION_FAILURE);
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.mipCount = 64; }) == XR_ERROR_VALIDATION_FAILURE);
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.arraySize = 100000; }) == XR_ERROR_FEATURE_UNSUPPORTED);
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.usageFlags |= XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT; }) ==
        XR_ERROR_FEATURE_UNSUPPORTED);
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.faceCount = 6, ci.width = 32; }) == XR_ERROR_VALIDATION_FAILURE);
  CHECK(create([](XrSwapchainCreateInfo& ci) { ci.arraySize = 2; }) == XR_SUCCESS);  // a stereo array stays fine
}
