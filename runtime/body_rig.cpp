#include "runtime/body_rig.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "avatar/body/eye_point.h"
#include "avatar/glm_eigen.h"
#include "avatar/humanoid/humanoid_map.h"

namespace embody::runtime {

using tracking::TrackerId;

namespace {

using avatar::toEigen;
using avatar::toGlm;

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

// buildBodyRig()'s steps, each filling part of `r`: the tracker joints, the rest geometry, the
// layout's tasks.
class RigBuilder {
 public:
  RigBuilder(const avatar::AvatarAsset& avatar, const AvatarBodyOptions& options, BodyRig& rig, int& refused)
      : avatar_(avatar), options_(options), r(rig), refused_(refused) {}
  Status build();

 private:
  Status bindJoints(ik::JointId& leftElbow);
  void bindLimbs(ik::JointId leftElbow, ik::JointId rightElbow);
  void measureRest(ik::JointId leftElbow, bool legs);
  void trackerFrames();
  Eigen::Vector3d standingAnkle(const Eigen::Vector3d& hipJoint, const Eigen::Vector3d& restAnkle) const;
  void addLayoutTask(const TaskSpec& spec, std::vector<ik::TaskDesc>& tasks);
  bool sharesLevelWithPelvisTurn(const TaskSpec& spec) const;
  void addJointMarkerTasks(std::vector<ik::TaskDesc>& tasks);
  void useSameBody(const AvatarBodyOptions::SameBody& same);
  void require(const Status& s) {
    if (!s) ++refused_;
  }

