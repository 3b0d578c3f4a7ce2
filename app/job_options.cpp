#include "app/job_options.h"

#include <cstdio>
#include <stdexcept>

#include "app/motion_export.h"
#include "avatar/body/calibration.h"

namespace embody::app {

void addJobOptions(Args& args, unsigned groups, const JobOptionDefaults& defaults) {
  auto orNone = [](const std::string& v) { return v.empty() ? std::nullopt : std::optional<std::string>(v); };
  if (groups & kAvatarOptions) {
    args.option("avatar", "FILE|default", "a .gltf/.glb/.vrm file, a .bvh clip (its own skeleton with a capsule per bone), or 'default': the "
                "built-in procedural avatar (when absent)");
    args.option("bone-map", "FILE", "JSON object VRM-1.0-bone-name -> node name; its entries win over every other mapping");
  }
  if (groups & kMotionOptions) {
    args.option("motion", "SOURCE", "FILE.bvh, FILE.jsonl or synthetic:NAME (embody motion list)", orNone(defaults.motion));
    args.option("fps", "HZ", "frame rate: the motion is sampled every 1/fps s (1 .. 1000)", "90");
    args.option("bvh-scale", "M_PER_UNIT", "metres per BVH unit (default: fit the clip to the user's height)");
    declareBvhOptions(args);
    args.flag("three-point", "keep only head and hands (HMD + controllers): the lower body is inferred, feet step");
  }
  if (groups & kBodyOptions) {
    args.option("spine", "MODE", "IK spine: auto, full (every vertebra) or simplified", "auto");
    args.flag("uncoupled-spine", "independent spine sites (one ball joint each) instead of the coupled spine "
                                 "(Raunhardt & Boulic 2008, the default)");
    args.option("user-height", "METRES", "the user's height, " + avatar::bodyHeightRange() +
                                             " (default: the profile's, else from the first head sample)");
    args.option("profile", "FILE", "user profile JSON (embody avatar calibrate): the user's height");
  }
  if (groups & kFrameOptions)
    args.option("size", "WxH", "frame size, 16x16 .. 8192x8192", orNone(defaults.size));
  if (groups & kBudgetOptions) args.option("ik-budget-ms", "MS", "IK time budget per frame (> 0, at most 1000)", "1");
  if (groups & kIterationOptions)
    args.option("ik-iterations", "N", "a fixed IK iteration count per frame (1 .. 1000) instead of the time budget: the "
                "same command gives the same output bytes (offline, reproducible runs)");
  if (groups & kExportOptions)
    args.option("export", "FILE.bvh|FILE.glb", "write the solved motion (the body shown, every frame): BVH on the "
                "avatar's hierarchy (for a BVH avatar the clip's own hierarchy, channels and frame time), or the avatar "
                "as glTF binary with the motion as an animation");
}

void parseSize(const std::string& text, int& width, int& height) {
  const std::invalid_argument bad("--size must look like 480x480 (16 .. 8192 each), got '" + text + "'");
  const size_t x = text.find('x');
  if (x == std::string::npos || x == 0 || x + 1 >= text.size()) throw bad;
  long w = 0, h = 0;
  try {
    size_t usedW = 0, usedH = 0;
    w = std::stol(text.substr(0, x), &usedW);
    h = std::stol(text.substr(x + 1), &usedH);
    if (usedW != x || usedH != text.size() - x - 1) throw bad;
  } catch (const std::logic_error&) {  // invalid_argument / out_of_range from stol
    throw bad;
  }
  if (w < kMinSide || h < kMinSide || w > kMaxSide || h > kMaxSide) throw bad;
  width = int(w);
  height = int(h);
}

double readFps(const Args& args) {
  const double fps = args.number("fps");
  if (!(fps >= kMinFps && fps <= kMaxFps)) throw std::invalid_argument("--fps must be 1 .. 1000 Hz");
  return fps;
}

void readJobOptions(const Args& args, unsigned groups, JobOptions& out) {
  if (groups & kAvatarOptions) {
    if (args.has("avatar")) out.avatar = args.get("avatar");
    out.boneMap = args.get("bone-map");
  }
  if (groups & kMotionOptions) {
    if (args.has("motion")) out.motion = args.get("motion");
    out.fps = readFps(args);
    if (args.has("bvh-scale")) {
      out.bvhScale = args.number("bvh-scale");
      if (!(out.bvhScale > 0.0)) throw std::invalid_argument("--bvh-scale must be positive");
    }
    out.bvh = readBvhOptions(args);
    out.threePoint = args.has("three-point");
  }
  if (groups & kBodyOptions) {
    if (!avatar::parseSpineMode(args.get("spine"), out.spine))
      throw std::invalid_argument("--spine must be auto, full or simplified");
    out.coupledSpine = !args.has("uncoupled-spine");
    out.profile = args.get("profile");
    if (args.has("user-height")) {
      const double h = args.number("user-height");
      if (!avatar::plausibleBodyHeight(h))
        throw std::invalid_argument("--user-height must be " + avatar::bodyHeightRange());
      out.userHeight = float(h);
    }
  }
  if ((groups & kFrameOptions) && args.has("size")) parseSize(args.get("size"), out.width, out.height);
  if (groups & kBudgetOptions) {
    out.budgetMs = args.number("ik-budget-ms");
    if (!(out.budgetMs > 0.0 && out.budgetMs <= kMaxBudgetMs))
      throw std::invalid_argument("--ik-budget-ms must be > 0 and at most 1000");
  }
  if ((groups & kIterationOptions) && args.has("ik-iterations")) {
    out.ikIterations = args.integer("ik-iterations");
    if (!(out.ikIterations >= 1 && out.ikIterations <= kMaxIkIterations))
      throw std::invalid_argument("--ik-iterations must be 1 .. 1000");
  }
  if (groups & kExportOptions) {
    out.exportPath = args.get("export");
    if (const std::string bad = checkExportPath(out.exportPath); !bad.empty()) throw std::invalid_argument(bad);
  }
}

}  // namespace embody::app
