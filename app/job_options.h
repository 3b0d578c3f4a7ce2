#pragma once
// The one option set the job commands share (`embody render`, `mirror`, `demo`, `xr`): each
// option's name, help text, default, limits and parser are written here once, so every command
// spells, documents, limits and rejects it the same way (a bad value: exit 2, one line
// "error: --NAME ..." naming the option).
//
// Extending it (e.g. --ik-iterations, --export, --bvh-up, --bvh-forward): add the field to
// JobOptions, its declaration to addJobOptions() under the group of the commands that take it
// (or a new JobOptionGroup bit), and its read + check to readJobOptions(). Every command that
// asks for the group gets the option, its help line and its checks; no cmd_*.cpp changes.
#include <string>

#include "app/args.h"
#include "app/bvh_options.h"
#include "avatar/body/body_model.h"
#include "core/frame_rate.h"

namespace embody::app {

// Which shared options a command offers (bits, combined with |).
enum JobOptionGroup : unsigned {
  kAvatarOptions = 1u << 0,  // --avatar, --bone-map
  kBodyOptions = 1u << 1,    // --spine, --uncoupled-spine, --user-height, --profile
  kMotionOptions = 1u << 2,  // --motion, --fps, --bvh-scale, --bvh-up/--bvh-forward/--bvh-bone-map, --three-point
  kFrameOptions = 1u << 3,   // --size
  kBudgetOptions = 1u << 4,  // --ik-budget-ms
  kAllJobOptions = 0x1Fu,
  kIterationOptions = 1u << 5,  // --ik-iterations (offline, reproducible runs: render, demo, mirror)
  kExportOptions = 1u << 6,     // --export FILE.bvh|FILE.glb (render, xr: app/motion_export.h)
};

// The values of the shared options (the defaults are the CLI's).
struct JobOptions {
  std::string avatar = "default";  // FILE or "default"
  std::string boneMap;             // --bone-map FILE ("" none)
  avatar::SpineMode spine = avatar::SpineMode::Auto;
  bool coupledSpine = true;        // ik/spine's coupled joints; --uncoupled-spine: one ball per site
  float userHeight = 0.0f;         // 0: the profile's, else from the first head sample
  std::string profile;             // --profile FILE (avatar/body/calibration.h: saveProfile)
  std::string motion = "synthetic:figure8";
  double fps = 90.0;
  double bvhScale = 0.0;           // 0: fit the clip to the user's height
  BvhOverrides bvh;                // --bvh-up, --bvh-forward, --bvh-bone-map (app/bvh_options.h)
  bool threePoint = false;         // keep only head and hands
  int width = 480, height = 480;
  double budgetMs = 1.0;
  int ikIterations = 0;            // --ik-iterations: > 0 a fixed count per frame (deterministic), 0 the budget
  std::string exportPath;          // --export FILE.bvh|.glb: the body shown, every frame ("" none)
};

// The limits every command applies (the frame rates: core/frame_rate.h, kMinFps .. kMaxFps).
constexpr int kMinSide = 16, kMaxSide = 8192;
constexpr double kMaxBudgetMs = 1000.0;
constexpr int kMaxIkIterations = 1000;

// Per-command defaults of the shared options that have one ("" : no default, the option is
// optional and the command decides).
struct JobOptionDefaults {
  std::string motion = "synthetic:figure8";
  std::string size = "480x480";
};

// Declares the options of `groups` on `args`.
void addJobOptions(Args& args, unsigned groups, const JobOptionDefaults& defaults = {});

// Reads and checks the options of `groups` that were given (or have defaults) into `out`; throws
// std::invalid_argument with a one-line message naming the option on a bad value.
void readJobOptions(const Args& args, unsigned groups, JobOptions& out);

// "WxH" -> width, height within [kMinSide, kMaxSide]; throws std::invalid_argument naming --size.
void parseSize(const std::string& text, int& width, int& height);

// --fps's value within [kMinFps, kMaxFps] (also `embody motion record --fps`).
double readFps(const Args& args);

}  // namespace embody::app
