#pragma once
// The main job behind `embody render --motion ...` and `embody demo`: a pose source drives the
// runtime (filter, loss guard, budgeted PIK on the IK thread, triple-buffer hand-off) and every
// solved pose is skinned and rendered offscreen. Writes frame_00000.png..., contact_sheet.png and
// stats.json into the output folder.
#include <filesystem>
#include <string>

#include "app/args.h"
#include "app/job_options.h"

namespace embody::app {

// The shared options (avatar, body, motion, size, budget: app/job_options.h) and the rest.
struct RenderJob : JobOptions {
  std::string record;              // --record FILE.jsonl ("" none)
  bool seated = false;             // seated mode (runtime::SeatOptions): the lower body sits on a seat
  int frames = 0;                  // 0: the motion's duration (at most 20 s)
  std::string view = "third";      // third | first | stereo
  float yaw = 0.5f, pitch = 0.15f; // third-person orbit (radians)
  std::string device = "auto";
  bool validate = false, msaa = false, skeleton = false, gizmos = false, grid = true;
  bool writeFrames = true;
  bool progress = true;            // a progress bar when stdout is a terminal
  std::filesystem::path out;
};

// Up to 12 thumbnails tiled four to a row (the contact sheet of render and eval), and a
// box-filtered downscale by an integer factor.
avatar::Image contactSheet(const std::vector<avatar::Image>& thumbs);
avatar::Image shrink(const avatar::Image& img, int factor);

// Runs the job; prints errors as "error: ..." and returns the process exit code (0, 1 runtime
// error, 2 bad option values).
int runRenderJob(const RenderJob& job);

}  // namespace embody::app
