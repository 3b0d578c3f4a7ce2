#pragma once
// Trackers and pose samples: what every pose source produces and every consumer (filters, the
// tracking-loss guard, the IK thread) takes.
//
// Conventions (OpenXR's): metres, right-handed, +Y up, -Z forward, +X to the user's right;
// quaternions rotate tracker-local vectors into the world. Tracker frames, identity orientation
// meaning the body part in its reference pose:
//   head       the point between the eyes (OpenXR VIEW space); identity = looking along -Z, +Y up.
//   left/right the wrist centre; axes as OpenXR's grip pose: -Z through the closed fist from the
//              little finger to the thumb, +X along the palm normal (away from the palm for the
//              left hand, into it for the right), +Y = Z x X. See gripOrientation().
//   hips       the pelvis centre (the skeleton root); identity = facing -Z, upright.
//   left_foot/right_foot  the ankle centre; identity = foot flat, toes along -Z.
#include <array>
#include <cstdint>
#include <initializer_list>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <optional>
#include <string_view>

namespace embody::tracking {

enum class TrackerId : uint8_t { Head, LeftHand, RightHand, Hips, LeftFoot, RightFoot };
inline constexpr int kTrackerCount = 6;
inline constexpr std::array<TrackerId, kTrackerCount> kAllTrackers = {
    TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand,
    TrackerId::Hips, TrackerId::LeftFoot, TrackerId::RightFoot};

constexpr int index(TrackerId id) { return static_cast<int>(id); }
// The key used in trace files and reports: "head", "left", "right", "hips", "left_foot", "right_foot".
std::string_view trackerKey(TrackerId id);
std::optional<TrackerId> trackerFromKey(std::string_view key);

// A set of trackers, one bit per TrackerId.
class TrackerMask {
 public:
  constexpr TrackerMask() = default;
  constexpr explicit TrackerMask(uint8_t bits) : bits_(bits) {}
  constexpr TrackerMask(std::initializer_list<TrackerId> ids) {
    for (auto id : ids) bits_ |= bit(id);
  }
  static constexpr TrackerMask threePoint() { return {TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand}; }
  static constexpr TrackerMask all() { return TrackerMask(uint8_t{(1u << kTrackerCount) - 1}); }
  constexpr bool has(TrackerId id) const { return (bits_ & bit(id)) != 0; }
  constexpr void set(TrackerId id, bool on = true) { bits_ = on ? (bits_ | bit(id)) : (bits_ & ~bit(id)); }
  constexpr uint8_t bits() const { return bits_; }
  constexpr bool operator==(const TrackerMask&) const = default;

 private:
  static constexpr uint8_t bit(TrackerId id) { return static_cast<uint8_t>(1u << index(id)); }
  uint8_t bits_ = 0;
};

// A rigid pose in these conventions: the project's one pose type (trackers, the OpenXR side,
// the headless OpenXR runtime).
struct Pose {
  glm::vec3 position{0.0f};
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // glm order (w, x, y, z); files use [x, y, z, w]
  glm::mat4 matrix() const;
  Pose operator*(const Pose& b) const;  // this * b (orientation renormalised)
  Pose inverse() const;
};

// A tracker's pose and whether it can be used this sample.
struct TrackerPose : Pose {
  TrackerPose() = default;
  TrackerPose(const glm::vec3& p, const glm::quat& q, bool isValid) : Pose{p, q}, valid(isValid) {}
  TrackerPose(const Pose& pose, bool isValid) : Pose(pose), valid(isValid) {}
  bool valid = false;
};

struct PoseSample {
  double time = 0.0;  // seconds since the start of the source
  std::array<TrackerPose, kTrackerCount> trackers{};
  // The hand controllers' trigger values (0..1; left, right) where a trace records them: the
  // headless OpenXR runtime curls its simulated fingers with them. The body ignores them.
  std::array<float, 2> triggers{};

  TrackerPose& operator[](TrackerId id) { return trackers[static_cast<size_t>(index(id))]; }
  const TrackerPose& operator[](TrackerId id) const { return trackers[static_cast<size_t>(index(id))]; }
  TrackerMask validMask() const;
};

// True when position and orientation are finite and the quaternion has a usable norm.
bool isUsable(const TrackerPose& pose);
// Marks trackers invalid whose data is not finite or whose quaternion cannot be normalised, and
// normalises the others; a sample that went through this never carries NaN in a valid tracker.
void sanitize(PoseSample& sample);

enum class Side { Left, Right };

// The grip-pose orientation (see above) of a hand whose fingers point along `fingers` and whose
// palm faces `palmFacing` (both world directions; palmFacing is orthogonalised against fingers).
// Hands hanging at the sides, palms facing the thighs, give -Z_grip = forward.
glm::quat gripOrientation(Side side, const glm::vec3& fingers, const glm::vec3& palmFacing);

// The grip orientation of a hand in a rest pose, from its forearm direction (elbow to wrist): the
// fingers continue the forearm, the palm faces down when the arm is raised (a T-pose) and towards
// the body when it hangs (an A-pose). Calibrates sources and avatars the same way.
glm::quat restGripOrientation(Side side, const glm::vec3& forearm);

// Rotation about +Y (heading) of an orientation: the yaw-only frame used to express targets
// "relative to the head" without them swinging when the user nods.
glm::quat headingOf(const glm::quat& orientation);

// Interpolates two poses (lerp + shortest-path slerp); validity is a's.
TrackerPose interpolate(const TrackerPose& a, const TrackerPose& b, float t);

}  // namespace embody::tracking
