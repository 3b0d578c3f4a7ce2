#include "xr/xr_session.h"

#include <algorithm>
#include <cstdio>

namespace embody::xr {

const char* sessionStateName(XrSessionState s) {
  switch (s) {
    case XR_SESSION_STATE_IDLE:
      return "IDLE";
    case XR_SESSION_STATE_READY:
      return "READY";
    case XR_SESSION_STATE_SYNCHRONIZED:
      return "SYNCHRONIZED";
    case XR_SESSION_STATE_VISIBLE:
      return "VISIBLE";
    case XR_SESSION_STATE_FOCUSED:
      return "FOCUSED";
    case XR_SESSION_STATE_STOPPING:
      return "STOPPING";
    case XR_SESSION_STATE_LOSS_PENDING:
      return "LOSS_PENDING";
    case XR_SESSION_STATE_EXITING:
      return "EXITING";
    default:
      return "UNKNOWN";
  }
}

Result<std::unique_ptr<XrSessionRunner>> XrSessionRunner::create(XrSystem& system) {
  std::unique_ptr<XrSessionRunner> r(new XrSessionRunner(system));
  if (auto s = r->init(); !s) return Error{s.error()};
  return r;
}

Status XrSessionRunner::init() {
  XrGraphicsBindingVulkan2KHR binding{XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR};
  binding.instance = system_.vkInstance();
  binding.physicalDevice = system_.vkPhysicalDevice();
  binding.device = system_.vkDevice();
  binding.queueFamilyIndex = system_.queueFamily();
  binding.queueIndex = 0;
  XrSessionCreateInfo ci{XR_TYPE_SESSION_CREATE_INFO, &binding};
  ci.systemId = system_.systemId();
  if (XrResult r = xrCreateSession(system_.instance(), &ci, &session_); XR_FAILED(r))
    return Error{"xrCreateSession failed: " + system_.result(r)};

  // STAGE (floor-level origin) when the runtime has one, else LOCAL: poses then start at eye
  // level and calibration cannot read the user's height from the HMD.
  uint32_t n = 0;
  xrEnumerateReferenceSpaces(session_, 0, &n, nullptr);
  std::vector<XrReferenceSpaceType> types(n);
  xrEnumerateReferenceSpaces(session_, n, &n, types.data());
  usingStage_ = std::find(types.begin(), types.end(), XR_REFERENCE_SPACE_TYPE_STAGE) != types.end();
  XrReferenceSpaceCreateInfo si{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  si.poseInReferenceSpace = toXr(Pose{});
  si.referenceSpaceType = usingStage_ ? XR_REFERENCE_SPACE_TYPE_STAGE : XR_REFERENCE_SPACE_TYPE_LOCAL;
  if (XrResult r = xrCreateReferenceSpace(session_, &si, &world_); XR_FAILED(r)) {
    if (!usingStage_) return Error{"cannot create the LOCAL reference space: " + system_.result(r)};
    usingStage_ = false;
    si.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
    if (XrResult r2 = xrCreateReferenceSpace(session_, &si, &world_); XR_FAILED(r2))
      return Error{"cannot create a STAGE or LOCAL reference space: " + system_.result(r2)};
  }
  si.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  if (XrResult r = xrCreateReferenceSpace(session_, &si, &view_); XR_FAILED(r))
    return Error{"cannot create the VIEW reference space: " + system_.result(r)};

  // Swapchain formats in our order of preference: 8-bit sRGB colour (the renderer writes linear
  // values and the format encodes them), 32-bit float depth.
  xrEnumerateSwapchainFormats(session_, 0, &n, nullptr);
  std::vector<int64_t> formats(n);
  xrEnumerateSwapchainFormats(session_, n, &n, formats.data());
  auto pick = [&](std::initializer_list<VkFormat> wanted) -> int64_t {
    for (VkFormat w : wanted)
      if (std::find(formats.begin(), formats.end(), static_cast<int64_t>(w)) != formats.end()) return w;
    return 0;
  };
  const int64_t colorFormat = pick({VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB});
  if (!colorFormat) return Error{"the runtime offers no 8-bit sRGB swapchain format"};
  const int64_t depthFormat = system_.depthLayerEnabled() ? pick({VK_FORMAT_D32_SFLOAT}) : 0;
  for (uint32_t eye = 0; eye < 2; ++eye) {
    if (auto s = createSwapchain(eye, false, colorFormat, color_[eye]); !s) return s;
    if (depthFormat)
      if (auto s = createSwapchain(eye, true, depthFormat, depth_[eye]); !s) return s;
  }
  return {};
}

Status XrSessionRunner::createSwapchain(uint32_t eye, bool depth, int64_t format, EyeSwapchain& out) {
  const auto& v = system_.views()[eye];
  XrSwapchainCreateInfo ci{XR_TYPE_SWAPCHAIN_CREATE_INFO};
  ci.usageFlags = depth ? XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT
                        : (XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_SAMPLED_BIT);
  ci.format = format;
  ci.sampleCount = 1;
  ci.width = v.recommendedImageRectWidth;
  ci.height = v.recommendedImageRectHeight;
  ci.faceCount = 1;
  ci.arraySize = 1;
  ci.mipCount = 1;
  if (XrResult r = xrCreateSwapchain(session_, &ci, &out.handle); XR_FAILED(r))
    return Error{"xrCreateSwapchain failed: " + system_.result(r)};
  out.format = static_cast<VkFormat>(format);
  out.extent = {ci.width, ci.height};
  uint32_t n = 0;
  xrEnumerateSwapchainImages(out.handle, 0, &n, nullptr);
  std::vector<XrSwapchainImageVulkan2KHR> images(n, {XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR});
  if (XrResult r = xrEnumerateSwapchainImages(out.handle, n, &n,
                                              reinterpret_cast<XrSwapchainImageBaseHeader*>(images.data()));
      XR_FAILED(r))
    return Error{"xrEnumerateSwapchainImages failed: " + system_.result(r)};
  for (const auto& img : images) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = img.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = out.format;
    vi.subresourceRange = {
        depth ? VkImageAspectFlags(VK_IMAGE_ASPECT_DEPTH_BIT) : VkImageAspectFlags(VK_IMAGE_ASPECT_COLOR_BIT),
        0, 1, 0, 1};
    SwapchainImage si{img.image, VK_NULL_HANDLE};
    if (vkCreateImageView(system_.vkDevice(), &vi, nullptr, &si.view) != VK_SUCCESS)
      return Error{"vkCreateImageView failed for a swapchain image"};
    out.images.push_back(si);
  }
  return {};
}

XrSessionRunner::~XrSessionRunner() {
  // The GPU may still read the image views of the last frames.
  if (system_.vkDevice()) vkDeviceWaitIdle(system_.vkDevice());
  for (auto* list : {&color_, &depth_})
    for (auto& sc : *list) {
      for (auto& img : sc.images)
        if (img.view) vkDestroyImageView(system_.vkDevice(), img.view, nullptr);
      if (sc.handle) xrDestroySwapchain(sc.handle);
    }
  if (view_) xrDestroySpace(view_);
  if (world_) xrDestroySpace(world_);
  if (session_) {
    // A session still running (an error path) is ended first when the runtime allows it.
    if (running_ && state_ == XR_SESSION_STATE_STOPPING) xrEndSession(session_);
    xrDestroySession(session_);
  }
}

void XrSessionRunner::noteLoss(XrResult r) {
  if (r == XR_ERROR_SESSION_LOST || r == XR_ERROR_INSTANCE_LOST) {
    running_ = false;
    lost_ = finished_ = true;
  }
}

void XrSessionRunner::setState(XrSessionState s) {
  state_ = s;
  history_.push_back(s);
}

Status XrSessionRunner::pollEvents() {
  for (;;) {
    XrEventDataBuffer ev{XR_TYPE_EVENT_DATA_BUFFER};
    const XrResult r = xrPollEvent(system_.instance(), &ev);
    if (r == XR_EVENT_UNAVAILABLE) return {};
    if (r == XR_ERROR_INSTANCE_LOST) {  // the runtime went away: torn down and retried like a loss
      noteLoss(r);
      return {};
    }
    if (XR_FAILED(r)) return Error{"xrPollEvent failed: " + system_.result(r)};
    switch (ev.type) {
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        const auto& e = reinterpret_cast<const XrEventDataSessionStateChanged&>(ev);
        if (e.session != session_) break;
        setState(e.state);
        if (e.state == XR_SESSION_STATE_READY) {
          XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
          bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
          if (XrResult br = xrBeginSession(session_, &bi); XR_FAILED(br))
            return Error{"xrBeginSession failed: " + system_.result(br)};
          running_ = true;
        } else if (e.state == XR_SESSION_STATE_STOPPING) {
          if (XrResult er = xrEndSession(session_); XR_FAILED(er))
            return Error{"xrEndSession failed: " + system_.result(er)};
          running_ = false;
        } else if (e.state == XR_SESSION_STATE_EXITING) {
          finished_ = true;
        } else if (e.state == XR_SESSION_STATE_LOSS_PENDING) {
          // The runtime is losing the device: stop using the session and tear down.
          running_ = false;
          lost_ = true;
          finished_ = true;
        }
        break;
      }
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        running_ = false;
        lost_ = true;
        finished_ = true;
        break;
      case XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED:
        profileChanged_ = true;
        break;
      case XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING: {
        const auto& e = reinterpret_cast<const XrEventDataReferenceSpaceChangePending&>(ev);
        const XrReferenceSpaceType world = usingStage_ ? XR_REFERENCE_SPACE_TYPE_STAGE : XR_REFERENCE_SPACE_TYPE_LOCAL;
        if (e.session == session_ && e.referenceSpaceType == world) worldSpaceChange_ = std::max<XrTime>(e.changeTime, 1);
        break;
      }
      default:
        break;  // events lost, other extensions' events: nothing to do
    }
  }
}

