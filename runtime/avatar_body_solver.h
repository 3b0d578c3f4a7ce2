#pragma once
// The runtime's BodySolver on a real avatar: the IK body model (avatar/body) with the PIK solver
// (ik), tasks from the tracker layout (task_layout.h), calibration from the user's height,
// procedural stepping in three-point mode (foot_planner.h), and retargeting onto the skeleton.
//
//   auto solver = AvatarBodySolver::create(avatar, options);   // builds the model, calibrates
//   IkStage stage(**solver, clock, stageConfig);                 // filter + guard + budget
//   stage.process(sample, frame);                                // frame.pose skins the avatar
//
// Spaces. Targets arrive in the tracking space (OpenXR: metres, +Y up, -Z forward, floor at y = 0)
// and are mapped into the avatar's model space: scaled by avatarEyeHeight / userEyeHeight about
// the floor and turned so the user's forward is the avatar's. Residuals are measured there, in
// metres on the avatar.
//
// Per frame, solve() runs small jobs (ozz's shape: inputs/outputs, Validate(), Run(), no
// allocation) over data built once: the body rig (body_rig.h: the model with its tasks, the rest
// geometry, the spaces; from create()) and the calibration (body_calibration.h: scale and height
// offsets, from the options or the first samples):
//   TrackerTargetsJob  guarded sample -> avatar-space targets and weights (tracker_targets_job.h)
//   TaskTargetsJob     targets -> ik::Data tasks, the inferred pelvis and feet, the seat, the poles
//   BudgetedSolveJob   PIK iterations under the one deadline policy (budgeted_solve_job.h)
//   SkeletonPoseJob    solved body -> avatar::SkeletonPose (skeleton_pose_job.h)
//   ResidualsJob       residuals and reach (residuals_job.h)
// then the collapse guard and the recovery fade. docs/runtime.md has the table.
#include <memory>

#include "avatar/avatar_asset.h"
#include "avatar/body/body_model.h"
#include "runtime/avatar_body_options.h"
#include "runtime/body_calibration.h"
#include "runtime/body_rig.h"
#include "runtime/body_seed.h"
#include "runtime/body_solver.h"
#include "runtime/body_targets.h"
#include "runtime/collapse_guard.h"
#include "runtime/foot_planner.h"
#include "runtime/pole_tasks.h"
#include "runtime/pose_blend.h"
#include "runtime/seated_pose.h"
#include "runtime/task_layout.h"
#include "runtime/task_targets_job.h"

namespace embody::runtime {

// The solved lower body and trunk, measured (avatar space; angles in radians).
struct LowerBodyPosture {
  Eigen::Vector3d pelvis = Eigen::Vector3d::Zero();  // the root joint (hips) pivot
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  std::array<Eigen::Vector3d, 2> hip{}, knee{}, ankle{};  // joint pivots, 0 = left
  std::array<double, 2> hipFlexion{}, kneeFlexion{};  // 0 standing straight, about pi/2 seated
  // The trunk's bend over the pelvis: the angle between the pelvis-to-head line and where the
  // pelvis's rest frame would put it (0 upright, grows as the spine bends).
  double spineFlexion = 0.0;
  double pelvisPitch = 0.0;  // the pelvis's tilt from upright (either way)
};

class AvatarBodySolver final : public BodySolver {
 public:
  // Fails when the avatar cannot be mapped to a body model (the error lists what is missing).
  static Result<std::unique_ptr<AvatarBodySolver>> create(const avatar::AvatarAsset& avatar, const AvatarBodyOptions& options = {});

  SolveResult solve(const SolveRequest& request, avatar::SkeletonPose& pose) override;
  void resetWarmStart() override;

