#include "app/mirror_job.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/constants.hpp>
#include <memory>
#include <optional>
#include <thread>

#include "app/job_inputs.h"
#include "avatar/vrm/secondary_motion.h"
#include "engine/avatar_renderer.h"
#include "engine/desktop_window.h"
#include "engine/image_io.h"
#include "engine/instance.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/frame_stats.h"
#include "runtime/ik_thread.h"
#include "tracking/pose_source.h"
#include "tracking/space_transform.h"

namespace embody::app {

namespace {

using Clock = std::chrono::steady_clock;

// One window frame of `pose`: the camera for the window's view, the scene, and the renderer's
// begin / draw / end / present. `drawn`: the window had an image to draw into.
// `secondary` adds the VRM spring bones, blinking and look-at (at the window's camera in third
// person) to the solved pose, in `shown`, before skinning.
Status drawFrame(engine::AvatarRenderer& ar, engine::DesktopWindow& win, VkQueue queue, const avatar::SkeletonPose& pose,
                 const RenderJob& job, uint64_t rendererFrame, bool screenshot, bool& drawn,
                 avatar::SecondaryMotion& secondary, avatar::SkeletonPose& shown, double dt) {
  if (auto s = ar.computePose(pose); !s) return s;
  engine::Camera cam;
  const bool third = win.thirdPerson();
  if (third) {
    cam = ar.orbitAround(pose, job.yaw, job.pitch);
  } else {
    // At the eyes, looking down at the own body (the head is hidden; arms, chest and feet show).
    const glm::mat4 eye = ar.eyePose(pose) * glm::mat4_cast(glm::angleAxis(glm::radians(-60.0f), glm::vec3(1, 0, 0)));
    cam = engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(90.0f), win.aspect()), 0.02f);
  }
  shown = pose;
  secondary.update(shown, dt, third ? std::optional<glm::vec3>(cam.position()) : std::nullopt);
  if (auto s = ar.computePose(shown); !s) return s;
  engine::SceneFrame scene;
  scene.avatar = &ar.gpuAvatar();
  scene.palette = ar.palette();
  scene.morphWeights = secondary.morphWeights();
  scene.materialStates = secondary.materialStates();
  scene.seconds = secondary.seconds();
  scene.firstPerson = !third;
  scene.grid = job.grid;
  engine::Renderer& r = ar.renderer();
  if (screenshot) win.requestScreenshot();
  engine::SubmitSync sync;
  if (auto s = r.beginFrame(); !s) return s;
  if (auto s = r.setScene(scene); !s) return s;
  auto d = win.draw(r, rendererFrame, cam, sync);
  if (!d) return Error{d.error()};
  drawn = *d;
  if (auto s = r.endFrame(sync); !s) return s;
  return win.present(queue);
}

void printSummary(uint64_t shown, double seconds, const runtime::StatsSummary& sum, uint64_t recenters) {
  std::printf(
      "mirror: %llu frames shown in %.2f s (%.1f fps); ik p50 %.2f ms, p99 %.2f ms, %zu deadline misses; %llu recenters\n",
      static_cast<unsigned long long>(shown), seconds, seconds > 0 ? double(shown) / seconds : 0.0, sum.ikP50Ms,
      sum.ikP99Ms, sum.deadlineMisses, static_cast<unsigned long long>(recenters));
}

// The window's last image as a PNG (--screenshot); "" when written, else the error.
std::string writeScreenshot(engine::DesktopWindow& win, const std::string& path) {
  auto img = win.takeScreenshot();
  if (!img) return img.error();
  if (auto s = engine::writePng(path, *img); !s) return s.error();
  std::printf("screenshot: %s (%dx%d)\n", path.c_str(), img->width, img->height);
  return "";
}

// The next frame shown is the last one --frames asks for.
bool lastFrameOf(const MirrorJob& mj, uint64_t shown) { return mj.frames > 0 && shown + 1 == uint64_t(mj.frames); }

}  // namespace