void XrSessionRunner::requestExit() {
  if (exitRequested_) return;
  exitRequested_ = true;
  if (running_) {
    xrRequestExitSession(session_);
  } else if (!finished_) {
    finished_ = true;  // never started (still IDLE): nothing to end
  }
}

XrTime XrSessionRunner::takeWorldSpaceChange() { return std::exchange(worldSpaceChange_, 0); }

bool XrSessionRunner::takeInteractionProfileChanged() {
  return std::exchange(profileChanged_, false);
}

Result<FrameTiming> XrSessionRunner::waitFrame() {
  XrFrameWaitInfo wi{XR_TYPE_FRAME_WAIT_INFO};
  XrFrameState fs{XR_TYPE_FRAME_STATE};
  if (XrResult r = xrWaitFrame(session_, &wi, &fs); XR_FAILED(r)) {
    noteLoss(r);
    return Error{"xrWaitFrame failed: " + system_.result(r)};
  }
  return FrameTiming{fs.predictedDisplayTime, fs.predictedDisplayPeriod, fs.shouldRender == XR_TRUE};
}

Status XrSessionRunner::beginFrame() {
  XrFrameBeginInfo bi{XR_TYPE_FRAME_BEGIN_INFO};
  const XrResult r = xrBeginFrame(session_, &bi);
  if (XR_FAILED(r)) {
    noteLoss(r);
    return Error{"xrBeginFrame failed: " + system_.result(r)};
  }
  return {};
}

