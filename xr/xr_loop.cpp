#include "xr/xr_loop.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>
#include <thread>

#include "avatar/hand/finger_retarget.h"
#include "avatar/vrm/secondary_motion.h"
#include "engine/avatar_renderer.h"
#include "engine/desktop_window.h"
#include "engine/device.h"
#include "engine/overlay.h"
#include "runtime/ik_thread.h"
#include "xr/hand_late_latch.h"
#include "xr/xr_input.h"
#include "xr/xr_pose_source.h"
#include "xr/xr_session.h"
#include "xr/xr_system.h"

namespace embody::xr {

namespace {

using SteadyClock = std::chrono::steady_clock;

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

engine::TargetImage swapchainTarget(const EyeSwapchain& sc, uint32_t index, VkImageLayout finalLayout) {
  return {sc.images[index].image, sc.images[index].view, sc.format, sc.extent, 0, 1, VK_IMAGE_LAYOUT_UNDEFINED,
          finalLayout};
}

double msBetween(XrTime later, XrTime earlier) { return double(later - earlier) * 1e-6; }

constexpr float kNear = 0.05f, kFar = 100.0f;
constexpr glm::vec4 kHandColors[2] = {{0.1f, 0.9f, 1.0f, 1.0f}, {1.0f, 0.3f, 0.9f, 1.0f}};
constexpr tracking::TrackerId kHandIds[2] = {tracking::TrackerId::LeftHand, tracking::TrackerId::RightHand};

// What one frame carries from phase to phase.
struct FrameWork {
  FrameTiming timing;
  Views views;
  Pose head;  // world (recentered)
  XrTime locatedAt = 0;  // the runtime's clock when the trackers were located (0: unknown)
  XrTime bodyLocatedAt = 0;   // ... when the trackers of the body shown were located
  XrTime handsLatchedAt = 0;  // ... when the late latch located the controllers
  SteadyClock::time_point submittedAt{};
  bool bodySubmitted = false;
  std::array<uint32_t, 2> color{}, depth{};
  bool imagesAcquired = false;
  SteadyClock::time_point renderStart{};
};

// The headset loop: the objects of one session and one function per frame phase.
class HeadsetLoop {
 public:
  HeadsetLoop(const XrLoopOptions& o, XrLoopReport& rep) : o_(o), rep_(rep) {}
  Status setup();
  void run();
  void finish();

 private:
  Status setupDevice();
  Status setupSession();
  void setupBody();
  bool pollSession();  // false: leave the loop
  Status frame();
  Status locate(FrameWork& f);
  void recenterAndCalibrate(FrameWork& f, const Pose& headTracking);
  void countTracking(const FrameWork& f);
  void publishTrackers(FrameWork& f);
  void submitBody(FrameWork& f);
  Status acquireImages(FrameWork& f);
  void releaseImages(FrameWork& f);
  bool joinBody(FrameWork& f);  // true: a solved body is posed
  void lateLatchHands(FrameWork& f);
  void driveFingers(const FrameWork& f);
  Status render(FrameWork& f);
  Status drawEyes(const FrameWork& f, engine::SceneFrame& scene);
  Status drawMirror(const FrameWork& f, engine::SceneFrame& scene, engine::SubmitSync& sync);
  void appendHandGizmos();
  void applySecondaryMotion(const FrameWork& f);
  void recordFrame(const FrameWork& f);
  void recordAges(const FrameWork& f);

