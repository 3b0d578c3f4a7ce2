#pragma once
// The body a BVH clip carries: which joints are the humanoid's, which way is up and forward in
// the file, how tall the performer is, and whether frame 0 is a reference pose. Shared by the
// tracking side (tracking/bvh_source.h: trackers from a clip) and avatar-side code (a clip's
// skeleton as an avatar).
//
// - Joints: the avatar name table (avatar/humanoid/humanoid_map.h, one table for every
//   convention); when names leave a body joint unmapped, the topology mapper runs on the clip's
//   skeleton as it stands in the first motion frame, tried with each axis as up; a user bone map
//   (VRM bone name -> BVH joint name) wins over both.
// - Up is measured on the motion, not the rest pose: the direction from the feet (else the hips)
//   to the head, averaged over the frames; the rest skeleton may lie down or have its bones along
//   any local axis. Snapped to the nearest signed axis within 25 degrees.
// - Forward: the way the performer faces over the first half second of motion, from the left
//   minus right hips/shoulders (left and right from the names), snapped within 30 degrees. The
//   walking direction is reported as a check.
// - Height: sole to the top of the head, the 95th percentile over the motion frames (people
//   stand up at some point; a jump lifts the feet with the head). Without a joint above the head
//   joint, the head joint is taken at 0.91 of the height. A foot with nothing below its joint (no
//   toe joint, no End Site away from it) has its sole estimated kAnkleHeightRatio (0.039) of the
//   height under the joint (soleBelowFoot), and everything that stands the clip on a floor uses
//   that estimate.
// - Frame 0 is a reference pose (a T-pose before the motion, as in CMU's converted clips) when a
//   body joint jumps faster than 5.7 heights/s (10 m/s at 1.75 m) into frame 1 and not after.
// - Left and right must agree with the toes: a body whose toes point behind the way its hips and
//   shoulders face (from the names) in most frames is a left-handed file or one with its Left/Right
//   names swapped, and is an Error naming --bvh-mirror and --bvh-bone-map.
// Axes that stay ambiguous (the head is not above the feet in most frames along any direction,
// no left/right limbs) are an Error naming --bvh-up / --bvh-forward.
#include <algorithm>
#include <array>
#include <glm/glm.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "avatar/bvh/bvh.h"
#include "avatar/humanoid/humanoid_map.h"
#include "avatar/skeleton.h"
#include "core/result.h"

namespace embody::avatar {

struct BvhBodyOptions {
  std::string up;           // "" = from the motion, else "+Y", "-Z", ... in file axes
  std::string forward;      // "" = from the motion, else the way the performer faces at the start
  std::string boneMapJson;  // {"head": "JointName", ...}; "" for none
  // --bvh-mirror: the file is left-handed; read it mirrored across its X axis (mirrorBvhClip).
  // Applied to the clip before anything is measured (tracking::bvhToTrace, buildBvhAvatar); an
  // `up` or `forward` along X is the file's, and is mirrored with it.
  bool mirror = false;
};

// The options for the clip mirrored by mirrorBvhClip: mirror off, a given up or forward along X
// turned with the clip.
BvhBodyOptions mirroredBvhOptions(BvhBodyOptions options);

struct BvhBody {
  Skeleton skeleton;     // the clip's joints (same indices as clip.joints) with the rest offsets
  HumanoidMap humanoid;  // which joint plays which bone
  glm::dvec3 up{0, 1, 0}, forward{0, 0, 1};  // unit, file axes
  std::string upAxis, forwardAxis;           // "+Y", "-Z", or "(0.00, 0.97, 0.24)" when not axis-aligned
  std::string upFrom, forwardFrom;           // "motion", "--bvh-up", "--bvh-forward"
  double upConfidence = 0.0;       // fraction of frames with the head within 40 deg of straight above the feet
  double forwardConfidence = 0.0;  // agreement of the facing over the first half second (1 = steady)
  std::string walking;             // "walks forward", "walks backwards", "sidesteps", "stays in place"
  double heightUnits = 0.0;        // standing height, sole to the top of the head, file units
  double headJointUnits = 0.0;     // the head joint above the sole when standing, file units
  // Per foot (left, right): the sole below the foot joint, file units, when nothing hangs below
  // the joint to stand on (no toe joint, no End Site away from it): the ankle joint centre stands
  // kAnkleHeightRatio of the height above the sole. 0 for a foot with toes or an End Site (the
  // lowest of them is the sole), or no foot. The one estimate of a bare ankle's sole: the height,
  // the floor (tracking/bvh_source.cpp), the clip as an avatar (tracking/bvh_avatar.cpp) and the
  // eval's soles (eval/clip_eval.cpp) all take it from here.
  std::array<double, 2> soleBelowFoot{0.0, 0.0};
  size_t firstFrame = 0;           // 1 when frame 0 is a reference pose, else 0
  glm::dmat3 toXr{1.0};            // file axes -> +X right, +Y up, +Z back (OpenXR's)
  std::vector<std::string> notes;

  int joint(HumanBone b) const { return humanoid.joint(b); }

  // The lowest of `lowest` and the soles under bare ankles (soleBelowFoot times `scale`):
  // `footHeight(side, joint)` is that foot joint's height in the caller's space and units
  // (+infinity leaves the foot out). What stands the clip on a floor calls this.
  template <class FootHeight>
  double lowestWithBareSoles(double lowest, double scale, FootHeight footHeight) const {
    for (size_t side = 0; side < 2; ++side)
      if (const int foot = joint(side == 0 ? HumanBone::leftFoot : HumanBone::rightFoot); foot >= 0 && soleBelowFoot[side] > 0.0)
        lowest = std::min(lowest, footHeight(side, foot) - soleBelowFoot[side] * scale);
    return lowest;
  }
};

// Parses "+X", "-y", "Z" (a sign is optional) into a unit axis.
Result<glm::dvec3> parseBvhAxis(std::string_view text);
// "+Y" for a signed coordinate axis, else the vector with two decimals.
std::string bvhAxisName(const glm::dvec3& axis);

// The clip's joints as a Skeleton: local rest translation = OFFSET (End Sites included).
Skeleton bvhSkeleton(const BvhClip& clip);

// Errors: a malformed axis or bone map, --bvh-forward not perpendicular to the up axis, axes
// that stay ambiguous. Missing joints are not errors here: humanoid.bones says what is mapped.
Result<BvhBody> analyseBvhBody(const BvhClip& clip, const BvhBodyOptions& options = {});

}  // namespace embody::avatar
