#pragma once
// A rigid move of the whole tracking space (a rotation about the origin, then a translation): what
// a recenter does to every tracker, and what a play-space change looks like to the runtime. The
// mirror's R key and --recenter, the headset's recenter (xr::AvatarPlacement) and the soak's
// injected play-space moves all use this one type.
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "tracking/tracker.h"

namespace embody::tracking {

struct SpaceTransform {
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
  glm::vec3 translation{0.0f};

  glm::vec3 apply(const glm::vec3& point) const { return rotation * point + translation; }
  // Position and orientation; validity is kept (an invalid tracker's data may be anything).
  void apply(TrackerPose& pose) const;
  // Every tracker of the sample.
  void apply(PoseSample& sample) const;
  // The move that does `first`, then this.
  SpaceTransform after(const SpaceTransform& first) const;
  SpaceTransform inverse() const;
};

// The recenter for a head pose: afterwards that head stands over the origin, its height kept, and
// its heading (headingOf) faces -Z. Only a yaw and a horizontal shift, so the floor stays the
// floor. Identity when the head is invalid or not usable (isUsable): a lost head never moves the world.
SpaceTransform recenterOn(const TrackerPose& head);

}  // namespace embody::tracking