  const XrLoopOptions& o_;
  XrLoopReport& rep_;
  std::unique_ptr<XrSystem> sys_;
  std::unique_ptr<engine::Device> device_;
  std::unique_ptr<engine::DesktopWindow> mirror_;
  std::unique_ptr<engine::AvatarRenderer> renderer_;
  std::unique_ptr<XrSessionRunner> run_;
  std::unique_ptr<XrInput> in_;
  std::unique_ptr<AvatarPlacement> placement_;
  std::unique_ptr<runtime::IkThread> ik_;
  std::atomic<bool> resetBody_{false};
  avatar::SkeletonPose rest_, pose_;
  // VRM spring bones, blinking and look-at on the shown body (after IK, before skinning).
  std::unique_ptr<avatar::SecondaryMotion> secondary_;
  XrTime lastSecondaryTime_ = 0;
  // Fingers: driven when the runtime tracks hands and the avatar has finger bones.
  avatar::FingerRig fingerRig_;
  bool driveFingers_ = false;
  avatar::FingerRetargetState fingerState_;
  avatar::FingerRetargetOutput fingerOut_;
  std::array<avatar::TrackedHandJoints, 2> trackedHands_;
  XrTime lastFingerTime_ = 0;
  XrPoseSource trackers_;  // this frame's head and wrists as a tracking sample
  XrTime firstDisplayTime_ = 0;
  std::array<std::pair<double, XrTime>, 8> locateTimes_{};  // sample time -> when it was located
  std::vector<glm::mat4> globals_;
  std::optional<runtime::FrameStats> shownStats_;  // a newly solved body this frame shows
  std::vector<engine::LineVertex> lines_, overlay_;
  bool recentered_ = false;
  XrTime pendingSpaceChange_ = 0;
  size_t statesSeen_ = 0;
  double renderSeconds_ = 0.0;
  uint64_t rendererFrames_ = 0;
  std::string error_;
};

Status HeadsetLoop::setup() {
  if (!o_.avatar) return Error{"runXrLoop: no avatar"};
  if (auto s = setupDevice(); !s) return s;
  if (auto s = setupSession(); !s) return s;
  setupBody();
  return {};
}

Status HeadsetLoop::setupDevice() {
  XrSystemOptions so;
  so.vulkanValidation = o_.vulkanValidation;
  if (o_.mirror) {
    auto exts = engine::DesktopWindow::requiredInstanceExtensions();
    if (!exts) return Error{exts.error()};
    so.vulkanInstanceExtensions = *exts;
    so.vulkanDeviceExtensions = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  }
  auto system = XrSystem::create(so);
  if (!system) return Error{system.error()};
  sys_ = std::move(system).value();
  rep_.runtime = sys_->runtimeName();
  rep_.system = sys_->systemName();
  engine::AdoptedDevice ad{sys_->vkInstance(), sys_->vkPhysicalDevice(), sys_->vkDevice(), sys_->queueFamily(), 0};
  auto device = engine::Device::adopt(ad);
  if (!device) return Error{device.error()};
  device_ = std::move(device).value();
  if (o_.mirror) {
    const auto& v = sys_->views()[0];
    auto m = engine::DesktopWindow::create(*device_, v.recommendedImageRectWidth, v.recommendedImageRectHeight,
                                           "embody xr (mirror)", engine::DesktopWindow::Keys{});
    if (!m) return Error{m.error()};
    mirror_ = std::move(m).value();
  }
  engine::AvatarRendererOptions ro;
  ro.width = ro.height = 16;  // its own offscreen target is unused: the eyes render into swapchains
  auto avatarRenderer = engine::AvatarRenderer::create(*device_, *o_.avatar, ro);
  if (!avatarRenderer) return Error{avatarRenderer.error()};
  renderer_ = std::move(avatarRenderer).value();
  return {};
}

Status HeadsetLoop::setupSession() {
  auto session = XrSessionRunner::create(*sys_);
  if (!session) return Error{session.error()};
  run_ = std::move(session).value();
  rep_.usedStage = run_->usingStage();
  rep_.depthSubmitted = run_->submitsDepth();
  auto input = XrInput::create(*sys_, *run_);
  if (!input) return Error{input.error()};
  in_ = std::move(input).value();
  rep_.handTracking = in_->handTracking();
  return {};
}

void HeadsetLoop::setupBody() {
  rest_ = avatar::SkeletonPose::rest(o_.avatar->skeleton);
  pose_ = rest_;
  secondary_ = std::make_unique<avatar::SecondaryMotion>(*o_.avatar);
  const glm::vec3 avatarEye(renderer_->eyePose(rest_)[3]);
  placement_ = std::make_unique<AvatarPlacement>(avatarEye, renderer_->anchors().forward, o_.placement);
  fingerRig_ = avatar::buildFingerRig(o_.avatar->skeleton, o_.avatar->humanoid);
  driveFingers_ = o_.fingers && in_->handTracking() && fingerRig_.mappedBones() > 0;
  rep_.fingers.drivenBones = fingerRig_.mappedBones();
  if (!o_.solveBody) return;
  // The IK thread: recenters reach the body on that thread, before its next solve.
  auto process = [this](const tracking::PoseSample& sample, runtime::SolvedFrame& out) {
    if (resetBody_.exchange(false) && o_.onRecenter) o_.onRecenter();
    o_.solveBody(sample, out);
  };
  ik_ = std::make_unique<runtime::IkThread>(process, rest_);
  ik_->start();
}

void HeadsetLoop::run() {
  while (!run_->finished()) {
    if (!pollSession()) break;
    if (!run_->running()) {  // IDLE before READY, or between STOPPING and EXITING
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    if (auto s = frame(); !s) {
      error_ = s.error();
      break;
    }
    if (o_.frames > 0 && run_->framesSubmitted() >= o_.frames) run_->requestExit();
  }
}

bool HeadsetLoop::pollSession() {
  if (mirror_) {
    mirror_->pollEvents();
    if (mirror_->closeRequested()) run_->requestExit();
  }
  if (o_.stopRequested && o_.stopRequested->load()) {
    rep_.stoppedBySignal = true;
    run_->requestExit();  // xrRequestExitSession: the runtime walks the session down to STOPPING
  }
  if (auto s = run_->pollEvents(); !s) {
    error_ = s.error();
    return false;
  }
  if (const XrTime change = run_->takeWorldSpaceChange()) pendingSpaceChange_ = change;
  for (; statesSeen_ < run_->stateHistory().size(); ++statesSeen_) {
    const XrSessionState st = run_->stateHistory()[statesSeen_];
    rep_.states.push_back(sessionStateName(st));
    rep_.reachedFocused = rep_.reachedFocused || st == XR_SESSION_STATE_FOCUSED;
    if (o_.verbose) std::printf("session state: %s\n", sessionStateName(st));
  }
  return !run_->finished();
}

// One frame, phase by phase. The body is solved on the IK thread between submitBody and joinBody
// while this thread acquires the swapchain images and starts the renderer's frame.
Status HeadsetLoop::frame() {
  FrameWork f;
  auto timing = run_->waitFrame();
  if (!timing) return Error{timing.error()};
  f.timing = *timing;
  ++rep_.framesWaited;
  const auto t0 = SteadyClock::now();
  if (auto s = run_->beginFrame(); !s) return s;
  if (auto s = locate(f); !s) return s;
  const bool draw = f.timing.shouldRender && f.views.valid;
  if (draw) {
    submitBody(f);
    if (auto s = acquireImages(f); !s) return s;
    if (auto s = render(f); !s) {
      releaseImages(f);
      return s;
    }
  }
  if (auto s = run_->endFrame(f.timing, draw ? &f.views : nullptr, kNear, kFar); !s) return s;
  if (draw) recordAges(f);
  if (draw) renderSeconds_ += std::chrono::duration<double>(SteadyClock::now() - t0).count();
  return {};
}

// Input and views at the predicted display time (that is the pose prediction), recentering,
// calibration, and the frame's tracker sample.
Status HeadsetLoop::locate(FrameWork& f) {
  const XrTime t = f.timing.predictedDisplayTime;
  if (auto s = in_->update(t); !s) return s;
  f.views = run_->locateViews(t);
  f.locatedAt = sys_->now();
  const Pose headTracking = headFromViews(f.views);
  recenterAndCalibrate(f, headTracking);
  countTracking(f);
  rep_.interactionProfile = in_->interactionProfile();
  if (!firstDisplayTime_) firstDisplayTime_ = t;
  publishTrackers(f);
  return {};
}

void HeadsetLoop::recenterAndCalibrate(FrameWork& f, const Pose& headTracking) {
  // The recenter button (or R in the mirror) also recalibrates the height: the user stands up
  // straight and presses it. C in the mirror recalibrates only. The runtime's own recenter
  // (REFERENCE_SPACE_CHANGE_PENDING on the world space) applies from its change time on.
  const bool buttonRecenter = in_->recenterPressed() || (mirror_ && mirror_->takeRecenterRequest());
  const bool recalibrate = buttonRecenter || (mirror_ && mirror_->takeCalibrateRequest());
  const bool runtimeRecenter = pendingSpaceChange_ && f.timing.predictedDisplayTime >= pendingSpaceChange_;
  if (f.views.valid && ((o_.recenterAtStart && !recentered_) || buttonRecenter || runtimeRecenter)) {
    placement_->recenter(headTracking);
    if (secondary_) secondary_->reset();  // the avatar jumps: the springs restart at rest
    recentered_ = true;
    ++rep_.recenters;
    if (runtimeRecenter) ++rep_.runtimeRecenters, pendingSpaceChange_ = 0;
    resetBody_ = true;
  }
  if (f.views.valid)
    for (auto& e : f.views.eyes) e.pose = placement_->toWorld(e.pose);
  f.head = headFromViews(f.views);
  // Valid is enough: Monado's simulated HMD and 3-dof headsets report a valid, untracked position.
  if (f.views.valid && (!placement_->calibrated() || recalibrate)) placement_->calibrate(f.head);
}

void HeadsetLoop::countTracking(const FrameWork& f) {
  rep_.headValidFrames += f.views.valid ? 1 : 0;
  rep_.headTrackedFrames += f.views.tracked ? 1 : 0;
  for (int h = 0; h < 2; ++h) {
    const TrackedPose& grip = in_->hand(h).grip;
    if (grip.valid)
      ++rep_.handValidFrames[h];
    else if (run_->focused())
      ++rep_.handLostFrames[h];
    rep_.handTrackedFrames[h] += grip.valid && grip.tracked ? 1 : 0;
  }
}

// Wrists to the world, and from OpenXR's hand-joint axes to the trackers' grip axes.
TrackedPose trackerWrist(const HandState& hand, const AvatarPlacement& placement, int h) {
  TrackedPose p = hand.wrist;
  if (p.valid) p.pose = placement.toWorld(p.pose);
  p.pose.orientation = trackerHandOrientation(p.pose.orientation, h == 0);
  return p;
}

void HeadsetLoop::publishTrackers(FrameWork& f) {
  const double time = double(f.timing.predictedDisplayTime - firstDisplayTime_) * 1e-9;
  trackers_.publish(time, TrackedPose{f.head, f.views.valid, f.views.tracked},
                    trackerWrist(in_->hand(0), *placement_, 0), trackerWrist(in_->hand(1), *placement_, 1));
  locateTimes_[trackers_.published() % locateTimes_.size()] = {time, f.locatedAt};
}

void HeadsetLoop::submitBody(FrameWork& f) {
  if (!ik_) return;
  f.submittedAt = SteadyClock::now();
  ik_->submit(trackers_.sample(0.0));
  f.bodySubmitted = true;
  ++rep_.ik.submitted;
}

// Both eyes' colour (and depth) images: acquired while the IK thread solves.
Status HeadsetLoop::acquireImages(FrameWork& f) {
  for (uint32_t e = 0; e < 2; ++e) {
    auto c = run_->acquire(run_->color()[e].handle);
    if (!c) return Error{c.error()};
    f.color[e] = *c;
    if (run_->submitsDepth()) {
      auto d = run_->acquire(run_->depth()[e].handle);
      if (!d) return Error{d.error()};
      f.depth[e] = *d;
    }
  }
  f.imagesAcquired = true;
  return {};
}

void HeadsetLoop::releaseImages(FrameWork& f) {
  if (!f.imagesAcquired) return;
  for (uint32_t e = 0; e < 2; ++e) {
    (void)run_->release(run_->color()[e].handle);
    if (run_->submitsDepth()) (void)run_->release(run_->depth()[e].handle);
  }
  f.imagesAcquired = false;
}

// The join: the newest solved body, waiting at most until submit + the budget.
bool HeadsetLoop::joinBody(FrameWork& f) {
  if (!f.bodySubmitted) return false;
  const auto deadline = f.submittedAt + std::chrono::duration_cast<SteadyClock::duration>(
                                            std::chrono::duration<double>(o_.ikBudgetSeconds));
  const auto waitStart = SteadyClock::now();
  const bool caughtUp = ik_->waitUntilCaughtUp(deadline);
  rep_.ik.waitMs.push_back(std::chrono::duration<double, std::milli>(SteadyClock::now() - waitStart).count());
  ++rep_.ik.joins;
  rep_.ik.lateJoins += caughtUp ? 0 : 1;
  const bool fresh = ik_->acquire();
  const runtime::SolvedFrame& body = ik_->frame();
  if (body.stats.sequence == 0) return false;  // no body yet (before the first valid head)
  pose_ = body.pose;
  for (const auto& [time, at] : locateTimes_)
    if (time == body.stats.sampleTime) f.bodyLocatedAt = at;
  if (fresh) shownStats_ = body.stats;  // recorded with its render time once drawn (recordFrame)
  return true;
}

// Just before skinning: the controllers again, and the solved hands moved rigidly onto them.
void HeadsetLoop::lateLatchHands(FrameWork& f) {
  const XrTime t = f.timing.predictedDisplayTime;
  in_->relocateWrists(t);
  const XrTime latchedAt = sys_->now();
  const runtime::SolvedFrame& body = ik_->frame();
  std::array<HandLatch, 2> latch;
  for (int h = 0; h < 2; ++h) {
    const TrackedPose newest = trackerWrist(in_->hand(h), *placement_, h);
    const auto& target = body.targets.pose[kHandIds[h]];
    latch[size_t(h)].joint = o_.avatar->humanoid.joint(h == 0 ? avatar::HumanBone::leftHand : avatar::HumanBone::rightHand);
    latch[size_t(h)].solvedFor = {target.position, target.orientation};
    latch[size_t(h)].newest = newest.pose;
    latch[size_t(h)].apply =
        o_.lateLatch && newest.valid && target.valid && body.targets[kHandIds[h]] == tracking::TrackerStatus::Tracked;
  }
  LatchResult out;
  latchHands(o_.avatar->skeleton, latch, pose_, globals_, out);
  for (size_t h = 0; h < 2; ++h) {
    if (!out.applied[h]) continue;
    ++rep_.lateLatch.frames;
    rep_.lateLatch.maxErrorM = std::max(rep_.lateLatch.maxErrorM, out.error[h]);
    rep_.lateLatch.correctionMm.push_back(double(out.correction[h]) * 1e3);
    f.handsLatchedAt = latchedAt;
  }
}

void HeadsetLoop::driveFingers(const FrameWork& f) {
  if (!driveFingers_) return;  // after the body: the fingers ride on the solved hands
  const XrTime t = f.timing.predictedDisplayTime;
  for (int h = 0; h < 2; ++h) toTrackedHand(in_->hand(h), trackedHands_[static_cast<size_t>(h)]);
  avatar::FingerRetargetJob job;
  job.skeleton = &o_.avatar->skeleton;
  job.rig = &fingerRig_;
  job.hands = {&trackedHands_[0], &trackedHands_[1]};
  job.deltaTime = lastFingerTime_ ? std::clamp(float(double(t - lastFingerTime_) * 1e-9), 0.0f, 0.1f) : 0.0f;
  job.state = &fingerState_;
  job.pose = &pose_;
  job.output = &fingerOut_;
  lastFingerTime_ = t;
  if (job.Validate() && job.Run()) recordFingers(fingerRig_, fingerOut_, rep_.fingers);
}

void HeadsetLoop::appendHandGizmos() {
  lines_.clear();
  overlay_.clear();
  for (int h = 0; h < 2; ++h) {
    const HandState& hs = in_->hand(h);
    if (!hs.grip.valid) continue;  // tracking lost: no gizmo rather than a stale one
    engine::Gizmo g;
    g.pose = placement_->toWorld(hs.grip.pose).matrix();
    g.color = kHandColors[h];
    g.size = 0.05f;
    engine::appendGizmo(overlay_, g);
  }
}

// Spring bones, blinking and look-at at the display time; the eyes look where the head looks
// (2 m ahead of the HMD), the springs swing in the world the avatar is placed in.
void HeadsetLoop::applySecondaryMotion(const FrameWork& f) {
  const XrTime t = f.timing.predictedDisplayTime;
  const double dt = lastSecondaryTime_ && t > lastSecondaryTime_ ? double(t - lastSecondaryTime_) * 1e-9 : 0.0;
  lastSecondaryTime_ = t;
  std::optional<glm::vec3> gaze;
  if (f.views.valid) gaze = glm::vec3(f.head.matrix() * glm::vec4(0.0f, 0.0f, -2.0f, 1.0f));
  secondary_->update(pose_, dt, gaze);
}

// The renderer's frame: started while the IK thread solves, then the body, skinning, the eyes,
// the mirror, submit, release.
Status HeadsetLoop::render(FrameWork& f) {
  engine::Renderer& r = renderer_->renderer();
  if (auto s = r.beginFrame(); !s) return s;  // waits for the GPU's previous frame: overlaps the solve
  const bool solved = joinBody(f);
  f.renderStart = SteadyClock::now();
  if (solved) {
    ++rep_.bodyPoseFrames;
    if (o_.lateLatch) lateLatchHands(f);
  } else {
    pose_ = rest_;
    placement_->place(o_.avatar->skeleton, f.head, pose_);
  }
  driveFingers(f);
  if (o_.onBodyShown) o_.onBodyShown(pose_, double(f.timing.predictedDisplayTime) * 1e-9);
  applySecondaryMotion(f);
  if (auto s = renderer_->computePose(pose_); !s) return s;
  appendHandGizmos();
  engine::SceneFrame scene;
  scene.avatar = &renderer_->gpuAvatar();
  scene.palette = renderer_->palette();
  scene.morphWeights = secondary_->morphWeights();
  scene.materialStates = secondary_->materialStates();
  scene.seconds = secondary_->seconds();
  scene.firstPerson = true;  // the user's own head is hidden
  scene.lines = lines_;
  scene.overlayLines = overlay_;  // hand gizmos stay visible through the avatar's hands
  Status st = drawEyes(f, scene);
  ++rendererFrames_;
  engine::SubmitSync sync;
  if (st && mirror_) st = drawMirror(f, scene, sync);
  if (st) st = r.endFrame(sync);  // submitted before the images are released, as OpenXR requires
  if (st && mirror_) st = mirror_->present(device_->queue());
  releaseImages(f);
  if (st) recordFrame(f);
  return st;
}

Status HeadsetLoop::drawEyes(const FrameWork& f, engine::SceneFrame& scene) {
  engine::Renderer& r = renderer_->renderer();
  Status st = r.setScene(scene);
  for (uint32_t e = 0; e < 2 && st; ++e) {
    engine::PassTarget target;
    target.color = swapchainTarget(run_->color()[e], f.color[e], VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
    if (run_->submitsDepth())  // OpenXR's release layout for depth
      target.depth = swapchainTarget(run_->depth()[e], f.depth[e], VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL);
    const engine::Camera cam =
        engine::cameraFromPose(f.views.eyes[e].pose.matrix(), fovOf(f.views.eyes[e].fov), kNear, kFar);
    st = r.drawPass(std::span<const engine::Camera>(&cam, 1), target);
  }
  return st;
}

// The left eye again (its pose, the window's aspect), or (V) the avatar from outside.
Status HeadsetLoop::drawMirror(const FrameWork& f, engine::SceneFrame& scene, engine::SubmitSync& sync) {
  engine::Renderer& r = renderer_->renderer();
  const float vfov = f.views.eyes[0].fov.angleUp - f.views.eyes[0].fov.angleDown;
  const engine::Camera cam =
      mirror_->thirdPerson() ? renderer_->orbitAround(pose_, 0.6f, 0.2f)
                             : engine::cameraFromPose(f.views.eyes[0].pose.matrix(),
                                                      engine::FovAngles::symmetric(vfov, mirror_->aspect()), kNear, kFar);
  if (mirror_->thirdPerson()) {  // the whole avatar from outside: the third-person draw list
    scene.firstPerson = false;
    if (auto s = r.setScene(scene); !s) return s;
  }
  auto shown = mirror_->draw(r, rendererFrames_, cam, sync);
  if (!shown) return Error{shown.error()};
  if (*shown) ++rep_.mirrorFrames;
  return {};
}

// The render time of the frame (join to submit) goes with the solved body it showed.
void HeadsetLoop::recordFrame(const FrameWork& f) {
  if (!shownStats_) return;
  shownStats_->renderSeconds = std::chrono::duration<double>(SteadyClock::now() - f.renderStart).count();
  rep_.ikFrames.add(*shownStats_);
  shownStats_.reset();
}

// Tracker-to-photon: from locating the trackers to the frame's photons, which leave at the
// predicted display time, or (a frame late for it) no earlier than its xrEndFrame.
void HeadsetLoop::recordAges(const FrameWork& f) {
  const XrTime ended = sys_->now();
  if (!ended) return;  // the runtime has no XR_KHR_convert_timespec_time: ages unknown
  const XrTime photons = std::max(f.timing.predictedDisplayTime, ended);
  if (f.bodyLocatedAt) rep_.ik.bodyAgeMs.push_back(msBetween(photons, f.bodyLocatedAt));
  if (f.handsLatchedAt) rep_.ik.handAgeMs.push_back(msBetween(photons, f.handsLatchedAt));
}

void HeadsetLoop::finish() {
  if (ik_) {
    rep_.ik.priority = runtime::toString(ik_->priority());
    ik_->stop();
  }
  if (run_) {
    for (; statesSeen_ < run_->stateHistory().size(); ++statesSeen_)
      rep_.states.push_back(sessionStateName(run_->stateHistory()[statesSeen_]));
    rep_.framesSubmitted = run_->framesSubmitted();
    rep_.sessionLost = run_->lost();
  }
  rep_.endedCleanly = !rep_.states.empty() && rep_.states.back() == std::string("EXITING") && error_.empty();
  if (placement_) {
    rep_.calibrated = placement_->calibrated();
    rep_.calibratedScale = placement_->scale();
  }
  rep_.meanFrameMs = rep_.framesSubmitted ? 1000.0 * renderSeconds_ / double(rep_.framesSubmitted) : 0.0;
  // Tear down in dependency order before reading the final validation count.
  if (renderer_) renderer_->renderer().waitIdle();
  in_.reset();
  run_.reset();
  renderer_.reset();
  mirror_.reset();
  device_.reset();
  if (sys_) {
    const auto counter = sys_->validationCounter();
    sys_.reset();  // destroying the device and instance can report leaks: count after
    rep_.vulkanValidationMessages = counter->load();
  }
  if (error_.empty() && rep_.sessionLost) error_ = "the OpenXR session was lost (the runtime or the headset went away)";
  if (rep_.error.empty()) rep_.error = error_;
}

}  // namespace

XrLoopReport runXrLoop(const XrLoopOptions& options) {
  XrLoopReport rep;
  HeadsetLoop loop(options, rep);
  if (auto s = loop.setup(); !s)
    rep.error = s.error();
  else
    loop.run();
  loop.finish();
  return rep;
}

}  // namespace embody::xr