bool displayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

namespace {

// The window side, in creation order (members are destroyed in reverse: window first, instance last).
struct MirrorDisplay {
  std::optional<engine::Instance> instance;
  std::unique_ptr<engine::WindowDevice> windowDevice;
  std::unique_ptr<engine::AvatarRenderer> renderer;
  std::unique_ptr<engine::DesktopWindow> window;

  engine::Device& device() { return windowDevice->device(); }
};

Status openDisplay(const RenderJob& job, const avatar::AvatarAsset& asset, MirrorDisplay& d) {
  auto extensions = engine::DesktopWindow::requiredInstanceExtensions();
  if (!extensions) return Error{"embody mirror: " + extensions.error()};
  engine::InstanceOptions io;
  io.validation = job.validate ? engine::Validation::IfPresent : engine::Validation::Off;
  io.extensions = *extensions;
  auto instance = engine::Instance::create(io);
  if (!instance) return Error{instance.error()};
  d.instance.emplace(std::move(*instance));
  auto windowDevice = engine::WindowDevice::create(*d.instance, job.device == "auto" ? "" : job.device);
  if (!windowDevice) return Error{windowDevice.error()};
  d.windowDevice = std::move(*windowDevice);
  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(job.width);  // its offscreen target is unused; the size gives the cameras' aspect
  ro.height = uint32_t(job.height);
  auto renderer = engine::AvatarRenderer::create(d.device(), asset, ro);
  if (!renderer) return Error{renderer.error()};
  d.renderer = std::move(*renderer);
  engine::DesktopWindow::Keys keys;
  keys.thirdPerson = job.view == "third";
  auto window = engine::DesktopWindow::create(d.device(), uint32_t(job.width), uint32_t(job.height),
                                              "embody mirror - V: view, Space: pause, R: recenter, Esc: quit", keys);
  if (!window) return Error{window.error()};
  d.window = std::move(*window);
  return {};
}

// The tracking side of the mirror: the motion's clock (paused by Space, looped), recentering (R,
// --recenter) and the hand-over of each sample to the IK thread.
struct MirrorMotion {
  tracking::PoseSource& source;
  runtime::IkThread& ik;
  bool loop = true;
  double time = 0.0;
  tracking::SpaceTransform space;  // the newest recenter: tracking space -> the mirror's world
  bool recenterPending = false;
  uint64_t recenters = 0;
  uint32_t submitted = 0;

  // Advances by `dt` seconds (not while paused) and submits the sample; a pending recenter takes
  // the motion's head as it is now (it waits for a valid head) and restarts the IK stage there.
  void step(double dt, bool paused, bool recenterRequested) {
    recenterPending = recenterPending || recenterRequested;
    if (paused && !recenterPending) return;
    if (!paused) {
      time += dt;
      const double duration = source.duration();
      if (loop && duration > 0.0 && time > duration) time = std::fmod(time, duration);
    }
    tracking::PoseSample sample = source.sample(time);
    if (recenterPending) recenterOn(sample[tracking::TrackerId::Head]);
    space.apply(sample);
    ik.submit(sample);
    ++submitted;
  }

  void recenterOn(const tracking::TrackerPose& head) {
    if (!head.valid || !tracking::isUsable(head)) return;
    space = tracking::recenterOn(head);
    ik.requestReset();
    recenterPending = false;
    ++recenters;
    const glm::vec3 turn = glm::degrees(glm::eulerAngles(space.rotation));
    std::printf("recentered: the head at (%.2f, %.2f) m, turned %.1f deg, now stands at the origin facing -Z\n",
                double(head.position.x), double(head.position.z), double(turn.y));
  }
};

}  // namespace

