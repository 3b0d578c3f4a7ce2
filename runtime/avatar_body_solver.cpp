#include "runtime/avatar_body_solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "avatar/body/anthropometry.h"
#include "avatar/body/eye_point.h"
#include "avatar/glm_eigen.h"
#include "avatar/humanoid/humanoid_map.h"

namespace embody::runtime {

using tracking::TrackerId;
using tracking::TrackerStatus;

namespace {

using avatar::toEigen;
using avatar::toGlm;

// The caps of the two settles outside the budget (settle()): the first live solve's (~40 x 0.25 ms
// at worst, once) and a seat placement's (sitting down from standing needs more).
constexpr int kFirstSolveSettleIterations = 40;
constexpr int kSeatSettleIterations = 80;

// The model `body` was built with, plus `tasks` (the builder's validation runs again).
Result<ik::Model> withTasks(const ik::Model& model, const std::vector<ik::TaskDesc>& tasks) {
  ik::ModelBuilder b;
  for (const auto& j : model.joints) b.addJoint(j.desc);
  for (const auto& e : model.equalities) b.addEquality(e);
  for (const auto& i : model.inequalities)
    if (i.kind == ik::InequalityKind::UserCoupling) b.addInequality(i);
  for (const auto& t : tasks) b.addTask(t);
  b.setUp(model.up);
  return b.build();
}

}  // namespace

Result<std::unique_ptr<AvatarBodySolver>> AvatarBodySolver::create(const avatar::AvatarAsset& avatar,
                                                                   const AvatarBodyOptions& options) {
  std::unique_ptr<AvatarBodySolver> s(new AvatarBodySolver(avatar));
  if (auto st = s->build(options); !st) return Error{st.error()};
  return s;
}

Status AvatarBodySolver::build(const AvatarBodyOptions& options) {
  options_ = options;
  guard_ = CollapseGuard(options.collapse);
  avatar::BodyModelOptions bo;
  bo.spine = options.spine;
  bo.totalMass = options.totalMass;
  bo.addTasks = false;
  bo.coupledSpine = options.coupledSpine;
  auto body = avatar::buildBodyModel(avatar_, bo);
  if (!body) return Error{body.error()};
  body_ = std::move(body).value();
  up_ = toEigen(avatar_.humanoid.up).normalized();
  forward_ = toEigen(avatar_.humanoid.forward);
  forward_ = (forward_ - up_ * up_.dot(forward_)).normalized();
  // Tracking space (+X right, +Y up, -Z forward) -> avatar space.
  Eigen::Matrix3d c;
  c.col(0) = forward_.cross(up_);
  c.col(1) = up_;
  c.col(2) = -forward_;
  fromTracking_ = Eigen::Quaterniond(c).normalized();
  ik::JointId leftElbow = -1;
  if (auto s = bindJoints(leftElbow); !s) return s;
  const bool legs = hipJoint_[0] >= 0 && hipJoint_[1] >= 0 && kneeJoint_[0] >= 0 && kneeJoint_[1] >= 0;
  if (options.seat.enabled && !legs) return Error{"seated mode: the avatar's upper and lower legs are not mapped"};
  measureRest(leftElbow, legs);
  if (options.sameBody.enabled) useSameBody(options.sameBody);  // before the tasks take the eye offset
  layout_ = options.seat.enabled ? seatedTaskLayoutFor(options.trackers) : taskLayoutFor(options.trackers);
  std::vector<ik::TaskDesc> tasks;
  for (const TaskSpec& spec : layout_.tasks) addLayoutTask(spec, tasks);
  if (options.jointMarkers) addJointMarkerTasks(tasks);
  auto model = withTasks(body_.model, tasks);
  if (!model) return Error{"body model with tracker tasks: " + model.error()};
  body_.model = std::move(model).value();
  data_ = std::make_unique<ik::Data>(body_.model);
  // The configuration a body starts from: the rest pose (q = 0 is the neutral pose, body_model.h)
  // with knees and elbows bent at least a little in their anatomical direction (a straight hinge
  // is singular).
  restQ_ = body_.restConfiguration;
  for (size_t k = 0; k < 4; ++k)
    if (limbHinge_[k] >= 0) {
      double& bend = restQ_[body_.model.joints[size_t(limbHinge_[k])].first_dof];
      bend = std::max(bend, k < 2 ? 0.15 : 0.3);
    }
  require(data_->setConfiguration(restQ_));
  lastGoodQ_ = restQ_;
  if (options.userHeight > 0.0f && !options.sameBody.enabled) calibrate(options.userHeight);
  return Status::success();
}

Status AvatarBodySolver::bindJoints(ik::JointId& leftElbow) {
  joint_[size_t(tracking::index(TrackerId::Head))] = body_.head;
  joint_[size_t(tracking::index(TrackerId::LeftHand))] = body_.leftHand;
  joint_[size_t(tracking::index(TrackerId::RightHand))] = body_.rightHand;
  joint_[size_t(tracking::index(TrackerId::Hips))] = body_.hips;
  joint_[size_t(tracking::index(TrackerId::LeftFoot))] = body_.leftFoot;
  joint_[size_t(tracking::index(TrackerId::RightFoot))] = body_.rightFoot;
  auto ikOf = [&](avatar::HumanBone bone) {
    const int a = avatar_.humanoid.joint(bone);
    return a >= 0 ? body_.ikJointOfAvatar[size_t(a)] : -1;
  };
  leftShoulder_ = ikOf(avatar::HumanBone::leftUpperArm);
  rightShoulder_ = ikOf(avatar::HumanBone::rightUpperArm);
  leftElbow = ikOf(avatar::HumanBone::leftLowerArm);
  if (leftShoulder_ < 0 || rightShoulder_ < 0 || leftElbow < 0) return Error{"the avatar's arms are not mapped"};
  hipJoint_ = {ikOf(avatar::HumanBone::leftUpperLeg), ikOf(avatar::HumanBone::rightUpperLeg)};
  kneeJoint_ = {ikOf(avatar::HumanBone::leftLowerLeg), ikOf(avatar::HumanBone::rightLowerLeg)};
  bindLimbs(leftElbow, ikOf(avatar::HumanBone::rightLowerArm));
  return Status::success();
}

// Limb chains for the knee and elbow direction tasks. The elbow's IK joint at the lower arm's
// pivot is its forearm twist; the hinge is the joint before it.
void AvatarBodySolver::bindLimbs(ik::JointId leftElbow, ik::JointId rightElbow) {
  for (size_t s = 0; s < 2; ++s) {
    const bool left = s == 0;
    limbRoot_[s] = hipJoint_[s];
    limbMiddle_[s] = limbHinge_[s] = kneeJoint_[s];
    limbEnd_[s] = left ? body_.leftFoot : body_.rightFoot;
    const ik::JointId elbow = left ? leftElbow : rightElbow;
    limbRoot_[2 + s] = left ? leftShoulder_ : rightShoulder_;
    limbMiddle_[2 + s] = elbow;
    limbEnd_[2 + s] = left ? body_.leftHand : body_.rightHand;
    if (elbow >= 0) {
      const ik::JointDesc& twist = body_.model.joints[size_t(elbow)].desc;
      limbHinge_[2 + s] = twist.type == ik::JointType::Revolute && twist.parent >= 0 &&
                                  body_.model.joints[size_t(twist.parent)].desc.type == ik::JointType::Revolute
                              ? twist.parent
                              : -1;
    }
  }
}

// Rest geometry from the model without tasks at the avatar's rest pose: heights, the eye point,
// the seated legs, the tracker -> joint frames and the foot planner's rest stance.
void AvatarBodySolver::measureRest(ik::JointId leftElbow, bool legs) {
  ik::Data rest(body_.model);
  require(rest.setConfiguration(body_.restConfiguration));
  ik::kinematics(body_.model, rest, false);
  auto pos = [&](ik::JointId j) { return Eigen::Vector3d(rest.jointFrame(j).translation()); };
  for (size_t k = 0; k < 4; ++k)
    if (limbRoot_[k] >= 0 && limbMiddle_[k] >= 0 && limbEnd_[k] >= 0)
      limb_[k] = {(pos(limbMiddle_[k]) - pos(limbRoot_[k])).norm(), (pos(limbEnd_[k]) - pos(limbMiddle_[k])).norm()};
  for (auto id : tracking::kAllTrackers)
    restRotation_[size_t(tracking::index(id))] = Eigen::Quaterniond(rest.jointFrame(joint_[size_t(tracking::index(id))]).rotation());
  armReach_ = (pos(leftElbow) - pos(leftShoulder_)).norm() + (pos(body_.leftHand) - pos(leftElbow)).norm();
  // The eyes: the avatar's one eye point (avatar/body/eye_point.h), the renderer's camera too;
  // floor and stature (avatar::restStature along the humanoid's up, up_) come with it.
  const avatar::EyePoint restEye =
      avatar::restEyePoint(avatar_, avatar_.humanoid.joint(avatar::HumanBone::head), toGlm(forward_));
  floor_ = restEye.stature.floor;
  avatarHeight_ = restEye.stature.height;
  for (auto id : tracking::kAllTrackers)
    restHeight_[size_t(tracking::index(id))] = up_.dot(pos(joint_[size_t(tracking::index(id))])) - floor_;
  const Eigen::Vector3d head = pos(body_.head);
  avatarEyeHeight_ = restEye.aboveFloor;
  const Eigen::Vector3d eye(restEye.position.x, restEye.position.y, restEye.position.z);
  eyeInHead_ = restRotation_[0].conjugate() * (eye - head);
  restHeadToHips_ = pos(body_.hips) - head;
  if (legs) {
    // Seated mode's leg geometry. The hip joint centres sit about a thigh's thickness (5 % of
    // stature) above the seat surface.
    legs_.up = up_;
    legs_.forward = forward_;
    legs_.floor = floor_;
    legs_.eye = eye;
    for (size_t s = 0; s < 2; ++s) {
      const ik::JointId foot = s == 0 ? body_.leftFoot : body_.rightFoot;
      legs_.hip[s] = pos(hipJoint_[s]);
      legs_.knee[s] = pos(kneeJoint_[s]);
      legs_.ankle[s] = pos(foot);
      legs_.footRotation[s] = Eigen::Quaterniond(rest.jointFrame(foot).rotation());
    }
    legs_.pelvisRotation = restRotation_[size_t(tracking::index(TrackerId::Hips))];
    legs_.hipAboveSeat = 0.05 * avatarHeight_;
  }
  trackerFrames();
  // Feet for three-point mode: the stance relative to the hips' ground point.
  const Eigen::Vector3d hipsGround = pos(body_.hips) - up_ * up_.dot(pos(body_.hips));
  std::array<Eigen::Vector3d, 2> stance{pos(body_.leftFoot) - hipsGround, pos(body_.rightFoot) - hipsGround};
  if (legs)
    for (size_t s = 0; s < 2; ++s) stance[s] = standingAnkle(pos(hipJoint_[s]), stance[s] + hipsGround) - hipsGround;
  planner_.configure(options_.feet, FootShape{}, up_, forward_, stance, avatarHeight_ / 1.75);
}

// Where a person stands a foot: the ankle under its hip joint (feet about hip-width apart), at the
// rest ankle's height. Rest poses spread the legs as their authors chose (CMU's zero pose stands
// them 60 cm apart, a T-pose or A-pose often 30-40 cm): a stance taken from them walks wide-legged.
Eigen::Vector3d AvatarBodySolver::standingAnkle(const Eigen::Vector3d& hipJoint, const Eigen::Vector3d& restAnkle) const {
  return hipJoint - up_ * up_.dot(hipJoint) + up_ * up_.dot(restAnkle);
}

// Tracker frame -> joint frame. Reference tracker orientations (tracking space) for the rest
// pose: identity for head, hips, feet; the grip pose of the rest hand for the hands.
void AvatarBodySolver::trackerFrames() {
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    glm::quat ref(1.0f, 0.0f, 0.0f, 0.0f);
    if (id == TrackerId::LeftHand || id == TrackerId::RightHand) {
      const bool left = id == TrackerId::LeftHand;
      const Eigen::Vector3d fingers = restRotation_[i] * Eigen::Vector3d::UnitY();
      const Eigen::Vector3d palm = restRotation_[i] * Eigen::Vector3d::UnitX() * (left ? 1.0 : -1.0);
      ref = tracking::gripOrientation(left ? tracking::Side::Left : tracking::Side::Right,
                                      toGlm(fromTracking_.conjugate() * fingers), toGlm(fromTracking_.conjugate() * palm));
    }
    jointFromTracker_[i] = (fromTracking_ * toEigen(ref)).conjugate() * restRotation_[i];
  }
}

