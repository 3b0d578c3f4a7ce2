#pragma once
// BVH motion capture as a pose source: head, hands, hips and feet trackers derived from the
// clip's joints, converted to OpenXR conventions and scaled to metres.
//
// - The body (avatar/bvh/bvh_body.h): joints from the one avatar name table (every common
//   convention), else the topology mapper, else the user's bone map; up, forward and the
//   performer's height measured on the motion; a leading reference pose found.
// - A tracker the run needs (`required`: head and hands by default) whose joint is not mapped is
//   an error naming the joint and the override; other missing trackers are absent with a note.
// - The clip is turned onto OpenXR's +Y up, the performer facing -Z at the start; scaled so the
//   performer is the user's height (`scale`, --bvh-scale, overrides: e.g. 0.0564 for CMU's
//   units); the floor (the 5th percentile of each frame's lowest point, robust to end sites
//   that dip through it) at y = 0, the first frame's hips over the origin.
#include <array>
#include <string>

#include "avatar/bvh/bvh.h"
#include "avatar/bvh/bvh_body.h"
#include "tracking/trace.h"

namespace embody::tracking {

// The rank over a clip's frames at which its floor (each frame's lowest point) and its standing
// ankle height (tracking/bvh_avatar.h) are read: low, yet robust to outliers in 1 frame in 20.
inline constexpr double kFloorPercentile = 0.05;

struct BvhTrackerOptions {
  float userHeight = 1.75f;
  double scale = 0.0;  // metres per file unit; 0 = fit the performer's height to userHeight
  bool alignGround = true;
  bool recentre = true;
  avatar::BvhBodyOptions body;                        // --bvh-up, --bvh-forward, --bvh-bone-map
  TrackerMask required = TrackerMask::threePoint();  // trackers whose absence is an error
};

struct BvhMapping {
  std::array<int, kTrackerCount> joint{-1, -1, -1, -1, -1, -1};  // clip joint per tracker, -1 missing
  avatar::BvhBody body;    // humanoid map, axes and their confidence, height, reference frame
  double heightUnits = 0.0;  // the performer's standing height in file units
  double scale = 0.0;        // metres per unit used
  std::string upAxis, facingAxis;  // in file axes, e.g. "+Y", "+Z"
  std::vector<std::string> notes;
  // File -> tracking space, as the trace uses it: p_tracking = toXr * p_file * scale + shift
  // (rotations: toXr * R * toXr^T), so the clip's joints can be set beside what the runtime made
  // of its trackers (tracking/bvh_avatar.h, embody eval).
  glm::dmat3 toXr{1.0};
  glm::dvec3 shift{0.0};
  size_t firstFrame = 0;  // 1 when frame 0 was a reference pose and skipped
  glm::dvec3 eyeOffset{0.0};  // tracking axes, from the head joint, in the rest pose
  std::array<glm::dquat, kTrackerCount> reference{};  // tracker orientation in the rest pose (tracking axes)
};

// The clip joint per tracker in a body's humanoid map (-1 where unmapped).
std::array<int, kTrackerCount> bvhTrackerJoints(const avatar::HumanoidMap& humanoid);

// Samples every frame of the clip into a trace (time = frame * frameTime).
Result<Trace> bvhToTrace(const avatar::BvhClip& clip, const BvhTrackerOptions& options, BvhMapping* mapping = nullptr);

// Frames whose root leaves and comes back faster than any body moves (a lost-marker sentinel such
// as Y = 99999 for a frame, a root zeroed for ten): `first..last`, with the good frames either
// side (`before`/`after`, SIZE_MAX at the clip's ends) and the jump in file units. Speeds are in
// the skeleton's size (its rest pose's farthest joint from the root), so any unit reads the same.
// A root that jumps and stays is a cut, left alone; one that stays beyond any capture volume
// (100 reaches) is an Error naming the frame.
struct BvhGlitch {
  size_t first = 0, last = 0;
  size_t before = 0, after = 0;
  double jump = 0.0;
};
Result<std::vector<BvhGlitch>> findBvhGlitches(const avatar::BvhClip& clip);
// Replaces the glitch frames' root positions (every position channel) by the line between the
// good frames either side, and adds one warning to clip.warnings naming the frames (which
// bvhToTrace copies into the notes: `motion info`, the trace, eval's metrics.json). Returns how
// many frames it repaired. bvhToTrace repairs a copy of a clip that has any; code that keeps the
// clip beside the trace (tracking/bvh_avatar.h) repairs its own first.
Result<size_t> repairBvhGlitches(avatar::BvhClip& clip);

// Loads a BVH file as a replayable source (linear interpolation between frames).
Result<std::unique_ptr<TraceSource>> openBvhSource(const std::string& path, const BvhTrackerOptions& options,
                                                   BvhMapping* mapping = nullptr);

}  // namespace embody::tracking