int runMirror(const MirrorJob& mj) {
  const RenderJob& job = mj.run;
  if (job.view != "third" && job.view != "first") return usageError("--view must be first or third");
  if (mj.frames < 0) return usageError("--frames must be 0 or more");
  // Files first (the likely errors, no display needed to report them), then the display.
  auto inputs = openJobInputs(job);
  if (!inputs) return runtimeError(inputs.error());
  const avatar::AvatarAsset& asset = inputs->asset;
  auto solver = runtime::AvatarBodySolver::create(asset, bodyOptionsFor(job, *inputs));
  if (!solver) return runtimeError("avatar " + job.avatar + ": " + solver.error());
  MirrorDisplay display;
  if (auto s = openDisplay(job, asset, display); !s) return runtimeError(s.error());
  engine::DesktopWindow& win = *display.window;

  const avatar::SkeletonPose rest = avatar::SkeletonPose::rest(asset.skeleton);
  runtime::IkStageConfig cfg;
  cfg.budgetSeconds = job.budgetMs * 1e-3;
  cfg.fixedIterations = job.ikIterations;
  cfg.guard.userHeight = inputs->sourceOptions.userHeight;
  runtime::IkThread ik(**solver, runtime::steadyClock(), cfg, rest);
  ik.start();
  MirrorMotion motion{*inputs->source, ik, mj.loop};
  motion.recenterPending = mj.recenterAtStart;
  runtime::StatsRecorder stats;
  avatar::SecondaryMotion secondary(asset);
  avatar::SkeletonPose shownPose = rest;  // the solved pose with the secondary motion on it
  uint64_t recentersSeen = 0;
  const auto frameTime = std::chrono::duration<double>(1.0 / job.fps);
  uint64_t rendererFrames = 0, shown = 0;
  auto last = Clock::now();
  const auto started = last;
  std::string error;
  std::printf("embody mirror: %s on %s, %s person (V: view, Space: pause, R: recenter, Esc: quit)\n",
              inputs->source->name().c_str(), job.avatar.c_str(), job.view.c_str());
  while (error.empty() && !win.closeRequested() && (mj.frames == 0 || shown < uint64_t(mj.frames))) {
    win.pollEvents();
    const auto now = Clock::now();
    // Real time, paused by Space; a fixed step when --frames makes the run repeatable.
    const double dt = mj.frames > 0 ? 1.0 / job.fps : std::chrono::duration<double>(now - last).count();
    last = now;
    motion.step(dt, win.paused(), win.takeRecenterRequest());
    // The newest completed pose; the first one is waited for (there is nothing to show before it).
    if (motion.submitted > 0 && ik.framesSolved() == 0 && !ik.waitForFrames(1, 10.0)) {
      error = "the IK thread stopped answering";
      break;
    }
    if (ik.acquire()) stats.add(ik.frame().stats);
    const avatar::SkeletonPose& pose = ik.framesSolved() > 0 ? ik.frame().pose : rest;
    bool drawn = false;
    const bool screenshot = lastFrameOf(mj, shown) && !mj.screenshot.empty();
    if (motion.recenters != recentersSeen) secondary.reset();  // the springs restart at rest after a recenter
    recentersSeen = motion.recenters;
    if (auto st = drawFrame(*display.renderer, win, display.device().queue(), pose, job, ++rendererFrames, screenshot,
                            drawn, secondary, shownPose, dt);
        !st) {
      error = st.error();
      break;
    }
    if (drawn) ++shown;
    if (drawn && win.screenshotReady()) error = writeScreenshot(win, mj.screenshot);
    // Without --frames, keep to the motion's rate instead of spinning the GPU.
    if (mj.frames == 0) std::this_thread::sleep_until(now + std::chrono::duration_cast<Clock::duration>(frameTime));
  }
  ik.stop();
  display.renderer->renderer().waitIdle();
  if (!error.empty()) return runtimeError(error);
  printSummary(shown, std::chrono::duration<double>(Clock::now() - started).count(), stats.summary(), motion.recenters);
  if (job.validate && display.instance->validationEnabled())
    std::fprintf(stderr, "validation messages: %u\n", display.instance->messageCount());
  return 0;
}

}  // namespace embody::app
