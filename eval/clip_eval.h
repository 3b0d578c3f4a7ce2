#pragma once
// One clip through the runtime, scored (`embody eval`, docs/eval.md). The avatar is the clip's
// own skeleton (tracking/bvh_avatar.h); only the chosen trackers reach the runtime, through the
// real path (One Euro filter, tracking-loss guard, stepping, PIK: runtime::IkStage with a fixed
// iteration count, so a score repeats to the bit); every joint is then set beside the clip's.
//
// Methods, side by side on the same clip: the coupled spine (the default body), the uncoupled
// spine, and a naive baseline that uses no solver: the rest pose stood on the floor under the
// head, turned to the head's heading, the head turned as the HMD, the arms by two-bone IK onto
// the hand trackers (elbows down and back), the hands turned as the controllers.
#include <array>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "core/result.h"
#include "eval/metrics.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_export.h"
#include "tracking/tracker.h"

namespace embody::eval {

// 3 = head + hands (HMD, controllers), 4 = + pelvis, 6 = + feet, full = 6 + a marker (position and
// orientation) on every joint the IK body has (AvatarBodyOptions::jointMarkers).
enum class TrackerSet { Three, Four, Six, Full };
bool parseTrackerSet(std::string_view text, TrackerSet& out);  // "3", "4", "6", "full"
const char* trackerSetName(TrackerSet set);
tracking::TrackerMask trackerMask(TrackerSet set);

enum class Method { Coupled, Uncoupled, Naive };
inline constexpr std::array<Method, 3> kMethods{Method::Coupled, Method::Uncoupled, Method::Naive};
const char* methodName(Method m);  // "coupled", "uncoupled", "naive"

struct EvalOptions {
  TrackerSet trackers = TrackerSet::Three;
  double fps = 0.0;      // 0: the clip's own rate
  int ikIterations = 10; // per frame (deterministic)
  int keepPoses = 0;     // > 0: keep this many of the coupled run's poses, evenly through the clip (contact sheet)
};

struct MethodRun {
  Method method = Method::Coupled;
  JointTrack solved;
  Metrics metrics;
  double seconds = 0.0;  // wall time of the run (not part of the score)
  std::vector<std::pair<int, avatar::SkeletonPose>> kept;  // (frame, pose), EvalOptions::keepPoses
};

struct ClipEval {
  std::string clip;
  double fps = 0.0;
  int frames = 0;
  JointTrack truth;
  ScoredSkeleton skeleton;
  std::vector<std::string> jointNames;
  std::vector<MethodRun> runs;  // in kMethods order
  std::vector<std::string> notes;
};

// The scored joints and groups of a BVH avatar (humanoid map, end sites excluded).
ScoredSkeleton scoredSkeleton(const tracking::BvhAvatar& avatar);

// Runs every method. `solvedBvh` (optional) receives the coupled run's poses on the clip's
// hierarchy. Errors: a clip too short to score (fewer than 2 frames at the chosen rate), a
// tracker set the clip lacks, a solver that cannot be built.
Result<ClipEval> evaluateClip(const tracking::BvhAvatar& avatar, const EvalOptions& options,
                              tracking::SolvedMotionBvh* solvedBvh = nullptr);

}  // namespace embody::eval
