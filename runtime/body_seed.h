#pragma once
// Where a body starts and restarts: standing upright under the head, facing where the head and
// the hands face, with its pelvis at the avatar's standing height (lowered with the head when the
// user crouches). The solver starts from this configuration on its first solve, after a reset and
// when the collapse guard (collapse_guard.h) finds the body in a heap.
//
// Avatar space (metres on the avatar, `up` its vertical, yaw about `up`, 0 = the avatar's forward,
// positive towards up x forward, as headingOf in foot_planner.h).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "ik/model.h"

namespace embody::runtime {

struct SeedInputs {
  Eigen::Vector3d up = Eigen::Vector3d::UnitY(), forward = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d headPivot = Eigen::Vector3d::Zero();  // the head joint's target
  double headYaw = 0.0;                                 // heading of the head's target
  // Wrist targets, when both hands are live (a controller in each hand).
  std::optional<Eigen::Vector3d> leftHand, rightHand;
  Eigen::Vector3d restHeadToHips = Eigen::Vector3d::Zero();  // hips pivot - head pivot at rest, unturned
  double floor = 0.0;              // the floor's height along `up`
  double restHipsHeight = 0.9;     // the hips pivot above the floor at rest
  double scale = 1.0;              // avatar height / 1.75 m: distances below scale with it
};

// The body's heading: the head's, turned halfway towards the hands' when both hands are live,
// at least a shoulder's width apart, and their heading (perpendicular to the line from the right
// hand to the left) lies within 90 degrees of the head's. A user looking over a shoulder still
// faces the controllers; a user holding the controllers behind the back faces the head's way.
double seedYaw(const SeedInputs& in);

// The hips pivot of a standing body under the head: the rest head-to-hips offset turned by the
// yaw, at the rest hips height, or lower by as much as the head is lower than standing (a crouch),
// never below half the rest height.
Eigen::Vector3d seedPelvis(const SeedInputs& in, double yaw);

// `base` (e.g. the model's neutral configuration: knees and elbows slightly bent) with the free
// root joint `root` placed at `pelvis`, its rest orientation turned by `yaw` about `up`. Returns
// `base` unchanged when `root` is not a free joint without a parent.
Eigen::VectorXd placeRoot(const ik::Model& model, ik::JointId root, const Eigen::VectorXd& base,
                          const Eigen::Vector3d& pelvis, double yaw, const Eigen::Vector3d& up);

}  // namespace embody::runtime
