#include "app/render_job.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <glm/gtc/constants.hpp>
#include <nlohmann/json.hpp>

#include "app/avatar_arg.h"
#include "app/job_inputs.h"
#include "app/motion_export.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/vrm/secondary_motion.h"
#include "engine/avatar_renderer.h"
#include "engine/device.h"
#include "engine/image_io.h"
#include "engine/instance.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/ik_thread.h"
#include "runtime/seated_stats.h"
#include "tracking/bvh_export.h"
#include "tracking/pose_source.h"
#include "tracking/trace.h"

namespace embody::app {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

// Up to `count` frames evenly through the run, tiled into one image at most ~1200 px wide.
avatar::Image contactSheet(const std::vector<avatar::Image>& thumbs) {
  avatar::Image sheet;
  if (thumbs.empty()) return sheet;
  const int cols = std::min<int>(4, int(thumbs.size()));
  const int rows = (int(thumbs.size()) + cols - 1) / cols;
  const int tw = thumbs[0].width, th = thumbs[0].height, gap = 4;
  sheet.width = cols * tw + (cols + 1) * gap;
  sheet.height = rows * th + (rows + 1) * gap;
  sheet.rgba.assign(size_t(sheet.width) * size_t(sheet.height) * 4, 24);
  for (size_t k = 3; k < sheet.rgba.size(); k += 4) sheet.rgba[k] = 255;
  for (size_t i = 0; i < thumbs.size(); ++i) {
    const int x0 = gap + int(i % size_t(cols)) * (tw + gap), y0 = gap + int(i / size_t(cols)) * (th + gap);
    for (int y = 0; y < th; ++y)
      std::copy_n(&thumbs[i].rgba[size_t(y) * size_t(tw) * 4], size_t(tw) * 4,
                  &sheet.rgba[(size_t(y0 + y) * size_t(sheet.width) + size_t(x0)) * 4]);
  }
  return sheet;
}

// Box-filtered downscale by an integer factor.
avatar::Image shrink(const avatar::Image& img, int factor) {
  if (factor <= 1) return img;
  avatar::Image out;
  out.width = img.width / factor;
  out.height = img.height / factor;
  out.rgba.resize(size_t(out.width) * size_t(out.height) * 4);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 4; ++c) {
        int sum = 0;
        for (int dy = 0; dy < factor; ++dy)
          for (int dx = 0; dx < factor; ++dx)
            sum += img.rgba[(size_t(y * factor + dy) * size_t(img.width) + size_t(x * factor + dx)) * 4 + size_t(c)];
        out.rgba[(size_t(y) * size_t(out.width) + size_t(x)) * 4 + size_t(c)] = uint8_t(sum / (factor * factor));
      }
  return out;
}

namespace {

// Two images side by side.
avatar::Image sideBySide(const avatar::Image& a, const avatar::Image& b) {
  avatar::Image out;
  out.width = a.width + b.width;
  out.height = std::max(a.height, b.height);
  out.rgba.assign(size_t(out.width) * size_t(out.height) * 4, 0);
  for (int y = 0; y < out.height; ++y) {
    if (y < a.height) std::copy_n(&a.rgba[size_t(y) * size_t(a.width) * 4], size_t(a.width) * 4, &out.rgba[size_t(y) * size_t(out.width) * 4]);
    if (y < b.height)
      std::copy_n(&b.rgba[size_t(y) * size_t(b.width) * 4], size_t(b.width) * 4,
                  &out.rgba[(size_t(y) * size_t(out.width) + size_t(a.width)) * 4]);
  }
  return out;
}

// A p95 error in millimetres, or "n/a" where the run had no such data (the summary's -1).
std::string millimetres(double metres) {
  if (metres < 0.0) return "n/a";
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f mm", metres * 1e3);
  return text;
}

void progressBar(int done, int total, double elapsed) {
  const int width = 30, filled = total > 0 ? done * width / total : width;
  std::printf("\r[%s%s] %d/%d frames  %.1f s", std::string(size_t(filled), '#').c_str(),
              std::string(size_t(width - filled), ' ').c_str(), done, total, elapsed);
  std::fflush(stdout);
}

// One frame of the solved pose in the job's view (third person, first person, or a stereo pair
// side by side).
Result<avatar::Image> renderView(engine::AvatarRenderer& renderer, const avatar::SkeletonPose& pose, const RenderJob& job,
                                 engine::FrameOptions fo) {
  if (job.gizmos) fo.gizmos = renderer.trackingGizmos(pose);
  if (job.view == "third") return renderer.render(pose, renderer.orbitAround(pose, job.yaw, job.pitch), fo);
  fo.view = engine::ViewKind::FirstPerson;
  // Looking a little down at the own body, as a person in a headset does.
  const glm::mat4 eye = renderer.eyePose(pose) * glm::mat4_cast(glm::angleAxis(glm::radians(-35.0f), glm::vec3(1, 0, 0)));
  if (job.view == "first") {
    const float aspect = float(job.width) / float(job.height);
    return renderer.render(pose, engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(90.0f), aspect), 0.02f), fo);
  }
  const engine::FovAngles left{-0.82f, 0.70f, 0.75f, -0.80f}, right{-0.70f, 0.82f, 0.75f, -0.80f};
  auto pair = renderer.renderStereo(pose, engine::stereoCameras(eye, 0.064f, left, right), fo);
  if (!pair) return Error{pair.error()};
  return sideBySide((*pair)[0], (*pair)[1]);
}

