#pragma once
// Targets -> tasks: one frame's avatar-space targets (tracker_targets_job.h) written into the body
// model's tasks in ik::Data: each tracker's position/orientation task enabled with its weight and
// target or disabled; then, by mode,
//   seated       the seat under the first tracked head (placeSeat), hips/knees/feet/pelvis on it;
//   three-point  the pelvis under the head and the feet from the foot planner (it steps; the
//                planner and the body's heading, body_heading.h, are this job's input-output
//                state), balance while the CoM is off support;
//   tracked feet strides scaled by the calibration's leg ratio about the pelvis;
// and the knee/elbow pole targets from the current (last solved) body. No allocation.
//
//   TaskTargetsJob job;
//   job.rig = &rig; job.calibration = &calibration; job.sample = &guarded; job.targets = &targets;
//   job.planner = &planner; job.heading = &heading; job.seat = &seat; job.data = &data; job.output = &out;
//   if (job.Run() && out.settleSeat) ...   // a new seat: settle outside the budget
#include "ik/solver.h"
#include "runtime/body_calibration.h"
#include "runtime/body_rig.h"
#include "runtime/body_targets.h"
#include "runtime/body_heading.h"
#include "runtime/foot_planner.h"
#include "runtime/seated_pose.h"

namespace embody::runtime {

// Seated mode: the seat in avatar space, once placed (under the first tracked head).
struct SeatState {
  SeatedPose pose;
  bool placed = false;
};

struct TaskTargetsOutput {
  bool settleSeat = false;  // the seat was placed before the first solve: settle it (settle())
  int refusedCalls = 0;     // ik::Data calls refused (non-finite values, unknown ids; 0 unless broken)
};

// Enables (weight > 0, times the task's own) or disables a position/orientation/pose task pair
// (-1: none) and sets its target; `refusedCalls` counts the ik::Data calls refused.
void setTaskPose(const ik::Model& model, ik::Data& data, ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p,
                 const Eigen::Quaterniond& q, double weight, int& refusedCalls);

struct TaskTargetsJob {
  const BodyRig* rig = nullptr;
  const BodyCalibration* calibration = nullptr;  // scaled()
  const tracking::GuardedSample* sample = nullptr;
  bool balanceRow = false;   // AvatarBodyOptions::balanceRow
  float seatHeight = 0.0f;   // AvatarBodyOptions::seat.seatHeight (tracking metres; <= 0: from the legs)
  bool solvedOnce = false;   // the body has been solved since the last warm-start reset
  BodyTargets* targets = nullptr;  // in: the trackers'; out: the feet replaced (planner, seat, strides)
  FootPlanner* planner = nullptr;  // in-out (three-point mode)
  BodyHeading* heading = nullptr;  // in-out (three-point mode)
  SeatState* seat = nullptr;       // in-out (seated mode)
  ik::Data* data = nullptr;        // in-out: the rig's model's data (task state; seated: the root)
  TaskTargetsOutput* output = nullptr;

  // Every pointer set, the data sized for the rig's model, the targets and sample time finite.
  bool Validate() const;
  bool Run() const;
};

}  // namespace embody::runtime