// One task of the layout (layout priority 1 = solver level 0), appended to `tasks`.
void AvatarBodySolver::addLayoutTask(const TaskSpec& spec, std::vector<ik::TaskDesc>& tasks) {
  auto add = [&](ik::TaskDesc t, float weight) {
    t.level = spec.priority - 1;
    t.weight = weight;
    tasks.push_back(std::move(t));
    return ik::TaskId(tasks.size() - 1);
  };
  const size_t i = size_t(tracking::index(spec.tracker));
  ik::TaskDesc t;
  t.name = std::string(taskKindName(spec.kind)) + "_" + std::string(tracking::trackerKey(spec.tracker));
  t.joint = joint_[i];
  t.position_tolerance = 5e-4;
  t.rotation_tolerance = 0.01;
  switch (spec.kind) {
    case TaskKind::TrackerPosition:
      t.type = ik::TaskType::Position;
      if (spec.tracker == TrackerId::Head) t.offset = eyeInHead_;
      // A tracked pelvis steers the trunk over the ground only: its height follows from the
      // head and the legs, whose proportions differ between user and avatar.
      if (spec.tracker == TrackerId::Hips && std::abs(std::abs(up_.y()) - 1.0) < 1e-6) t.axes = ik::kAxisX | ik::kAxisZ;
      positionTask_[i] = add(t, spec.weight);
      break;
    case TaskKind::TrackerOrientation:
      t.type = ik::TaskType::Orientation;
      if (spec.tracker != TrackerId::Head) t.rotation_tolerance = 0.05;
      orientationTask_[i] = add(t, spec.weight);
      break;
    case TaskKind::FootPlant:
      t.type = ik::TaskType::Pose;
      positionTask_[i] = add(t, spec.weight);
      break;
    case TaskKind::Balance:
      t.type = ik::TaskType::CenterOfMass;
      t.position_tolerance = 0.005;
      balanceTask_ = add(t, spec.weight);
      break;
    case TaskKind::SeatedHip:
    case TaskKind::SeatedKnee: {
      const size_t side = spec.tracker == TrackerId::LeftFoot ? 0 : 1;
      const bool hip = spec.kind == TaskKind::SeatedHip;
      t.name = std::string(hip ? "seated_hip_" : "seated_knee_") + (side == 0 ? "left" : "right");
      t.type = ik::TaskType::Position;
      t.joint = hip ? hipJoint_[side] : kneeJoint_[side];
      (hip ? seatHipTask_ : seatKneeTask_)[side] = add(t, spec.weight);
      break;
    }
    case TaskKind::SeatedPelvis:
      t.name = "seated_pelvis";
      t.type = ik::TaskType::Orientation;
      t.joint = body_.hips;
      t.rotation_tolerance = 0.05;
      seatPelvisTask_ = add(t, spec.weight);
      break;
    case TaskKind::LimbPole: {
      const size_t k = spec.tracker == TrackerId::LeftFoot    ? 0
                       : spec.tracker == TrackerId::RightFoot ? 1
                       : spec.tracker == TrackerId::LeftHand  ? 2
                                                              : 3;
      // Joint markers say where every knee and elbow is: a pole would only pull it off.
      if (!options_.limbPoles || (k >= 2 && !options_.elbowPoles) || options_.jointMarkers || limbMiddle_[k] < 0 || limbRoot_[k] < 0 || !(limb_[k].upper > 0.0)) break;
      t.name = std::string(k < 2 ? "pole_knee_" : "pole_elbow_") + (k % 2 == 0 ? "left" : "right");
      t.type = ik::TaskType::Position;
      t.joint = limbMiddle_[k];
      t.position_tolerance = 0.02;  // a direction, not a place: it need not hold a solve back
      poleTask_[k] = add(t, spec.weight);
      break;
    }
    case TaskKind::InferredHips:
      t.type = ik::TaskType::Position;
      t.position_tolerance = 0.05;
      hipsPosTask_ = add(t, spec.weight);
      t.type = ik::TaskType::Orientation;
      t.name += "_rotation";
      t.rotation_tolerance = 0.2;
      hipsRotTask_ = add(t, spec.weight * 0.5f);
      break;
  }
}

