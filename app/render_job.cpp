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
#include "avatar/gltf/glb_writer.h"
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

int fail(const std::string& message, int code = 1) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return code;
}

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

void progressBar(int done, int total, double elapsed) {
  const int width = 30, filled = total > 0 ? done * width / total : width;
  std::printf("\r[%s%s] %d/%d frames  %.1f s", std::string(size_t(filled), '#').c_str(),
              std::string(size_t(width - filled), ' ').c_str(), done, total, elapsed);
  std::fflush(stdout);
}

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

int runRenderJob(const RenderJob& job) {
  if (job.view != "third" && job.view != "first" && job.view != "stereo") return fail("--view must be first, third or stereo", 2);
  if (!(job.fps >= 1.0 && job.fps <= 1000.0)) return fail("--fps must be 1 .. 1000", 2);
  if (job.frames < 0 || job.frames > 100000) return fail("--frames must be 0 .. 100000", 2);
  if (job.width < 16 || job.height < 16 || job.width > 8192 || job.height > 8192) return fail("--size must be 16x16 .. 8192x8192", 2);
  if (!(job.budgetMs > 0.0 && job.budgetMs <= 1000.0)) return fail("--ik-budget-ms must be > 0 and <= 1000", 2);
  if (job.ikIterations < 0 || job.ikIterations > 1000) return fail("--ik-iterations must be 1 .. 1000", 2);
  if (job.userHeight != 0.0f && !(job.userHeight >= 0.5f && job.userHeight <= 2.5f)) return fail("--user-height must be 0.5 .. 2.5 m", 2);
  avatar::SpineMode spine;
  if (!avatar::parseSpineMode(job.spine, spine)) return fail("--spine must be auto, full or simplified", 2);

  // The avatar and the motion first: bad files are the likely errors and need no GPU to report.
  auto inputs = openJobInputs(job);
  if (!inputs) return fail(inputs.error());
  const float userHeight = inputs->userHeight;
  const avatar::AvatarAsset& asset = inputs->asset;
  const tracking::SourceOptions& so = inputs->sourceOptions;
  tracking::PoseSource& source = *inputs->source;
  for (const auto& note : source.notes()) std::printf("motion: %s\n", note.c_str());
  const int frames = job.frames > 0 ? job.frames : std::max(1, int(std::min(source.duration(), 20.0) * job.fps));

  auto solver = runtime::AvatarBodySolver::create(asset, bodyOptionsFor(job, spine, *inputs));
  if (!solver) return fail("avatar " + job.avatar + ": " + solver.error());

  const bool exportGlb = job.exportPath.size() > 4 && job.exportPath.substr(job.exportPath.size() - 4) == ".glb";
  if (!job.exportPath.empty() && !isBvhPath(job.exportPath) && !exportGlb)
    return fail("--export writes FILE.bvh or FILE.glb: " + job.exportPath, 2);
  std::optional<tracking::SolvedMotionBvh> exported;
  avatar::GlbAnimation animation;
  animation.frameTime = 1.0 / job.fps;
  if (exportGlb) animation.frames.reserve(size_t(frames));
  if (isBvhPath(job.exportPath)) {
    exported = inputs->bvhAvatar ? tracking::SolvedMotionBvh::forBvhAvatar(*inputs->bvhAvatar)
                                 : tracking::SolvedMotionBvh::forAvatar(asset, 1.0 / job.fps);
    exported->reserve(size_t(frames));
    if (std::abs(exported->clip().frameTime * job.fps - 1.0) > 1e-6) {
      if (inputs->bvhAvatar)
        std::printf("export: frames at %.6g Hz (--fps), not the clip's %.6g Hz: pass --fps %.6g to keep its frame time\n",
                    job.fps, 1.0 / exported->clip().frameTime, 1.0 / exported->clip().frameTime);
      exported->setFrameTime(1.0 / job.fps);
    }
  }

  tracking::TraceWriter recorder;
  if (!job.record.empty())
    if (auto s = recorder.open(job.record, source.trackers(), source.name(), so.userHeight); !s) return fail(s.error());

  engine::InstanceOptions io;
  io.validation = job.validate ? engine::Validation::IfPresent : engine::Validation::Off;
  auto instance = engine::Instance::create(io);
  if (!instance) return fail(instance.error());
  auto device = engine::Device::create(*instance, job.device);
  if (!device) return fail(device.error());
  engine::AvatarRendererOptions ro;
  ro.width = uint32_t(job.width);
  ro.height = uint32_t(job.height);
  ro.samples = job.msaa ? VK_SAMPLE_COUNT_4_BIT : VK_SAMPLE_COUNT_1_BIT;
  ro.stereo = job.view == "stereo";
  auto created = engine::AvatarRenderer::create(**device, asset, ro);
  if (!created) return fail(created.error());
  engine::AvatarRenderer& renderer = **created;

  std::error_code ec;
  std::filesystem::create_directories(job.out, ec);
  if (ec) return fail("cannot create " + job.out.string() + ": " + ec.message());

  // Frame loop: sample -> IK thread (budgeted) -> triple buffer -> skin + render.
  const runtime::Clock& clock = runtime::steadyClock();
  runtime::IkStageConfig cfg;
  cfg.budgetSeconds = job.budgetMs * 1e-3;
  cfg.fixedIterations = job.ikIterations;
  cfg.guard.userHeight = so.userHeight;
  const avatar::SkeletonPose rest = avatar::SkeletonPose::rest(asset.skeleton);
  runtime::IkThread ik(**solver, clock, cfg, rest);
  ik.start();
  runtime::StatsRecorder stats;
  stats.reserve(size_t(frames));
  runtime::SeatedStats seated;
  const int sheetCount = std::min(frames, 12);
  std::vector<avatar::Image> thumbs;
  const int shrinkFactor = std::max(1, (job.view == "stereo" ? 2 * job.width : job.width) / 280);
  const bool bar = job.progress && isatty(STDOUT_FILENO);
  const auto started = Clock::now();
  engine::FrameOptions fo;
  fo.grid = job.grid;
  fo.skeleton = job.skeleton;
  const float aspect = float(job.width) / float(job.height);
  for (int i = 0; i < frames; ++i) {
    const tracking::PoseSample sample = source.sample(double(i) / job.fps);
    if (!job.record.empty())
      if (auto s = recorder.write(sample); !s) return ik.stop(), fail(s.error());
    ik.submit(sample);
    if (!ik.waitForFrames(uint32_t(i + 1), 30.0)) return ik.stop(), fail("the IK thread stopped answering");
    ik.acquire();
    const runtime::SolvedFrame& solved = ik.frame();
    runtime::FrameStats fs = solved.stats;
    if (exported) exported->add(solved.pose);
    if (exportGlb) animation.frames.push_back(solved.pose);
    // The IK thread is idle until the next submit (waitForFrames synchronised with its solve).
    if (job.seated) seated.add(**solver);
    const auto t0 = Clock::now();
    if (job.gizmos) fo.gizmos = renderer.trackingGizmos(solved.pose);
    Result<avatar::Image> image = Error{"no frame"};
    if (job.view == "third") {
      image = renderer.render(solved.pose, renderer.orbitAround(solved.pose, job.yaw, job.pitch), fo);
    } else {
      fo.view = engine::ViewKind::FirstPerson;
      // Looking a little down at the own body, as a person in a headset does.
      const glm::mat4 eye = renderer.eyePose(solved.pose) * glm::mat4_cast(glm::angleAxis(glm::radians(-35.0f), glm::vec3(1, 0, 0)));
      if (job.view == "first") {
        image = renderer.render(solved.pose, engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(90.0f), aspect), 0.02f), fo);
      } else {
        const engine::FovAngles left{-0.82f, 0.70f, 0.75f, -0.80f}, right{-0.70f, 0.82f, 0.75f, -0.80f};
        auto pair = renderer.renderStereo(solved.pose, engine::stereoCameras(eye, 0.064f, left, right), fo);
        if (pair) image = sideBySide((*pair)[0], (*pair)[1]);
        else image = Error{pair.error()};
      }
    }
    if (!image) return ik.stop(), fail(image.error());
    fs.renderSeconds = std::chrono::duration<double>(Clock::now() - t0).count();
    stats.add(fs);
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%05d.png", i);
    if (job.writeFrames)
      if (auto s = engine::writePng((job.out / name).string(), *image); !s) return ik.stop(), fail(s.error());
    if (sheetCount > 0 && (i * sheetCount) / frames != ((i + 1) * sheetCount) / frames) thumbs.push_back(shrink(*image, shrinkFactor));
    if (bar) progressBar(i + 1, frames, std::chrono::duration<double>(Clock::now() - started).count());
  }
  ik.stop();
  if (bar) std::printf("\n");
  if (!job.record.empty())
    if (auto s = recorder.close(); !s) return fail(s.error());

  if (exported)
    if (auto s = exported->write(job.exportPath); !s) return fail(s.error());
  if (exportGlb)
    if (auto s = avatar::writeGlbFile(asset, job.exportPath, &animation); !s) return fail("--export " + job.exportPath + ": " + s.error());
  if (!job.exportPath.empty()) std::printf("exported the solved motion (%d frames) to %s\n", frames, job.exportPath.c_str());
  if (auto s = engine::writePng((job.out / "contact_sheet.png").string(), contactSheet(thumbs)); !s) return fail(s.error());
  const runtime::StatsSummary sum = stats.summary();
  nlohmann::json j;
  runtime::toJson(j, sum);
  const runtime::AvatarBodySolver& body = **solver;
  j["avatar"] = job.avatar;
  j["motion"] = source.name();
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
               {"recoveries", body.collapseGuard().recoveries()}};
  j["ik"]["samples_skipped"] = ik.samplesSkipped();
  if (job.seated) seated.toJson(j);
  std::ofstream(job.out / "stats.json") << j.dump(2) << "\n";

  std::printf("wrote %d frames, contact_sheet.png and stats.json to %s\n", job.writeFrames ? frames : 0, job.out.c_str());
  std::printf("ik: p50 %.2f ms, p99 %.2f ms (budget %.2f ms), %zu deadline misses, %.1f iterations\n", sum.ikP50Ms,
              sum.ikP99Ms, sum.budgetMs, sum.deadlineMisses, sum.iterationsMean);
  std::printf("tracking: head error p95 %.1f mm, hand error p95 %.1f mm; render p50 %.1f ms\n", sum.headErrorP95 * 1e3,
              sum.handErrorP95 * 1e3, sum.renderP50Ms);
  if (job.validate && instance->validationEnabled()) std::fprintf(stderr, "validation messages: %u\n", instance->messageCount());
  return 0;
}

void readSharedJobOptions(const app::Args& args, RenderJob& job) {
  job.avatar = args.get("avatar");
  job.motion = args.get("motion");
  job.spine = args.get("spine");
  job.boneMap = args.get("bone-map");
  job.profile = args.get("profile");
  if (args.has("user-height")) job.userHeight = float(args.number("user-height"));
  if (args.has("bvh-scale")) job.bvhScale = args.number("bvh-scale");
  if (args.has("bvh-scale") && !(job.bvhScale > 0.0)) throw std::invalid_argument("--bvh-scale must be positive");
  job.fps = args.number("fps");
  job.budgetMs = args.number("ik-budget-ms");
  if (args.has("ik-iterations")) job.ikIterations = args.integer("ik-iterations");
  if (args.has("ik-iterations") && !(job.ikIterations >= 1 && job.ikIterations <= 1000))
    throw std::invalid_argument("--ik-iterations must be 1 .. 1000");
}

}  // namespace embody::app
