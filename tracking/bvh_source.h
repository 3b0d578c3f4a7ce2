#pragma once
// BVH motion capture as a pose source: head, hands, hips and feet trackers derived from the
// clip's joints, converted to OpenXR conventions and scaled to metres.
//
// - Joints are found by name in the common namings (CMU Head/LeftHand/LeftFoot, Mixamo
//   mixamorig:LeftHand, Bandai-Namco Hand_L/Foot_L, Biped "Bip01 L Hand", ...); a tracker whose
//   joint is missing is absent and reported in notes().
// - Axes: the up axis is the rest skeleton's hips-to-head direction and the facing comes from its
//   left/right limbs (most files are +Y up facing +Z), snapped to the nearest axis-aligned frame
//   and rotated onto OpenXR's +Y up / -Z forward (for the usual case: 180 deg about Y).
// - Scale: the rest skeleton's height (sole to the top of the head) in file units is mapped to
//   the user's height, so the motion fits the user's avatar; `scale` (metres per unit,
//   --bvh-scale) overrides, e.g. 0.0564 for CMU's real units.
// - The lowest point of the clip is put on the floor (y = 0) and the first frame's hips over the
//   origin.
#include <array>
#include <string>

#include "avatar/bvh/bvh.h"
#include "tracking/trace.h"

namespace embody::tracking {

struct BvhTrackerOptions {
  float userHeight = 1.75f;
  double scale = 0.0;  // metres per file unit; 0 = fit the rest skeleton to userHeight
  bool alignGround = true;
  bool recentre = true;
};

struct BvhMapping {
  std::array<int, kTrackerCount> joint{-1, -1, -1, -1, -1, -1};  // clip joint per tracker, -1 missing
  double restHeightUnits = 0.0;  // rest skeleton height in file units
  double scale = 0.0;            // metres per unit used
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

// Samples every frame of the clip into a trace (time = frame * frameTime).
Result<Trace> bvhToTrace(const avatar::BvhClip& clip, const BvhTrackerOptions& options, BvhMapping* mapping = nullptr);

// Loads a BVH file as a replayable source (linear interpolation between frames).
Result<std::unique_ptr<TraceSource>> openBvhSource(const std::string& path, const BvhTrackerOptions& options,
                                                   BvhMapping* mapping = nullptr);

}  // namespace embody::tracking