  const avatar::AvatarAsset& avatar_;
  const AvatarBodyOptions& options_;
  BodyRig& r;
  int& refused_;
};

Status RigBuilder::build() {
  avatar::BodyModelOptions bo;
  bo.spine = options_.spine;
  bo.totalMass = options_.totalMass;
  bo.addTasks = false;
  bo.coupledSpine = options_.coupledSpine;
  auto body = avatar::buildBodyModel(avatar_, bo);
  if (!body) return Error{body.error()};
  r.body = std::move(body).value();
  r.up = toEigen(avatar_.humanoid.up).normalized();
  r.forward = toEigen(avatar_.humanoid.forward);
  r.forward = (r.forward - r.up * r.up.dot(r.forward)).normalized();
  // Tracking space (+X right, +Y up, -Z forward) -> avatar space.
  Eigen::Matrix3d c;
  c.col(0) = r.forward.cross(r.up);
  c.col(1) = r.up;
  c.col(2) = -r.forward;
  r.fromTracking = Eigen::Quaterniond(c).normalized();
  ik::JointId leftElbow = -1;
  if (auto s = bindJoints(leftElbow); !s) return s;
  const bool legs = r.hipJoint[0] >= 0 && r.hipJoint[1] >= 0 && r.kneeJoint[0] >= 0 && r.kneeJoint[1] >= 0;
  if (options_.seat.enabled && !legs) return Error{"seated mode: the avatar's upper and lower legs are not mapped"};
  measureRest(leftElbow, legs);
  if (options_.sameBody.enabled) useSameBody(options_.sameBody);  // before the tasks take the eye offset
  r.layout = options_.seat.enabled ? seatedTaskLayoutFor(options_.trackers) : taskLayoutFor(options_.trackers);
  std::vector<ik::TaskDesc> tasks;
  for (const TaskSpec& spec : r.layout.tasks) addLayoutTask(spec, tasks);
  if (options_.jointMarkers) addJointMarkerTasks(tasks);
  auto model = withTasks(r.body.model, tasks);
  if (!model) return Error{"body model with tracker tasks: " + model.error()};
  r.body.model = std::move(model).value();
  // The configuration a body starts from: the rest pose (q = 0 is the neutral pose, body_model.h)
  // with knees and elbows bent at least a little in their anatomical direction (a straight hinge
  // is singular).
  r.restQ = r.body.restConfiguration;
  for (size_t k = 0; k < 4; ++k)
    if (r.limbHinge[k] >= 0) {
      double& bend = r.restQ[r.body.model.joints[size_t(r.limbHinge[k])].first_dof];
      bend = std::max(bend, k < 2 ? 0.15 : 0.3);
    }
  return Status::success();
}

Status RigBuilder::bindJoints(ik::JointId& leftElbow) {
  r.joint[size_t(tracking::index(TrackerId::Head))] = r.body.head;
  r.joint[size_t(tracking::index(TrackerId::LeftHand))] = r.body.leftHand;
  r.joint[size_t(tracking::index(TrackerId::RightHand))] = r.body.rightHand;
  r.joint[size_t(tracking::index(TrackerId::Hips))] = r.body.hips;
  r.joint[size_t(tracking::index(TrackerId::LeftFoot))] = r.body.leftFoot;
  r.joint[size_t(tracking::index(TrackerId::RightFoot))] = r.body.rightFoot;
  auto ikOf = [&](avatar::HumanBone bone) {
    const int a = avatar_.humanoid.joint(bone);
    return a >= 0 ? r.body.ikJointOfAvatar[size_t(a)] : -1;
  };
  // A clavicle's own IK joint only: a bone that is not driven maps to none, and one whose pivot
  // another joint drives (ikJointOfAvatar's last joint at the pivot) is not the clavicle's.
  auto ownJoint = [&](avatar::HumanBone bone) {
    const ik::JointId j = ikOf(bone);
    return j >= 0 && r.body.avatarJoint[size_t(j)] == avatar_.humanoid.joint(bone) ? j : -1;
  };
  r.clavicleJoint = {ownJoint(avatar::HumanBone::leftShoulder), ownJoint(avatar::HumanBone::rightShoulder)};
  r.leftShoulder = ikOf(avatar::HumanBone::leftUpperArm);
  r.rightShoulder = ikOf(avatar::HumanBone::rightUpperArm);
  leftElbow = ikOf(avatar::HumanBone::leftLowerArm);
  if (r.leftShoulder < 0 || r.rightShoulder < 0 || leftElbow < 0) return Error{"the avatar's arms are not mapped"};
  r.hipJoint = {ikOf(avatar::HumanBone::leftUpperLeg), ikOf(avatar::HumanBone::rightUpperLeg)};
  r.kneeJoint = {ikOf(avatar::HumanBone::leftLowerLeg), ikOf(avatar::HumanBone::rightLowerLeg)};
  bindLimbs(leftElbow, ikOf(avatar::HumanBone::rightLowerArm));
  return Status::success();
}

// Limb chains for the knee and elbow direction tasks. The elbow's IK joint at the lower arm's
// pivot is its forearm twist; the hinge is the joint before it.
void RigBuilder::bindLimbs(ik::JointId leftElbow, ik::JointId rightElbow) {
  for (size_t s = 0; s < 2; ++s) {
    const bool left = s == 0;
    r.limbRoot[s] = r.hipJoint[s];
    r.limbMiddle[s] = r.limbHinge[s] = r.kneeJoint[s];
    r.limbEnd[s] = left ? r.body.leftFoot : r.body.rightFoot;
    const ik::JointId elbow = left ? leftElbow : rightElbow;
    r.limbRoot[2 + s] = left ? r.leftShoulder : r.rightShoulder;
    r.limbMiddle[2 + s] = elbow;
    r.limbEnd[2 + s] = left ? r.body.leftHand : r.body.rightHand;
    if (elbow >= 0) {
      const ik::JointDesc& twist = r.body.model.joints[size_t(elbow)].desc;
      r.limbHinge[2 + s] = twist.type == ik::JointType::Revolute && twist.parent >= 0 &&
                                  r.body.model.joints[size_t(twist.parent)].desc.type == ik::JointType::Revolute
                              ? twist.parent
                              : -1;
    }
  }
}

// Rest geometry from the model without tasks at the avatar's rest pose: heights, the eye point,
// the seated legs, the tracker -> joint frames and the foot planner's rest stance.
void RigBuilder::measureRest(ik::JointId leftElbow, bool legs) {
  ik::Data rest(r.body.model);
  require(rest.setConfiguration(r.body.restConfiguration));
  ik::kinematics(r.body.model, rest, false);
  auto pos = [&](ik::JointId j) { return Eigen::Vector3d(rest.jointFrame(j).translation()); };
  for (size_t k = 0; k < 4; ++k)
    if (r.limbRoot[k] >= 0 && r.limbMiddle[k] >= 0 && r.limbEnd[k] >= 0)
      r.limb[k] = {(pos(r.limbMiddle[k]) - pos(r.limbRoot[k])).norm(), (pos(r.limbEnd[k]) - pos(r.limbMiddle[k])).norm()};
  for (auto id : tracking::kAllTrackers)
    r.restRotation[size_t(tracking::index(id))] = Eigen::Quaterniond(rest.jointFrame(r.joint[size_t(tracking::index(id))]).rotation());
  r.armReach = (pos(leftElbow) - pos(r.leftShoulder)).norm() + (pos(r.body.leftHand) - pos(leftElbow)).norm();
  // The eyes: the avatar's one eye point (avatar/body/eye_point.h), the renderer's camera too;
  // floor and stature (avatar::restStature along the humanoid's up, r.up) come with it.
  const avatar::EyePoint restEye =
      avatar::restEyePoint(avatar_, avatar_.humanoid.joint(avatar::HumanBone::head), toGlm(r.forward));
  r.floor = restEye.stature.floor;
  r.avatarHeight = restEye.stature.height;
  for (auto id : tracking::kAllTrackers)
    r.restHeight[size_t(tracking::index(id))] = r.up.dot(pos(r.joint[size_t(tracking::index(id))])) - r.floor;
  const Eigen::Vector3d head = pos(r.body.head);
  r.avatarEyeHeight = restEye.aboveFloor;
  const Eigen::Vector3d eye(restEye.position.x, restEye.position.y, restEye.position.z);
  r.eyeInHead = r.restRotation[0].conjugate() * (eye - head);
  r.restHeadToHips = pos(r.body.hips) - head;
  if (legs) {
    // Seated mode's leg geometry. The hip joint centres sit about a thigh's thickness (5 % of
    // stature) above the seat surface.
    r.legs.up = r.up;
    r.legs.forward = r.forward;
    r.legs.floor = r.floor;
    r.legs.eye = eye;
    for (size_t s = 0; s < 2; ++s) {
      const ik::JointId foot = s == 0 ? r.body.leftFoot : r.body.rightFoot;
      r.legs.hip[s] = pos(r.hipJoint[s]);
      r.legs.knee[s] = pos(r.kneeJoint[s]);
      r.legs.ankle[s] = pos(foot);
      r.legs.footRotation[s] = Eigen::Quaterniond(rest.jointFrame(foot).rotation());
    }
    r.legs.pelvisRotation = r.restRotation[size_t(tracking::index(TrackerId::Hips))];
    r.legs.hipAboveSeat = 0.05 * r.avatarHeight;
  }
  trackerFrames();
  // Feet for three-point mode: the stance relative to the hips' ground point.
  const Eigen::Vector3d hipsGround = pos(r.body.hips) - r.up * r.up.dot(pos(r.body.hips));
  std::array<Eigen::Vector3d, 2> stance{pos(r.body.leftFoot) - hipsGround, pos(r.body.rightFoot) - hipsGround};
  if (legs) {
    r.standingHeadRise = 1e300;
    for (size_t s = 0; s < 2; ++s) {
      stance[s] = standingAnkle(pos(r.hipJoint[s]), stance[s] + hipsGround) - hipsGround;
      // A straight leg under its hip joint against the rest's height of the hip over the ankle.
      const double leg = r.limb[s].upper + r.limb[s].lower;
      r.standingHeadRise = std::min(r.standingHeadRise, std::max(0.0, leg - r.up.dot(pos(r.hipJoint[s]) - stance[s] - hipsGround)));
    }
  }
  r.stance = stance;
}

// Where a person stands a foot: the ankle under its hip joint (feet about hip-width apart), at the
// rest ankle's height. Rest poses spread the legs as their authors chose (CMU's zero pose stands
// them 60 cm apart, a T-pose or A-pose often 30-40 cm): a stance taken from them walks wide-legged.
Eigen::Vector3d RigBuilder::standingAnkle(const Eigen::Vector3d& hipJoint, const Eigen::Vector3d& restAnkle) const {
  return hipJoint - r.up * r.up.dot(hipJoint) + r.up * r.up.dot(restAnkle);
}

// Tracker frame -> joint frame. Reference tracker orientations (tracking space) for the rest
// pose: identity for head, hips, feet; the grip pose of the rest hand for the hands.
void RigBuilder::trackerFrames() {
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    glm::quat ref(1.0f, 0.0f, 0.0f, 0.0f);
    if (id == TrackerId::LeftHand || id == TrackerId::RightHand) {
      const bool left = id == TrackerId::LeftHand;
      const Eigen::Vector3d fingers = r.restRotation[i] * Eigen::Vector3d::UnitY();
      const Eigen::Vector3d palm = r.restRotation[i] * Eigen::Vector3d::UnitX() * (left ? 1.0 : -1.0);
      ref = tracking::gripOrientation(left ? tracking::Side::Left : tracking::Side::Right,
                                      toGlm(r.fromTracking.conjugate() * fingers), toGlm(r.fromTracking.conjugate() * palm));
    }
    r.jointFromTracker[i] = (r.fromTracking * toEigen(ref)).conjugate() * r.restRotation[i];
  }
}

// Whether `spec` sits on one level with a tracked pelvis's orientation task (not with joint
// markers, which turn the pelvis instead).
bool RigBuilder::sharesLevelWithPelvisTurn(const TaskSpec& spec) const {
  if (options_.jointMarkers) return false;
  for (const TaskSpec& t : r.layout.tasks)
    if (t.kind == TaskKind::TrackerOrientation && t.tracker == TrackerId::Hips && t.priority == spec.priority) return true;
  return false;
}

// One task of the layout (layout priority 1 = solver level 0), appended to `tasks`.
void RigBuilder::addLayoutTask(const TaskSpec& spec, std::vector<ik::TaskDesc>& tasks) {
  auto add = [&](ik::TaskDesc t, float weight) {
    t.level = spec.priority - 1;
    t.weight = weight;
    tasks.push_back(std::move(t));
    return ik::TaskId(tasks.size() - 1);
  };
  const size_t i = size_t(tracking::index(spec.tracker));
  ik::TaskDesc t;
  t.name = std::string(taskKindName(spec.kind)) + "_" + std::string(tracking::trackerKey(spec.tracker));
  t.joint = r.joint[i];
  t.position_tolerance = 5e-4;
  t.rotation_tolerance = 0.01;
  switch (spec.kind) {
    case TaskKind::TrackerPosition:
      t.type = ik::TaskType::Position;
      if (spec.tracker == TrackerId::Head) t.offset = r.eyeInHead;
      // A tracked pelvis steers the trunk over the ground only: its height follows from the
      // head and the legs, whose proportions differ between user and avatar.
      if (spec.tracker == TrackerId::Hips && std::abs(std::abs(r.up.y()) - 1.0) < 1e-6) t.axes = ik::kAxisX | ik::kAxisZ;
      r.tasks.position[i] = add(t, spec.weight);
      break;
    case TaskKind::TrackerOrientation:
      // Joint markers turn the pelvis: its tracker's turn, taken from a joint of the clip's, only
      // duplicates the pelvis marker's.
      if (options_.jointMarkers && spec.tracker == TrackerId::Hips) break;
      t.type = ik::TaskType::Orientation;
      if (spec.tracker != TrackerId::Head) t.rotation_tolerance = 0.05;
      // On one level with a tracked pelvis's turn (task_layout.cpp) the head meets its orientation
      // to within the two's least-squares compromise (0.7 degrees each on synthetic:figure8), not
      // 0.01 rad: every solve then ran to its cap or budget for nothing (2.3 -> 4.5 iterations).
      else if (sharesLevelWithPelvisTurn(spec)) t.rotation_tolerance = 0.02;
      r.tasks.orientation[i] = add(t, spec.weight);
      break;
    case TaskKind::FootPlant:
      t.type = ik::TaskType::Pose;
      r.tasks.position[i] = add(t, spec.weight);
      break;
    case TaskKind::Balance:
      t.type = ik::TaskType::CenterOfMass;
      t.position_tolerance = 0.005;
      r.tasks.balance = add(t, spec.weight);
      break;
    case TaskKind::SeatedHip:
    case TaskKind::SeatedKnee: {
      const size_t side = spec.tracker == TrackerId::LeftFoot ? 0 : 1;
      const bool hip = spec.kind == TaskKind::SeatedHip;
      t.name = std::string(hip ? "seated_hip_" : "seated_knee_") + (side == 0 ? "left" : "right");
      t.type = ik::TaskType::Position;
      t.joint = hip ? r.hipJoint[side] : r.kneeJoint[side];
      (hip ? r.tasks.seatHip : r.tasks.seatKnee)[side] = add(t, spec.weight);
      break;
    }
    case TaskKind::SeatedPelvis:
      t.name = "seated_pelvis";
      t.type = ik::TaskType::Orientation;
      t.joint = r.body.hips;
      t.rotation_tolerance = 0.05;
      r.tasks.seatPelvis = add(t, spec.weight);
      break;
    case TaskKind::LimbPole: {
      const size_t k = spec.tracker == TrackerId::LeftFoot    ? 0
                       : spec.tracker == TrackerId::RightFoot ? 1
                       : spec.tracker == TrackerId::LeftHand  ? 2
                                                              : 3;
      // Joint markers say where every knee and elbow is: a pole would only pull it off.
      if (!options_.limbPoles || (k >= 2 && !options_.elbowPoles) || options_.jointMarkers || r.limbMiddle[k] < 0 || r.limbRoot[k] < 0 || !(r.limb[k].upper > 0.0)) break;
      t.name = std::string(k < 2 ? "pole_knee_" : "pole_elbow_") + (k % 2 == 0 ? "left" : "right");
      t.type = ik::TaskType::Position;
      t.joint = r.limbMiddle[k];
      t.position_tolerance = 0.02;  // a direction, not a place: it need not hold a solve back
      r.tasks.pole[k] = add(t, spec.weight);
      break;
    }
    case TaskKind::ClavicleRest: {
      const size_t s = spec.tracker == TrackerId::LeftHand ? 0 : 1;
      const ik::JointId c = r.clavicleJoint[s];
      // Joint markers say where every clavicle is; an avatar without clavicle bones has none.
      if (!options_.restClavicles || options_.jointMarkers || c < 0) break;
      t.name = std::string("clavicle_rest_") + (s == 0 ? "left" : "right");
      t.type = ik::TaskType::Orientation;
      t.joint = c;
      t.recruit = ik::Recruit::Explicit;
      t.joints = {c};
      t.reference = r.body.model.joints[size_t(c)].desc.parent;
      t.rotation_tolerance = 0.05;
      r.tasks.clavicle[s] = add(t, spec.weight);
      break;
    }
    case TaskKind::InferredHips:
      t.type = ik::TaskType::Position;
      t.position_tolerance = 0.05;
      r.tasks.hipsPosition = add(t, spec.weight);
      t.type = ik::TaskType::Orientation;
      t.name += "_rotation";
      t.rotation_tolerance = 0.2;
      r.tasks.hipsRotation = add(t, spec.weight * 0.5f);
      break;
  }
}

// --trackers full (embody eval): a marker on every mapped avatar joint, its position one level below
// the layout's lowest and its orientation one level lower still. Positions say where every bone
// points; the orientations then settle what they leave free, the turn about each bone. On one
// level a rotation row weighs a radian as a position row weighs a metre, so where the coupled spine
// cannot take the clip's shape its orientation rows outweighed centimetres of position: on the
// CMU walk the pelvis turned 8 degrees off the clip's to share the spine's orientation error, and
// moved the hips and knees 1-4 cm (docs/eval.md).
void RigBuilder::addJointMarkerTasks(std::vector<ik::TaskDesc>& tasks) {
  int lowest = 1;
  for (const TaskSpec& spec : r.layout.tasks)
    if (spec.kind != TaskKind::LimbPole && spec.kind != TaskKind::ClavicleRest)  // neither with markers
      lowest = std::max(lowest, spec.priority);
  auto add = [&](ik::TaskDesc t) {
    tasks.push_back(std::move(t));
    return ik::TaskId(tasks.size() - 1);
  };
  const std::vector<std::string> names = avatar::uniqueJointNames(avatar_.skeleton);  // duplicate node names
  for (size_t a = 0; a < avatar_.skeleton.joints.size(); ++a) {
    const int j = r.body.ikJointOfAvatar[a];
    if (j < 0 || r.body.avatarJoint[size_t(j)] != int(a)) continue;
    ik::TaskDesc t;
    t.name = "marker_" + names[a];
    t.joint = j;
    t.position_tolerance = 5e-4;
    t.rotation_tolerance = 0.01;
    t.weight = 1.0f;
    BodyTasks::JointMarker m;
    m.avatarJoint = int(a);
    t.type = ik::TaskType::Position;
    t.level = lowest;  // layout priority lowest + 1 = solver level lowest
    m.position = add(t);
    t.type = ik::TaskType::Orientation;
    t.name += "_rotation";
    t.level = lowest + 1;
    m.orientation = add(t);
    r.tasks.marker.push_back(m);
  }
}

void RigBuilder::useSameBody(const AvatarBodyOptions::SameBody& same) {
  // (the calibration's scale is 1: BodyCalibration::sameBody)
  // The floor is the tracking space's, y = 0, where the clip stands (tracking/bvh_avatar.h), not
  // the rest mesh's lowest point (a capsule's radius under the lowest joint): the rest heights
  // are measured from it too, so a head where the clip's stands is at its rest height (no drop,
  // no crouch) and the planted ankles are where the clip's stand.
  const double restFloor = r.floor;  // the heights were measured from it until now
  for (double& h : r.restHeight) h += restFloor;
  r.avatarEyeHeight += restFloor;
  r.floor = 0.0;
  r.legs.floor = 0.0;
  r.fromTracking = Eigen::Quaterniond::Identity();
  const size_t head = size_t(tracking::index(TrackerId::Head));
  r.eyeInHead = r.restRotation[head].conjugate() * same.eyeOffset;
  for (size_t i = 0; i < tracking::kTrackerCount; ++i)
    r.jointFromTracker[i] = same.reference[i].normalized().conjugate() * r.restRotation[i];
}

}  // namespace

Result<BodyRig> buildBodyRig(const avatar::AvatarAsset& avatar, const AvatarBodyOptions& options, int& refusedCalls) {
  BodyRig rig;
  if (auto st = RigBuilder(avatar, options, rig, refusedCalls).build(); !st) return Error{st.error()};
  return rig;
}

Eigen::Vector3d footForward(const BodyRig& rig, const ik::Data& data, int side) {
  const TrackerId id = side == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot;
  const Eigen::Quaterniond foot(data.jointFrame(rig.joint[size_t(tracking::index(id))]).rotation());
  return foot * rig.restRotation[size_t(tracking::index(id))].conjugate() * rig.forward;
}

}  // namespace embody::runtime
