#pragma once
// The avatar's body as the per-frame jobs see it, built once at AvatarBodySolver::create() and
// const after: the IK body model with the tracker layout's tasks, which IK joint each tracker
// drives and where its task ids are, the rest geometry the jobs measure against (heights, the eye
// point, limb lengths, the seated legs, the feet's stance) and the spaces (up, forward, tracking
// space -> avatar space). Everything here depends on the avatar and the options only; what
// depends on the user (scale, height offsets, stride ratio) is the calibration
// (body_calibration.h).
//
// Tracker -> IK joint: head (the eyes, an offset in the head joint's frame), hands (wrist = the
// hand joint's pivot), hips (pelvis = the root), feet (ankle = the foot joint's pivot). The
// rotation from a tracker's frame to its joint's frame is fixed here: the tracker orientation
// that corresponds to the avatar's rest pose (identity for head, hips and feet; for a hand the
// grip pose of the rest hand) maps onto the joint's rest orientation.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <utility>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/body/body_model.h"
#include "core/result.h"
#include "runtime/avatar_body_options.h"
#include "runtime/pole_tasks.h"
#include "runtime/seated_pose.h"
#include "runtime/task_layout.h"

namespace embody::runtime {

// The layout's tasks in the body model (-1: none).
struct BodyTasks {
  // Per tracker (position, orientation; a planted foot's pose task is its position task).
  std::array<ik::TaskId, tracking::kTrackerCount> position{-1, -1, -1, -1, -1, -1};
  std::array<ik::TaskId, tracking::kTrackerCount> orientation{-1, -1, -1, -1, -1, -1};
  ik::TaskId balance = -1, hipsPosition = -1, hipsRotation = -1;  // three-point mode
  std::array<ik::TaskId, 4> pole{-1, -1, -1, -1};  // knees (0 left, 1 right), elbows (2, 3)
  std::array<ik::TaskId, 2> clavicle{-1, -1};      // the clavicles' rest turns (0 left)
  // Seated mode, per side (0 = left), and the pelvis.
  std::array<ik::TaskId, 2> seatHip{-1, -1}, seatKnee{-1, -1};
  ik::TaskId seatPelvis = -1;
  // Joint markers: the avatar joint, its position task, and one level lower its orientation task.
  struct JointMarker {
    int avatarJoint = -1;
    ik::TaskId position = -1, orientation = -1;
  };
  std::vector<JointMarker> marker;
};

struct BodyRig {
  avatar::BodyModel body;  // its model carries the layout's tasks
  TaskLayout layout;
  BodyTasks tasks;

  // Spaces. Tracking space: +X right, +Y up, -Z forward, metres, floor at y = 0.
  Eigen::Vector3d up = Eigen::Vector3d::UnitY(), forward = Eigen::Vector3d::UnitZ();
  Eigen::Quaterniond fromTracking = Eigen::Quaterniond::Identity();  // -Z -> the avatar's forward
  double floor = 0.0;  // along up

  // Tracker joints, their rest rotations, tracker frame -> joint frame (avatar space), and the
  // joint pivots' heights above the floor at rest.
  std::array<ik::JointId, tracking::kTrackerCount> joint{-1, -1, -1, -1, -1, -1};
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> restRotation{};
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> jointFromTracker{};
  std::array<double, tracking::kTrackerCount> restHeight{};
  ik::JointId leftShoulder = -1, rightShoulder = -1;
  std::array<ik::JointId, 2> clavicleJoint{-1, -1};  // the clavicles' IK joints (0 left), -1 unmapped
  std::array<ik::JointId, 2> hipJoint{-1, -1}, kneeJoint{-1, -1};  // 0 = left
  // Limbs: knees (0 left, 1 right) then elbows (2, 3): the chain's root, middle and end joints,
  // the hinge joint, and the rest segment lengths.
  std::array<ik::JointId, 4> limbRoot{-1, -1, -1, -1}, limbMiddle{-1, -1, -1, -1}, limbEnd{-1, -1, -1, -1},
      limbHinge{-1, -1, -1, -1};
  std::array<LimbGeometry, 4> limb{};

  // Rest measures (avatar metres).
  double avatarHeight = 1.75, avatarEyeHeight = 1.64, armReach = 0.6;
  Eigen::Vector3d eyeInHead = Eigen::Vector3d::Zero();       // head joint frame
  Eigen::Vector3d restHeadToHips = Eigen::Vector3d::Zero();  // avatar space
  SeatedLegs legs;                                           // seated mode (legs mapped)
  std::array<Eigen::Vector3d, 2> stance{};  // three-point feet relative to the hips' ground point
  // How far the head pivot can rise above its rest height with the feet on the floor at the
  // stance (both legs straight under their hip joints): above that, a three-point body jumps.
  double standingHeadRise = 0.0;
  // The configuration a body starts from: the rest pose with knees and elbows slightly bent.
  Eigen::VectorXd restQ;

  ik::JointId shoulder(tracking::Side side) const { return side == tracking::Side::Left ? leftShoulder : rightShoulder; }
  // Tracking metres -> avatar metres for a user calibrated at `scale`.
  Eigen::Vector3d toAvatar(double scale, const Eigen::Vector3d& trackingPoint) const {
    return fromTracking * (scale * trackingPoint) + up * floor;
  }
};

// Builds the rig of `avatar` for `options` (the body model, its tasks, the rest geometry).
// `refusedCalls` counts ik::Data calls refused while measuring the rest pose (0 unless broken).
// Fails when the avatar cannot be mapped to a body model (the error lists what is missing).
Result<BodyRig> buildBodyRig(const avatar::AvatarAsset& avatar, const AvatarBodyOptions& options, int& refusedCalls);

// Where a solved foot (0 left, 1 right) points: its rest forward turned as the foot is.
Eigen::Vector3d footForward(const BodyRig& rig, const ik::Data& data, int side);

}  // namespace embody::runtime
