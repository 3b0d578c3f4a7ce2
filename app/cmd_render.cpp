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
#include "app/job_options.h"
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

// The frame size, camera angles and view every render takes (the rest of its options are shared
// with mirror/demo/xr through app/job_options.h or read by renderMotion/renderRestPose).
struct RenderView {
  int width = 0, height = 0;
  float yaw = 0.0f, pitch = 0.0f;
  std::string view;
};

void declareRenderOptions(app::Args& args) {
  app::JobOptionDefaults defaults;
  defaults.motion = "";  // without --motion: the rest pose
  defaults.size = "";    // motion 480x480, rest pose 1280x720
  app::addJobOptions(args, app::kAllJobOptions | app::kIterationOptions | app::kExportOptions, defaults);
  args.option("out", "DIR", "output folder (created if missing)");
  args.option("frames", "N", "frames to render (default: the motion's duration, at most 20 s)");
  args.option("width", "PIXELS", "frame width (or --size; motion default 480, rest pose 1280)");
  args.option("height", "PIXELS", "frame height (or --size; motion default 480, rest pose 720)");
  args.option("view", "KIND", "third (orbit camera), first (at the eyes) or stereo (two eyes, side by side with "
              "--motion); third-person/first-person also accepted", "third");
  args.option("record", "FILE.jsonl", "also record the motion's samples as a JSON Lines trace");
  args.flag("seated", "seated mode: the lower body sits on a seat placed under the first head sample, the spine and "
                      "arms follow (try --motion synthetic:seated)");
  args.option("yaw", "DEGREES", "orbit camera yaw around the avatar (0 = from the front)", "30");
  args.option("pitch", "DEGREES", "orbit camera pitch (positive looks down)", "10");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.option("stereo-mode", "MODE", "stereo pair as one 'multiview' pass or 'two-pass' (default: two-pass)");
  args.flag("msaa", "4x multisampling");
  args.flag("skeleton", "draw the skeleton overlay");
  args.flag("gizmos", "draw the tracking-target gizmos (head, hands)");
  args.flag("no-grid", "hide the ground grid");
  args.flag("validate", "enable the Khronos validation layer and print the message count at exit");
}

// Size, orbit angles and view; throws std::invalid_argument naming the option.
RenderView readRenderView(const app::Args& args) {
  RenderView v;
  const bool motion = args.has("motion");
  v.width = motion ? 480 : 1280;
  v.height = motion ? 480 : 720;
  if (args.has("size")) app::parseSize(args.get("size"), v.width, v.height);
  if (args.has("width")) v.width = args.integer("width");
  if (args.has("height")) v.height = args.integer("height");
  if (v.width < app::kMinSide || v.height < app::kMinSide || v.width > app::kMaxSide || v.height > app::kMaxSide)
    throw std::invalid_argument("--width/--height must be between 16 and 8192");
  v.yaw = glm::radians(float(args.number("yaw")));
  v.pitch = glm::radians(float(args.number("pitch")));
  v.view = args.get("view");
  if (v.view == "third-person" || v.view == "first-person") v.view = v.view.substr(0, v.view.find('-'));
  if (v.view != "third" && v.view != "first" && v.view != "stereo")
    throw std::invalid_argument("--view must be first, third or stereo");
  if (!motion && args.has("seated")) throw std::invalid_argument("--seated needs --motion (e.g. --motion synthetic:seated)");
  return v;
}

// With --motion: the whole runtime (app/render_job.h).
int renderMotion(const app::Args& args, const RenderView& v) {
  app::RenderJob job;
  try {
    app::readJobOptions(args, app::kAllJobOptions | app::kIterationOptions | app::kExportOptions, job);
    if (args.has("frames")) job.frames = args.integer("frames");
    if (args.has("frames") && job.frames < 1) throw std::invalid_argument("--frames must be at least 1");
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  job.record = args.get("record");
  job.seated = args.has("seated");
  job.width = v.width;
  job.height = v.height;
  job.view = v.view;
  job.yaw = v.yaw;
  job.pitch = v.pitch;
  job.device = args.get("device");
  job.validate = args.has("validate");
  job.msaa = args.has("msaa");
  job.skeleton = args.has("skeleton");
  job.gizmos = args.has("gizmos");
  job.grid = !args.has("no-grid");
  job.out = args.get("out");
  return app::runRenderJob(job);
}

// The rest pose's images for the view: one frame, or the left and right eyes for stereo.
Result<std::vector<std::pair<std::string, avatar::Image>>> restPoseImages(engine::AvatarRenderer& r,
                                                                          const avatar::SkeletonPose& pose,
                                                                          const RenderView& v, engine::FrameOptions fo) {
  std::vector<std::pair<std::string, avatar::Image>> frames;
  const float aspect = float(v.width) / float(v.height);
  if (v.view == "stereo") {
    // Third-person stereo pair from the orbit camera's position, with headset-like asymmetric fovs.
    const engine::Camera orbit = r.orbitAround(pose, v.yaw, v.pitch);
    const engine::FovAngles left{-0.82f, 0.70f, 0.75f, -0.80f}, right{-0.70f, 0.82f, 0.75f, -0.80f};
    auto pair = r.renderStereo(pose, engine::stereoCameras(glm::inverse(orbit.view), 0.064f, left, right), fo);
    if (!pair) return Error{pair.error()};
    frames.emplace_back("frame_0000_left.png", std::move((*pair)[0]));
    frames.emplace_back("frame_0000_right.png", std::move((*pair)[1]));
    return frames;
  }
  engine::Camera camera = r.orbitAround(pose, v.yaw, v.pitch);
  if (v.view == "first") {
    fo.view = engine::ViewKind::FirstPerson;
    // Look a little down at the own body, as a person in a headset does.
    const glm::mat4 eye = r.eyePose(pose) * glm::mat4_cast(glm::angleAxis(glm::radians(-60.0f), glm::vec3(1, 0, 0)));
    camera = engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(90.0f), aspect), 0.02f);
  }
  auto img = r.render(pose, camera, fo);
  if (!img) return Error{img.error()};
  frames.emplace_back("frame_0000.png", std::move(img).value());
  return frames;
}

