#include "xr/xr_loop.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include "avatar/hand/finger_retarget.h"
#include "engine/avatar_renderer.h"
#include "engine/desktop_window.h"
#include "engine/device.h"
#include "engine/overlay.h"
#include "xr/xr_input.h"
#include "xr/xr_pose_source.h"
#include "xr/xr_session.h"
#include "xr/xr_system.h"

namespace embody::xr {

namespace {

engine::FovAngles fovOf(const XrFovf& f) {
  return {f.angleLeft, f.angleRight, f.angleUp, f.angleDown};
}

// Midpoint of the eyes with the left eye's orientation: the head pose the body follows.
Pose headFromViews(const Views& v) {
  return {0.5f * (v.eyes[0].pose.position + v.eyes[1].pose.position), v.eyes[0].pose.orientation};
}

// The hand tracker's joints as the finger retargeting job reads them (any rigid frame will do:
// it only uses the joints' placement relative to each other).
void toTrackedHand(const HandState& hs, avatar::TrackedHandJoints& out) {
  out.active = hs.jointsValid;
  for (int j = 0; j < kHandJointCount; ++j) {
    out.position[static_cast<size_t>(j)] = hs.joints[static_cast<size_t>(j)].pose.position;
    out.orientation[static_cast<size_t>(j)] = hs.joints[static_cast<size_t>(j)].pose.orientation;
    out.valid[static_cast<size_t>(j)] = hs.jointsValid && hs.joints[static_cast<size_t>(j)].valid;
  }
}

// Folds one frame's finger output into the run's report.
void recordFingers(const avatar::FingerRig& rig, const avatar::FingerRetargetOutput& out, FingerReport& rep) {
  float sum = 0.0f;
  int n = 0;
  bool any = false, full = true;
  for (int h = 0; h < 2; ++h)
    for (int f = 0; f < avatar::kFingerCount; ++f) {
      const float w = out.weight[static_cast<size_t>(h)][static_cast<size_t>(f)];
      any = any || w > 0.0f;
      for (int s = 0; s < avatar::kFingerSegments; ++s) {
        const size_t b = static_cast<size_t>(f * avatar::kFingerSegments + s);
        if (f == 0 || rig.hands[static_cast<size_t>(h)].bones[b].joint < 0) continue;
        full = full && w >= 1.0f;
        sum += out.bend[static_cast<size_t>(h)][b];
        ++n;
      }
    }
  if (!any) return;
  ++rep.frames;
  if (!full || n == 0) return;
  const float curl = sum / float(n) * 57.29578f;
  rep.curlMinDeg = rep.fullFrames == 0 ? curl : std::min(rep.curlMinDeg, curl);
  rep.curlMaxDeg = rep.fullFrames == 0 ? curl : std::max(rep.curlMaxDeg, curl);
  ++rep.fullFrames;
  rep.curlLastDeg = curl;
}

constexpr float kNear = 0.05f, kFar = 100.0f;
constexpr glm::vec4 kHandColors[2] = {{0.1f, 0.9f, 1.0f, 1.0f}, {1.0f, 0.3f, 0.9f, 1.0f}};

}  // namespace

XrLoopReport runXrLoop(const XrLoopOptions& o) {
  XrLoopReport rep;
  auto fail = [&](const std::string& e) {
    rep.error = e;
    return rep;
  };
  if (!o.avatar) return fail("runXrLoop: no avatar");
  XrSystemOptions so;
  so.vulkanValidation = o.vulkanValidation;
  if (o.mirror) {
    auto exts = engine::DesktopWindow::requiredInstanceExtensions();
    if (!exts) return fail(exts.error());
    so.vulkanInstanceExtensions = *exts;
    so.vulkanDeviceExtensions = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  }
  auto system = XrSystem::create(so);
  if (!system) return fail(system.error());
  XrSystem& sys = **system;
  rep.runtime = sys.runtimeName();
  rep.system = sys.systemName();

  engine::AdoptedDevice ad{sys.vkInstance(), sys.vkPhysicalDevice(), sys.vkDevice(), sys.queueFamily(), 0};
  auto device = engine::Device::adopt(ad);
  if (!device) return fail(device.error());
  std::unique_ptr<engine::DesktopWindow> mirror;
  if (o.mirror) {
    const auto& v = sys.views()[0];
    auto m = engine::DesktopWindow::create(**device, v.recommendedImageRectWidth, v.recommendedImageRectHeight,
                                        "embody xr (mirror)", engine::DesktopWindow::Keys{});
    if (!m) return fail(m.error());
    mirror = std::move(m).value();
  }
  engine::AvatarRendererOptions ro;
  ro.width = ro.height = 16;  // its own offscreen target is unused: the eyes render into swapchains
  auto avatarRenderer = engine::AvatarRenderer::create(**device, *o.avatar, ro);
  if (!avatarRenderer) return fail(avatarRenderer.error());
  engine::AvatarRenderer& ar = **avatarRenderer;

  auto session = XrSessionRunner::create(sys);
  if (!session) return fail(session.error());
  XrSessionRunner& run = **session;
  rep.usedStage = run.usingStage();
  rep.depthSubmitted = run.submitsDepth();
  auto input = XrInput::create(sys, run);
  if (!input) return fail(input.error());
  XrInput& in = **input;
  rep.handTracking = in.handTracking();

  const auto rest = avatar::SkeletonPose::rest(o.avatar->skeleton);
  const glm::vec3 avatarEye(ar.eyePose(rest)[3]);
  AvatarPlacement placement(avatarEye, ar.anchors().forward, o.placement);
  avatar::SkeletonPose pose = rest;
  // Fingers: driven when the runtime tracks hands and the avatar has finger bones.
  const avatar::FingerRig fingerRig = avatar::buildFingerRig(o.avatar->skeleton, o.avatar->humanoid);
  const bool driveFingers = o.fingers && in.handTracking() && fingerRig.mappedBones() > 0;
  rep.fingers.drivenBones = fingerRig.mappedBones();
  avatar::FingerRetargetState fingerState;
  avatar::FingerRetargetOutput fingerOut;
  std::array<avatar::TrackedHandJoints, 2> trackedHands;
  XrTime lastFingerTime = 0;
  XrPoseSource trackers;  // this frame's head and wrists as a tracking sample
  XrTime firstDisplayTime = 0;
  std::vector<engine::LineVertex> lines, overlay;
  bool recentered = false;

  size_t statesSeen = 0;
  double renderSeconds = 0.0;
  std::string error;
  uint64_t rendererFrames = 0;
  while (!run.finished()) {
    if (mirror) {
      mirror->pollEvents();
      if (mirror->closeRequested()) run.requestExit();
    }
    if (auto s = run.pollEvents(); !s) {
      error = s.error();
      break;
    }
    for (; statesSeen < run.stateHistory().size(); ++statesSeen) {
      const XrSessionState st = run.stateHistory()[statesSeen];
      rep.states.push_back(sessionStateName(st));
      rep.reachedFocused = rep.reachedFocused || st == XR_SESSION_STATE_FOCUSED;
      if (o.verbose) std::printf("session state: %s\n", sessionStateName(st));
    }
    if (run.finished()) break;
    if (!run.running()) {  // IDLE before READY, or between STOPPING and EXITING
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    auto timing = run.waitFrame();
    if (!timing) {
      error = timing.error();
      break;
    }
    ++rep.framesWaited;
    const auto t0 = std::chrono::steady_clock::now();
    if (auto s = run.beginFrame(); !s) {
      error = s.error();
      break;
    }
    const XrTime t = timing->predictedDisplayTime;  // poses predicted for when the frame is shown
    if (auto s = in.update(t); !s) {
      error = s.error();
      break;
    }
    Views views = run.locateViews(t);
    const Pose headTracking = headFromViews(views);
    // The recenter button (or R in the mirror) also recalibrates the height: the user stands
    // up straight and presses it. C in the mirror recalibrates only.
    const bool buttonRecenter = in.recenterPressed() || (mirror && mirror->takeRecenterRequest());
    const bool recalibrate = buttonRecenter || (mirror && mirror->takeCalibrateRequest());
    if (views.valid && ((o.recenterAtStart && !recentered) || buttonRecenter)) {
      placement.recenter(headTracking);
      recentered = true;
      if (o.onRecenter) o.onRecenter();
    }
    if (views.valid)
      for (auto& e : views.eyes) e.pose = placement.toWorld(e.pose);
    const Pose head = headFromViews(views);
    if (views.tracked) {
      ++rep.headTrackedFrames;
      if (!placement.calibrated() || recalibrate) placement.calibrate(head);
    }
    for (int h = 0; h < 2; ++h) {
      if (in.hand(h).grip.valid)
        ++rep.handValidFrames[h];
      else if (run.focused())
        ++rep.handLostFrames[h];
    }
    rep.interactionProfile = in.interactionProfile();
    if (!firstDisplayTime) firstDisplayTime = t;
    // Wrists to the world, and from OpenXR's hand-joint axes to the trackers' grip axes.
    auto wrist = [&](int h) {
      TrackedPose p = in.hand(h).wrist;
      if (p.valid) p.pose = placement.toWorld(p.pose);
      p.pose.orientation = trackerHandOrientation(p.pose.orientation, h == 0);
      return p;
    };
    trackers.publish(double(t - firstDisplayTime) * 1e-9, TrackedPose{head, views.valid, views.tracked}, wrist(0),
                     wrist(1));

    bool rendered = false;
    if (timing->shouldRender && views.valid) {
      pose = rest;
      if (o.bodyPose && o.bodyPose(trackers.sample(0.0), pose)) {
        ++rep.bodyPoseFrames;
      } else {
        pose = rest;
        placement.place(o.avatar->skeleton, head, pose);
      }
      if (driveFingers) {  // after the body: the fingers ride on the solved hands
        for (int h = 0; h < 2; ++h) toTrackedHand(in.hand(h), trackedHands[static_cast<size_t>(h)]);
        avatar::FingerRetargetJob job;
        job.skeleton = &o.avatar->skeleton;
        job.rig = &fingerRig;
        job.hands = {&trackedHands[0], &trackedHands[1]};
        job.deltaTime =
            lastFingerTime ? std::clamp(float(double(t - lastFingerTime) * 1e-9), 0.0f, 0.1f) : 0.0f;
        job.state = &fingerState;
        job.pose = &pose;
        job.output = &fingerOut;
        lastFingerTime = t;
        if (job.Validate() && job.Run()) recordFingers(fingerRig, fingerOut, rep.fingers);
      }
      if (auto s = ar.computePose(pose); !s) {
        error = s.error();
        break;
      }
      lines.clear();
      overlay.clear();
      for (int h = 0; h < 2; ++h) {
        const HandState& hs = in.hand(h);
        if (!hs.grip.valid) continue;  // tracking lost: no gizmo rather than a stale one
        engine::Gizmo g;
        g.pose = placement.toWorld(hs.grip.pose).matrix();
        g.color = kHandColors[h];
        g.size = 0.05f;
        engine::appendGizmo(overlay, g);
      }
      std::array<uint32_t, 2> color{}, depth{};
      for (uint32_t e = 0; e < 2; ++e) {
        auto c = run.acquire(run.color()[e].handle);
        if (!c) {
          error = c.error();
          break;
        }
        color[e] = *c;
        if (run.submitsDepth()) {
          auto d = run.acquire(run.depth()[e].handle);
          if (!d) {
            error = d.error();
            break;
          }
          depth[e] = *d;
        }
      }
      if (!error.empty()) break;
      engine::Renderer& r = ar.renderer();
      engine::SceneFrame scene;
      scene.avatar = &ar.gpuAvatar();
      scene.palette = ar.palette();
      scene.firstPerson = true;  // the user's own head is hidden
      scene.lines = lines;
      scene.overlayLines = overlay;  // hand gizmos stay visible through the avatar's hands
      Status st = r.beginFrame();
      if (st) st = r.setScene(scene);
      for (uint32_t e = 0; e < 2 && st; ++e) {
        const auto& sc = run.color()[e];
        engine::PassTarget target;
        target.color = {sc.images[color[e]].image,
                        sc.images[color[e]].view,
                        sc.format,
                        sc.extent,
                        0,
                        1,
                        VK_IMAGE_LAYOUT_UNDEFINED,
                        VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
        if (run.submitsDepth()) {
          const auto& dc = run.depth()[e];
          target.depth =
              engine::TargetImage{dc.images[depth[e]].image,
                               dc.images[depth[e]].view,
                               dc.format,
                               dc.extent,
                               0,
                               1,
                               VK_IMAGE_LAYOUT_UNDEFINED,
                               VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};  // OpenXR's release layout
        }
        const engine::Camera cam =
            engine::cameraFromPose(views.eyes[e].pose.matrix(), fovOf(views.eyes[e].fov), kNear, kFar);
        st = r.drawPass(std::span<const engine::Camera>(&cam, 1), target);
      }
      ++rendererFrames;
      engine::SubmitSync sync;
      if (st && mirror) {
        // The left eye again (its pose, the window's aspect), or the avatar from outside.
        const float vfov = views.eyes[0].fov.angleUp - views.eyes[0].fov.angleDown;
        const engine::Camera cam =
            mirror->thirdPerson()
                ? ar.orbitAround(pose, 0.6f, 0.2f)
                : engine::cameraFromPose(views.eyes[0].pose.matrix(),
                                      engine::FovAngles::symmetric(vfov, mirror->aspect()), kNear, kFar);
        if (mirror->thirdPerson()) {  // the whole avatar from outside: the third-person draw list
          scene.firstPerson = false;
          st = r.setScene(scene);
        }
        auto shown = st ? mirror->draw(r, rendererFrames, cam, sync) : Result<bool>(false);
        if (!shown)
          st = Status(Error{shown.error()});
        else if (*shown)
          ++rep.mirrorFrames;
      }
      if (st) st = r.endFrame(sync);  // submitted before the images are released, as OpenXR requires
      if (st && mirror) st = mirror->present((*device)->queue());
      for (uint32_t e = 0; e < 2; ++e) {
        (void)run.release(run.color()[e].handle);
        if (run.submitsDepth()) (void)run.release(run.depth()[e].handle);
      }
      if (!st) {
        error = st.error();
        break;
      }
      rendered = true;
    }
    if (auto s = run.endFrame(*timing, rendered ? &views : nullptr, kNear, kFar); !s) {
      error = s.error();
      break;
    }
    if (rendered)
      renderSeconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (o.frames > 0 && run.framesSubmitted() >= o.frames) run.requestExit();
  }
  for (; statesSeen < run.stateHistory().size(); ++statesSeen)
    rep.states.push_back(sessionStateName(run.stateHistory()[statesSeen]));
  rep.framesSubmitted = run.framesSubmitted();
  rep.sessionLost = run.lost();
  rep.endedCleanly = !rep.states.empty() && rep.states.back() == std::string("EXITING") && error.empty();
  rep.calibrated = placement.calibrated();
  rep.calibratedScale = placement.scale();
  rep.meanFrameMs = rep.framesSubmitted ? 1000.0 * renderSeconds / double(rep.framesSubmitted) : 0.0;
  // Tear down in dependency order before reading the final validation count.
  ar.renderer().waitIdle();
  input->reset();
  session->reset();
  avatarRenderer->reset();
  mirror.reset();
  device->reset();
  const auto counter = sys.validationCounter();
  system->reset();  // destroying the device and instance can report leaks: count after
  rep.vulkanValidationMessages = counter->load();
  if (error.empty() && rep.sessionLost)
    error = "the OpenXR session was lost (the runtime or the headset went away)";
  rep.error = error;
  return rep;
}

}  // namespace embody::xr
