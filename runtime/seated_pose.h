#pragma once
// Seated mode's lower body: where the seat is, and the targets that keep the avatar sitting on it
// (both hip joints on the seat, thighs along the seat, shins down to feet planted flat on the
// floor in front of it). Pure geometry on the avatar's rest proportions; AvatarBodySolver turns
// the targets into the top-priority tasks (task_layout.h) so the spine and arms follow the head
// and hands while the lower body stays put. docs/runtime.md, "Seated mode".
//
//   SeatedLegs legs = SeatedLegs::fromRest(...);              // once, at build
//   SeatedPose seat = placeSeat(legs, eyeTarget, yaw, -1.0);   // at the first valid head sample
//
// Everything here is in the avatar's model space (metres on the avatar, up_ vertical, the floor
// at floor height); heights are above that floor.
#include <Eigen/Geometry>
#include <array>

namespace embody::runtime {

struct SeatOptions {
  bool enabled = false;
  // Height of the seat surface above the floor in tracking metres (the user's chair). 0: derived
  // at the first valid head sample from the head's height and the avatar's sitting proportions.
  // Either way it is kept within the range the avatar's legs sit at with the feet flat on the
  // floor (the hip joints within ±half a thigh of the knee height).
  float seatHeight = 0.0f;
};

// The avatar's legs at rest (avatar space), index 0 = left, 1 = right.
struct SeatedLegs {
  Eigen::Vector3d up = Eigen::Vector3d::UnitY(), forward = Eigen::Vector3d::UnitZ();
  double floor = 0.0;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();  // the eye point at rest
  std::array<Eigen::Vector3d, 2> hip{}, knee{}, ankle{};  // joint pivots at rest
  std::array<Eigen::Quaterniond, 2> footRotation{};  // foot joints' rest rotations (flat on the floor)
  Eigen::Quaterniond pelvisRotation = Eigen::Quaterniond::Identity();
  double hipAboveSeat = 0.0;  // hip joint centres above the seat surface (the thighs' thickness)
  double thigh(int side) const { return (knee[size_t(side)] - hip[size_t(side)]).norm(); }
  double shin(int side) const { return (ankle[size_t(side)] - knee[size_t(side)]).norm(); }
  double ankleHeight(int side) const { return up.dot(ankle[size_t(side)]) - floor; }
  // Knee pivot height with the shin vertical and the ankle at its rest height (thighs level when
  // the hip joints sit this high).
  double kneeHeight() const { return 0.5 * (ankleHeight(0) + shin(0) + ankleHeight(1) + shin(1)); }
  double meanThigh() const { return 0.5 * (thigh(0) + thigh(1)); }
  // Seat surface heights the legs sit at with the feet flat (hip joints within ±thigh/2 of the knee height).
  double minSeatHeight() const { return kneeHeight() - 0.5 * meanThigh() - hipAboveSeat; }
  double maxSeatHeight() const { return kneeHeight() + 0.5 * meanThigh() - hipAboveSeat; }
  // The eye's height above the seat surface when sitting upright (the rest trunk on the seat).
  double sittingEyeHeight() const { return up.dot(eye - 0.5 * (hip[0] + hip[1])) + hipAboveSeat; }
};

// One seat, placed: the seated targets in avatar space.
struct SeatedPose {
  double yaw = 0.0;          // heading about `up` (0: the avatar's rest forward)
  double seatHeight = 0.0;   // seat surface above the floor
  Eigen::Vector3d seat = Eigen::Vector3d::Zero();  // the point of the seat surface under the hip joints' midpoint
  std::array<Eigen::Vector3d, 2> hip{}, knee{}, ankle{};
  std::array<Eigen::Quaterniond, 2> footRotation{};
  Eigen::Quaterniond pelvisRotation = Eigen::Quaterniond::Identity();  // upright, facing `yaw`
};

// The seat for an upright sitter whose eyes are at `eye` (avatar space) facing `yaw`: under the
// eyes as far back as the rest trunk puts the hips; its surface `seatHeight` above the floor
// (< 0: where the eyes put it), clamped to [minSeatHeight, maxSeatHeight].
SeatedPose placeSeat(const SeatedLegs& legs, const Eigen::Vector3d& eye, double yaw, double seatHeight);

}  // namespace embody::runtime