void AvatarBodySolver::calibrate(float userHeight) {
  const auto dims = tracking::BodyDimensions::fromHeight(userHeight);
  scale_ = avatarEyeHeight_ / double(dims.eyeHeight);
}

// --trackers full (embody eval): a pose marker on every mapped avatar joint, one level below the
// layout's lowest.
void AvatarBodySolver::addJointMarkerTasks(std::vector<ik::TaskDesc>& tasks) {
  int lowest = 1;
  for (const TaskSpec& spec : layout_.tasks)
    if (spec.kind != TaskKind::LimbPole) lowest = std::max(lowest, spec.priority);  // no poles with markers
  for (size_t a = 0; a < avatar_.skeleton.joints.size(); ++a) {
    const int j = body_.ikJointOfAvatar[a];
    if (j < 0 || body_.avatarJoint[size_t(j)] != int(a)) continue;
    ik::TaskDesc t;
    t.name = "marker_" + avatar_.skeleton.joints[a].name;
    t.type = ik::TaskType::Pose;
    t.joint = j;
    t.position_tolerance = 5e-4;
    t.rotation_tolerance = 0.01;
    t.level = lowest;  // layout priority lowest + 1 = solver level lowest
    t.weight = 1.0f;
    tasks.push_back(std::move(t));
    markerTask_.emplace_back(int(a), ik::TaskId(tasks.size() - 1));
  }
}

