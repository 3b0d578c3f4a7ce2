// embody render: an avatar driven by a motion (pose source -> IK thread -> skinning -> offscreen
// frames, app/render_job.h), or without --motion one frame of its rest pose, written as PNG.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <glm/gtc/constants.hpp>
#include <memory>
#include <optional>
#include <stdexcept>

#include "app/avatar_arg.h"
#include "app/args.h"
#include "app/render_job.h"
#include "engine/avatar_renderer.h"
#include "engine/device.h"
#include "engine/image_io.h"
#include "engine/instance.h"

namespace {

using namespace embody;

// Prints the validation count when the instance goes away, on every exit path.
struct ValidationReport {
  const engine::Instance* instance = nullptr;
  ~ValidationReport() {
    if (instance && instance->validationEnabled())
      std::fprintf(stderr, "validation messages: %u\n", instance->messageCount());
  }
};

int runRender(app::Argv argv) {
  app::Args args("embody render",
                 "Drives an avatar with a motion through the runtime (tracking -> budgeted IK thread -> skinning -> "
                 "offscreen frames) and writes frame_00000.png..., contact_sheet.png and stats.json into --out. "
                 "Without --motion: one frame of the rest pose (frame_0000.png).");
  args.option("avatar", "FILE|default", "a .gltf/.glb/.vrm file, a .bvh clip (its skeleton with capsules), or "
              "'default' (the built-in procedural avatar)",
              "default");
  args.option("out", "DIR", "output folder (created if missing)");
  args.option("motion", "SOURCE", "FILE.bvh, FILE.jsonl or synthetic:NAME (embody motion list)");
  args.option("frames", "N", "frames to render (default: the motion's duration, at most 20 s)");
  args.option("fps", "HZ", "frame rate: the motion is sampled every 1/fps s", "90");
  args.option("size", "WxH", "frame size (motion default 480x480; rest pose 1280x720)");
  args.option("width", "PIXELS", "frame width (or --size)");
  args.option("height", "PIXELS", "frame height (or --size)");
  args.option("view", "KIND", "third (orbit camera), first (at the eyes) or stereo (two eyes, side by side with "
              "--motion); third-person/first-person also accepted", "third");
  args.option("spine", "MODE", "IK spine: auto, full (every vertebra) or simplified", "auto");
  args.option("bone-map", "FILE", "JSON object VRM-1.0-bone-name -> node name");
  args.option("user-height", "METRES", "the user's height (default: the profile's, else from the first head sample)");
  args.option("profile", "FILE", "user profile JSON (embody avatar calibrate): the user's height");
  args.option("bvh-scale", "M_PER_UNIT", "metres per BVH unit (default: fit the clip to the user's height)");
  args.option("ik-budget-ms", "MS", "IK time budget per frame", "1");
  args.option("ik-iterations", "N", "a fixed IK iteration count per frame instead of the time budget: the same "
              "command gives the same output bytes (offline, reproducible runs)");
  args.option("record", "FILE.jsonl", "also record the motion's samples as a JSON Lines trace");
  args.option("export", "FILE.bvh|FILE.glb", "write the solved motion (the body shown, every frame): BVH on the "
              "avatar's hierarchy (for a BVH avatar the clip's own hierarchy, channels and frame time), or the avatar "
              "as glTF binary with the motion as an animation");
  args.flag("uncoupled-spine", "independent spine sites (one ball joint each) instead of the coupled spine (the default)");
  args.flag("coupled-spine", "the coupled spine model (Raunhardt & Boulic 2008; the default, kept for old scripts)");
  args.flag("three-point", "keep only head and hands (HMD + controllers): the lower body is inferred, feet step");
  args.flag("seated", "seated mode: the lower body sits on a seat placed under the first head sample, the spine and "
                      "arms follow (try --motion synthetic:seated)");
  args.option("yaw", "DEGREES", "orbit camera yaw around the avatar (0 = from the front)", "30");
  args.option("pitch", "DEGREES", "orbit camera pitch (positive looks down)", "10");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.option("stereo-mode", "MODE", "stereo pair as one 'multiview' pass or 'two-pass'", "default");
  args.flag("msaa", "4x multisampling");
  args.flag("skeleton", "draw the skeleton overlay");
  args.flag("gizmos", "draw the tracking-target gizmos (head, hands)");
  args.flag("no-grid", "hide the ground grid");
  args.flag("validate", "enable the Khronos validation layer and print the message count at exit");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  if (!args.has("out")) {
    std::fprintf(stderr, "error: --out DIR is required\n\n%s", args.usage().c_str());
    return 2;
  }
  const bool motion = args.has("motion");
  int width = motion ? 480 : 1280, height = motion ? 480 : 720;
  float yaw = 0.0f, pitch = 0.0f;
  try {
    if (args.has("size")) {
      const std::string size = args.get("size");
      const size_t x = size.find('x');
      size_t used = 0;
      if (x == std::string::npos) throw std::invalid_argument("--size must look like 256x256");
      width = std::stoi(size.substr(0, x), &used);
      if (used != x) throw std::invalid_argument("--size must look like 256x256");
      height = std::stoi(size.substr(x + 1), &used);
      if (used != size.size() - x - 1) throw std::invalid_argument("--size must look like 256x256");
    }
    if (args.has("width")) width = args.integer("width");
    if (args.has("height")) height = args.integer("height");
    yaw = glm::radians(float(args.number("yaw")));
    pitch = glm::radians(float(args.number("pitch")));
  } catch (const std::exception& e) {  // invalid_argument / out_of_range from stoi
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    std::fprintf(stderr, "error: --width/--height must be between 16 and 8192\n");
    return 2;
  }
  std::string view = args.get("view");
  if (view == "third-person" || view == "first-person") view = view.substr(0, view.find('-'));
  if (view != "third" && view != "first" && view != "stereo") {
    std::fprintf(stderr, "error: --view must be first, third or stereo\n");
    return 2;
  }
  if (!motion && args.has("seated")) {
    std::fprintf(stderr, "error: --seated needs --motion (e.g. --motion synthetic:seated)\n");
    return 2;
  }
  if (motion) {
    app::RenderJob job;
    try {
      app::readSharedJobOptions(args, job);
      job.record = args.get("record");
      job.exportPath = args.get("export");
      if (args.has("frames")) job.frames = args.integer("frames");
      if (args.has("frames") && job.frames < 1) throw std::invalid_argument("--frames must be at least 1");
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return 2;
    }
    job.threePoint = args.has("three-point");
    job.seated = args.has("seated");
    if (args.has("uncoupled-spine") && args.has("coupled-spine")) {
      std::fprintf(stderr, "error: --coupled-spine and --uncoupled-spine exclude each other\n");
      return 2;
    }
    job.coupledSpine = !args.has("uncoupled-spine");
    job.width = width;
    job.height = height;
    job.view = view;
    job.yaw = yaw;
    job.pitch = pitch;
    job.device = args.get("device");
    job.validate = args.has("validate");
    job.msaa = args.has("msaa");
    job.skeleton = args.has("skeleton");
    job.gizmos = args.has("gizmos");
    job.grid = !args.has("no-grid");
    job.out = args.get("out");
    return app::runRenderJob(job);
  }

  // The avatar first: a bad file is the most likely error and needs no GPU to report.
  const std::string avatarArg = args.get("avatar");
  auto loaded = app::loadAvatarArg(avatarArg);
  if (!loaded) {
    std::fprintf(stderr, "error: %s\n", loaded.error().c_str());
    return 1;
  }
  avatar::AvatarAsset asset = std::move(loaded).value();

  engine::InstanceOptions io;
#ifdef NDEBUG
  io.validation = args.has("validate") ? engine::Validation::IfPresent : engine::Validation::Off;
#else
  io.validation = engine::Validation::IfPresent;  // debug builds always validate when the layer exists
#endif
  auto instance = engine::Instance::create(io);
  if (!instance) {
    std::fprintf(stderr, "error: %s\n", instance.error().c_str());
    return 1;
  }
  ValidationReport report{&instance.value()};
  if (args.has("validate") && !instance->validationEnabled())
    std::fprintf(stderr, "warning: the validation layer is not installed (vulkan-validationlayers)\n");
  auto device = engine::Device::create(*instance, args.get("device"));
  if (!device) {
    std::fprintf(stderr, "error: %s\n", device.error().c_str());
    return 1;
  }

  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(width);
  ro.height = uint32_t(height);
  ro.samples = args.has("msaa") ? VK_SAMPLE_COUNT_4_BIT : VK_SAMPLE_COUNT_1_BIT;
  ro.stereo = view == "stereo";
  if (const std::string m = args.get("stereo-mode"); m == "multiview" || m == "two-pass") {
    ro.stereoMode = m == "multiview" ? engine::StereoMode::Multiview : engine::StereoMode::TwoPass;
  } else if (m != "default") {
    std::fprintf(stderr, "error: --stereo-mode must be multiview, two-pass or default\n");
    return 2;
  }
  auto renderer = engine::AvatarRenderer::create(**device, asset, ro);
  if (!renderer) {
    std::fprintf(stderr, "error: %s\n", renderer.error().c_str());
    return 1;
  }
  auto& r = **renderer;
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  engine::FrameOptions fo;
  fo.grid = !args.has("no-grid");
  fo.skeleton = args.has("skeleton");
  if (args.has("gizmos")) fo.gizmos = r.trackingGizmos(pose);

  std::error_code ec;
  const std::filesystem::path out = args.get("out");
  std::filesystem::create_directories(out, ec);
  if (ec) {
    std::fprintf(stderr, "error: cannot create %s: %s\n", out.c_str(), ec.message().c_str());
    return 1;
  }
  std::vector<std::pair<std::filesystem::path, avatar::Image>> frames;
  const float aspect = float(width) / float(height);
  if (view == "third") {
    auto img = r.render(pose, r.orbitAround(pose, yaw, pitch), fo);
    if (!img) return std::fprintf(stderr, "error: %s\n", img.error().c_str()), 1;
    frames.emplace_back(out / "frame_0000.png", std::move(img).value());
  } else if (view == "first") {
    fo.view = engine::ViewKind::FirstPerson;
    // Look a little down at the own body, as a person in a headset does.
    const glm::mat4 eye = r.eyePose(pose) * glm::mat4_cast(glm::angleAxis(glm::radians(-60.0f), glm::vec3(1, 0, 0)));
    auto img = r.render(pose, engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(90.0f), aspect), 0.02f), fo);
    if (!img) return std::fprintf(stderr, "error: %s\n", img.error().c_str()), 1;
    frames.emplace_back(out / "frame_0000.png", std::move(img).value());
  } else {
    // Third-person stereo pair from the orbit camera's position, with headset-like asymmetric fovs.
    const engine::Camera orbit = r.orbitAround(pose, yaw, pitch);
    const engine::FovAngles left{-0.82f, 0.70f, 0.75f, -0.80f}, right{-0.70f, 0.82f, 0.75f, -0.80f};
    auto pair = r.renderStereo(pose, engine::stereoCameras(glm::inverse(orbit.view), 0.064f, left, right), fo);
    if (!pair) return std::fprintf(stderr, "error: %s\n", pair.error().c_str()), 1;
    frames.emplace_back(out / "frame_0000_left.png", std::move((*pair)[0]));
    frames.emplace_back(out / "frame_0000_right.png", std::move((*pair)[1]));
  }
  for (const auto& [path, img] : frames) {
    if (auto s = engine::writePng(path.string(), img); !s) {
      std::fprintf(stderr, "error: %s\n", s.error().c_str());
      return 1;
    }
    std::printf("wrote %s\n", path.c_str());
  }
  std::printf("device: %s\n", (*device)->driverString().c_str());
  std::printf("avatar: %s, %zu triangles, %zu joints\n", avatarArg.c_str(), asset.mesh.triangleCount(),
              asset.skeleton.joints.size());
  return 0;
}

}  // namespace

EMBODY_COMMAND("render", "drive an avatar with a motion through the IK runtime and render it offscreen to PNG frames + stats", runRender);
