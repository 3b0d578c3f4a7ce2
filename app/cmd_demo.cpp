// embody demo: the main job on the embedded defaults. The default avatar does the paper's
// figure-eight with both hands (all trackers), rendered offscreen through the whole runtime
// (app/render_job.h); frames, a contact sheet and stats.json land in --out (out/demo). When a
// display is available and `embody mirror` is built, the mirror window opens too.
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/args.h"
#include "app/job_options.h"
#include "app/mirror_job.h"
#include "app/render_job.h"

namespace {

using namespace embody;

const app::Command* findCommand(const char* name) {
  for (const auto& c : app::commands())
    if (std::string(c.name) == name) return &c;
  return nullptr;
}

// The mirror's command line: the demo's own shared options (what the user gave, and the
// defaults), for --mirror-frames frames.
std::vector<std::string> mirrorArgs(const app::Args& demo) {
  std::vector<std::string> out = {"--frames", demo.get("mirror-frames")};
  for (const char* name : {"avatar", "bone-map", "motion", "fps", "bvh-scale", "spine", "user-height", "profile", "ik-budget-ms"})
    if (demo.has(name)) out.insert(out.end(), {std::string("--") + name, demo.get(name)});
  for (const char* flag : {"three-point", "uncoupled-spine"})
    if (demo.has(flag)) out.push_back(std::string("--") + flag);
  return out;
}

int runDemo(app::Argv argv) {
  app::Args args("embody demo",
                 "The main job on the embedded defaults: the default avatar follows a built-in motion through the IK "
                 "runtime; frames, contact_sheet.png and stats.json go to --out. Opens the mirror window too when a "
                 "display is available.");
  app::addJobOptions(args, app::kAllJobOptions | app::kIterationOptions);  // default avatar, synthetic:figure8, 480x480, 90 Hz, 1 ms
  args.option("out", "DIR", "output folder", "out/demo");
  args.option("frames", "N", "frames to render", "270");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.flag("no-mirror", "do not open the mirror window even when a display is available");
  args.option("mirror-frames", "N", "frames the mirror window shows (10 s at 90 Hz)", "900");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  app::RenderJob job;
  try {
    app::readJobOptions(args, app::kAllJobOptions | app::kIterationOptions, job);
    job.frames = args.integer("frames");
    if (job.frames < 1) throw std::invalid_argument("--frames must be at least 1");
    if (args.integer("mirror-frames") < 1) throw std::invalid_argument("--mirror-frames must be at least 1");
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  job.device = args.get("device");
  job.out = args.get("out");
  std::printf("embody demo: %s avatar, %s, %d frames at %.0f Hz, IK budget %.2f ms\n", job.avatar.c_str(), job.motion.c_str(),
              job.frames, job.fps, job.budgetMs);
  if (const int rc = app::runRenderJob(job); rc != 0) return rc;

  // The mirror window: only with a display, and only where the command exists.
  const bool display = app::displayAvailable();
  const app::Command* mirror = findCommand("mirror");
  if (args.has("no-mirror")) {
    std::printf("mirror: skipped (--no-mirror)\n");
  } else if (!display) {
    std::printf("mirror: skipped (no display)\n");
  } else if (!mirror) {
    std::printf("mirror: skipped (embody mirror is not part of this build)\n");
  } else {
    return mirror->run(mirrorArgs(args));
  }
  return 0;
}

}  // namespace

EMBODY_COMMAND("demo", "the main job on the embedded defaults: default avatar + built-in motion -> frames, contact sheet, stats", runDemo);
