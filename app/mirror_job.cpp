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

int fail(const std::string& message, int code = 1) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return code;
}

}  // namespace

bool displayAvailable() {
  const char* x = std::getenv("DISPLAY");
  const char* w = std::getenv("WAYLAND_DISPLAY");
  return (x && *x) || (w && *w);
}

int runMirror(const MirrorJob& mj) {
  const RenderJob& job = mj.run;
  if (job.view != "third" && job.view != "first") return fail("--view must be first or third", 2);
  if (!(job.fps >= 1.0 && job.fps <= 1000.0)) return fail("--fps must be 1 .. 1000", 2);
  if (mj.frames < 0) return fail("--frames must be 0 or more", 2);
  if (job.width < 64 || job.height < 64 || job.width > 8192 || job.height > 8192)
    return fail("--size must be 64x64 .. 8192x8192", 2);
  if (!(job.budgetMs > 0.0 && job.budgetMs <= 1000.0)) return fail("--ik-budget-ms must be > 0 and <= 1000", 2);
  if (job.userHeight != 0.0f && !(job.userHeight >= 0.5f && job.userHeight <= 2.5f))
    return fail("--user-height must be 0.5 .. 2.5 m", 2);
  avatar::SpineMode spine;
  if (!avatar::parseSpineMode(job.spine, spine)) return fail("--spine must be auto, full or simplified", 2);
  // Files first (the likely errors, no display needed to report them), then the display.
  auto inputs = openJobInputs(job);
  if (!inputs) return fail(inputs.error());
  const avatar::AvatarAsset& asset = inputs->asset;
  const tracking::SourceOptions& so = inputs->sourceOptions;
  tracking::PoseSource& source = *inputs->source;
  auto solver = runtime::AvatarBodySolver::create(asset, bodyOptionsFor(job, spine, *inputs));
  if (!solver) return fail("avatar " + job.avatar + ": " + solver.error());

  auto extensions = engine::DesktopWindow::requiredInstanceExtensions();
  if (!extensions) return fail("embody mirror: " + extensions.error());
  engine::InstanceOptions io;
  io.validation = job.validate ? engine::Validation::IfPresent : engine::Validation::Off;
  io.extensions = *extensions;
  auto instance = engine::Instance::create(io);
  if (!instance) return fail(instance.error());
  auto windowDevice = engine::WindowDevice::create(*instance, job.device == "auto" ? "" : job.device);
  if (!windowDevice) return fail(windowDevice.error());
  engine::Device& device = (*windowDevice)->device();
  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(job.width);  // its offscreen target is unused; the size gives the cameras' aspect
  ro.height = uint32_t(job.height);
  auto created = engine::AvatarRenderer::create(device, asset, ro);
  if (!created) return fail(created.error());
  engine::AvatarRenderer& ar = **created;
  engine::DesktopWindow::Keys keys;
  keys.thirdPerson = job.view == "third";
  auto window = engine::DesktopWindow::create(device, uint32_t(job.width), uint32_t(job.height),
                                           "embody mirror - V: view, Space: pause, Esc: quit", keys);
  if (!window) return fail(window.error());
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
    if (auto s = ar.computePose(pose); !s) {
      error = s.error();
      break;
    }
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
    const bool lastFrame = mj.frames > 0 && shown + 1 == uint64_t(mj.frames);
    if (lastFrame && !mj.screenshot.empty()) win.requestScreenshot();
    engine::SubmitSync sync;
    Status st = r.beginFrame();
    if (st) st = r.setScene(scene);
    ++rendererFrames;
    bool drawn = false;
    if (st) {
      auto d = win.draw(r, rendererFrames, cam, sync);
      if (!d) st = Status(Error{d.error()});
      else drawn = *d;
    }
    if (st) st = r.endFrame(sync);
    if (st) st = win.present(device.queue());
    if (!st) {
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
  if (!error.empty()) return fail(error);
  const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
  const runtime::StatsSummary sum = stats.summary();
  std::printf("mirror: %llu frames shown in %.2f s (%.1f fps); ik p50 %.2f ms, p99 %.2f ms, %zu deadline misses\n",
              static_cast<unsigned long long>(shown), seconds, seconds > 0 ? double(shown) / seconds : 0.0, sum.ikP50Ms,
              sum.ikP99Ms, sum.deadlineMisses);
  if (job.validate && instance->validationEnabled()) std::fprintf(stderr, "validation messages: %u\n", instance->messageCount());
  return 0;
}

}  // namespace embody::app
