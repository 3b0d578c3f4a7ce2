#include "app/mirror_job.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <glm/gtc/constants.hpp>
#include <thread>

#include "app/job_inputs.h"
#include "engine/avatar_renderer.h"
#include "engine/desktop_window.h"
#include "engine/image_io.h"
#include "engine/instance.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/frame_stats.h"
#include "runtime/ik_thread.h"
#include "tracking/pose_source.h"

namespace embody::app {

namespace {

using Clock = std::chrono::steady_clock;

// One window frame of `pose`: the camera for the window's view, the scene, and the renderer's
// begin / draw / end / present. `drawn`: the window had an image to draw into.
Status drawFrame(engine::AvatarRenderer& ar, engine::DesktopWindow& win, VkQueue queue, const avatar::SkeletonPose& pose,
                 const RenderJob& job, uint64_t rendererFrame, bool screenshot, bool& drawn) {
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
  engine::SceneFrame scene;
  scene.avatar = &ar.gpuAvatar();
  scene.palette = ar.palette();
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

void printSummary(uint64_t shown, double seconds, const runtime::StatsSummary& sum) {
  std::printf("mirror: %llu frames shown in %.2f s (%.1f fps); ik p50 %.2f ms, p99 %.2f ms, %zu deadline misses\n",
              static_cast<unsigned long long>(shown), seconds, seconds > 0 ? double(shown) / seconds : 0.0, sum.ikP50Ms,
              sum.ikP99Ms, sum.deadlineMisses);
}

// The next frame shown is the last one --frames asks for.
bool lastFrameOf(const MirrorJob& mj, uint64_t shown) { return mj.frames > 0 && shown + 1 == uint64_t(mj.frames); }

}  // namespace

bool displayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

int runMirror(const MirrorJob& mj) {
  const RenderJob& job = mj.run;
  if (job.view != "third" && job.view != "first") return usageError("--view must be first or third");
  if (mj.frames < 0) return usageError("--frames must be 0 or more");
  // Files first (the likely errors, no display needed to report them), then the display.
  auto inputs = openJobInputs(job);
  if (!inputs) return runtimeError(inputs.error());
  const avatar::AvatarAsset& asset = inputs->asset;
  const tracking::SourceOptions& so = inputs->sourceOptions;
  tracking::PoseSource& source = *inputs->source;
  auto solver = runtime::AvatarBodySolver::create(asset, bodyOptionsFor(job, *inputs));
  if (!solver) return runtimeError("avatar " + job.avatar + ": " + solver.error());

  auto extensions = engine::DesktopWindow::requiredInstanceExtensions();
  if (!extensions) return runtimeError("embody mirror: " + extensions.error());
  engine::InstanceOptions io;
  io.validation = job.validate ? engine::Validation::IfPresent : engine::Validation::Off;
  io.extensions = *extensions;
  auto instance = engine::Instance::create(io);
  if (!instance) return runtimeError(instance.error());
  auto windowDevice = engine::WindowDevice::create(*instance, job.device == "auto" ? "" : job.device);
  if (!windowDevice) return runtimeError(windowDevice.error());
  engine::Device& device = (*windowDevice)->device();
  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(job.width);  // its offscreen target is unused; the size gives the cameras' aspect
  ro.height = uint32_t(job.height);
  auto created = engine::AvatarRenderer::create(device, asset, ro);
  if (!created) return runtimeError(created.error());
  engine::AvatarRenderer& ar = **created;
  engine::DesktopWindow::Keys keys;
  keys.thirdPerson = job.view == "third";
  auto window = engine::DesktopWindow::create(device, uint32_t(job.width), uint32_t(job.height),
                                           "embody mirror - V: view, Space: pause, Esc: quit", keys);
  if (!window) return runtimeError(window.error());
  engine::DesktopWindow& win = **window;

  const avatar::SkeletonPose rest = avatar::SkeletonPose::rest(asset.skeleton);
  runtime::IkStageConfig cfg;
  cfg.budgetSeconds = job.budgetMs * 1e-3;
  cfg.guard.userHeight = so.userHeight;
  runtime::IkThread ik(**solver, runtime::steadyClock(), cfg, rest);
  ik.start();
  runtime::StatsRecorder stats;
  const double duration = source.duration();
  const auto frameTime = std::chrono::duration<double>(1.0 / job.fps);
  double motionTime = 0.0;
  uint64_t rendererFrames = 0, shown = 0;
  uint32_t submitted = 0;
  auto last = Clock::now();
  const auto started = last;
  std::string error;
  std::printf("embody mirror: %s on %s, %s person (V: view, Space: pause, Esc: quit)\n", source.name().c_str(),
              job.avatar.c_str(), job.view.c_str());
  while (error.empty() && !win.closeRequested() && (mj.frames == 0 || shown < uint64_t(mj.frames))) {
    win.pollEvents();
    const auto now = Clock::now();
    // Real time, paused by Space; a fixed step when --frames makes the run repeatable.
    const double dt = mj.frames > 0 ? 1.0 / job.fps : std::chrono::duration<double>(now - last).count();
    last = now;
    if (!win.paused()) {
      motionTime += dt;
      if (mj.loop && duration > 0.0 && motionTime > duration) motionTime = std::fmod(motionTime, duration);
      ik.submit(source.sample(motionTime));
      ++submitted;
    }
    // The newest completed pose; the first one is waited for (there is nothing to show before it).
    if (submitted > 0 && ik.framesSolved() == 0 && !ik.waitForFrames(1, 10.0)) {
      error = "the IK thread stopped answering";
      break;
    }
    if (ik.acquire()) stats.add(ik.frame().stats);
    const avatar::SkeletonPose& pose = ik.framesSolved() > 0 ? ik.frame().pose : rest;
    bool drawn = false;
    const bool screenshot = lastFrameOf(mj, shown) && !mj.screenshot.empty();
    if (auto st = drawFrame(ar, win, device.queue(), pose, job, ++rendererFrames, screenshot, drawn); !st) {
      error = st.error();
      break;
    }
    if (drawn) ++shown;
    if (drawn && win.screenshotReady()) {
      auto img = win.takeScreenshot();
      if (!img) error = img.error();
      else if (auto s = engine::writePng(mj.screenshot, *img); !s) error = s.error();
      else std::printf("screenshot: %s (%dx%d)\n", mj.screenshot.c_str(), img->width, img->height);
    }
    // Without --frames, keep to the motion's rate instead of spinning the GPU.
    if (mj.frames == 0) std::this_thread::sleep_until(now + std::chrono::duration_cast<Clock::duration>(frameTime));
  }
  ik.stop();
  ar.renderer().waitIdle();
  if (!error.empty()) return runtimeError(error);
  printSummary(shown, std::chrono::duration<double>(Clock::now() - started).count(), stats.summary());
  if (job.validate && instance->validationEnabled()) std::fprintf(stderr, "validation messages: %u\n", instance->messageCount());
  return 0;
}

}  // namespace embody::app