void AvatarBodySolver::useSameBody(const AvatarBodyOptions::SameBody& same) {
  scale_ = 1.0;
  floor_ = 0.0;
  fromTracking_ = Eigen::Quaterniond::Identity();
  const size_t head = size_t(tracking::index(TrackerId::Head));
  eyeInHead_ = restRotation_[head].conjugate() * same.eyeOffset;
  for (size_t i = 0; i < tracking::kTrackerCount; ++i)
    jointFromTracker_[i] = same.reference[i].normalized().conjugate() * restRotation_[i];
}

void AvatarBodySolver::setMarkers(const std::vector<glm::dvec3>& positions, const std::vector<glm::dquat>& rotations) {
  for (const auto& [a, task] : markerTask_) {
    if (size_t(a) >= positions.size() || size_t(a) >= rotations.size()) continue;
    const glm::dvec3& p = positions[size_t(a)];
    const glm::dquat& r = rotations[size_t(a)];
    const int j = body_.ikJointOfAvatar[size_t(a)];
    const Eigen::Quaterniond world = Eigen::Quaterniond(r.w, r.x, r.y, r.z).normalized() * body_.ikRestRotation[size_t(j)];
    setPose(task, -1, Eigen::Vector3d(p.x, p.y, p.z), world, 1.0);
  }
}

Eigen::Vector3d AvatarBodySolver::toAvatar(const glm::vec3& p) const {
  return fromTracking_ * (scale_ * toEigen(p)) + up_ * floor_;
}

// The ik::Data setters refuse only non-finite values and unknown ids, which the solver never hands
// them: a refusal is counted (refusedCalls(), 0 in every test run), the state stays as it was.
void AvatarBodySolver::require(const Status& s) {
  if (!s) ++refusedCalls_;
}

Eigen::Vector3d AvatarBodySolver::eyePosition() const { return data_->jointFrame(body_.head) * eyeInHead_; }

Eigen::Vector3d AvatarBodySolver::restEyePosition() const {
  ik::Data rest(body_.model);
  if (!rest.setConfiguration(body_.restConfiguration)) return Eigen::Vector3d::Constant(std::nan(""));
  ik::kinematics(body_.model, rest, false);
  return rest.jointFrame(body_.head) * eyeInHead_;
}

void AvatarBodySolver::resetWarmStart() {
  require(data_->setConfiguration(restQ_));
  lastGoodQ_ = restQ_;
  heightsCalibrated_ = false;
  seatPlaced_ = false;
  heightOffset_.fill(0.0);
  legRatio_ = 1.0;
  solvedOnce_ = false;
  reseeded_ = false;
  guard_.reset();
  fade_ = PoseFade{};
  planner_.restart();
}

void AvatarBodySolver::setPose(ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p,
                               const Eigen::Quaterniond& q, double weight) {
  ik::Data& d = *data_;
  for (ik::TaskId t : {position, orientation}) {
    if (t < 0) continue;
    if (!(weight > 0.0)) {
      require(d.setEnabled(t, false));
      continue;
    }
    require(d.setEnabled(t, true));
    require(d.setWeight(t, weight * body_.model.tasks[size_t(t)].desc.weight));
    const ik::TaskType type = body_.model.tasks[size_t(t)].desc.type;
    if (type == ik::TaskType::Pose) {
      Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
      iso.linear() = q.toRotationMatrix();
      iso.translation() = p;
      require(d.setTarget(t, iso));
    } else if (type == ik::TaskType::Orientation) {
      require(d.setTarget(t, q));
    } else {
      require(d.setTarget(t, p));
    }
  }
}