// Frames whose solved body stands the right way up: the eyes above the pelvis, the pelvis above
// both ankles, each by a tenth of the avatar's height along its up axis. A squat, a bow or
// a seat still counts; a body lying down, folded in a heap or upside down does not. The figure a
// user checks a new avatar or clip with (docs/tracking.md), beside the tracker errors.
struct UprightCount {
  size_t frames = 0, upright = 0;

  void add(const runtime::AvatarBodySolver& solver) {
    const runtime::LowerBodyPosture p = solver.posture();
    const Eigen::Vector3d& up = solver.up();
    const double margin = 0.1 * solver.avatarHeight();  // posture() is in avatar space
    const double pelvis = up.dot(p.pelvis);
    bool ok = up.dot(p.eye) > pelvis + margin;
    for (const auto& ankle : p.ankle)
      if (!ankle.isZero()) ok = ok && pelvis > up.dot(ankle) + margin;  // zero: the avatar has no such leg
    ++frames;
    upright += ok ? 1 : 0;
  }
};

// stats.json: the runtime's summary, the job and the body the solver built.
void writeStats(const RenderJob& job, const std::string& motion, float userHeight, const runtime::StatsSummary& sum,
                const runtime::AvatarBodySolver& body, uint64_t samplesSkipped, const runtime::SeatedStats& seated,
                const UprightCount& upright) {
  nlohmann::json j;
  runtime::toJson(j, sum);
  j["avatar"] = job.avatar;
  j["motion"] = motion;
  j["view"] = job.view;
  j["size"] = {job.width, job.height};
  j["fps"] = job.fps;
  j["calibration"] = {{"scale", body.scale()},
                      {"avatar_height_m", body.avatarHeight()},
                      {"user_height_m", userHeight > 0.0f ? nlohmann::json(double(userHeight)) : nlohmann::json(nullptr)},
                      {"from_first_head_sample", body.calibratedFromHead()}};
  j["body"] = {{"spine_model", body.body().spineModel},
               {"coupled_spine", job.coupledSpine},
               {"dofs", body.body().model.dofs},
               {"three_point", body.threePoint()},
               {"steps", body.feet().steps()},
               {"collapsed_frames", body.collapseGuard().collapsedFrames()},
               {"recoveries", body.collapseGuard().recoveries()},
               {"upright_frames", upright.upright}};
  j["ik"]["samples_skipped"] = samplesSkipped;
  if (job.seated) seated.toJson(j);
  std::ofstream(job.out / "stats.json") << j.dump(2) << "\n";
}

