#pragma once
// Where the avatar goes in the tracked world, before a solved body exists: calibration of its
// size from the HMD height, recentering, and a seated mode. Pure math, no OpenXR calls.
//
//   calibrate(head):  scale = user's eye height (HMD y above the STAGE floor) / avatar eye height
//   recenter(head):   the world is re-anchored so the head stands over the origin facing -Z
//   root(head):       the avatar's root transform: its eyes under the HMD (horizontally), feet on
//                     the floor (standing) or eyes at the HMD (seated), facing the head's yaw
//
// This places the rest pose only: `embody xr --body rest`, and the frames before the solved body
// exists. A rest pose cannot sit, so seated it sinks with the user's eyes; the solved body sits on
// a seat (runtime::SeatOptions, docs/runtime.md "Seated mode").
#include <glm/glm.hpp>

#include "avatar/skeleton.h"
#include "xr/xr_common.h"

namespace embody::xr {

struct PlacementOptions {
  bool seated = false;
  float userEyeHeight = 0.0f;  // metres; > 0 fixes the calibration instead of reading the HMD
};

class AvatarPlacement {
 public:
  // avatarEye: eye position of the avatar's rest pose in model space (root at origin, metres);
  // avatarForward: the way the rest pose faces (glTF +Z).
  AvatarPlacement(const glm::vec3& avatarEye, const glm::vec3& avatarForward,
                  const PlacementOptions& options);

  // Standing calibration from a head pose in the world; ignored (returns false) when the head is
  // implausibly low or high (< 0.8 m or > 2.5 m above the floor), or in seated mode.
  bool calibrate(const Pose& headWorld);
  void recenter(const Pose& headTracking);
  Pose toWorld(const Pose& tracking) const { return recenter_ * tracking; }
  // Root transform (rotation, translation, uniform scale) for a head pose in the world.
  glm::mat4 root(const Pose& headWorld) const;
  // Applies root(headWorld) to every root joint of `pose` (which starts from the rest pose).
  void place(const avatar::Skeleton& skeleton, const Pose& headWorld, avatar::SkeletonPose& pose) const;
  float scale() const { return scale_; }
  bool calibrated() const { return calibrated_; }

 private:
  glm::vec3 eye_, forward_;
  PlacementOptions options_;
  float scale_ = 1.0f;
  bool calibrated_ = false;
  Pose recenter_;
};

// Yaw (radians about +Y) of a pose's forward (-Z) direction; 0 faces -Z. Looking down or up the
// pose's up vector fills in (tracking::headingOf), so a head looking at the floor has one too.
float headingOf(const Pose& p);

}  // namespace embody::xr