// On the first sample with a tracked head: the vertical offsets that stand the user's ankles and
// pelvis at the avatar's rest heights, and the stride scaling (avatar leg / user leg).
void AvatarBodySolver::calibrateHeights(const tracking::GuardedSample& targets) {
  heightsCalibrated_ = true;
  const auto& lf = targets.pose[TrackerId::LeftFoot];
  const auto& rf = targets.pose[TrackerId::RightFoot];
  if (targets[TrackerId::LeftFoot] == TrackerStatus::Tracked && targets[TrackerId::RightFoot] == TrackerStatus::Tracked) {
    const double lowest = scale_ * std::min(lf.position.y, rf.position.y);
    for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot})
      heightOffset_[size_t(tracking::index(id))] = restHeight_[size_t(tracking::index(id))] - lowest;
  }
  if (targets[TrackerId::Hips] == TrackerStatus::Tracked) {
    const size_t h = size_t(tracking::index(TrackerId::Hips));
    heightOffset_[h] = restHeight_[h] - scale_ * targets.pose[TrackerId::Hips].position.y;
    // Stride scaling: the user's leg (pelvis to ankle) against the avatar's.
    const double userLeg = scale_ * (targets.pose[TrackerId::Hips].position.y - std::min(lf.position.y, rf.position.y));
    const double avatarLeg = restHeight_[h] - restHeight_[size_t(tracking::index(TrackerId::LeftFoot))];
    if (userLeg > 0.2 && avatarLeg > 0.2) legRatio_ = std::clamp(avatarLeg / userLeg, 0.5, 2.0);
  }
}

// Tracked feet with a tracked pelvis: strides scaled by the leg ratio about the pelvis's ground
// point, so a longer-legged user's steps stay within the avatar's legs.
void AvatarBodySolver::scaleStrides(const tracking::GuardedSample& targets) {
  const size_t hipsI = size_t(tracking::index(TrackerId::Hips));
  if (legRatio_ == 1.0 || targets.status[hipsI] == TrackerStatus::Absent) return;
  const Eigen::Vector3d pelvis = targetPoint_[hipsI];
  for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot}) {
    const size_t i = size_t(tracking::index(id));
    if (positionTask_[i] < 0 || !data_->enabled(positionTask_[i])) continue;
    Eigen::Vector3d offset = targetPoint_[i] - pelvis;
    offset -= up_ * up_.dot(offset);
    targetPoint_[i] += (legRatio_ - 1.0) * offset;
    require(data_->setTarget(positionTask_[i], targetPoint_[i]));
  }
}

// Three-point mode: the pelvis and the feet are inferred from the head (the foot planner steps).
void AvatarBodySolver::setInferredLowerBody(const tracking::GuardedSample& targets) {
  ik::Data& d = *data_;
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  const Eigen::Quaterniond headTurn = targetRotation_[headIndex] * restRotation_[headIndex].conjugate();
  const double yaw = headingOf(headTurn, up_, forward_);
  const Eigen::Quaterniond heading = yawRotation(yaw, up_);
  const Eigen::Vector3d headPivot = targetPoint_[headIndex] - targetRotation_[headIndex] * eyeInHead_;
  const Eigen::Vector3d hips = headPivot + heading * restHeadToHips_;
  const size_t hipsIndex = size_t(tracking::index(TrackerId::Hips));
  setPose(hipsPosTask_, hipsRotTask_, hips, heading * restRotation_[hipsIndex], 1.0);

  const double time = targets.pose.time;
  if (!planner_.initialised()) planner_.reset(hips, yaw, time);
  const Eigen::Vector3d com = solvedOnce_ ? Eigen::Vector3d(d.centerOfMass()) : hips;
  const auto& feet = planner_.update(time, hips, yaw, com);
  for (int f = 0; f < 2; ++f) {
    const size_t i = size_t(tracking::index(f == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot));
    targetPoint_[i] = feet[size_t(f)].position;
    targetRotation_[i] = yawRotation(feet[size_t(f)].yaw, up_) * restRotation_[i];
    setPose(positionTask_[i], -1, targetPoint_[i], targetRotation_[i], 1.0);
  }
  // Balance as an inequality: only while the centre of mass is off the support polygon.
  if (balanceTask_ >= 0) {
    const bool over = !solvedOnce_ || planner_.overSupport(com);
    require(d.setEnabled(balanceTask_, !over && options_.balanceRow));
    if (!over) require(d.setTarget(balanceTask_, planner_.nearestSupportPoint(com, 0.01 * avatarHeight_ / 1.75)));
  }
}

void AvatarBodySolver::setTargets(const tracking::GuardedSample& targets) {
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  if (!heightsCalibrated_ && !options_.sameBody.enabled && targets.status[headIndex] == TrackerStatus::Tracked)
    calibrateHeights(targets);
  // Every tracker's target, in avatar space, as its joint's pose.
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    const tracking::TrackerPose& tp = targets.pose[id];
    double w = tp.valid ? statusWeight(targets.status[i]) : 0.0;
    if (id == TrackerId::Hips && !options_.pelvisRow) w = 0.0;
    targetPoint_[i] = toAvatar(tp.position) + up_ * heightOffset_[i];
    targetRotation_[i] = (fromTracking_ * toEigen(tp.orientation)).normalized() * jointFromTracker_[i];
    if (positionTask_[i] >= 0 && body_.model.tasks[size_t(positionTask_[i])].desc.type == ik::TaskType::Pose) continue;
    setPose(positionTask_[i], orientationTask_[i], targetPoint_[i], targetRotation_[i], w);
  }
  if (layout_.seated) {
    setSeatedTargets(targets);
    return;
  }
  if (layout_.inferLowerBody)
    setInferredLowerBody(targets);
  else
    scaleStrides(targets);
  setPoleTargets();
}