// The frame loop: sample -> IK thread (budgeted, lockstep: each frame waits for its sample's
// solve, so runs are repeatable) -> triple buffer -> skin + render -> PNG. Returns "" or the error.
struct FrameLoop {
  const RenderJob& job;
  tracking::PoseSource& source;
  runtime::AvatarBodySolver& solver;
  engine::AvatarRenderer& renderer;
  tracking::TraceWriter& recorder;
  runtime::IkThread& ik;
  MotionExport& exported;
  avatar::SecondaryMotion& secondary;  // VRM spring bones, blinking, look-at (after IK, before skinning)
  int frames = 0;
  avatar::SkeletonPose shown;  // the solved pose with the secondary motion on it
  runtime::StatsRecorder stats;
  runtime::SeatedStats seated = runtime::SeatedStats();
  UprightCount upright;
  std::vector<avatar::Image> thumbs;

  std::string run() {
    stats.reserve(size_t(frames));
    const int sheetCount = std::min(frames, 12);
    const int shrinkFactor = std::max(1, (job.view == "stereo" ? 2 * job.width : job.width) / 280);
    const bool bar = job.progress && isatty(STDOUT_FILENO);
    const auto started = Clock::now();
    engine::FrameOptions fo;
    fo.grid = job.grid;
    fo.skeleton = job.skeleton;
    for (int i = 0; i < frames; ++i) {
      const tracking::PoseSample sample = source.sample(double(i) / job.fps);
      if (!job.record.empty())
        if (auto s = recorder.write(sample); !s) return s.error();
      ik.submit(sample);
      if (!ik.waitForFrames(uint32_t(i + 1), 30.0)) return "the IK thread stopped answering";
      ik.acquire();
      const runtime::SolvedFrame& solved = ik.frame();
      runtime::FrameStats fs = solved.stats;
      exported.add(solved.pose);
      // The IK thread is idle until the next submit (waitForFrames synchronised with its solve).
      if (job.seated) seated.add(solver);
      upright.add(solver);
      const auto t0 = Clock::now();
      // Third person: the avatar looks at the viewer (the orbit camera); first person: ahead.
      std::optional<glm::vec3> viewer;
      if (job.view == "third") viewer = renderer.orbitAround(solved.pose, job.yaw, job.pitch).position();
      shown = solved.pose;
      secondary.update(shown, 1.0 / job.fps, viewer);
      fo.morphWeights = secondary.morphWeights();
      fo.materialStates = secondary.materialStates();
      fo.seconds = secondary.seconds();
      Result<avatar::Image> image = renderView(renderer, shown, job, fo);
      if (!image) return image.error();
      fs.renderSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
      stats.add(fs);
      char name[32];
      std::snprintf(name, sizeof(name), "frame_%05d.png", i);
      if (job.writeFrames)
        if (auto s = engine::writePng((job.out / name).string(), *image); !s) return s.error();
      if (sheetCount > 0 && (i * sheetCount) / frames != ((i + 1) * sheetCount) / frames) thumbs.push_back(shrink(*image, shrinkFactor));
      if (bar) progressBar(i + 1, frames, std::chrono::duration<double>(Clock::now() - started).count());
    }
    if (bar) std::printf("\n");
    return "";
  }
};

}  // namespace

