// embody xr: embody the user in an OpenXR headset (or the headless runtime in CI).
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <thread>

#include "app/avatar_arg.h"
#include "app/args.h"
#include "app/job_inputs.h"
#include "app/job_options.h"
#include "app/motion_export.h"
#include "avatar/body/calibration.h"
#include "core/percentile.h"
#include "runtime/frame_stats.h"
#include "runtime/seated_stats.h"
#include "runtime/tracked_avatar_body.h"
#include "tracking/trace.h"
#include "xr/xr_loop.h"

namespace {

using namespace embody;

// SIGINT/SIGTERM end the session the OpenXR way (the loop requests the exit; the runtime walks it
// down through STOPPING -> xrEndSession -> EXITING). A second signal kills (SA_RESETHAND).
std::atomic<bool> gStopRequested{false};
extern "C" void onStopSignal(int) { gStopRequested.store(true); }

void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sa.sa_flags = SA_RESETHAND;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// A lost session (LOSS_PENDING, instance loss) is retried with a fresh instance this many times
// in all, a second apart, before embody xr gives up.
constexpr int kSessionAttempts = 3;

struct XrCommand {
  xr::XrLoopOptions loop;
  runtime::SeatOptions seat;
  app::JobOptions shared;  // avatar, bone map, spine, user height, profile, IK budget
  std::optional<avatar::BodyProfile> profile;  // shared.profile, once read
  std::string bodyMode, avatarArg, recordPath, statsPath;
  double budgetMs = 1.0;
};

// The options shared with render/mirror/demo (app/job_options.h).
constexpr unsigned kSharedOptions = app::kAvatarOptions | app::kBodyOptions | app::kBudgetOptions | app::kExportOptions;

void declareOptions(app::Args& args) {
  app::addJobOptions(args, kSharedOptions);
  args.option("frames", "N", "end the session after N submitted frames (0: until the runtime ends it)", "0");
  args.option("height", "METRES", "your standing eye height (skips the calibration from the HMD height; or give "
              "--user-height / --profile)");
  args.option("stats", "FILE", "write a JSON report of the run (states, frames, tracking, IK thread, validation)");
  args.option("body", "ik|rest",
              "ik: the body follows head and hands (AvatarBodySolver on the IK thread); rest: the rest pose "
              "placed under the head",
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
  args.flag("no-late-latch", "draw the hands where the IK thread solved them (no second controller locate)");
  args.flag("validate", "enable the Khronos validation layer on the Vulkan device and count its messages");
  args.flag("verbose", "print every session state change");
}

// Numbers and their ranges; throws std::invalid_argument with the message for the user.
void readNumbers(const app::Args& args, XrCommand& c) {
  app::readJobOptions(args, kSharedOptions, c.shared);
  const int frames = args.integer("frames");
  if (frames < 0) throw std::invalid_argument("--frames must be 0 or more");
  c.loop.frames = static_cast<uint64_t>(frames);
  if (args.has("height")) {
    c.loop.placement.userEyeHeight = static_cast<float>(args.number("height"));
    if (!(c.loop.placement.userEyeHeight > 0.5f && c.loop.placement.userEyeHeight < 2.5f))
      throw std::invalid_argument("--height must be between 0.5 and 2.5 metres");
    if (args.has("user-height") || args.has("profile"))
      throw std::invalid_argument("--height (eye height) excludes --user-height and --profile");
  }
  c.seat.enabled = c.loop.placement.seated = args.has("seated");
  if (args.has("seat-height")) {
    c.seat.seatHeight = static_cast<float>(args.number("seat-height"));
    if (!c.seat.enabled || !(c.seat.seatHeight >= 0.2f && c.seat.seatHeight <= 1.2f))
      throw std::invalid_argument("--seat-height needs --seated and must be between 0.2 and 1.2 metres");
  }
  c.budgetMs = c.shared.budgetMs;
  c.bodyMode = args.get("body");
  if (c.bodyMode != "ik" && c.bodyMode != "rest") throw std::invalid_argument("--body must be ik or rest");
}

// Parses the command line into `c`; returns an exit code when the command must end now.
std::optional<int> parseCommand(app::Argv argv, XrCommand& c) {
  app::Args args(
      "embody xr",
      "Puts you in the avatar through the active OpenXR runtime (a headset, or the headless runtime "
      "selected by XR_RUNTIME_JSON). The avatar's body is solved from the HMD and the controllers "
      "(three-point IK on its own thread: head and hands tracked, hips and feet inferred, the feet step); "
      "gizmos mark the controllers. Ctrl-C ends the session cleanly.");
  declareOptions(args);
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  try {
    readNumbers(args, c);
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  if (c.shared.userHeight == 0.0f && !c.shared.profile.empty()) {  // a bad file is a runtime error (1)
    auto profile = avatar::loadProfile(c.shared.profile);
    if (!profile) return app::runtimeError("profile " + c.shared.profile + ": " + profile.error());
    c.shared.userHeight = float(profile->userHeight);
    c.profile = std::move(profile).value();
  }
  // The standing eye height the placement and the solver take (avatar::kEyeHeightRatio).
  if (c.shared.userHeight > 0.0f) c.loop.placement.userEyeHeight = c.shared.userHeight * float(avatar::kEyeHeightRatio);
  c.loop.recenterAtStart = args.has("recenter");
  c.loop.vulkanValidation = args.has("validate");
  c.loop.verbose = args.has("verbose");
  c.loop.mirror = args.has("mirror");
  c.loop.lateLatch = !args.has("no-late-latch");
  c.loop.ikBudgetSeconds = c.budgetMs * 1e-3;
  c.avatarArg = c.shared.avatar;
  c.recordPath = args.get("record");
  c.statsPath = args.get("stats");
  return std::nullopt;
}

// The body of `--body ik`: three-point PIK (head + controllers) on the loop's IK thread, placed
// back in the tracking space. Everything here runs on that thread; read it after the loop ends.
struct BodyHook {
  std::unique_ptr<runtime::TrackedAvatarBody> body;
  tracking::TraceWriter recorder;
  bool record = false;
  runtime::SeatedStats seatedStats;
};

Result<bool> attachBody(const XrCommand& c, const avatar::AvatarAsset& asset, BodyHook& hook,
                        xr::XrLoopOptions& lo) {
  if (c.bodyMode != "ik") return false;
  hook.record = !c.recordPath.empty();
  if (hook.record)
    if (auto s = hook.recorder.open(c.recordPath, tracking::TrackerMask::threePoint(), "openxr", 0.0f); !s)
      return Error{s.error()};
  runtime::TrackedBodyOptions bo;
  bo.body.trackers = tracking::TrackerMask::threePoint();
  bo.body.seat = c.seat;
  bo.body.spine = c.shared.spine;
  bo.body.coupledSpine = c.shared.coupledSpine;
  // The solver takes a body height (0: from the first head sample, standing); seated, the solver
  // assumes 1.75 m unless --height gives the standing eye height.
  const float eye = c.loop.placement.userEyeHeight;
  bo.body.userHeight = eye > 0.0f ? eye / float(avatar::kEyeHeightRatio) : 0.0f;
  std::optional<avatar::BodyProfile> profile = c.profile;
  if (!c.shared.profile.empty() && !profile) {  // not read yet: --user-height was given
    auto loaded = avatar::loadProfile(c.shared.profile);
    if (!loaded) return Error{"profile " + c.shared.profile + ": " + loaded.error()};
    profile = std::move(loaded).value();
  }
  if (profile) {
    auto arms = app::profileArmScale(*profile, c.shared.profile, asset, bo.body.userHeight);
    if (!arms) return Error{arms.error()};
    bo.body.armScale = *arms;
  }
  bo.stage.budgetSeconds = c.budgetMs * 1e-3;
  auto created = runtime::TrackedAvatarBody::create(asset, bo);
  if (!created) return Error{"avatar " + c.avatarArg + ": " + created.error()};
  hook.body = std::move(created).value();
  lo.solveBody = [&hook, seated = c.seat.enabled](const tracking::PoseSample& sample, runtime::SolvedFrame& out) {
    if (hook.record) (void)hook.recorder.write(sample);
    hook.body->solveInto(sample, out);
    if (out.stats.sequence != 0 && seated) hook.seatedStats.add(hook.body->solver());
  };
  lo.onRecenter = [&hook] { hook.body->reset(); };
  return true;
}

// Runs the headset loop; a lost session is retried with a fresh instance a few times.
xr::XrLoopReport runWithRetries(const xr::XrLoopOptions& lo, BodyHook& hook, int& attempts) {
  xr::XrLoopReport r;
  for (attempts = 1;; ++attempts) {
    r = xr::runXrLoop(lo);
    if (!r.sessionLost || gStopRequested.load() || attempts >= kSessionAttempts) break;
    std::fprintf(stderr, "warning: %s; creating a new OpenXR instance (attempt %d of %d)\n", r.error.c_str(),
                 attempts + 1, kSessionAttempts);
    if (hook.body) hook.body->reset();
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  if (r.sessionLost && attempts > 1)
    r.error = "the OpenXR session was lost and could not be recreated (" + std::to_string(attempts) +
              " attempts): " + r.error;
  return r;
}

double percentileOf(std::vector<double> v, double p) { return percentileNearestRank(v, p); }
double maxOf(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }

void printSession(const xr::XrLoopReport& r) {
  std::string states;
  for (const auto& s : r.states) states += (states.empty() ? "" : " ") + s;
  std::printf("runtime: %s (%s)\n", r.runtime.empty() ? "none" : r.runtime.c_str(), r.system.c_str());
  std::printf("space: %s, hand tracking: %s, depth layer: %s, profile: %s\n", r.usedStage ? "STAGE" : "LOCAL",
              r.handTracking ? "yes" : "no", r.depthSubmitted ? "yes" : "no",
              r.interactionProfile.empty() ? "(none)" : r.interactionProfile.c_str());
  std::printf("session states: %s%s\n", states.c_str(), r.stoppedBySignal ? " (stopped by a signal)" : "");
  std::printf("frames: %llu submitted of %llu, %.2f ms each; head valid in %llu, tracked in %llu\n",
              static_cast<unsigned long long>(r.framesSubmitted), static_cast<unsigned long long>(r.framesWaited),
              r.meanFrameMs, static_cast<unsigned long long>(r.headValidFrames),
              static_cast<unsigned long long>(r.headTrackedFrames));
  std::printf("hands valid: left %llu, right %llu; tracked: left %llu, right %llu; lost: left %llu, right %llu\n",
              static_cast<unsigned long long>(r.handValidFrames[0]), static_cast<unsigned long long>(r.handValidFrames[1]),
              static_cast<unsigned long long>(r.handTrackedFrames[0]),
              static_cast<unsigned long long>(r.handTrackedFrames[1]),
              static_cast<unsigned long long>(r.handLostFrames[0]), static_cast<unsigned long long>(r.handLostFrames[1]));
}

void printBody(const XrCommand& c, const xr::XrLoopReport& r, const BodyHook& hook) {
  std::printf("body: %s, %llu frames solved\n", c.bodyMode.c_str(), static_cast<unsigned long long>(r.bodyPoseFrames));
  if (r.fingers.drivenBones > 0)
    std::printf("fingers: %d bones, hand-tracked in %llu frames, curl %.1f..%.1f deg\n", r.fingers.drivenBones,
                static_cast<unsigned long long>(r.fingers.frames), r.fingers.curlMinDeg, r.fingers.curlMaxDeg);
  std::printf("calibration: %s, avatar scale %.3f; %llu recenters (%llu by the runtime)\n",
              r.calibrated ? "done" : "not done", r.calibratedScale, static_cast<unsigned long long>(r.recenters),
              static_cast<unsigned long long>(r.runtimeRecenters));
  if (hook.body && c.seat.enabled && hook.body->solver().seat())
    std::printf("seated: seat %.2f m high, placed under the head\n",
                hook.body->solver().seat()->seatHeight / hook.body->solver().scale());
  if (c.loop.mirror) std::printf("mirror: %llu frames shown\n", static_cast<unsigned long long>(r.mirrorFrames));
  if (c.loop.vulkanValidation) std::printf("validation messages: %u\n", r.vulkanValidationMessages);
  if (!hook.body) return;
  const runtime::StatsSummary ik = r.ikFrames.summary();
  std::printf("ik thread (%s priority): solve p50 %.2f ms, p99 %.2f ms (budget %.2f ms), %zu deadline misses, "
              "%.1f iterations; join wait p50 %.2f ms, max %.2f ms, %llu late joins\n",
              r.ik.priority, ik.ikP50Ms, ik.ikP99Ms, c.budgetMs, ik.deadlineMisses, ik.iterationsMean,
              percentileOf(r.ik.waitMs, 50), maxOf(r.ik.waitMs), static_cast<unsigned long long>(r.ik.lateJoins));
  if (!r.ik.bodyAgeMs.empty())
    std::printf("tracker-to-photon: body p50 %.1f ms, hands (late-latched) p50 %.1f ms\n",
                percentileOf(r.ik.bodyAgeMs, 50), percentileOf(r.ik.handAgeMs, 50));
  std::printf("late latch: %llu hand frames, worst %.3f mm from the controller after it\n",
              static_cast<unsigned long long>(r.lateLatch.frames), double(r.lateLatch.maxErrorM) * 1e3);
}

nlohmann::json sessionJson(const XrCommand& c, const xr::XrLoopReport& r, int attempts) {
  return {{"runtime", r.runtime},
          {"system", r.system},
          {"interaction_profile", r.interactionProfile},
          {"stage", r.usedStage},
          {"hand_tracking", r.handTracking},
          {"depth_submitted", r.depthSubmitted},
          {"states", r.states},
          {"reached_focused", r.reachedFocused},
          {"ended_cleanly", r.endedCleanly},
          {"session_lost", r.sessionLost},
          {"session_attempts", attempts},
          {"stopped_by_signal", r.stoppedBySignal},
          {"frames_waited", r.framesWaited},
          {"frames_submitted", r.framesSubmitted},
          {"head_valid_frames", r.headValidFrames},
          {"head_tracked_frames", r.headTrackedFrames},
          {"hand_valid_frames", {r.handValidFrames[0], r.handValidFrames[1]}},
          {"hand_tracked_frames", {r.handTrackedFrames[0], r.handTrackedFrames[1]}},
          {"hand_lost_frames", {r.handLostFrames[0], r.handLostFrames[1]}},
          {"calibrated", r.calibrated},
          {"avatar_scale", r.calibratedScale},
          {"recenters", r.recenters},
          {"runtime_recenters", r.runtimeRecenters},
          {"vulkan_validation_messages", r.vulkanValidationMessages},
          {"mean_frame_ms", r.meanFrameMs},
          {"mirror_frames", r.mirrorFrames},
          {"body", c.bodyMode},
          {"body_pose_frames", r.bodyPoseFrames},
          {"fingers",
           {{"driven_bones", r.fingers.drivenBones},
            {"frames", r.fingers.frames},
            {"full_frames", r.fingers.fullFrames},
            {"curl_min_deg", r.fingers.curlMinDeg},
            {"curl_max_deg", r.fingers.curlMaxDeg},
            {"curl_last_deg", r.fingers.curlLastDeg}}},
          {"error", r.error}};
}

// "ik_thread" and "late_latch": the render thread's view of the IK thread.
void ikThreadJson(nlohmann::json& j, const xr::XrLoopReport& r) {
  j["ik_thread"] = {{"priority", r.ik.priority},
                    {"submitted", r.ik.submitted},
                    {"joins", r.ik.joins},
                    {"late_joins", r.ik.lateJoins},
                    {"wait_p50_ms", percentileOf(r.ik.waitMs, 50)},
                    {"wait_p99_ms", percentileOf(r.ik.waitMs, 99)},
                    {"wait_max_ms", maxOf(r.ik.waitMs)},
                    {"body_age_frames", r.ik.bodyAgeMs.size()},
                    {"body_age_p50_ms", percentileOf(r.ik.bodyAgeMs, 50)},
                    {"body_age_max_ms", maxOf(r.ik.bodyAgeMs)},
                    {"hand_age_p50_ms", percentileOf(r.ik.handAgeMs, 50)},
                    {"hand_age_max_ms", maxOf(r.ik.handAgeMs)}};
  j["late_latch"] = {{"hand_frames", r.lateLatch.frames},
                     {"max_error_mm", double(r.lateLatch.maxErrorM) * 1e3},
                     {"correction_p50_mm", percentileOf(r.lateLatch.correctionMm, 50)},
                     {"correction_max_mm", maxOf(r.lateLatch.correctionMm)}};
}

bool writeStats(const XrCommand& c, const xr::XrLoopReport& r, const BodyHook& hook, int attempts) {
  nlohmann::json j = sessionJson(c, r, attempts);
  if (hook.body) {
    runtime::toJson(j, r.ikFrames.summary());  // "ik", "tracking", "render" as in embody render's stats.json
    ikThreadJson(j, r);
  }
  if (hook.body && c.seat.enabled) hook.seatedStats.toJson(j);
  std::ofstream out(c.statsPath);
  out << j.dump(2) << "\n";
  if (!out) std::fprintf(stderr, "error: cannot write %s\n", c.statsPath.c_str());
  return bool(out);
}

// --export: every frame's body as shown, recorded on the render thread; written when the session
// ends, at the headset's mean display period (OpenXR frames are paced by the runtime).
struct ShownMotion {
  app::MotionExport file;
  double firstSeconds = 0.0, lastSeconds = 0.0;

  void attach(const std::string& path, const avatar::AvatarAsset& asset, uint64_t frames, xr::XrLoopOptions& lo) {
    if (path.empty()) return;
    file.open(path, asset, nullptr, 1.0 / 90.0, size_t(frames));
    lo.onBodyShown = [this](const avatar::SkeletonPose& pose, double displaySeconds) {
      if (file.frames() == 0) firstSeconds = displaySeconds;
      lastSeconds = displaySeconds;
      file.add(pose);
    };
  }
  // Exit code contribution: 0 written (or nothing asked), 1 an error (printed).
  int write(const avatar::AvatarAsset& asset) {
    if (!file.active()) return 0;
    if (file.frames() == 0) {
      std::fprintf(stderr, "error: --export %s: no frame was shown, nothing to write\n", file.path().c_str());
      return 1;
    }
    if (file.frames() > 1 && lastSeconds > firstSeconds) file.setFrameTime((lastSeconds - firstSeconds) / double(file.frames() - 1));
    if (auto s = file.write(asset); !s) {
      std::fprintf(stderr, "error: %s\n", s.error().c_str());
      return 1;
    }
    std::printf("exported the body shown (%zu frames) to %s\n", file.frames(), file.path().c_str());
    return 0;
  }
};

int runXr(app::Argv argv) {
  XrCommand c;
  if (auto code = parseCommand(argv, c)) return *code;
  auto loaded = app::loadAvatarArg(c.avatarArg, c.shared.boneMap);
  if (!loaded) {
    std::fprintf(stderr, "error: %s\n", loaded.error().c_str());
    return 1;
  }
  const avatar::AvatarAsset asset = std::move(loaded).value();
  c.loop.avatar = &asset;
  BodyHook hook;
  if (auto attached = attachBody(c, asset, hook, c.loop); !attached) {
    std::fprintf(stderr, "error: %s\n", attached.error().c_str());
    return 1;
  }
  ShownMotion shown;
  shown.attach(c.shared.exportPath, asset, c.loop.frames, c.loop);
  installStopHandlers();
  c.loop.stopRequested = &gStopRequested;
  int attempts = 0;
  const xr::XrLoopReport r = runWithRetries(c.loop, hook, attempts);
  printSession(r);
  printBody(c, r, hook);
  if (!c.statsPath.empty() && !writeStats(c, r, hook, attempts)) return 1;
  if (shown.write(asset) != 0) return 1;
  if (!r.error.empty()) {
    std::fprintf(stderr, "error: %s\n", r.error.c_str());
    return 1;
  }
  return 0;
}

}  // namespace

EMBODY_COMMAND("xr", "embody the user in an OpenXR headset (three-point IK body in first person, hand gizmos)", runXr);
