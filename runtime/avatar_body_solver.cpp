#include "runtime/avatar_body_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "avatar/body/calibration.h"
#include "avatar/glm_eigen.h"
#include "runtime/budgeted_solve_job.h"
#include "runtime/residuals_job.h"
#include "runtime/skeleton_pose_job.h"
#include "runtime/tracker_targets_job.h"

namespace embody::runtime {

using tracking::TrackerId;
using tracking::TrackerStatus;

namespace {

// A seat placement's cap outside the budget (sitting down from standing needs more than the
// first live solve's, budgeted_solve_job.cpp).
constexpr int kSeatSettleIterations = 80;

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

}  // namespace

Result<std::unique_ptr<AvatarBodySolver>> AvatarBodySolver::create(const avatar::AvatarAsset& avatar,
                                                                   const AvatarBodyOptions& options) {
  if (!avatar::plausibleArmScale(options.armScale))
    return Error{"arm scale " + std::to_string(options.armScale) + " is outside 0.5-2 (user arm span over the avatar's)"};
  // An avatar in the wrong units (175 m: centimetres) or of no size is refused here, for every
  // command that drives one, with the height and the likely unit (`avatar calibrate`'s check).
  if (auto height = avatar::measureAvatarHeight(avatar); !height) return Error{height.error()};
  std::unique_ptr<AvatarBodySolver> s(new AvatarBodySolver(avatar));
  if (auto st = s->build(options); !st) return Error{st.error()};
  return s;
}

Status AvatarBodySolver::build(const AvatarBodyOptions& options) {
  options_ = options;
  guard_ = CollapseGuard(options.collapse);
  auto rig = buildBodyRig(avatar_, options, refusedCalls_);
  if (!rig) return Error{rig.error()};
  rig_ = std::move(rig).value();
  // The calibration's scale is the eye height over the user's: never zero, negative or NaN.
  if (!(rig_.avatarEyeHeight > 0.0 && std::isfinite(rig_.avatarEyeHeight) && rig_.avatarHeight > 0.0))
    return Error{"the avatar's eyes are not above its floor at rest (eye height " + std::to_string(rig_.avatarEyeHeight) +
                 " m of a " + std::to_string(rig_.avatarHeight) + " m stature)"};
  planner_.configure(options.feet, FootShape{}, rig_.up, rig_.forward, rig_.stance, rig_.avatarHeight / 1.75);
  data_ = std::make_unique<ik::Data>(rig_.body.model);
  require(data_->setConfiguration(rig_.restQ));
  lastGoodQ_ = rig_.restQ;
  if (options.sameBody.enabled)
    calibration_ = BodyCalibration::sameBody();
  else if (options.userHeight > 0.0f)
    calibration_ = BodyCalibration::fromUserHeight(rig_, options.userHeight);
  return Status::success();
}

SolveResult AvatarBodySolver::solve(const SolveRequest& request, avatar::SkeletonPose& pose) {
  SolveResult result;
  const Clock& clock = *request.clock;
  const tracking::GuardedSample& sample = *request.targets;
  calibrate(sample);
  const bool seatSettled = setTargets(sample);
  if (!solvedOnce_ && !rig_.layout.seated) seedStanding(sample);

  const bool cold = !solvedOnce_ || reseeded_;
  reseeded_ = false;
  BudgetedSolveOutput solved;
  BudgetedSolveJob solveJob;
  solveJob.model = &rig_.body.model;
  solveJob.clock = &clock;
  solveJob.deadline = request.deadline - finishCost_.predicted();
  solveJob.fixedIterations = request.fixedIterations;
  solveJob.maxIterations = options_.maxIterations;
  solveJob.maxLevelStep = options_.maxLevelStep;
  solveJob.cold = cold;
  solveJob.settleFirst = !solvedOnce_ && !rig_.layout.seated;
  solveJob.iterationCost = &iterationCost_;
  solveJob.data = data_.get();
  solveJob.output = &solved;
  require(solveJob.Run());
  const TimePoint solvedAt = clock.now();
  result.iterations = solved.iterations;
  result.converged = solved.converged;
  // Outside the budget (only a budgeted solve has one): a new seat, or the first live solve.
  result.settled = request.fixedIterations == 0 && (seatSettled || solveJob.settleFirst);

  keepLastGood(solved.broken);
  solvedOnce_ = true;
  require(SkeletonPoseJob{&rig_.body, &avatar_, data_.get(), &pose}.Run());
  require(ResidualsJob{&rig_, data_.get(), &targets_, &result}.Run());
  if (!rig_.layout.seated) guardAgainstCollapse(sample, result, pose);
  fade_.apply(sample.pose.time, pose);
  finishCost_.observe(clock.now() - solvedAt);
  return result;
}

// The scale on the first sample (unless the options gave it), the height offsets on the first
// sample with a tracked head (again after resetWarmStart).
void AvatarBodySolver::calibrate(const tracking::GuardedSample& sample) {
  if (!calibration_.scaled()) calibration_ = BodyCalibration::fromFirstSample(rig_, sample);
  if (!calibration_.heightsCalibrated && !options_.sameBody.enabled && sample[TrackerId::Head] == TrackerStatus::Tracked)
    calibration_ = calibration_.withHeights(rig_, sample);
}

// Returns whether a new seat was settled outside the budget.
bool AvatarBodySolver::setTargets(const tracking::GuardedSample& sample) {
  TrackerTargetsJob trackers;
  trackers.rig = &rig_;
  trackers.calibration = &calibration_;
  trackers.sample = &sample;
  trackers.pelvisRow = options_.pelvisRow;
  trackers.armScale = options_.armScale;
  trackers.targets = &targets_;
  require(trackers.Run());
  TaskTargetsOutput out;
  TaskTargetsJob tasks;
  tasks.rig = &rig_;
  tasks.calibration = &calibration_;
  tasks.sample = &sample;
  tasks.balanceRow = options_.balanceRow;
  tasks.seatHeight = options_.seat.seatHeight;
  tasks.solvedOnce = solvedOnce_;
  tasks.targets = &targets_;
  tasks.planner = &planner_;
  tasks.heading = &heading_;
  tasks.seat = &seat_;
  tasks.data = data_.get();
  tasks.output = &out;
  require(tasks.Run());
  refusedCalls_ += out.refusedCalls;
  // A new seat before the first solve: sit down and reach the first targets outside the budget.
  if (out.settleSeat) (void)settle(rig_.body.model, *data_, {}, kSeatSettleIterations);
  return out.settleSeat;
}

// Never publish a broken configuration: fall back to the last good one.
void AvatarBodySolver::keepLastGood(bool broken) {
  broken_ = !data_->q().allFinite() || broken;
  if (broken_) {
    require(data_->setConfiguration(lastGoodQ_));
    ik::kinematics(rig_.body.model, *data_, false);
  } else {
    lastGoodQ_ = data_->q();
  }
}

Eigen::Vector3d AvatarBodySolver::toAvatar(const glm::vec3& p) const { return rig_.toAvatar(calibration_.scale, avatar::toEigen(p)); }

// The ik::Data setters refuse only non-finite values and unknown ids, which the solver never hands
// them, and the jobs refuse only inputs the solver never builds: a refusal is counted
// (refusedCalls(), 0 in every test run), the state stays as it was.
void AvatarBodySolver::require(const Status& s) {
  if (!s) ++refusedCalls_;
}

void AvatarBodySolver::require(bool jobRan) {
  if (!jobRan) ++refusedCalls_;
}

Eigen::Vector3d AvatarBodySolver::eyePosition() const { return data_->jointFrame(rig_.body.head) * rig_.eyeInHead; }

LowerBodyPosture AvatarBodySolver::posture() const {
  LowerBodyPosture p;
  const Eigen::Isometry3d& root = data_->jointFrame(rig_.body.hips);
  p.pelvis = root.translation();
  p.eye = eyePosition();
  const Eigen::Quaterniond pelvisTurn =
      Eigen::Quaterniond(root.rotation()) * rig_.restRotation[size_t(tracking::index(TrackerId::Hips))].conjugate();
  const Eigen::Vector3d trunkDown = pelvisTurn * -rig_.up;
  for (size_t s = 0; s < 2; ++s) {
    if (rig_.hipJoint[s] < 0 || rig_.kneeJoint[s] < 0) continue;
    p.hip[s] = jointPosition(rig_.hipJoint[s]);
    p.knee[s] = jointPosition(rig_.kneeJoint[s]);
    p.ankle[s] = jointPosition(s == 0 ? rig_.body.leftFoot : rig_.body.rightFoot);
    p.hipFlexion[s] = angleBetween(trunkDown, p.knee[s] - p.hip[s]);
    p.kneeFlexion[s] = angleBetween(p.knee[s] - p.hip[s], p.ankle[s] - p.knee[s]);
  }
  p.spineFlexion = angleBetween(pelvisTurn * -rig_.restHeadToHips, jointPosition(rig_.body.head) - p.pelvis);
  p.pelvisPitch = angleBetween(pelvisTurn * rig_.up, rig_.up);
  return p;
}

bool AvatarBodySolver::seedStanding(const tracking::GuardedSample& targets) {
  const size_t h = size_t(tracking::index(TrackerId::Head));
  if (!targets.pose[TrackerId::Head].valid || targets.status[h] == TrackerStatus::Absent) return false;
  // No standing body fits under a head lower than the standing pelvis (a user lying or sitting
  // on the floor): the solve goes on from where it is.
  const double headHeight = rig_.up.dot(targets_.point[h]) - rig_.floor;
  if (headHeight < rig_.restHeight[size_t(tracking::index(TrackerId::Hips))]) return false;
  SeedInputs in;
  in.up = rig_.up;
  in.forward = rig_.forward;
  in.headPivot = targets_.point[h] - targets_.rotation[h] * rig_.eyeInHead;
  // The forward's ground projection, not faceHeadingOf: a seed is only planted under a standing
  // head, and with a start yaw half a degree either way the all-trackers body held with its hands
  // beyond reach fell into a cycle (a 4 mm jump every 60-180 frames; docs/runtime.md, "Known
  // limits"), which the start from this yaw happens not to.
  in.headYaw = headingOf(targets_.rotation[h] * rig_.restRotation[h].conjugate(), rig_.up, rig_.forward);
  for (auto id : {TrackerId::LeftHand, TrackerId::RightHand}) {
    const size_t i = size_t(tracking::index(id));
    if (targets.status[i] != TrackerStatus::Tracked || !targets.pose[id].valid) continue;
    (id == TrackerId::LeftHand ? in.leftHand : in.rightHand) = targets_.point[i];
  }
  in.restHeadToHips = rig_.restHeadToHips;
  in.floor = rig_.floor;
  in.restHipsHeight = rig_.restHeight[size_t(tracking::index(TrackerId::Hips))];
  in.scale = rig_.avatarHeight / 1.75;
  const double yaw = seedYaw(in);
  require(data_->setConfiguration(placeRoot(rig_.body.model, rig_.body.hips, rig_.restQ, seedPelvis(in, yaw), yaw, rig_.up)));
  ik::kinematics(rig_.body.model, *data_, false);
  return true;
}

double AvatarBodySolver::hingeAngle(int limb) const {
  if (limb < 0 || limb > 3 || rig_.limbHinge[size_t(limb)] < 0) return 0.0;
  return data_->q()[rig_.body.model.joints[size_t(rig_.limbHinge[size_t(limb)])].first_dof];
}

Status AvatarBodySolver::seedConfiguration(const Eigen::VectorXd& q) {
  if (auto st = data_->setConfiguration(q); !st) return st;
  ik::kinematics(rig_.body.model, *data_, false);
  lastGoodQ_ = q;
  solvedOnce_ = true;
  return Status::success();
}

BodySignals AvatarBodySolver::bodySignals(double time, const SolveResult& result) const {
  BodySignals s;
  s.time = time;
  s.finite = !broken_;
  s.scale = rig_.avatarHeight / 1.75;
  const size_t hips = size_t(tracking::index(TrackerId::Hips)), head = size_t(tracking::index(TrackerId::Head));
  const Eigen::Isometry3d& root = data_->jointFrame(rig_.body.hips);
  auto height = [&](const Eigen::Vector3d& p) { return rig_.up.dot(p) - rig_.floor; };
  s.pelvisHeight = height(root.translation());
  s.standingPelvisHeight = rig_.restHeight[hips];
  s.headTargetHeight = height(targets_.point[head]);
  s.standingEyeHeight = rig_.avatarEyeHeight;
  const Eigen::Quaterniond pelvisTurn = Eigen::Quaterniond(root.rotation()) * rig_.restRotation[hips].conjugate();
  const Eigen::Vector3d pelvisUp = pelvisTurn * rig_.up;
  s.pelvisTilt = std::atan2(pelvisUp.cross(rig_.up).norm(), pelvisUp.dot(rig_.up));
  s.lowestTrunkOrKnee = std::min(s.pelvisHeight, height(jointPosition(rig_.body.head)));
  // Sides across the feet's own heading: on a walk the stride runs along it, where the pelvis
  // (which turns with the head and the gait) would let the stride leak into the sideways measure.
  Eigen::Vector3d heading = footForward(0) + footForward(1);
  heading -= rig_.up * rig_.up.dot(heading);
  if (heading.norm() < 0.5) heading = pelvisTurn * rig_.forward - rig_.up * rig_.up.dot(pelvisTurn * rig_.forward);
  const Eigen::Vector3d left = heading.norm() > 1e-6 ? Eigen::Vector3d(rig_.up.cross(heading).normalized()) : Eigen::Vector3d(rig_.up.cross(rig_.forward));
  s.legSeparation = left.dot(jointPosition(rig_.body.leftFoot) - jointPosition(rig_.body.rightFoot));
  if (rig_.kneeJoint[0] >= 0 && rig_.kneeJoint[1] >= 0) {
    for (ik::JointId k : rig_.kneeJoint) s.lowestTrunkOrKnee = std::min(s.lowestTrunkOrKnee, height(jointPosition(k)));
    s.legSeparation = std::min(s.legSeparation, left.dot(jointPosition(rig_.kneeJoint[0]) - jointPosition(rig_.kneeJoint[1])));
  }
  s.inferredLegs = rig_.layout.inferLowerBody;
  s.iterations = result.iterations;
  // The errors a body can fix: the head's (less what a target above standing height explains),
  // the hands' while within the arm's reach.
  if (result.residual[head] >= 0.0f) s.residual = fixableHeadError(result.residual[head], s.headTargetHeight, s.standingEyeHeight);
  for (auto id : {TrackerId::LeftHand, TrackerId::RightHand}) {
    const size_t i = size_t(tracking::index(id));
    if (result.residual[i] >= 0.0f && result.reachable[i]) s.residual = std::max(s.residual, double(result.residual[i]));
  }
  return s;
}

void AvatarBodySolver::guardAgainstCollapse(const tracking::GuardedSample& targets, const SolveResult& result,
                                            avatar::SkeletonPose& pose) {
  const double time = targets.pose.time;
  if (guard_.update(bodySignals(time, result)) == CollapseReason::None) return;
  // Stand up under the head, plant the feet afresh, solve cold next frame; the shown pose fades
  // from the heap to the new solution. Under a head too low to stand under (seedStanding), only
  // the cold solve.
  reseeded_ = true;
  if (!seedStanding(targets)) return;
  fade_.start(pose, time, options_.recoveryBlendSeconds);  // `pose` is still the heap
  lastGoodQ_ = data_->q();
  planner_.restart();
  heading_.reset();
}

void AvatarBodySolver::setMarkers(const std::vector<glm::dvec3>& positions, const std::vector<glm::dquat>& rotations) {
  for (const BodyTasks::JointMarker& m : rig_.tasks.marker) {
    const size_t a = size_t(m.avatarJoint);
    if (a >= positions.size() || a >= rotations.size()) continue;
    const glm::dvec3& p = positions[a];
    const glm::dquat& r = rotations[a];
    const int j = rig_.body.ikJointOfAvatar[a];
    const Eigen::Quaterniond world = Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized() * rig_.body.ikRestRotation[size_t(j)];
    setTaskPose(rig_.body.model, *data_, m.position, m.orientation, Eigen::Vector3d(p.x, p.y, p.z), world, 1.0, refusedCalls_);
  }
}

Eigen::Vector3d AvatarBodySolver::restEyePosition() const {
  ik::Data rest(rig_.body.model);
  if (!rest.setConfiguration(rig_.body.restConfiguration)) return Eigen::Vector3d::Constant(std::nan(""));
  ik::kinematics(rig_.body.model, rest, false);
  return rest.jointFrame(rig_.body.head) * rig_.eyeInHead;
}

void AvatarBodySolver::resetWarmStart() {
  require(data_->setConfiguration(rig_.restQ));
  lastGoodQ_ = rig_.restQ;
  calibration_ = calibration_.withoutHeights();
  seat_.placed = false;
  solvedOnce_ = false;
  reseeded_ = false;
  guard_.reset();
  fade_ = PoseFade{};
  planner_.restart();
  heading_.reset();
}

}  // namespace embody::runtime
