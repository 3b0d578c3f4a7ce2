#pragma once
// The main job behind `embody render --motion ...` and `embody demo`: a pose source drives the
// runtime (filter, loss guard, budgeted PIK on the IK thread, triple-buffer hand-off) and every
// solved pose is skinned and rendered offscreen. Writes frame_00000.png..., contact_sheet.png and
// stats.json into the output folder.
#include <filesystem>
#include <string>
#include <vector>

#include "app/args.h"
#include "avatar/avatar_asset.h"

namespace embody::app {

struct RenderJob {
  std::string avatar = "default";  // FILE or "default"
  std::string boneMap;             // --bone-map FILE ("" none)
  std::string spine = "auto";      // auto | full | simplified
  bool coupledSpine = true;        // ik/spine's coupled joints; --uncoupled-spine: one ball per site
  std::string motion = "synthetic:figure8";
  std::string profile;             // --profile FILE (avatar/body/calibration.h: saveProfile)
  std::string record;              // --record FILE.jsonl ("" none)
  std::string exportPath;          // --export FILE.bvh|.glb: the solved motion, every frame ("" none)
  float userHeight = 0.0f;         // 0: the profile's, else from the first head sample
  double bvhScale = 0.0;
  bool threePoint = false;         // keep only head and hands
  bool seated = false;             // seated mode (runtime::SeatOptions): the lower body sits on a seat
  int frames = 0;                  // 0: the motion's duration (at most 20 s)
  double fps = 90.0;
  int width = 480, height = 480;
  std::string view = "third";      // third | first | stereo
  float yaw = 0.5f, pitch = 0.15f; // third-person orbit (radians)
  double budgetMs = 1.0;
  int ikIterations = 0;            // --ik-iterations: > 0 a fixed count per frame (deterministic), 0 the budget
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

// Reads the options `embody render --motion` and `embody mirror` share (avatar, motion, spine,
// bone map, profile, user height, BVH scale, fps, IK budget) into `job`; throws
// std::invalid_argument with a message naming the option on a bad value.
void readSharedJobOptions(const app::Args& args, RenderJob& job);

}  // namespace embody::app
