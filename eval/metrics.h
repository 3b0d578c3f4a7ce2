#pragma once
// Scoring a solved body against motion capture, joint by joint (docs/eval.md). Pure functions on
// world joint positions and rotations sampled at one rate; no runtime, no files.
//
// Definitions (the sparse-tracking literature's, so figures sit beside published tables):
// - MPJPE: mean Euclidean distance between world joint positions, per group, with the 95th
//   percentile of the per-frame group mean.
// - MPJRE: mean GEODESIC angle between world joint rotations, 2 acos |<q_s, q_c>| (not
//   AvatarPoser's mean absolute axis-angle component).
// - MPJVE: mean norm of the joint velocity difference (backward differences × fps).
// - Jitter: mean norm of the third backward difference × fps³ (solution and clip), over every
//   scored joint and per group (which part of the body shakes: a root alternating from frame to
//   frame shows in the root's figure, not only diluted in the mean).
// - Foot skating: mean horizontal speed of a solved foot over the frames where the clip's foot
//   is in contact (its sole point within 5 cm of the floor, y = 0, and slower than 20 cm/s).
// - Reverse bends: frames where a solved knee or elbow, bent by more than 15°, bends the other
//   way round than the clip's (bend normals (hip→knee)×(knee→ankle) opposed, the clip bent by
//   more than 15° too): the clip's bend is the anatomical one.
// - Spine torsion sign changes: frames where the twist (about each bone's axis, |twist| > 1°)
//   changes sign along the chain inside one spine region (trunk: hips to the neck; neck: neck to
//   the head); a head turning against the trunk is no sign change.
// - Collapsed: frames where the solved pelvis is below half its standing height while the clip's
//   is not.
// - Per-joint bias: the mean of solved - clip in the clip's body frame (forward, left, up; left
//   from the clip's right hip to its left one on the ground, up +Y): where a joint sits on
//   average, not only how far (a pelvis 15 cm behind the performer's reads -0.15 forward). Only
//   with both hips scored.
#include <array>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <vector>

namespace embody::eval {

// Frames × joints, frame-major: index = frame * joints + joint.
struct JointTrack {
  int joints = 0;
  std::vector<glm::dvec3> position;  // metres, +Y up, floor at y = 0
  std::vector<glm::dquat> rotation;  // world rotations (identity at rest for both tracks)
  int frames() const { return joints > 0 ? int(position.size() / size_t(joints)) : 0; }
  const glm::dvec3& p(int f, int j) const { return position[size_t(f) * size_t(joints) + size_t(j)]; }
  const glm::dquat& q(int f, int j) const { return rotation[size_t(f) * size_t(joints) + size_t(j)]; }
};

enum Group { kAll, kHands, kFeet, kHead, kUpper, kLower, kRoot, kGroupCount };
const char* groupName(Group g);  // "all", "hands", ...

// What the scorer needs to know about the skeleton (joint indices into the tracks).
struct ScoredSkeleton {
  std::array<std::vector<int>, kGroupCount> groups;  // kAll: every scored joint (end sites excluded)
  int pelvis = -1;
  double standingPelvisHeight = 0.0;  // metres above the floor
  std::array<std::array<int, 3>, 2> legs{{{-1, -1, -1}, {-1, -1, -1}}};  // hip, knee, ankle (0 = left)
  std::array<std::array<int, 3>, 2> arms{{{-1, -1, -1}, {-1, -1, -1}}};  // shoulder, elbow, wrist
  std::array<std::vector<int>, 2> soles;  // per foot: the ankle and every joint below it (toes, end sites)
  // Per foot: metres the sole lies under the ankle when nothing hangs below it (no toes, no End
  // Site; avatar::BvhBody::soleBelowFoot), else 0.
  std::array<double, 2> soleBelowAnkle{0.0, 0.0};
  // Spine regions (trunk: hips up to the neck; neck: neck up to the head), each a chain of joints
  // from the region's base, with per joint k > 0 the rest direction chain[k-1] -> chain[k].
  struct SpineRegion {
    std::vector<int> chain;
    std::vector<glm::dvec3> axis;
  };
  std::vector<SpineRegion> spineRegions;
};

struct GroupError {
  double mean = 0.0;  // metres
  double p95 = 0.0;   // of the per-frame mean
};

struct Metrics {
  int frames = 0;
  std::array<GroupError, kGroupCount> mpjpe{};
  double mpjreDegrees = 0.0;
  double mpjve = 0.0;                                // m/s
  double jitter = 0.0, clipJitter = 0.0;             // m/s³, every scored joint (= groupJitter[kAll])
  std::array<double, kGroupCount> groupJitter{}, clipGroupJitter{};  // m/s³ per group (0 for an empty one)
  double footSkating = 0.0, clipFootSkating = 0.0;   // m/s, over contact frames
  int contactFrames = 0;
  int kneeReverseFrames = 0, elbowReverseFrames = 0;
  int torsionSignChangeFrames = 0, clipTorsionSignChangeFrames = 0;
  int collapsedFrames = 0;
  std::vector<double> perJointError;                 // mean metres per joint (every joint of the track)
  std::vector<glm::dvec3> perJointBias;              // mean (forward, left, up) metres per joint; empty without hips
  std::array<std::vector<double>, kGroupCount> perFrame;  // per-frame group mean, metres
  // Per frame, which plausibility counts it added to (bits of PlausibilityFlag): where in a
  // clip the knees reversed or the body collapsed, for frames.csv.
  std::vector<unsigned char> perFrameFlags;
};

enum PlausibilityFlag : unsigned char { kKneeReversed = 1, kElbowReversed = 2, kCollapsed = 4 };

// Both tracks must have the same joints and frames (>= 1); fps > 0.
Metrics score(const JointTrack& solved, const JointTrack& clip, const ScoredSkeleton& skeleton, double fps);

// The 95th percentile (nearest rank) of `values` (copied; empty -> 0).
double percentile95(std::vector<double> values);

}  // namespace embody::eval
