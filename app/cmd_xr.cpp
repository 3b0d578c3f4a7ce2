// embody xr: embody the user in an OpenXR headset (or the headless runtime in CI).
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "app/avatar_arg.h"
#include "app/args.h"
#include "app/job_options.h"
#include "avatar/body/calibration.h"
#include "runtime/frame_stats.h"
#include "runtime/seated_stats.h"
#include "runtime/tracked_avatar_body.h"
#include "tracking/trace.h"
#include "xr/xr_loop.h"

namespace {

using namespace embody;

int runXr(app::Argv argv) {
  app::Args args(
      "embody xr",
      "Puts you in the avatar through the active OpenXR runtime (a headset, or the headless runtime "
      "selected by XR_RUNTIME_JSON). The avatar's body is solved from the HMD and the controllers "
      "(three-point IK: head and hands tracked, hips and feet inferred, the feet step); gizmos mark the controllers.");
  // The options shared with render/mirror/demo (app/job_options.h): avatar, bone map, spine, user
  // height, profile, IK budget.
  constexpr unsigned kShared = app::kAvatarOptions | app::kBodyOptions | app::kBudgetOptions;
  app::addJobOptions(args, kShared);
  args.option("frames", "N", "end the session after N submitted frames (0: until the runtime ends it)", "0");
  args.option("height", "METRES", "your standing eye height (skips the calibration from the HMD height; or give "
              "--user-height / --profile)");
  args.option("stats", "FILE", "write a JSON report of the run (states, frames, tracking, validation)");
  args.option("body", "ik|rest",
              "ik: the body follows head and hands (AvatarBodySolver); rest: the rest pose placed under the head",
              "ik");
  args.option("record", "FILE.jsonl", "record the head and wrist trackers as a trace (replay with embody render --motion)");
  args.flag("seated",
            "seated mode: the avatar sits on a seat placed under your head at the first frame (again on recenter), "
            "feet on the floor; the spine and arms follow your head and hands");
  args.option("seat-height", "METRES",
              "seated mode: the seat's height above the floor (default: from your head height and the avatar's legs)");
  args.flag("recenter", "recenter at start (your position and heading become the origin)");
  args.flag(
      "mirror",
      "show the left eye in a desktop window (V: third-person view, R: recenter, C: recalibrate, Esc: quit)");
  args.flag("validate", "enable the Khronos validation layer on the Vulkan device and count its messages");
  args.flag("verbose", "print every session state change");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  xr::XrLoopOptions lo;
  app::JobOptions shared;
  try {
    app::readJobOptions(args, kShared, shared);
    const int frames = args.integer("frames");
    if (frames < 0) throw std::invalid_argument("--frames must be 0 or more");
    lo.frames = static_cast<uint64_t>(frames);
    if (args.has("height")) {
      lo.placement.userEyeHeight = static_cast<float>(args.number("height"));
      if (!(lo.placement.userEyeHeight > 0.5f && lo.placement.userEyeHeight < 2.5f))
        throw std::invalid_argument("--height must be between 0.5 and 2.5 metres");
      if (args.has("user-height") || args.has("profile"))
        throw std::invalid_argument("--height (eye height) excludes --user-height and --profile");
    }
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  if (shared.userHeight == 0.0f && !shared.profile.empty()) {  // a bad file is a runtime error (1)
    auto profile = avatar::loadProfile(shared.profile);
    if (!profile) return std::fprintf(stderr, "error: profile %s: %s\n", shared.profile.c_str(), profile.error().c_str()), 1;
    shared.userHeight = float(profile->userHeight);
  }
  // The standing eye height the placement and the solver take (avatar::kEyeHeightRatio).
  if (shared.userHeight > 0.0f) lo.placement.userEyeHeight = shared.userHeight * float(avatar::kEyeHeightRatio);
  lo.placement.seated = args.has("seated");
  runtime::SeatOptions seat;
  seat.enabled = lo.placement.seated;
  if (args.has("seat-height")) {
    try {
      seat.seatHeight = static_cast<float>(args.number("seat-height"));
    } catch (const std::invalid_argument& e) {
      return app::usageError(e.what());
    }
    if (!seat.enabled || !(seat.seatHeight >= 0.2f && seat.seatHeight <= 1.2f))
      return app::usageError("--seat-height needs --seated and must be between 0.2 and 1.2 metres");
  }
  lo.recenterAtStart = args.has("recenter");
  lo.vulkanValidation = args.has("validate");
  lo.verbose = args.has("verbose");
  lo.mirror = args.has("mirror");
  const std::string bodyMode = args.get("body");
  if (bodyMode != "ik" && bodyMode != "rest") return app::usageError("--body must be ik or rest");
  const double budgetMs = shared.budgetMs;

  const std::string avatarArg = shared.avatar;
  auto loaded = app::loadAvatarArg(avatarArg, shared.boneMap);
  if (!loaded) {
    std::fprintf(stderr, "error: %s\n", loaded.error().c_str());
    return 1;
  }
  avatar::AvatarAsset asset = std::move(loaded).value();
  lo.avatar = &asset;

  // The body: three-point PIK (head + controllers), solved synchronously each frame from the
  // trackers predicted for the frame's display time, placed back in the tracking space.
  tracking::TraceWriter recorder;
  const bool record = !args.get("record").empty();
  if (record)
    if (auto s = recorder.open(args.get("record"), tracking::TrackerMask::threePoint(), "openxr", 0.0f); !s) {
      std::fprintf(stderr, "error: %s\n", s.error().c_str());
      return 1;
    }
  std::unique_ptr<runtime::TrackedAvatarBody> body;
  runtime::StatsRecorder ikStats;  // per solved frame, for --stats (grows with the session)
  runtime::SeatedStats seatedStats;
  const bool keepStats = args.has("stats");
  if (bodyMode == "ik") {
    runtime::TrackedBodyOptions bo;
    bo.body.trackers = tracking::TrackerMask::threePoint();
    bo.body.seat = seat;
    bo.body.spine = shared.spine;
    bo.body.coupledSpine = shared.coupledSpine;
    // The solver takes a body height (0: from the first head sample, standing); seated, the
    // solver assumes 1.75 m unless --height gives the standing eye height.
    const float eye = lo.placement.userEyeHeight;
    bo.body.userHeight = eye > 0.0f ? eye / float(avatar::kEyeHeightRatio) : 0.0f;
    bo.stage.budgetSeconds = budgetMs * 1e-3;
    auto created = runtime::TrackedAvatarBody::create(asset, bo);
    if (!created) {
      std::fprintf(stderr, "error: avatar %s: %s\n", avatarArg.c_str(), created.error().c_str());
      return 1;
    }
    body = std::move(created).value();
    lo.bodyPose = [&](const tracking::PoseSample& sample, avatar::SkeletonPose& pose) {
      if (record) (void)recorder.write(sample);
      const bool ok = body->solve(sample, pose);
      if (ok && keepStats) ikStats.add(body->frame().stats);
      if (ok && seat.enabled) seatedStats.add(body->solver());
      return ok;
    };
    lo.onRecenter = [&] { body->reset(); };
  }

  const xr::XrLoopReport r = xr::runXrLoop(lo);
  std::string states;
  for (const auto& s : r.states) states += (states.empty() ? "" : " ") + s;
  std::printf("runtime: %s (%s)\n", r.runtime.empty() ? "none" : r.runtime.c_str(), r.system.c_str());
  std::printf("space: %s, hand tracking: %s, depth layer: %s, profile: %s\n", r.usedStage ? "STAGE" : "LOCAL",
              r.handTracking ? "yes" : "no", r.depthSubmitted ? "yes" : "no",
              r.interactionProfile.empty() ? "(none)" : r.interactionProfile.c_str());
  std::printf("session states: %s\n", states.c_str());
  std::printf("frames: %llu submitted of %llu, %.2f ms each; head tracked in %llu\n",
              static_cast<unsigned long long>(r.framesSubmitted),
              static_cast<unsigned long long>(r.framesWaited), r.meanFrameMs,
              static_cast<unsigned long long>(r.headTrackedFrames));
  std::printf("hands valid: left %llu, right %llu; lost: left %llu, right %llu\n",
              static_cast<unsigned long long>(r.handValidFrames[0]),
              static_cast<unsigned long long>(r.handValidFrames[1]),
              static_cast<unsigned long long>(r.handLostFrames[0]),
              static_cast<unsigned long long>(r.handLostFrames[1]));
  std::printf("body: %s, %llu frames solved\n", bodyMode.c_str(), static_cast<unsigned long long>(r.bodyPoseFrames));
  if (r.fingers.drivenBones > 0)
    std::printf("fingers: %d bones, hand-tracked in %llu frames, curl %.1f..%.1f deg\n",
                r.fingers.drivenBones, static_cast<unsigned long long>(r.fingers.frames),
                r.fingers.curlMinDeg, r.fingers.curlMaxDeg);
  std::printf("calibration: %s, avatar scale %.3f\n", r.calibrated ? "done" : "not done", r.calibratedScale);
  if (body && seat.enabled && body->solver().seat())
    std::printf("seated: seat %.2f m high, placed under the head\n", body->solver().seat()->seatHeight / body->solver().scale());
  if (lo.mirror) std::printf("mirror: %llu frames shown\n", static_cast<unsigned long long>(r.mirrorFrames));
  if (lo.vulkanValidation) std::printf("validation messages: %u\n", r.vulkanValidationMessages);

  const runtime::StatsSummary ik = ikStats.summary();
  if (body)
    std::printf("ik: p50 %.2f ms, p99 %.2f ms (budget %.2f ms), %zu deadline misses, %.1f iterations\n", ik.ikP50Ms,
                ik.ikP99Ms, budgetMs, ik.deadlineMisses, ik.iterationsMean);
  if (args.has("stats")) {
    nlohmann::json j = {{"runtime", r.runtime},
                        {"system", r.system},
                        {"interaction_profile", r.interactionProfile},
                        {"stage", r.usedStage},
                        {"hand_tracking", r.handTracking},
                        {"depth_submitted", r.depthSubmitted},
                        {"states", r.states},
                        {"reached_focused", r.reachedFocused},
                        {"ended_cleanly", r.endedCleanly},
                        {"session_lost", r.sessionLost},
                        {"frames_waited", r.framesWaited},
                        {"frames_submitted", r.framesSubmitted},
                        {"head_tracked_frames", r.headTrackedFrames},
                        {"hand_valid_frames", {r.handValidFrames[0], r.handValidFrames[1]}},
                        {"hand_lost_frames", {r.handLostFrames[0], r.handLostFrames[1]}},
                        {"calibrated", r.calibrated},
                        {"avatar_scale", r.calibratedScale},
                        {"vulkan_validation_messages", r.vulkanValidationMessages},
                        {"mean_frame_ms", r.meanFrameMs},
                        {"mirror_frames", r.mirrorFrames},
                        {"body", bodyMode},
                        {"body_pose_frames", r.bodyPoseFrames},
                        {"fingers",
                         {{"driven_bones", r.fingers.drivenBones},
                          {"frames", r.fingers.frames},
                          {"full_frames", r.fingers.fullFrames},
                          {"curl_min_deg", r.fingers.curlMinDeg},
                          {"curl_max_deg", r.fingers.curlMaxDeg},
                          {"curl_last_deg", r.fingers.curlLastDeg}}},
                        {"error", r.error}};
    if (body) runtime::toJson(j, ik);
    if (body && seat.enabled) seatedStats.toJson(j);  // "ik" and "tracking" objects as in embody render's stats.json
    std::ofstream out(args.get("stats"));
    out << j.dump(2) << "\n";
    if (!out) {
      std::fprintf(stderr, "error: cannot write %s\n", args.get("stats").c_str());
      return 1;
    }
  }
  if (!r.error.empty()) {
    std::fprintf(stderr, "error: %s\n", r.error.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

EMBODY_COMMAND("xr", "embody the user in an OpenXR headset (three-point IK body in first person, hand gizmos)", runXr);