int runRenderJob(const RenderJob& job) {
  if (job.view != "third" && job.view != "first" && job.view != "stereo") return usageError("--view must be first, third or stereo");
  if (job.frames < 0 || job.frames > 100000) return usageError("--frames must be 0 .. 100000");
  if (const std::string bad = checkExportPath(job.exportPath); !bad.empty()) return usageError(bad);

  // The avatar and the motion first: bad files are the likely errors and need no GPU to report.
  auto inputs = openJobInputs(job);
  if (!inputs) return runtimeError(inputs.error());
  const avatar::AvatarAsset& asset = inputs->asset;
  tracking::PoseSource& source = *inputs->source;
  for (const auto& note : source.notes()) std::printf("motion: %s\n", note.c_str());
  const int frames = job.frames > 0 ? job.frames : std::max(1, int(std::min(source.duration(), 20.0) * job.fps));

  auto solver = runtime::AvatarBodySolver::create(asset, bodyOptionsFor(job, *inputs));
  if (!solver) return runtimeError("avatar " + job.avatar + ": " + solver.error());

  MotionExport exported;
  exported.open(job.exportPath, asset, inputs->bvhAvatar ? &*inputs->bvhAvatar : nullptr, 1.0 / job.fps, size_t(frames));
  if (exported.clipFrameTime() > 0.0 && std::abs(exported.clipFrameTime() * job.fps - 1.0) > 1e-6)
    std::printf("export: frames at %.6g Hz (--fps), not the clip's %.6g Hz: pass --fps %.6g to keep its frame time\n",
                job.fps, 1.0 / exported.clipFrameTime(), 1.0 / exported.clipFrameTime());

  tracking::TraceWriter recorder;
  if (!job.record.empty())
    if (auto s = recorder.open(job.record, source.trackers(), source.name(), inputs->sourceOptions.userHeight); !s)
      return runtimeError(s.error());

  engine::InstanceOptions io;
  io.validation = job.validate ? engine::Validation::IfPresent : engine::Validation::Off;
  auto instance = engine::Instance::create(io);
  if (!instance) return runtimeError(instance.error());
  auto device = engine::Device::create(*instance, job.device);
  if (!device) return runtimeError(device.error());
  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(job.width);
  ro.height = uint32_t(job.height);
  ro.samples = job.msaa ? VK_SAMPLE_COUNT_4_BIT : VK_SAMPLE_COUNT_1_BIT;
  ro.stereo = job.view == "stereo";
  auto created = engine::AvatarRenderer::create(**device, asset, ro);
  if (!created) return runtimeError(created.error());

  std::error_code ec;
  std::filesystem::create_directories(job.out, ec);
  if (ec) return runtimeError("cannot create " + job.out.string() + ": " + ec.message());

  runtime::IkStageConfig cfg;
  cfg.budgetSeconds = job.budgetMs * 1e-3;
  cfg.fixedIterations = job.ikIterations;
  cfg.guard.userHeight = inputs->sourceOptions.userHeight;
  runtime::IkThread ik(**solver, runtime::steadyClock(), cfg, avatar::SkeletonPose::rest(asset.skeleton));
  ik.start();
  avatar::SecondaryMotion secondary(asset);
  FrameLoop loop{job, source, **solver, **created, recorder, ik, exported, secondary, frames};
  const std::string error = loop.run();
  ik.stop();
  if (!error.empty()) return runtimeError(error);
  if (!job.record.empty())
    if (auto s = recorder.close(); !s) return runtimeError(s.error());

  if (!job.exportPath.empty()) {
    if (auto s = exported.write(asset); !s) return runtimeError(s.error());
    std::printf("exported the solved motion (%d frames) to %s\n", frames, job.exportPath.c_str());
  }
  if (auto s = engine::writePng((job.out / "contact_sheet.png").string(), contactSheet(loop.thumbs)); !s) return runtimeError(s.error());
  const runtime::StatsSummary sum = loop.stats.summary();
  writeStats(job, source.name(), inputs->userHeight, sum, **solver, ik.samplesSkipped(), loop.seated, loop.upright);
  std::printf("wrote %d frames, contact_sheet.png and stats.json to %s\n", job.writeFrames ? frames : 0, job.out.c_str());
  std::printf("ik: p50 %.2f ms, p99 %.2f ms (budget %.2f ms), %zu deadline misses, %.1f iterations", sum.ikP50Ms,
              sum.ikP99Ms, sum.budgetMs, sum.deadlineMisses, sum.iterationsMean);
  if (sum.startupMs >= 0.0)
    std::printf("; start-up solve %.1f ms (%d iterations, once, outside the budget)", sum.startupMs, sum.startupIterations);
  std::printf("\n");
  std::printf("tracking: head error p95 %s, hand error p95 %s; body upright in %zu of %zu frames; render p50 %.1f ms\n",
              millimetres(sum.headErrorP95).c_str(), millimetres(sum.handErrorP95).c_str(), loop.upright.upright,
              loop.upright.frames, sum.renderP50Ms);
  if (job.validate && instance->validationEnabled()) std::fprintf(stderr, "validation messages: %u\n", instance->messageCount());
  return 0;
}

}  // namespace embody::app
