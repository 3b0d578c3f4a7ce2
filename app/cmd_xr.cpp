// embody xr: embody the user in an OpenXR headset (or the headless runtime in CI).
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "app/args.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "xr/openxr/xr_loop.h"

namespace {

using namespace embody;

int runXr(cli::Argv argv) {
  cli::Args args(
      "embody xr",
      "Puts you in the avatar through the active OpenXR runtime (a headset, or the headless runtime "
      "selected by XR_RUNTIME_JSON). Until the body solver is connected the avatar stands in its rest "
      "pose under your head and gizmos follow your hands.");
  args.option("avatar", "FILE|default",
              "a .gltf/.glb/.vrm file, or 'default' (the built-in humanoid avatar)", "default");
  args.option("frames", "N", "end the session after N submitted frames (0: until the runtime ends it)", "0");
  args.option("height", "METRES", "your standing eye height (skips the calibration from the HMD height)");
  args.option("stats", "FILE", "write a JSON report of the run (states, frames, tracking, validation)");
  args.flag("seated", "seated mode: the avatar follows your head down instead of standing on the floor");
  args.flag("recenter", "recenter at start (your position and heading become the origin)");
  args.flag(
      "mirror",
      "show the left eye in a desktop window (V: third-person view, R: recenter, C: recalibrate, Esc: quit)");
  args.flag("validate", "enable the Khronos validation layer on the Vulkan device and count its messages");
  args.flag("verbose", "print every session state change");
  if (auto o = args.parse(argv); o != cli::Args::Outcome::Ok) return cli::Args::exitCode(o);

  xr::XrLoopOptions lo;
  try {
    const int frames = args.integer("frames");
    if (frames < 0) throw std::invalid_argument("--frames must be 0 or more");
    lo.frames = static_cast<uint64_t>(frames);
    if (args.has("height")) {
      lo.placement.userEyeHeight = static_cast<float>(args.number("height"));
      if (!(lo.placement.userEyeHeight > 0.5f && lo.placement.userEyeHeight < 2.5f))
        throw std::invalid_argument("--height must be between 0.5 and 2.5 metres");
    }
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  lo.placement.seated = args.has("seated");
  lo.recenterAtStart = args.has("recenter");
  lo.vulkanValidation = args.has("validate");
  lo.verbose = args.has("verbose");
  lo.mirror = args.has("mirror");

  avatar::AvatarAsset asset;
  const std::string avatarArg = args.get("avatar");
  if (avatarArg == "default") {
    asset = avatar::buildDefaultAvatar();
  } else {
    auto loaded = avatar::loadAvatarFile(avatarArg);
    if (!loaded) {
      std::fprintf(stderr, "error: %s\n", loaded.error().c_str());
      return 1;
    }
    asset = std::move(loaded).value();
  }
  lo.avatar = &asset;

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
  std::printf("calibration: %s, avatar scale %.3f\n", r.calibrated ? "done" : "not done", r.calibratedScale);
  if (lo.mirror) std::printf("mirror: %llu frames shown\n", static_cast<unsigned long long>(r.mirrorFrames));
  if (lo.vulkanValidation) std::printf("validation messages: %u\n", r.vulkanValidationMessages);

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
                        {"error", r.error}};
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

EMBODY_COMMAND("xr", "embody the user in an OpenXR headset (avatar in first person, hand gizmos)", runXr);
