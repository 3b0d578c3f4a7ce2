// embody demo: the main job on the embedded defaults. The default avatar does the paper's
// figure-eight with both hands (all trackers), rendered offscreen through the whole runtime
// (app/render_job.h); frames, a contact sheet and stats.json land in --out (out/demo). When a
// display is available and `embody mirror` is built, the mirror window opens too.
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "app/args.h"
#include "app/render_job.h"

namespace {

using namespace embody;

const app::Command* findCommand(const char* name) {
  for (const auto& c : app::commands())
    if (std::string(c.name) == name) return &c;
  return nullptr;
}

int runDemo(app::Argv argv) {
  app::Args args("embody demo",
                 "The main job on the embedded defaults: the default avatar follows a built-in motion through the IK "
                 "runtime; frames, contact_sheet.png and stats.json go to --out. Opens the mirror window too when a "
                 "display is available.");
  args.option("out", "DIR", "output folder", "out/demo");
  args.option("motion", "SOURCE", "the motion (embody motion list)", "synthetic:figure8");
  args.option("frames", "N", "frames to render", "270");
  args.option("size", "WxH", "frame size", "480x480");
  args.option("ik-budget-ms", "MS", "IK time budget per frame", "1");
  args.option("ik-iterations", "N", "a fixed IK iteration count per frame instead of the time budget (reproducible output)");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.flag("no-mirror", "do not open the mirror window even when a display is available");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  app::RenderJob job;
  try {
    job.frames = args.integer("frames");
    job.budgetMs = args.number("ik-budget-ms");
    if (args.has("ik-iterations")) job.ikIterations = args.integer("ik-iterations");
    if (args.has("ik-iterations") && !(job.ikIterations >= 1 && job.ikIterations <= 1000))
      throw std::invalid_argument("--ik-iterations must be 1 .. 1000");
    const std::string size = args.get("size");
    const size_t x = size.find('x');
    if (x == std::string::npos) throw std::invalid_argument("--size must look like 480x480");
    job.width = std::stoi(size.substr(0, x));
    job.height = std::stoi(size.substr(x + 1));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  if (job.frames < 1) {
    std::fprintf(stderr, "error: --frames must be at least 1\n");
    return 2;
  }
  job.motion = args.get("motion");
  job.device = args.get("device");
  job.out = args.get("out");
  job.fps = 90.0;
  std::printf("embody demo: default avatar, %s, %d frames at %.0f Hz, IK budget %.2f ms\n", job.motion.c_str(), job.frames,
              job.fps, job.budgetMs);
  if (const int rc = app::runRenderJob(job); rc != 0) return rc;

  // The mirror window: only with a display, and only where the command exists.
  const bool display = std::getenv("DISPLAY") || std::getenv("WAYLAND_DISPLAY");
  const app::Command* mirror = findCommand("mirror");
  if (args.has("no-mirror")) {
    std::printf("mirror: skipped (--no-mirror)\n");
  } else if (!display) {
    std::printf("mirror: skipped (no display)\n");
  } else if (!mirror) {
    std::printf("mirror: skipped (embody mirror is not part of this build)\n");
  } else {
    const std::vector<std::string> mirrorArgs = {"--avatar", "default", "--motion", job.motion, "--frames", "900"};
    return mirror->run(mirrorArgs);
  }
  return 0;
}

}  // namespace

EMBODY_COMMAND("demo", "the main job on the embedded defaults: default avatar + built-in motion -> frames, contact sheet, stats", runDemo);