Views XrSessionRunner::locateViews(XrTime time) {
  Views out;
  XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
  li.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  li.displayTime = time;
  li.space = world_;
  XrViewState vs{XR_TYPE_VIEW_STATE};
  std::array<XrView, 2> views{{{XR_TYPE_VIEW}, {XR_TYPE_VIEW}}};
  uint32_t n = 0;
  if (XR_FAILED(xrLocateViews(session_, &li, &vs, 2, &n, views.data())) || n != 2) return out;
  out.valid = (vs.viewStateFlags & XR_VIEW_STATE_ORIENTATION_VALID_BIT) &&
              (vs.viewStateFlags & XR_VIEW_STATE_POSITION_VALID_BIT);
  out.tracked = out.valid && (vs.viewStateFlags & XR_VIEW_STATE_ORIENTATION_TRACKED_BIT) &&
                (vs.viewStateFlags & XR_VIEW_STATE_POSITION_TRACKED_BIT);
  for (int i = 0; i < 2; ++i) out.eyes[i] = {fromXr(views[i].pose), views[i].fov};
  return out;
}

Result<uint32_t> XrSessionRunner::acquire(XrSwapchain swapchain) {
  XrSwapchainImageAcquireInfo ai{XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO};
  uint32_t index = 0;
  if (XrResult r = xrAcquireSwapchainImage(swapchain, &ai, &index); XR_FAILED(r))
    return Error{"xrAcquireSwapchainImage failed: " + system_.result(r)};
  XrSwapchainImageWaitInfo wi{XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO};
  wi.timeout = XR_INFINITE_DURATION;
  if (XrResult r = xrWaitSwapchainImage(swapchain, &wi); XR_FAILED(r))
    return Error{"xrWaitSwapchainImage failed: " + system_.result(r)};
  return index;
}

Status XrSessionRunner::release(XrSwapchain swapchain) {
  XrSwapchainImageReleaseInfo ri{XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO};
  if (XrResult r = xrReleaseSwapchainImage(swapchain, &ri); XR_FAILED(r))
    return Error{"xrReleaseSwapchainImage failed: " + system_.result(r)};
  return {};
}

Status XrSessionRunner::endFrame(const FrameTiming& timing, const Views* views, float nearZ, float farZ) {
  std::array<XrCompositionLayerProjectionView, 2> pv{
      {{XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}, {XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW}}};
  std::array<XrCompositionLayerDepthInfoKHR, 2> depth{
      {{XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}, {XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR}}};
  XrCompositionLayerProjection layer{XR_TYPE_COMPOSITION_LAYER_PROJECTION};
  const XrCompositionLayerBaseHeader* layers[] = {
      reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer)};
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.displayTime = timing.predictedDisplayTime;
  ei.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  if (views) {
    for (int i = 0; i < 2; ++i) {
      pv[i].pose = toXr(views->eyes[i].pose);
      pv[i].fov = views->eyes[i].fov;
      pv[i].subImage.swapchain = color_[i].handle;
      pv[i].subImage.imageRect = {{0, 0},
                                  {int32_t(color_[i].extent.width), int32_t(color_[i].extent.height)}};
      if (submitsDepth()) {
        depth[i].subImage.swapchain = depth_[i].handle;
        depth[i].subImage.imageRect = pv[i].subImage.imageRect;
        depth[i].minDepth = 0.0f;
        depth[i].maxDepth = 1.0f;
        depth[i].nearZ = nearZ;
        depth[i].farZ = farZ;
        pv[i].next = &depth[i];
      }
    }
    layer.space = world_;
    layer.viewCount = 2;
    layer.views = pv.data();
    ei.layerCount = 1;
    ei.layers = layers;
  }
  if (XrResult r = xrEndFrame(session_, &ei); XR_FAILED(r)) {
    noteLoss(r);
    return Error{"xrEndFrame failed: " + system_.result(r)};
  }
  if (views) ++framesSubmitted_;
  return {};
}

}  // namespace embody::xr