void AvatarBodySolver::setSeatedTargets(const tracking::GuardedSample& targets) {
  ik::Data& d = *data_;
  bool settleSeat = false;
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  if (!seatPlaced_ && targets.status[headIndex] == TrackerStatus::Tracked && targets.pose[TrackerId::Head].valid) {
    // The seat goes under the first tracked head, facing where it looks.
    const Eigen::Quaterniond headTurn = targetRotation_[headIndex] * restRotation_[headIndex].conjugate();
    const double seatHeight = options_.seat.seatHeight > 0.0f ? scale_ * double(options_.seat.seatHeight) : -1.0;
    seat_ = placeSeat(legs_, targetPoint_[headIndex], headingOf(headTurn, up_, forward_), seatHeight);
    seatPlaced_ = true;
    if (!solvedOnce_) {
      // Start the cold solve with the hips over the seat: the legs then only fold.
      ik::kinematics(body_.model, d, false);
      const ik::Model::Joint& root = body_.model.joints[size_t(body_.hips)];
      if (root.desc.type == ik::JointType::Free && root.desc.parent == ik::kNoParent) {
        const Eigen::Vector3d shift = 0.5 * (seat_.hip[0] + seat_.hip[1] - jointPosition(hipJoint_[0]) - jointPosition(hipJoint_[1]));
        Eigen::VectorXd q = d.q();
        q.segment<3>(root.first_dof) += root.desc.rest.linear().transpose() * shift;
        require(d.setConfiguration(q));
      }
      settleSeat = true;
    }
  }
  // Until then (no tracked head yet) the lower body is left to the warm start.
  const double w = seatPlaced_ ? 1.0 : 0.0;
  const Eigen::Quaterniond none = Eigen::Quaterniond::Identity();
  for (size_t s = 0; s < 2; ++s) {
    setPose(seatHipTask_[s], -1, seat_.hip[s], none, w);
    setPose(seatKneeTask_[s], -1, seat_.knee[s], none, w);
    const size_t f = size_t(tracking::index(s == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot));
    targetPoint_[f] = seat_.ankle[s];
    targetRotation_[f] = seat_.footRotation[s];
    setPose(positionTask_[f], -1, targetPoint_[f], targetRotation_[f], w);
  }
  setPose(-1, seatPelvisTask_, Eigen::Vector3d::Zero(), seat_.pelvisRotation, w);
  if (!settleSeat) return;
  // A cold start sits down and reaches the first targets outside the budget (once per placement:
  // the first frame and each recenter). Within a 1 ms budget the budgeted solve otherwise folded
  // the legs and raised the arms over dozens of frames (hand p95 35 cm over the first 2 s of
  // `embody xr --seated`).
  (void)settle({}, kSeatSettleIterations);
}

// Iterations outside the budget, once, from a cold start (the seat's placement, the first live
// solve): until converged or `maxIterations`.
const ik::SolveReport& AvatarBodySolver::settle(ik::SolveOptions options, int maxIterations) {
  options.max_iterations = maxIterations;
  return ik::solve(body_.model, *data_, options);
}

namespace {
double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }
}  // namespace

LowerBodyPosture AvatarBodySolver::posture() const {
  LowerBodyPosture p;
  const Eigen::Isometry3d& root = data_->jointFrame(body_.hips);
  p.pelvis = root.translation();
  p.eye = eyePosition();
  const Eigen::Quaterniond pelvisTurn =
      Eigen::Quaterniond(root.rotation()) * restRotation_[size_t(tracking::index(TrackerId::Hips))].conjugate();
  const Eigen::Vector3d trunkDown = pelvisTurn * -up_;
  for (size_t s = 0; s < 2; ++s) {
    if (hipJoint_[s] < 0 || kneeJoint_[s] < 0) continue;
    p.hip[s] = jointPosition(hipJoint_[s]);
    p.knee[s] = jointPosition(kneeJoint_[s]);
    p.ankle[s] = jointPosition(s == 0 ? body_.leftFoot : body_.rightFoot);
    p.hipFlexion[s] = angleBetween(trunkDown, p.knee[s] - p.hip[s]);
    p.kneeFlexion[s] = angleBetween(p.knee[s] - p.hip[s], p.ankle[s] - p.knee[s]);
  }
  p.spineFlexion = angleBetween(pelvisTurn * -restHeadToHips_, jointPosition(body_.head) - p.pelvis);
  p.pelvisPitch = angleBetween(pelvisTurn * up_, up_);
  return p;
}

