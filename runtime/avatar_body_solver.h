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
// Tracker -> IK joint: head (the eyes, an offset in the head joint's frame), hands (wrist = the
// hand joint's pivot), hips (pelvis = the root), feet (ankle = the foot joint's pivot). The
// rotation from a tracker's frame to its joint's frame is fixed at calibration: the tracker
// orientation that corresponds to the avatar's rest pose (identity for head, hips and feet; for a
// hand the grip pose of the rest hand) maps onto the joint's rest orientation.
//
// Budget. The solve runs PIK iterations until converged, the iteration cap, or the deadline minus
// the predicted cost of one more iteration (the runtime's one deadline policy: IterationBudget and
// IterationCostModel, runtime/clock.h), so it returns before the deadline while iterations cost
// what they did and by the deadline plus at most one iteration when one suddenly costs more.
#include <memory>

#include "avatar/avatar_asset.h"
#include "avatar/body/body_model.h"
#include "runtime/avatar_body_options.h"
#include "runtime/body_seed.h"
#include "runtime/body_solver.h"
#include "runtime/collapse_guard.h"
#include "runtime/foot_planner.h"
#include "runtime/pole_tasks.h"
#include "runtime/pose_blend.h"
#include "runtime/seated_pose.h"
#include "runtime/task_layout.h"

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

  const avatar::BodyModel& body() const { return body_; }
  const ik::Data& data() const { return *data_; }
  const TaskLayout& layout() const { return layout_; }
  const FootPlanner& feet() const { return planner_; }
  bool threePoint() const { return layout_.inferLowerBody; }
  // Calibration: tracking metres -> avatar metres (0 until the first head sample when the user's
  // height comes from it).
  double scale() const { return scale_; }
  double avatarHeight() const { return avatarHeight_; }
  double armReach() const { return armReach_; }
  Eigen::Vector3d toAvatar(const glm::vec3& trackingPoint) const;
  // Solved positions in the avatar's model space: the eye point, wrists, ankles, shoulders.
  Eigen::Vector3d eyePosition() const;
  // The eye point at the avatar's rest pose, as the head targets place it: avatar::restEyePoint,
  // the point the renderer's first-person camera uses too.
  Eigen::Vector3d restEyePosition() const;
  Eigen::Vector3d jointPosition(ik::JointId joint) const { return data_->jointFrame(joint).translation(); }
  ik::JointId trackerJoint(tracking::TrackerId id) const { return joint_[size_t(tracking::index(id))]; }
  // The last targets in avatar space (feet: the planner's in three-point mode).
  const Eigen::Vector3d& target(tracking::TrackerId id) const { return targetPoint_[size_t(tracking::index(id))]; }
  bool calibratedFromHead() const { return calibratedFromHead_; }
  ik::JointId shoulderJoint(tracking::Side side) const { return side == tracking::Side::Left ? leftShoulder_ : rightShoulder_; }
  const Eigen::Vector3d& up() const { return up_; }
  bool seated() const { return layout_.seated; }
  // Seated mode: the seat in avatar space, once placed (null before the first tracked head).
  const SeatedPose* seat() const { return seatPlaced_ ? &seat_ : nullptr; }
  const SeatedLegs& seatedLegs() const { return legs_; }
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
  Eigen::Vector3d footForward(int side) const;
  // Marker targets (jointMarkers) per avatar skeleton joint, avatar space: world positions and
  // world rotations relative to the joint's rest (identity at rest). Joints without a marker are
  // ignored; call before each solve.
  void setMarkers(const std::vector<glm::dvec3>& positions, const std::vector<glm::dquat>& rotations);
  size_t markerCount() const { return markerTask_.size(); }
  // ik::Data setter calls that were refused (non-finite values, unknown ids): 0 unless broken.
  int refusedCalls() const { return refusedCalls_; }

 private:
  AvatarBodySolver(const avatar::AvatarAsset& avatar) : avatar_(avatar) {}
  // create()'s steps: the body model and the frames, the tracker joints, the rest geometry, the
  // layout's tasks.
  Status build(const AvatarBodyOptions& options);
  Status bindJoints(ik::JointId& leftElbow);
  void bindLimbs(ik::JointId leftElbow, ik::JointId rightElbow);
  void measureRest(ik::JointId leftElbow, bool legs);
  void trackerFrames();
  Eigen::Vector3d standingAnkle(const Eigen::Vector3d& hipJoint, const Eigen::Vector3d& restAnkle) const;
  void addLayoutTask(const TaskSpec& spec, std::vector<ik::TaskDesc>& tasks);
  void addJointMarkerTasks(std::vector<ik::TaskDesc>& tasks);
  void calibrate(float userHeight);
  void useSameBody(const AvatarBodyOptions::SameBody& same);
  // setTargets' steps: the first sample's height calibration, stride scaling (tracked feet), the
  // inferred pelvis and feet (three-point).
  void setTargets(const tracking::GuardedSample& targets);
  void calibrateHeights(const tracking::GuardedSample& targets);
  void scaleStrides(const tracking::GuardedSample& targets);
  void setInferredLowerBody(const tracking::GuardedSample& targets);
  void setSeatedTargets(const tracking::GuardedSample& targets);
  const ik::SolveReport& settle(ik::SolveOptions options, int maxIterations);
  // Standing start: the root under the head, facing the head's and hands' heading (body_seed.h).
  // False (nothing changed) without a live head or under a head lower than the standing pelvis.
  bool seedStanding(const tracking::GuardedSample& targets);
  void setPoleTargets();
  // After a solve: asks the collapse guard; on a collapse re-seeds and starts the fade.
  void guardAgainstCollapse(const tracking::GuardedSample& targets, const SolveResult& result, avatar::SkeletonPose& pose);
  void require(const Status& s);  // counts a refused ik::Data call
  // Enables (weight > 0, times the task's own) or disables a position/orientation/pose task pair.
  void setPose(ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p, const Eigen::Quaterniond& q, double weight);

  const avatar::AvatarAsset& avatar_;
  AvatarBodyOptions options_;
  avatar::BodyModel body_;
  std::unique_ptr<ik::Data> data_;
  TaskLayout layout_;
  FootPlanner planner_;
  Eigen::VectorXd restQ_, lastGoodQ_;
  std::array<Eigen::Vector3d, tracking::kTrackerCount> targetPoint_{};
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> targetRotation_{};

  // Tasks per tracker (position, orientation; -1 none), balance, and the inferred hips.
  std::array<ik::TaskId, tracking::kTrackerCount> positionTask_{-1, -1, -1, -1, -1, -1};
  std::array<ik::TaskId, tracking::kTrackerCount> orientationTask_{-1, -1, -1, -1, -1, -1};
  std::array<ik::JointId, tracking::kTrackerCount> joint_{-1, -1, -1, -1, -1, -1};
  // Tracker frame -> joint frame rotation (avatar space, see above), and the joint's rest rotation.
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> jointFromTracker_{};
  std::array<Eigen::Quaterniond, tracking::kTrackerCount> restRotation_{};
  ik::TaskId balanceTask_ = -1, hipsPosTask_ = -1, hipsRotTask_ = -1;
  std::vector<std::pair<int, ik::TaskId>> markerTask_;  // avatar joint, its pose task
  ik::JointId leftShoulder_ = -1, rightShoulder_ = -1;
  // Limb direction: knees (0 left, 1 right) then elbows (2, 3): the task, the chain's root,
  // middle and end joints and the hinge joint, and the rest segment lengths.
  std::array<ik::TaskId, 4> poleTask_{-1, -1, -1, -1};
  std::array<ik::JointId, 4> limbRoot_{-1, -1, -1, -1}, limbMiddle_{-1, -1, -1, -1}, limbEnd_{-1, -1, -1, -1},
      limbHinge_{-1, -1, -1, -1};
  std::array<LimbGeometry, 4> limb_{};
  CollapseGuard guard_;
  PoseFade fade_;
  bool reseeded_ = false;  // the next solve starts cold (after a re-seed)
  bool broken_ = false;    // the last solve produced a non-finite or invalid configuration
  // Seated mode: tasks per side (0 = left), the legs' rest geometry and the placed seat.
  std::array<ik::TaskId, 2> seatHipTask_{-1, -1}, seatKneeTask_{-1, -1};
  ik::TaskId seatPelvisTask_ = -1;
  std::array<ik::JointId, 2> hipJoint_{-1, -1}, kneeJoint_{-1, -1};
  SeatedLegs legs_;
  SeatedPose seat_;
  bool seatPlaced_ = false;

  Eigen::Vector3d up_ = Eigen::Vector3d::UnitY(), forward_ = Eigen::Vector3d::UnitZ();
  Eigen::Quaterniond fromTracking_ = Eigen::Quaterniond::Identity();  // -Z -> the avatar's forward
  double floor_ = 0.0, avatarHeight_ = 1.75, avatarEyeHeight_ = 1.64, armReach_ = 0.6, scale_ = 0.0;
  Eigen::Vector3d eyeInHead_ = Eigen::Vector3d::Zero();  // head joint frame
  Eigen::Vector3d restHeadToHips_ = Eigen::Vector3d::Zero();  // avatar space, at rest
  // Vertical offsets (avatar metres) added to the hips and feet targets, fixed on the first sample
  // that has them: the user's (or performer's) pelvis and ankles stand at the avatar's rest
  // heights then, whatever the proportions. 0 for the other trackers.
  std::array<double, tracking::kTrackerCount> heightOffset_{};
  std::array<double, tracking::kTrackerCount> restHeight_{};  // joint pivot above the floor at rest
  bool heightsCalibrated_ = false;
  double legRatio_ = 1.0;  // avatar leg / user leg, for tracked feet
  IterationCostModel iterationCost_;  // one PIK iteration
  IterationCostModel finishCost_;     // retargeting and residuals after the iterations
  bool solvedOnce_ = false;
  bool calibratedFromHead_ = false;
  int refusedCalls_ = 0;
};

}  // namespace embody::runtime