  const avatar::BodyModel& body() const { return rig_.body; }
  const BodyRig& rig() const { return rig_; }
  const BodyCalibration& calibration() const { return calibration_; }
  const ik::Data& data() const { return *data_; }
  const TaskLayout& layout() const { return rig_.layout; }
  const FootPlanner& feet() const { return planner_; }
  bool threePoint() const { return rig_.layout.inferLowerBody; }
  // Calibration: tracking metres -> avatar metres (0 until the first head sample when the user's
  // height comes from it).
  double scale() const { return calibration_.scale; }
  double avatarHeight() const { return rig_.avatarHeight; }
  double armReach() const { return rig_.armReach; }
  Eigen::Vector3d toAvatar(const glm::vec3& trackingPoint) const;
  // Solved positions in the avatar's model space: the eye point, wrists, ankles, shoulders.
  Eigen::Vector3d eyePosition() const;
  // The eye point at the avatar's rest pose, as the head targets place it: avatar::restEyePoint,
  // the point the renderer's first-person camera uses too.
  Eigen::Vector3d restEyePosition() const;
  Eigen::Vector3d jointPosition(ik::JointId joint) const { return data_->jointFrame(joint).translation(); }
  const Eigen::Isometry3d& jointFrame(ik::JointId joint) const { return data_->jointFrame(joint); }
  ik::JointId trackerJoint(tracking::TrackerId id) const { return rig_.joint[size_t(tracking::index(id))]; }
  // The last targets in avatar space (feet: the planner's in three-point mode).
  const Eigen::Vector3d& target(tracking::TrackerId id) const { return targets_.point[size_t(tracking::index(id))]; }
  bool calibratedFromHead() const { return calibration_.fromHead; }
  ik::JointId shoulderJoint(tracking::Side side) const { return rig_.shoulder(side); }
  const Eigen::Vector3d& up() const { return rig_.up; }
  bool seated() const { return rig_.layout.seated; }
  // Seated mode: the seat in avatar space, once placed (null before the first tracked head).
  const SeatedPose* seat() const { return seat_.placed ? &seat_.pose : nullptr; }
  const SeatedLegs& seatedLegs() const { return rig_.legs; }
  LowerBodyPosture posture() const;
  const CollapseGuard& collapseGuard() const { return guard_; }
  // The measures the collapse guard judges, for the current configuration.
  BodySignals bodySignals(double time, const SolveResult& result) const;
  // Continues from `q` (tests, tools): e.g. a body laid on the floor, to check that it stands up.
  Status seedConfiguration(const Eigen::VectorXd& q);
  // Knee (0 left, 1 right) and elbow (2 left, 3 right) flexion in radians, 0 = straight; positive
  // is the anatomical direction.
  double hingeAngle(int limb) const;
  // Where a solved foot (0 left, 1 right) points: its rest forward turned as the foot is.
  Eigen::Vector3d footForward(int side) const { return runtime::footForward(rig_, *data_, side); }
  // Marker targets (jointMarkers) per avatar skeleton joint, avatar space: world positions and
  // world rotations relative to the joint's rest (identity at rest). Joints without a marker are
  // ignored; call before each solve.
  void setMarkers(const std::vector<glm::dvec3>& positions, const std::vector<glm::dquat>& rotations);
  size_t markerCount() const { return rig_.tasks.marker.size(); }
  // ik::Data setter calls and per-frame jobs that were refused (non-finite values, unknown ids,
  // inputs a job's Validate() rejects): 0 unless broken.
  int refusedCalls() const { return refusedCalls_; }

 private:
  AvatarBodySolver(const avatar::AvatarAsset& avatar) : avatar_(avatar) {}
  Status build(const AvatarBodyOptions& options);
  // solve()'s steps around the jobs: the calibration on the first samples, the targets and tasks,
  // the fallback to the last good configuration.
  void calibrate(const tracking::GuardedSample& sample);
  bool setTargets(const tracking::GuardedSample& sample);
  void keepLastGood(bool broken);
  // Standing start: the root under the head, facing the head's and hands' heading (body_seed.h).
  // False (nothing changed) without a live head or under a head lower than the standing pelvis.
  bool seedStanding(const tracking::GuardedSample& targets);
  // After a solve: asks the collapse guard; on a collapse re-seeds and starts the fade.
  void guardAgainstCollapse(const tracking::GuardedSample& targets, const SolveResult& result, avatar::SkeletonPose& pose);
  void require(const Status& s);  // counts a refused ik::Data call
  void require(bool jobRan);      // counts a refused job

  const avatar::AvatarAsset& avatar_;
  AvatarBodyOptions options_;
  BodyRig rig_;                      // built once (create)
  BodyCalibration calibration_;      // replaced whole, never edited (body_calibration.h)
  std::unique_ptr<ik::Data> data_;   // the warm start and the tasks' state
  // Per-frame state the jobs carry: the targets, the stepping feet, the seat.
  BodyTargets targets_;
  FootPlanner planner_;
  BodyHeading heading_;
  SeatState seat_;
  Eigen::VectorXd lastGoodQ_;
  CollapseGuard guard_;
  PoseFade fade_;
  bool reseeded_ = false;  // the next solve starts cold (after a re-seed)
  bool broken_ = false;    // the last solve produced a non-finite or invalid configuration
  IterationCostModel iterationCost_;  // one PIK iteration
  IterationCostModel finishCost_;     // retargeting and residuals after the iterations
  bool solvedOnce_ = false;
  int refusedCalls_ = 0;
};

}  // namespace embody::runtime
