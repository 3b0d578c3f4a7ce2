// embody mirror: the avatar live in a desktop window, driven by a motion through the same runtime
// as `embody render --motion` (app/mirror_job.h). V switches first/third person, Space pauses,
// Esc quits; --frames N exits by itself (with --screenshot, after writing the last frame).
#include <cstdio>
#include <glm/glm.hpp>
#include <stdexcept>

#include "app/args.h"
#include "app/bvh_options.h"
#include "app/mirror_job.h"

namespace {

using namespace embody;

int runMirrorCommand(app::Argv argv) {
  app::Args args("embody mirror",
                 "Shows the avatar live in a desktop window, driven by a motion through the IK runtime (pose source -> "
                 "budgeted IK thread -> skinning -> render). Keys: V first/third person, Space pause, Esc quit. Needs a "
                 "display (X11 or Wayland; Xvfb works).");
  args.option("avatar", "FILE|default", "a .gltf/.glb/.vrm file, or 'default' (the built-in procedural avatar)",
              "default");
  args.option("motion", "SOURCE", "FILE.bvh, FILE.jsonl or synthetic:NAME (embody motion list)", "synthetic:figure8");
  args.option("frames", "N", "exit after N frames shown (0: until the window is closed)", "0");
  args.option("fps", "HZ", "motion sampling rate (with --frames: one step of 1/fps per frame)", "90");
  args.option("size", "WxH", "window size", "640x640");
  args.option("view", "KIND", "third (orbit camera) or first (at the eyes); V switches", "third");
  args.option("spine", "MODE", "IK spine: auto, full (every vertebra) or simplified", "auto");
  args.option("bone-map", "FILE", "JSON object VRM-1.0-bone-name -> node name");
  args.option("user-height", "METRES", "the user's height (default: the profile's, else from the first head sample)");
  args.option("profile", "FILE", "user profile JSON (embody avatar calibrate): the user's height");
  args.option("bvh-scale", "M_PER_UNIT", "metres per BVH unit (default: fit the clip to the user's height)");
  app::declareBvhOptions(args);
  args.option("ik-budget-ms", "MS", "IK time budget per frame", "1");
  args.option("yaw", "DEGREES", "third-person orbit yaw (0 = from the front)", "30");
  args.option("pitch", "DEGREES", "third-person orbit pitch (positive looks down)", "10");
  args.option("screenshot", "FILE.png", "with --frames: write the window's last frame as PNG");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.flag("coupled-spine", "the coupled spine model (Raunhardt & Boulic) instead of independent spine sites");
  args.flag("three-point", "keep only head and hands (HMD + controllers): the lower body is inferred, feet step");
  args.flag("no-grid", "hide the ground grid");
  args.flag("validate", "enable the Khronos validation layer and print the message count at exit");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  app::MirrorJob mj;
  app::RenderJob& job = mj.run;
  try {
    app::readSharedJobOptions(args, job);
    mj.frames = args.integer("frames");
    job.yaw = glm::radians(float(args.number("yaw")));
    job.pitch = glm::radians(float(args.number("pitch")));
    const std::string size = args.get("size");
    const size_t x = size.find('x');
    size_t used = 0;
    if (x == std::string::npos) throw std::invalid_argument("--size must look like 640x640");
    job.width = std::stoi(size.substr(0, x), &used);
    if (used != x) throw std::invalid_argument("--size must look like 640x640");
    job.height = std::stoi(size.substr(x + 1), &used);
    if (used != size.size() - x - 1) throw std::invalid_argument("--size must look like 640x640");
  } catch (const std::exception& e) {  // invalid_argument / out_of_range from stoi
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  job.view = args.get("view");
  if (job.view == "third-person" || job.view == "first-person") job.view = job.view.substr(0, job.view.find('-'));
  job.threePoint = args.has("three-point");
  job.coupledSpine = args.has("coupled-spine");
  job.grid = !args.has("no-grid");
  job.validate = args.has("validate");
  job.device = args.get("device");
  mj.screenshot = args.get("screenshot");
  if (!mj.screenshot.empty() && mj.frames <= 0) {
    std::fprintf(stderr, "error: --screenshot needs --frames N\n");
    return 2;
  }
  return app::runMirror(mj);
}

}  // namespace

EMBODY_COMMAND("mirror", "the avatar live in a desktop window, driven by a motion through the IK runtime (V view, Space pause)",
               runMirrorCommand);