SolveResult AvatarBodySolver::solve(const SolveRequest& request, avatar::SkeletonPose& pose) {
  SolveResult result;
  const Clock& clock = *request.clock;
  const tracking::GuardedSample& targets = *request.targets;
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  if (scale_ <= 0.0) {
    // Calibrate from the first live head sample: its height is a standing eye height.
    const tracking::TrackerPose& head = targets.pose[TrackerId::Head];
    const float eye = head.position.y;
    const bool live = targets.status[headIndex] == TrackerStatus::Tracked && head.valid && eye > 0.4f && eye < 2.4f;
    // Seated, the head's height says nothing about the user's stature: 1.75 m unless given.
    const bool standing = live && !layout_.seated;
    calibrate(standing ? eye / float(avatar::kEyeHeightRatio) : 1.75f);
    if (standing) calibratedFromHead_ = true;
  }
  setTargets(targets);
  if (!solvedOnce_ && !layout_.seated) seedStanding(targets);

  // One PIK iteration per call, under the runtime's one deadline policy (IterationBudget with
  // this solver's IterationCostModel): the next one starts only when the largest recent iteration
  // (iterations with many clamping passes cost several times the average) still fits before the
  // deadline less the predicted retargeting.
  ik::SolveOptions o;
  o.max_iterations = 1;
  // A cold start (the first solve, or after resetWarmStart) begins far from the targets: the
  // small trust region that keeps conflicting levels from pulling the feet would make it crawl,
  // so it gets the library's default cap and four times the iterations (the budget still rules).
  const bool cold = !solvedOnce_ || reseeded_;
  reseeded_ = false;
  o.max_level_step = cold ? std::max(options_.maxLevelStep, ik::SolveOptions{}.max_level_step) : options_.maxLevelStep;
  // Deterministic mode: the fixed count (four times it on a cold start, as the cap), no clock.
  const bool fixed = request.fixedIterations > 0;
  const int cap = fixed ? request.fixedIterations : options_.maxIterations;
  const int maxIterations = cold ? 4 * cap : cap;
  o.clock = &clock;
  const TimePoint iterationDeadline = request.deadline - finishCost_.predicted();
  IterationBudget budget(clock, iterationDeadline, &iterationCost_);
  int iterations = 0;
  bool converged = false, broken = false;
  // The first live solve settles outside the budget, once (a few ms on the first frame), as the
  // seated placement does: from the rest pose the hands start ~0.5 m off, and at the two
  // iterations a 1 ms frame allows the body took 13-17 frames (0.15-0.19 s) to reach them, which
  // alone decided `embody demo`'s hand p95 (0.2 mm or 160 mm, by how the first frames were
  // scheduled). Fixed-iteration runs keep their counts (their outputs repeat to the bit).
  if (!solvedOnce_ && !fixed && !layout_.seated) {
    const ik::SolveReport& report = settle(o, kFirstSolveSettleIterations);
    iterations += report.iterations;
    converged = report.converged();
    broken = report.stop == ik::StopReason::InvalidState;
  }
  while (!converged && !broken && iterations < maxIterations) {
    // Not even the retargeting fits: no iteration (the first one otherwise always runs).
    if (!fixed && (clock.now() >= iterationDeadline || !budget.startIteration())) break;
    const ik::SolveReport& report = ik::solve(body_.model, *data_, o);
    iterations += report.iterations;
    if (report.converged()) converged = true;
    if (report.stop == ik::StopReason::InvalidState) broken = true;
    if (report.iterations == 0 || report.stop != ik::StopReason::IterationCap) break;
  }
  const TimePoint solvedAt = clock.now();
  result.iterations = iterations;
  result.converged = converged;

  // Never publish a broken configuration: fall back to the last good one.
  broken_ = !data_->q().allFinite() || broken;
  if (broken_) {
    require(data_->setConfiguration(lastGoodQ_));
    ik::kinematics(body_.model, *data_, false);
  } else {
    lastGoodQ_ = data_->q();
  }
  solvedOnce_ = true;
  avatar::retarget(body_, avatar_, *data_, pose);

  // Residuals in avatar metres: the tracked point against the body part it drives.
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    if (positionTask_[i] < 0 || !data_->enabled(positionTask_[i])) continue;
    const Eigen::Vector3d actual = id == TrackerId::Head ? eyePosition() : jointPosition(joint_[i]);
    result.residual[i] = float((actual - targetPoint_[i]).norm());
    if (id == TrackerId::LeftHand || id == TrackerId::RightHand) {
      const ik::JointId shoulder = shoulderJoint(id == TrackerId::LeftHand ? tracking::Side::Left : tracking::Side::Right);
      result.reachable[i] = (targetPoint_[i] - jointPosition(shoulder)).norm() <= armReach_;
    }
  }
  if (!layout_.seated) guardAgainstCollapse(targets, result, pose);
  fade_.apply(targets.pose.time, pose);
  finishCost_.observe(clock.now() - solvedAt);
  return result;
}

bool AvatarBodySolver::seedStanding(const tracking::GuardedSample& targets) {
  const size_t h = size_t(tracking::index(TrackerId::Head));
  if (!targets.pose[TrackerId::Head].valid || targets.status[h] == TrackerStatus::Absent) return false;
  // No standing body fits under a head lower than the standing pelvis (a user lying or sitting
  // on the floor): the solve goes on from where it is.
  const double headHeight = up_.dot(targetPoint_[h]) - floor_;
  if (headHeight < restHeight_[size_t(tracking::index(TrackerId::Hips))]) return false;
  SeedInputs in;
  in.up = up_;
  in.forward = forward_;
  in.headPivot = targetPoint_[h] - targetRotation_[h] * eyeInHead_;
  in.headYaw = headingOf(targetRotation_[h] * restRotation_[h].conjugate(), up_, forward_);
  for (auto id : {TrackerId::LeftHand, TrackerId::RightHand}) {
    const size_t i = size_t(tracking::index(id));
    if (targets.status[i] != TrackerStatus::Tracked || !targets.pose[id].valid) continue;
    (id == TrackerId::LeftHand ? in.leftHand : in.rightHand) = targetPoint_[i];
  }
  in.restHeadToHips = restHeadToHips_;
  in.floor = floor_;
  in.restHipsHeight = restHeight_[size_t(tracking::index(TrackerId::Hips))];
  in.scale = avatarHeight_ / 1.75;
  const double yaw = seedYaw(in);
  require(data_->setConfiguration(placeRoot(body_.model, body_.hips, restQ_, seedPelvis(in, yaw), yaw, up_)));
  ik::kinematics(body_.model, *data_, false);
  return true;
}

