#pragma once
// One frame's tracker targets in the avatar's model space, as the poses of the joints they drive
// (the head's point is the eyes). Written by TrackerTargetsJob; the task job replaces the feet's
// with the foot planner's (three-point) or the seat's, and scales tracked strides.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "tracking/tracking_guard.h"

namespace embody::runtime {

struct BodyTargets {
  std::array<Eigen::Vector3d, tracking::kTrackerCount> point{};
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> rotation{};
  // How strongly each tracker's tasks pull this frame (statusWeight; 0 = off).
  std::array<double, tracking::kTrackerCount> weight{};
};

}  // namespace embody::runtime