// Without --motion: one frame of the rest pose.
int renderRestPose(const app::Args& args, const RenderView& v) {
  std::optional<engine::StereoMode> stereoMode;
  if (args.has("stereo-mode")) {
    const std::string m = args.get("stereo-mode");
    if (m != "multiview" && m != "two-pass") return app::usageError("--stereo-mode must be multiview or two-pass");
    stereoMode = m == "multiview" ? engine::StereoMode::Multiview : engine::StereoMode::TwoPass;
  }
  // The avatar first: a bad file is the most likely error and needs no GPU to report.
  app::JobOptions chosen;
  app::readJobOptions(args, app::kAvatarOptions, chosen);  // checked already: throws nothing here
  const std::string avatarArg = chosen.avatar;
  auto loaded = app::loadAvatarArg(avatarArg, chosen.boneMap);
  if (!loaded) return app::runtimeError(loaded.error());
  avatar::AvatarAsset asset = std::move(loaded).value();

  engine::InstanceOptions io;
#ifdef NDEBUG
  io.validation = args.has("validate") ? engine::Validation::IfPresent : engine::Validation::Off;
#else
  io.validation = engine::Validation::IfPresent;  // debug builds always validate when the layer exists
#endif
  auto instance = engine::Instance::create(io);
  if (!instance) return app::runtimeError(instance.error());
  ValidationReport report{&instance.value()};
  if (args.has("validate") && !instance->validationEnabled())
    std::fprintf(stderr, "warning: the validation layer is not installed (vulkan-validationlayers)\n");
  auto device = engine::Device::create(*instance, args.get("device"));
  if (!device) return app::runtimeError(device.error());

  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(v.width);
  ro.height = uint32_t(v.height);
  ro.samples = args.has("msaa") ? VK_SAMPLE_COUNT_4_BIT : VK_SAMPLE_COUNT_1_BIT;
  ro.stereo = v.view == "stereo";
  if (stereoMode) ro.stereoMode = *stereoMode;
  auto renderer = engine::AvatarRenderer::create(**device, asset, ro);
  if (!renderer) return app::runtimeError(renderer.error());
  auto& r = **renderer;
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  engine::FrameOptions fo;
  fo.grid = !args.has("no-grid");
  fo.skeleton = args.has("skeleton");
  if (args.has("gizmos")) fo.gizmos = r.trackingGizmos(pose);

  std::error_code ec;
  const std::filesystem::path out = args.get("out");
  std::filesystem::create_directories(out, ec);
  if (ec) return app::runtimeError("cannot create " + out.string() + ": " + ec.message());
  auto frames = restPoseImages(r, pose, v, fo);
  if (!frames) return app::runtimeError(frames.error());
  for (const auto& [name, img] : *frames) {
    if (auto s = engine::writePng((out / name).string(), img); !s) return app::runtimeError(s.error());
    std::printf("wrote %s\n", (out / name).c_str());
  }
  std::printf("device: %s\n", (*device)->driverString().c_str());
  std::printf("avatar: %s, %zu triangles, %zu joints\n", avatarArg.c_str(), asset.mesh.triangleCount(),
              asset.skeleton.joints.size());
  return 0;
}

int runRender(app::Argv argv) {
  app::Args args("embody render",
                 "Drives an avatar with a motion through the runtime (tracking -> budgeted IK thread -> skinning -> "
                 "offscreen frames) and writes frame_00000.png..., contact_sheet.png and stats.json into --out. "
                 "Without --motion: one frame of the rest pose (frame_0000.png).");
  declareRenderOptions(args);
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);
  if (!args.has("out")) return app::usageError("--out DIR is required");
  RenderView view;
  try {
    view = readRenderView(args);
    // The shared options are checked with or without --motion: a bad value is an error either way.
    app::JobOptions checked;
    app::readJobOptions(args, app::kAllJobOptions | app::kIterationOptions | app::kExportOptions, checked);
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  return args.has("motion") ? renderMotion(args, view) : renderRestPose(args, view);
}

}  // namespace

EMBODY_COMMAND("render", "drive an avatar with a motion through the IK runtime and render it offscreen to PNG frames + stats", runRender);
