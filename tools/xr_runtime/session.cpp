// Session lifecycle and state machine, frame timing, reference spaces and view location.
#include <cmath>
#include <cstdlib>
#include <ctime>

#include "tools/xr_runtime/runtime.h"
#include "tools/xr_runtime/two_call.h"

namespace embody::xr_runtime {

namespace {

uint64_t envCount(const char* name) {
  const char* e = std::getenv(name);
  if (!e || !*e) return 0;
  char* end = nullptr;
  const unsigned long long v = std::strtoull(e, &end, 10);
  return end && *end == '\0' ? v : 0;
}

float ipdMetres() {
  if (const char* e = std::getenv("EMBODY_XR_IPD")) {
    const float v = std::strtof(e, nullptr);
    if (std::isfinite(v) && v > 0.04f && v < 0.09f) return v;
  }
  return 0.064f;
}

// Asymmetric per-eye field of view: each eye sees more on its outer side (like most HMDs).
XrFovf eyeFov(int eye) {
  XrFovf f;
  f.angleUp = 0.82f;
  f.angleDown = -0.90f;
  f.angleLeft = eye == 0 ? -0.90f : -0.76f;
  f.angleRight = eye == 0 ? 0.76f : 0.90f;
  return f;
}

bool poseValid(const XrPosef& p) {
  const float n = std::sqrt(p.orientation.x * p.orientation.x + p.orientation.y * p.orientation.y +
                            p.orientation.z * p.orientation.z + p.orientation.w * p.orientation.w);
  return std::isfinite(n) && std::fabs(n - 1.0f) < 1e-3f && std::isfinite(p.position.x) &&
         std::isfinite(p.position.y) && std::isfinite(p.position.z);
}

// Runtime-initiated or application-requested exit: walk the states down to STOPPING.
void requestExit(Instance& inst, Session& s, XrTime t) {
  s.exitRequested = true;
  if (s.state == XR_SESSION_STATE_FOCUSED) inst.setState(s, XR_SESSION_STATE_VISIBLE, t);
  if (s.state == XR_SESSION_STATE_VISIBLE) inst.setState(s, XR_SESSION_STATE_SYNCHRONIZED, t);
  if (s.state == XR_SESSION_STATE_READY) inst.setState(s, XR_SESSION_STATE_SYNCHRONIZED, t);
  if (s.state == XR_SESSION_STATE_SYNCHRONIZED) inst.setState(s, XR_SESSION_STATE_STOPPING, t);
}

// A system-level recenter (EMBODY_XR_SPACE_CHANGE_FRAMES): the runtime announces that LOCAL and
// STAGE change at the next frame's display time. The poses themselves stay put: the event is what
// the test checks the application reacts to.
void pushSpaceChange(Instance& inst, Session& s, XrTime t) {
  for (XrReferenceSpaceType type : {XR_REFERENCE_SPACE_TYPE_LOCAL, XR_REFERENCE_SPACE_TYPE_STAGE}) {
    XrEventDataReferenceSpaceChangePending ev{XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING};
    ev.session = reinterpret_cast<XrSession>(&s);
    ev.referenceSpaceType = type;
    ev.changeTime = t + kFramePeriodNs;
    ev.poseValid = XR_TRUE;
    ev.poseInPreviousSpace = toXr(Pose{});
    inst.pushEvent(&ev, sizeof(ev));
  }
}

XrResult XRAPI_CALL CreateSession(XrInstance instance, const XrSessionCreateInfo* ci, XrSession* out) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_SESSION_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (ci->systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  std::lock_guard lock(inst->mutex);
  const XrGraphicsBindingVulkanKHR* binding = nullptr;
  for (auto* n = static_cast<const XrBaseInStructure*>(ci->next); n; n = n->next)
    if (n->type == XR_TYPE_GRAPHICS_BINDING_VULKAN_KHR)
      binding = reinterpret_cast<const XrGraphicsBindingVulkanKHR*>(n);
  if (!binding) return XR_ERROR_GRAPHICS_DEVICE_INVALID;  // headless sessions are not offered
  if (!inst->graphicsRequirementsQueried) return XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING;
  if (!binding->instance || !binding->physicalDevice || !binding->device)
    return XR_ERROR_GRAPHICS_DEVICE_INVALID;
  if (!inst->sessions.empty()) return XR_ERROR_LIMIT_REACHED;
  auto s = std::make_unique<Session>();
  s->instance = inst;
  s->vkInstance = binding->instance;
  s->vkPhysicalDevice = binding->physicalDevice;
  s->vkDevice = binding->device;
  s->queueFamily = binding->queueFamilyIndex;
  s->queueIndex = binding->queueIndex;
  if (!initSessionVulkan(*s)) return XR_ERROR_GRAPHICS_DEVICE_INVALID;
  s->startTime = nowNs();
  if (const char* c = std::getenv("EMBODY_XR_CAPTURE")) s->captureDir = c;
  s->frameLimit = envCount("EMBODY_XR_FRAMES");
  s->lossAt = envCount("EMBODY_XR_LOSS_FRAMES");
  s->spaceChangeAt = envCount("EMBODY_XR_SPACE_CHANGE_FRAMES");
  s->headUntracked = envCount("EMBODY_XR_HEAD_UNTRACKED") != 0;
  const BodySample first = inst->poses.sample(0.0);
  const Pose head = first.head.valid ? Pose(first.head) : Pose{{0.0f, 1.6f, 0.0f}, {1, 0, 0, 0}};
  const glm::vec3 fwd = head.orientation * glm::vec3(0, 0, -1);
  s->localOrigin = {head.position, glm::angleAxis(std::atan2(-fwd.x, -fwd.z), glm::vec3(0, 1, 0))};
  s->lastHead = {head, true};
  Session* raw = s.release();
  registerHandle(inst->sessions, raw);
  const XrTime t = nowNs();
  inst->setState(*raw, XR_SESSION_STATE_IDLE, t);
  inst->setState(*raw, XR_SESSION_STATE_READY, t);
  *out = reinterpret_cast<XrSession>(raw);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(CreateSession)

XrResult XRAPI_CALL DestroySession(XrSession session) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  unregisterHandle(inst->sessions, s);
  destroySessionChildren(*s);
  forgetSessionActions(*s);
  releaseSessionVulkan(*s);
  // Events of a destroyed session must not reach the application.
  std::erase_if(inst->events, [&](const Event& e) {
    const auto* base = reinterpret_cast<const XrEventDataBaseHeader*>(&e.data);
    if (base->type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED)
      return reinterpret_cast<const XrEventDataSessionStateChanged*>(&e.data)->session == session;
    if (base->type == XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED)
      return reinterpret_cast<const XrEventDataInteractionProfileChanged*>(&e.data)->session == session;
    if (base->type == XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING)
      return reinterpret_cast<const XrEventDataReferenceSpaceChangePending*>(&e.data)->session == session;
    return false;
  });
  delete s;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroySession)

XrResult XRAPI_CALL BeginSession(XrSession session, const XrSessionBeginInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_SESSION_BEGIN_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (info->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (s->running) return XR_ERROR_SESSION_RUNNING;
  if (s->state != XR_SESSION_STATE_READY) return XR_ERROR_SESSION_NOT_READY;
  s->running = true;
  s->framesWaited = s->framesBegun = s->framesEnded = 0;
  s->frameBegun = false;
  s->waitedNotBegun = 0;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(BeginSession)

XrResult XRAPI_CALL EndSession(XrSession session) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (s->state != XR_SESSION_STATE_STOPPING) return XR_ERROR_SESSION_NOT_STOPPING;
  s->running = false;
  s->frameBegun_cv.notify_all();  // a blocked xrWaitFrame returns XR_ERROR_SESSION_NOT_RUNNING
  const XrTime t = nowNs();
  inst->setState(*s, XR_SESSION_STATE_IDLE, t);
  if (s->exitRequested) inst->setState(*s, XR_SESSION_STATE_EXITING, t);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(EndSession)

XrResult XRAPI_CALL RequestExitSession(XrSession session) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  requestExit(*inst, *s, nowNs());
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(RequestExitSession)

XrResult XRAPI_CALL WaitFrame(XrSession session, const XrFrameWaitInfo* info, XrFrameState* state) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if ((info && info->type != XR_TYPE_FRAME_WAIT_INFO) || !state || state->type != XR_TYPE_FRAME_STATE)
    return XR_ERROR_VALIDATION_FAILURE;
  XrTime wakeAt = 0;
  {
    std::unique_lock lock(inst->mutex);
    if (s->lost) return XR_ERROR_SESSION_LOST;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    // "A subsequent xrWaitFrame call must block until the previous frame has been begun with
    // xrBeginFrame" (OpenXR 1.0, xrWaitFrame): another thread's xrBeginFrame releases it.
    s->frameBegun_cv.wait(lock, [&] { return s->waitedNotBegun == 0 || !s->running || s->lost; });
    if (s->lost) return XR_ERROR_SESSION_LOST;
    if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
    // Display times sit on a 90 Hz grid anchored at session start. The frame is predicted one
    // period after the next vsync; the call returns at the vsync before it (throttling the
    // application to 90 Hz when it is faster, never blocking when it is slower).
    const XrTime now = nowNs();
    if (s->traceStart == 0) s->traceStart = now;
    const XrTime since = now - s->startTime;
    XrTime predicted = s->startTime + (since / kFramePeriodNs + 2) * kFramePeriodNs;
    if (predicted <= s->lastPredicted) predicted = s->lastPredicted + kFramePeriodNs;
    s->lastPredicted = predicted;
    wakeAt = predicted - kFramePeriodNs;
    ++s->framesWaited;
    ++s->waitedNotBegun;
    state->predictedDisplayTime = predicted;
    state->predictedDisplayPeriod = kFramePeriodNs;
    state->shouldRender =
        (s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED) ? XR_TRUE : XR_FALSE;
  }
  const XrTime now = nowNs();
  if (wakeAt > now) {
    timespec ts{static_cast<time_t>((wakeAt - now) / 1000000000),
                static_cast<long>((wakeAt - now) % 1000000000)};
    nanosleep(&ts, nullptr);
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(WaitFrame)

XrResult XRAPI_CALL BeginFrame(XrSession session, const XrFrameBeginInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (info && info->type != XR_TYPE_FRAME_BEGIN_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (s->waitedNotBegun == 0) return XR_ERROR_CALL_ORDER_INVALID;
  --s->waitedNotBegun;
  s->frameBegun_cv.notify_all();  // the next xrWaitFrame may return (never tied to xrEndFrame)
  ++s->framesBegun;
  if (s->frameBegun) return XR_FRAME_DISCARDED;  // the previous frame was never ended
  s->frameBegun = true;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(BeginFrame)

XrResult checkSubImage(const XrSwapchainSubImage& sub, bool wantDepth) {
  Swapchain* sc = findSwapchain(sub.swapchain);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (sc->depth != wantDepth) return XR_ERROR_VALIDATION_FAILURE;
  if (sc->lastReleased < 0) return XR_ERROR_LAYER_INVALID;
  const auto& r = sub.imageRect;
  if (r.offset.x < 0 || r.offset.y < 0 || r.extent.width <= 0 || r.extent.height <= 0 ||
      uint32_t(r.offset.x + r.extent.width) > sc->info.width ||
      uint32_t(r.offset.y + r.extent.height) > sc->info.height)
    return XR_ERROR_SWAPCHAIN_RECT_INVALID;
  if (sub.imageArrayIndex >= sc->info.arraySize) return XR_ERROR_VALIDATION_FAILURE;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EndFrame(XrSession session, const XrFrameEndInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_FRAME_END_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->running) return XR_ERROR_SESSION_NOT_RUNNING;
  if (!s->frameBegun) return XR_ERROR_CALL_ORDER_INVALID;
  if (info->displayTime <= 0) return XR_ERROR_TIME_INVALID;
  if (info->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE)
    return XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED;
  if (info->layerCount > XR_MIN_COMPOSITION_LAYERS_SUPPORTED) return XR_ERROR_LAYER_LIMIT_EXCEEDED;
  if (info->layerCount > 0 && !info->layers) return XR_ERROR_VALIDATION_FAILURE;
  const XrCompositionLayerProjection* firstProjection = nullptr;
  for (uint32_t i = 0; i < info->layerCount; ++i) {
    const XrCompositionLayerBaseHeader* layer = info->layers[i];
    if (!layer) return XR_ERROR_LAYER_INVALID;
    if (!findSpace(layer->space)) return XR_ERROR_HANDLE_INVALID;
    if (layer->type == XR_TYPE_COMPOSITION_LAYER_PROJECTION) {
      const auto* proj = reinterpret_cast<const XrCompositionLayerProjection*>(layer);
      if (proj->viewCount != 2 || !proj->views) return XR_ERROR_VALIDATION_FAILURE;
      for (uint32_t v = 0; v < 2; ++v) {
        if (proj->views[v].type != XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW)
          return XR_ERROR_VALIDATION_FAILURE;
        if (!poseValid(proj->views[v].pose)) return XR_ERROR_POSE_INVALID;
        if (XrResult r = checkSubImage(proj->views[v].subImage, false); XR_FAILED(r)) return r;
        for (auto* n = static_cast<const XrBaseInStructure*>(proj->views[v].next); n; n = n->next)
          if (n->type == XR_TYPE_COMPOSITION_LAYER_DEPTH_INFO_KHR &&
              inst->extension(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME)) {
            const auto* d = reinterpret_cast<const XrCompositionLayerDepthInfoKHR*>(n);
            if (XrResult r = checkSubImage(d->subImage, true); XR_FAILED(r)) return r;
            if (!(d->minDepth >= 0.0f && d->maxDepth <= 1.0f && d->minDepth < d->maxDepth) ||
                !std::isfinite(d->nearZ) || !std::isfinite(d->farZ) || d->nearZ == d->farZ)
              return XR_ERROR_VALIDATION_FAILURE;
          }
      }
      if (!firstProjection) firstProjection = proj;
    } else if (layer->type == XR_TYPE_COMPOSITION_LAYER_QUAD) {
      const auto* quad = reinterpret_cast<const XrCompositionLayerQuad*>(layer);
      if (!poseValid(quad->pose)) return XR_ERROR_POSE_INVALID;
      if (XrResult r = checkSubImage(quad->subImage, false); XR_FAILED(r)) return r;
    } else {
      return XR_ERROR_LAYER_INVALID;
    }
  }
  if (firstProjection) {
    const auto& sub = firstProjection->views[0].subImage;
    Swapchain* sc = findSwapchain(sub.swapchain);
    captureLeftEye(*s, *sc, static_cast<uint32_t>(sc->lastReleased), sub.imageRect, sub.imageArrayIndex);
  }
  s->frameBegun = false;
  ++s->framesEnded;
  const XrTime t = nowNs();
  if (s->framesEnded == 1 && s->state == XR_SESSION_STATE_READY && !s->exitRequested) {
    // The first frame reached the "compositor": the application is shown and has input focus.
    inst->setState(*s, XR_SESSION_STATE_SYNCHRONIZED, t);
    inst->setState(*s, XR_SESSION_STATE_VISIBLE, t);
    inst->setState(*s, XR_SESSION_STATE_FOCUSED, t);
  }
  if (s->spaceChangeAt && s->framesEnded == s->spaceChangeAt) pushSpaceChange(*inst, *s, t);
  if (s->lossAt && s->framesEnded == s->lossAt) {
    inst->setState(*s, XR_SESSION_STATE_LOSS_PENDING, t);
    s->lost = true;
    s->frameBegun_cv.notify_all();
  } else if (s->frameLimit && s->framesEnded == s->frameLimit && !s->exitRequested) {
    requestExit(*inst, *s, t);
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(EndFrame)

// ---- spaces ---------------------------------------------------------------------------------

XrResult XRAPI_CALL EnumerateReferenceSpaces(XrSession session, uint32_t capacity, uint32_t* count,
                                             XrReferenceSpaceType* spaces) {
  if (!findSession(session)) return XR_ERROR_HANDLE_INVALID;
  static constexpr XrReferenceSpaceType kTypes[] = {
      XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL, XR_REFERENCE_SPACE_TYPE_STAGE};
  return twoCall(capacity, count, spaces, 3, [](XrReferenceSpaceType* t, size_t i) { *t = kTypes[i]; });
}
EMBODY_XR_ENTRY(EnumerateReferenceSpaces)

XrResult XRAPI_CALL CreateReferenceSpace(XrSession session, const XrReferenceSpaceCreateInfo* ci,
                                         XrSpace* out) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_REFERENCE_SPACE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_VIEW &&
      ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_LOCAL &&
      ci->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE)
    return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  if (!poseValid(ci->poseInReferenceSpace)) return XR_ERROR_POSE_INVALID;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  auto* sp = new Space;
  sp->session = s;
  sp->kind = SpaceKind::Reference;
  sp->refType = ci->referenceSpaceType;
  sp->offset = fromXr(ci->poseInReferenceSpace);
  return publishHandle(s->spaces, sp, out);
}
EMBODY_XR_ENTRY(CreateReferenceSpace)

XrResult XRAPI_CALL GetReferenceSpaceBoundsRect(XrSession session, XrReferenceSpaceType type,
                                                XrExtent2Df* bounds) {
  if (!findSession(session)) return XR_ERROR_HANDLE_INVALID;
  if (!bounds) return XR_ERROR_VALIDATION_FAILURE;
  if (type == XR_REFERENCE_SPACE_TYPE_STAGE) {
    *bounds = {3.0f, 3.0f};  // a 3 m x 3 m play area centred on the stage origin
    return XR_SUCCESS;
  }
  if (type != XR_REFERENCE_SPACE_TYPE_VIEW && type != XR_REFERENCE_SPACE_TYPE_LOCAL)
    return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  *bounds = {0.0f, 0.0f};
  return XR_SPACE_BOUNDS_UNAVAILABLE;
}
EMBODY_XR_ENTRY(GetReferenceSpaceBoundsRect)

XrResult XRAPI_CALL DestroySpace(XrSpace space) {
  Instance* inst = nullptr;
  Space* sp = findSpace(space, &inst);
  if (!sp) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  unregisterHandle(sp->session->spaces, sp);
  delete sp;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroySpace)

struct Relative {
  Pose pose;
  bool valid = false, tracked = false;
};

Relative locateRelative(Session& s, const Space& space, const Space& base, XrTime t) {
  const Located a = locateInStage(s, space, t), b = locateInStage(s, base, t);
  Relative r;
  r.valid = a.valid && b.valid;
  r.tracked = r.valid && a.tracked && b.tracked;
  if (r.valid) r.pose = b.pose.inverse() * a.pose;
  return r;
}

XrResult XRAPI_CALL LocateSpace(XrSpace space, XrSpace baseSpace, XrTime time, XrSpaceLocation* location) {
  Instance* inst = nullptr;
  Space* sp = findSpace(space, &inst);
  Space* base = findSpace(baseSpace);
  if (!sp || !base) return XR_ERROR_HANDLE_INVALID;
  if (!location || location->type != XR_TYPE_SPACE_LOCATION) return XR_ERROR_VALIDATION_FAILURE;
  if (sp->session != base->session) return XR_ERROR_VALIDATION_FAILURE;
  if (time <= 0) return XR_ERROR_TIME_INVALID;
  std::lock_guard lock(inst->mutex);
  Session& s = *sp->session;
  if (s.lost) return XR_ERROR_SESSION_LOST;
  const Relative r = locateRelative(s, *sp, *base, time);
  location->locationFlags = 0;
  location->pose = toXr(Pose{});
  if (r.valid) {
    location->pose = toXr(r.pose);
    location->locationFlags = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT;
    if (r.tracked)
      location->locationFlags |=
          XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT;
  }
  for (auto* n = static_cast<XrBaseOutStructure*>(location->next); n; n = n->next) {
    if (n->type != XR_TYPE_SPACE_VELOCITY) continue;
    auto* vel = reinterpret_cast<XrSpaceVelocity*>(n);
    vel->velocityFlags = 0;
    vel->linearVelocity = {0, 0, 0};
    vel->angularVelocity = {0, 0, 0};
    // Central difference over +-5 ms of the same relative pose.
    constexpr XrTime kDt = 5000000;
    const Relative a = locateRelative(s, *sp, *base, time - kDt),
                   b = locateRelative(s, *sp, *base, time + kDt);
    if (a.valid && b.valid) {
      const float dt = 2.0f * kDt * 1e-9f;
      const glm::vec3 lin = (b.pose.position - a.pose.position) / dt;
      glm::quat dq = b.pose.orientation * glm::conjugate(a.pose.orientation);
      if (dq.w < 0) dq = -dq;
      const glm::vec3 ang = glm::axis(dq) * (glm::angle(dq) / dt);
      vel->linearVelocity = {lin.x, lin.y, lin.z};
      vel->angularVelocity = {std::isfinite(ang.x) ? ang.x : 0.0f, std::isfinite(ang.y) ? ang.y : 0.0f,
                              std::isfinite(ang.z) ? ang.z : 0.0f};
      vel->velocityFlags = XR_SPACE_VELOCITY_LINEAR_VALID_BIT | XR_SPACE_VELOCITY_ANGULAR_VALID_BIT;
    }
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(LocateSpace)

XrResult XRAPI_CALL LocateViews(XrSession session, const XrViewLocateInfo* info, XrViewState* viewState,
                                uint32_t capacity, uint32_t* count, XrView* views) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_VIEW_LOCATE_INFO || !viewState || viewState->type != XR_TYPE_VIEW_STATE)
    return XR_ERROR_VALIDATION_FAILURE;
  if (info->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (info->displayTime <= 0) return XR_ERROR_TIME_INVALID;
  Space* base = findSpace(info->space);
  if (!base || base->session != s) return XR_ERROR_HANDLE_INVALID;
  if (views)
    for (uint32_t i = 0; i < capacity && i < 2; ++i)
      if (views[i].type != XR_TYPE_VIEW) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  Space head;
  head.session = s;
  head.refType = XR_REFERENCE_SPACE_TYPE_VIEW;
  const Relative r = locateRelative(*s, head, *base, info->displayTime);
  viewState->viewStateFlags = 0;
  if (r.valid) {
    viewState->viewStateFlags = XR_VIEW_STATE_ORIENTATION_VALID_BIT | XR_VIEW_STATE_POSITION_VALID_BIT;
    if (r.tracked)
      viewState->viewStateFlags |= XR_VIEW_STATE_ORIENTATION_TRACKED_BIT | XR_VIEW_STATE_POSITION_TRACKED_BIT;
  }
  const float halfIpd = 0.5f * ipdMetres();
  return twoCall(capacity, count, views, 2, [&](XrView* v, size_t eye) {
    const Pose eyeInHead{{eye == 0 ? -halfIpd : halfIpd, 0.0f, 0.0f}, {1, 0, 0, 0}};
    v->pose = toXr(r.pose * eyeInHead);
    v->fov = eyeFov(static_cast<int>(eye));
  });
}
EMBODY_XR_ENTRY(LocateViews)

}  // namespace

void destroySessionChildren(Session& s) {
  for (Swapchain* sc : s.swapchains) {
    destroySwapchainImages(*sc);
    delete sc;
  }
  for (Space* sp : s.spaces) delete sp;
  for (HandTracker* h : s.handTrackers) delete h;
}

double traceSeconds(const Session& s, XrTime t) {
  return static_cast<double>(t - (s.traceStart != 0 ? s.traceStart : s.startTime)) * 1e-9;
}

Located locateInStage(Session& s, const Space& space, XrTime t) {
  const BodySample body = s.instance->poses.sample(traceSeconds(s, t));
  Located base;
  if (space.kind == SpaceKind::Action) {
    base = actionPoseInStage(s, space, body);
  } else {
    switch (space.refType) {
      case XR_REFERENCE_SPACE_TYPE_STAGE:
        base = {Pose{}, true, true};
        break;
      case XR_REFERENCE_SPACE_TYPE_LOCAL:
        base = {s.localOrigin, true, true};
        break;
      default:  // VIEW: the head; while tracking is lost, the last known pose, valid but untracked
        if (body.head.valid) {
          s.lastHead = body.head;
          base = {body.head, true, !s.headUntracked};
        } else {
          base = {s.lastHead, true, false};
        }
        break;
    }
  }
  if (base.valid) base.pose = base.pose * space.offset;
  return base;
}

}  // namespace embody::xr_runtime