void AvatarBodySolver::setPoleTargets() {
  const ik::Data& d = *data_;
  const size_t hips = size_t(tracking::index(TrackerId::Hips));
  const Eigen::Quaterniond pelvisTurn = Eigen::Quaterniond(d.jointFrame(body_.hips).rotation()) * restRotation_[hips].conjugate();
  const Eigen::Vector3d fwd = yawRotation(headingOf(pelvisTurn, up_, forward_), up_) * forward_;
  const Eigen::Vector3d left = up_.cross(fwd);
  for (size_t k = 0; k < 4; ++k) {
    if (poleTask_[k] < 0) continue;
    const Eigen::Vector3d root = jointPosition(limbRoot_[k]), end = jointPosition(limbEnd_[k]);
    Eigen::Vector3d pole, fallback;
    if (k < 2) {  // the knee over the toes
      pole = footForward(int(k));
      fallback = fwd;
    } else {
      const bool leftArm = k == 2;
      const Eigen::Vector3d palm = d.jointFrame(limbEnd_[k]).rotation() * Eigen::Vector3d::UnitX() * (leftArm ? 1.0 : -1.0);
      pole = elbowPole(up_, fwd, leftArm ? left : Eigen::Vector3d(-left), palm, end - root);
      fallback = -up_;
    }
    setPose(poleTask_[k], -1, poleTarget(root, end, limb_[k], pole, fallback), Eigen::Quaterniond::Identity(), 1.0);
  }
}

Eigen::Vector3d AvatarBodySolver::footForward(int side) const {
  const TrackerId id = side == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot;
  const Eigen::Quaterniond foot(data_->jointFrame(joint_[size_t(tracking::index(id))]).rotation());
  return foot * restRotation_[size_t(tracking::index(id))].conjugate() * forward_;
}

double AvatarBodySolver::hingeAngle(int limb) const {
  if (limb < 0 || limb > 3 || limbHinge_[size_t(limb)] < 0) return 0.0;
  return data_->q()[body_.model.joints[size_t(limbHinge_[size_t(limb)])].first_dof];
}

Status AvatarBodySolver::seedConfiguration(const Eigen::VectorXd& q) {
  if (auto st = data_->setConfiguration(q); !st) return st;
  ik::kinematics(body_.model, *data_, false);
  lastGoodQ_ = q;
  solvedOnce_ = true;
  return Status::success();
}

BodySignals AvatarBodySolver::bodySignals(double time, const SolveResult& result) const {
  BodySignals s;
  s.time = time;
  s.finite = !broken_;
  s.scale = avatarHeight_ / 1.75;
  const size_t hips = size_t(tracking::index(TrackerId::Hips)), head = size_t(tracking::index(TrackerId::Head));
  const Eigen::Isometry3d& root = data_->jointFrame(body_.hips);
  auto height = [&](const Eigen::Vector3d& p) { return up_.dot(p) - floor_; };
  s.pelvisHeight = height(root.translation());
  s.standingPelvisHeight = restHeight_[hips];
  s.headTargetHeight = height(targetPoint_[head]);
  s.standingEyeHeight = avatarEyeHeight_;
  const Eigen::Quaterniond pelvisTurn = Eigen::Quaterniond(root.rotation()) * restRotation_[hips].conjugate();
  const Eigen::Vector3d pelvisUp = pelvisTurn * up_;
  s.pelvisTilt = std::atan2(pelvisUp.cross(up_).norm(), pelvisUp.dot(up_));
  s.lowestTrunkOrKnee = std::min(s.pelvisHeight, height(jointPosition(body_.head)));
  // Sides across the feet's own heading: on a walk the stride runs along it, where the pelvis
  // (which turns with the head and the gait) would let the stride leak into the sideways measure.
  Eigen::Vector3d heading = footForward(0) + footForward(1);
  heading -= up_ * up_.dot(heading);
  if (heading.norm() < 0.5) heading = pelvisTurn * forward_ - up_ * up_.dot(pelvisTurn * forward_);
  const Eigen::Vector3d left = heading.norm() > 1e-6 ? Eigen::Vector3d(up_.cross(heading).normalized()) : Eigen::Vector3d(up_.cross(forward_));
  s.legSeparation = left.dot(jointPosition(body_.leftFoot) - jointPosition(body_.rightFoot));
  if (kneeJoint_[0] >= 0 && kneeJoint_[1] >= 0) {
    for (ik::JointId k : kneeJoint_) s.lowestTrunkOrKnee = std::min(s.lowestTrunkOrKnee, height(jointPosition(k)));
    s.legSeparation = std::min(s.legSeparation, left.dot(jointPosition(kneeJoint_[0]) - jointPosition(kneeJoint_[1])));
  }
  s.inferredLegs = layout_.inferLowerBody;
  s.iterations = result.iterations;
  // The errors a body can fix: the head while its target is no higher than standing allows, the
  // hands while within the arm's reach.
  if (result.residual[head] >= 0.0f && s.headTargetHeight <= 1.02 * s.standingEyeHeight) s.residual = result.residual[head];
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
}

}  // namespace embody::runtime
