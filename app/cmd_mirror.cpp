// embody mirror: the avatar live in a desktop window, driven by a motion through the same runtime
// as `embody render --motion` (app/mirror_job.h). V switches first/third person, Space pauses,
// R recenters, Esc quits; --frames N exits by itself (with --screenshot, after writing the last
// frame), and with --ik-iterations such a run is repeatable.
#include <cstdio>
#include <glm/glm.hpp>
#include <stdexcept>

#include "app/args.h"
#include "app/job_options.h"
#include "app/mirror_job.h"

namespace {

using namespace embody;

int runMirrorCommand(app::Argv argv) {
  app::Args args("embody mirror",
                 "Shows the avatar live in a desktop window, driven by a motion through the IK runtime (pose source -> "
                 "budgeted IK thread -> skinning -> render). Keys: V first/third person, Space pause, R recenter (the "
                 "motion's head as it is now becomes the origin, facing -Z), Esc quit. Needs a display (X11 or "
                 "Wayland; Xvfb works).");
  app::JobOptionDefaults defaults;
  defaults.size = "640x640";
  app::addJobOptions(args, app::kAllJobOptions | app::kIterationOptions, defaults);
  args.option("frames", "N", "exit after N frames shown (0: until the window is closed)", "0");
  args.option("view", "KIND", "third (orbit camera) or first (at the eyes); V switches", "third");
  args.option("yaw", "DEGREES", "third-person orbit yaw (0 = from the front)", "30");
  args.option("pitch", "DEGREES", "third-person orbit pitch (positive looks down)", "10");
  args.option("screenshot", "FILE.png", "with --frames: write the window's last frame as PNG");
  args.option("device", "SELECTOR", "Vulkan device: auto, an index, 'lavapipe', or part of its name", "auto");
  args.flag("recenter", "recenter at start: the motion's first valid head becomes the origin, facing -Z (R does it live)");
  args.flag("no-grid", "hide the ground grid");
  args.flag("validate", "enable the Khronos validation layer and print the message count at exit");
  if (auto o = args.parse(argv); o != app::Args::Outcome::Ok) return app::Args::exitCode(o);

  app::MirrorJob mj;
  app::RenderJob& job = mj.run;
  try {
    app::readJobOptions(args, app::kAllJobOptions | app::kIterationOptions, job);
    mj.frames = args.integer("frames");
    if (mj.frames < 0) throw std::invalid_argument("--frames must be 0 or more");
    job.yaw = glm::radians(float(args.number("yaw")));
    job.pitch = glm::radians(float(args.number("pitch")));
  } catch (const std::invalid_argument& e) {
    return app::usageError(e.what());
  }
  job.view = args.get("view");
  if (job.view == "third-person" || job.view == "first-person") job.view = job.view.substr(0, job.view.find('-'));
  if (job.view != "third" && job.view != "first") return app::usageError("--view must be first or third");
  job.grid = !args.has("no-grid");
  mj.recenterAtStart = args.has("recenter");
  job.validate = args.has("validate");
  job.device = args.get("device");
  mj.screenshot = args.get("screenshot");
  if (!mj.screenshot.empty() && mj.frames <= 0) return app::usageError("--screenshot needs --frames N");
  return app::runMirror(mj);
}

}  // namespace

EMBODY_COMMAND("mirror", "the avatar live in a desktop window, driven by a motion through the IK runtime (V view, Space pause, R recenter)",
               runMirrorCommand);
