#include "runtime/task_targets_job.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/smoothstep.h"

namespace embody::runtime {

using tracking::TrackerId;
using tracking::TrackerStatus;

namespace {

// Three-point mode: the trunk a head `drop` metres below its standing height implies, looking
// `pitchDown` radians below the horizon, with a trunk `trunk` metres from hips to head pivot.
//   - Looking at the floor (45 -> 80 degrees down) the sinking head is a bend at the hips
//     (washing, picking something up): that share of the drop becomes a lean a of the trunk that
//     lowers the head by as much, L (1 - cos a) = share * drop, the legs straight.
//   - A head sunk far (0.3 -> 0.7 trunk lengths) looking down by 35 -> 60 degrees is bent over
//     too: people reach low by stooping and bend the knees only for the rest. In cmu_002_10
//     (washing the legs, the head 0.5 of the body's height down, looking 42-63 degrees down) the
//     pelvis sank only 0.16-0.38 of the head's drop; taken as a crouch, the inferred pelvis sank
//     twice as far and, with its row let go, under half its standing height (14 frames).
//   - What the bend does not take (it stops at 90 degrees) is a crouch: beyond 0.05 trunk lengths
//     (gait, posture) the trunk leans 0.8 rad per trunk length of it (up to 45 degrees; a squat
//     0.35 m deep leans it about 24), the pelvis back over the heels. The clips' performers lean
//     more (docs/eval.md, session 23), but at 1.1-1.5 CesiumMan's hands missed the controllers
//     by 2-3 cm (p95) in cmu_131_03's crouches (8 mm where within the arm's reach, 1.5 at 0.8).
//   - The deeper the crouch the less the pelvis row pulls (`weight`, 1 down to 0 between 0.1 and
//     0.4 trunk lengths of crouch): where the pelvis goes in a deep squat depends on the person,
//     and a row that held it cost the squat crossed knees.
// Measured over the eight eval clips (docs/eval.md); looking down by less than 45 degrees is
// looking, not bending (a lower onset leant the crouch before a jump, cmu_131_03, 2 cm of head).
struct InferredTrunk {
  double lean = 0.0;    // radians, forward about the hips
  double bend = 0.0;    // the part of it that bends over (looking down)
  double weight = 1.0;  // of the pelvis row
};
InferredTrunk inferTrunk(double drop, double pitchDown, double trunk) {
  constexpr double kDegree = std::numbers::pi / 180.0;
  InferredTrunk out;
  if (!(drop > 0.0) || !(trunk > 0.0) || !std::isfinite(drop) || !std::isfinite(pitchDown)) return out;
  const double looking = smoothstep((pitchDown - 45.0 * kDegree) / (35.0 * kDegree));
  const double reaching = smoothstep((pitchDown - 35.0 * kDegree) / (25.0 * kDegree)) * smoothstep((drop / trunk - 0.3) / 0.4);
  const double bendShare = std::max(looking, reaching);
  out.bend = std::acos(std::clamp(1.0 - bendShare * drop / trunk, 0.0, 1.0));
  const double crouch = std::max(0.0, drop / trunk - (1.0 - std::cos(out.bend)));  // trunk lengths
  out.lean = std::min(out.bend + std::min(0.8 * std::max(0.0, crouch - 0.05), 45.0 * kDegree), 90.0 * kDegree);
  out.weight = 1.0 - smoothstep((crouch - 0.1) / 0.3);
  return out;
}

// How far (radians) the head looks below the horizon, from its turn off the rest pose: the tilt
// of its up vector, signed by whether the face points down (fully beyond 0.2 of it). The forward's
// own elevation shrinks when a bent-over head turns to look at one leg: with the head 55 degrees
// down turning 35 degrees to a leg (body_plausibility_tests), the pitch read that way fell from
// 53 to 40 degrees, the bend below took the drop for a crouch and let the pelvis row go (weight
// 0.9 -> 0) and back, and the pelvis sank to 0.41 of its standing height.
double headPitchDown(const Eigen::Quaterniond& headTurn, const Eigen::Vector3d& up, const Eigen::Vector3d& forward) {
  const double faceDown = -up.dot(headTurn * forward);
  const double tilt = std::acos(std::clamp(up.dot(headTurn * up), -1.0, 1.0));
  return tilt * std::clamp(faceDown / 0.2, -1.0, 1.0);
}

// The head target read once per frame for the steps that infer from it (the neck's band, the
// trunk and feet of three-point mode).
struct HeadReading {
  Eigen::Quaterniond turn = Eigen::Quaterniond::Identity();  // off the rest pose
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();           // the head joint
  double pitchDown = 0.0;                                    // headPitchDown
  double drop = 0.0;  // metres the pivot is below its standing height
};

// Bent over by this much or more (radians), the head may look this far to either side of the
// body's heading (upright: not at all, the body turns with the head; smoothly in between).
constexpr double kBentNeckTurn = std::numbers::pi / 4.0;

// TaskTargetsJob::Run()'s steps over one frame's state.
class TaskWriter {
 public:
  explicit TaskWriter(const TaskTargetsJob& job)
      : r(*job.rig), calibration(*job.calibration), sample(*job.sample), job_(job), targets(*job.targets),
        planner(*job.planner), seat(*job.seat), d(*job.data), out(*job.output) {}
  void setTargets();

 private:
  void scaleStrides();
  void setInferredLowerBody();
  void setSeatedTargets();
  void setPoleTargets();
  void setClavicleTargets();
  void setNeckBand();
  HeadReading readHead() const;
  // Enables (weight > 0, times the task's own) or disables a position/orientation/pose task pair.
  void setPose(ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p, const Eigen::Quaterniond& q, double weight);
  Eigen::Vector3d jointPosition(ik::JointId joint) const { return d.jointFrame(joint).translation(); }
  void require(const Status& s) {
    if (!s) ++out.refusedCalls;
  }

  const BodyRig& r;
  const BodyCalibration& calibration;
  const tracking::GuardedSample& sample;
  const TaskTargetsJob& job_;
  BodyTargets& targets;
  FootPlanner& planner;
  SeatState& seat;
  ik::Data& d;
  TaskTargetsOutput& out;
  HeadReading head_;  // setTargets()
};

HeadReading TaskWriter::readHead() const {
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  HeadReading h;
  h.turn = targets.rotation[headIndex] * r.restRotation[headIndex].conjugate();
  h.pivot = targets.point[headIndex] - targets.rotation[headIndex] * r.eyeInHead;
  h.pitchDown = headPitchDown(h.turn, r.up, r.forward);
  h.drop = r.restHeight[headIndex] - (r.up.dot(h.pivot) - r.floor);
  return h;
}

void TaskWriter::setTargets() {
  for (auto id : tracking::kAllTrackers) {
    const size_t i = size_t(tracking::index(id));
    if (r.tasks.position[i] >= 0 && r.body.model.tasks[size_t(r.tasks.position[i])].desc.type == ik::TaskType::Pose) continue;
    setPose(r.tasks.position[i], r.tasks.orientation[i], targets.point[i], targets.rotation[i], targets.weight[i]);
  }
  head_ = readHead();
  setNeckBand();
  if (r.layout.seated) {
    setSeatedTargets();
    return;
  }
  if (r.layout.inferLowerBody)
    setInferredLowerBody();
  else
    scaleStrides();
  setPoleTargets();
  setClavicleTargets();
}

// The coupled spine's band between the thoracic and cervical regions keeps the neck's bend in
// proportion to the chest's (2 degrees of slack per component in the default description). Looking
// down from an upright stance people bend the neck, not the chest: with the band tight, a head
// pitched 57-77 degrees down (cmu_131_02, walking and looking at the floor) curled the thoracic spine
// with it and held the pelvis 12 cm behind its target. So the band widens to 40 degrees (the
// cervical joints' own limits still hold) as the head looks 40 -> 70 degrees down, unless the head
// has also sunk (0.1 -> 0.3 trunk lengths: bending over, where the whole spine flexes and the tight
// band helped, cmu_002_10). Over the eval's 24 runs (docs/eval.md, session 20): MPJPE 7.33 ->
// 7.25 cm, jitter 1.81 -> 1.50 x the clip's, reversed knees and elbows unchanged; four and six
// trackers gain as well. Measured on the head target, so it holds in every tracker layout.
constexpr double kLookDownOnset = 40.0 * std::numbers::pi / 180.0, kLookDownFull = 70.0 * std::numbers::pi / 180.0;
constexpr double kLookingNeckBand = 40.0 * std::numbers::pi / 180.0;
constexpr double kSunkOnset = 0.1, kSunkFull = 0.3;  // head drop, trunk lengths

void TaskWriter::setNeckBand() {
  if (r.body.neckBandRows.empty()) return;
  const double lookingDown = smoothstep(kLookDownOnset, kLookDownFull, head_.pitchDown);
  const double upright = 1.0 - smoothstep(kSunkOnset, kSunkFull, head_.drop / r.restHeadToHips.norm());
  const double slack = r.body.bandSlack + std::max(0.0, kLookingNeckBand - r.body.bandSlack) * lookingDown * upright;
  for (int row : r.body.neckBandRows) require(d.setInequalityBound(row, slack));
}

// Tracked feet with a tracked pelvis: strides scaled by the leg ratio about the pelvis's ground
// point, so a longer-legged user's steps stay within the avatar's legs.
void TaskWriter::scaleStrides() {
  const size_t hipsI = size_t(tracking::index(TrackerId::Hips));
  if (calibration.legRatio == 1.0 || sample.status[hipsI] == TrackerStatus::Absent) return;
  const Eigen::Vector3d pelvis = targets.point[hipsI];
  for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot}) {
    const size_t i = size_t(tracking::index(id));
    if (r.tasks.position[i] < 0 || !d.enabled(r.tasks.position[i])) continue;
    Eigen::Vector3d offset = targets.point[i] - pelvis;
    offset -= r.up * r.up.dot(offset);
    targets.point[i] += (calibration.legRatio - 1.0) * offset;
    require(d.setTarget(r.tasks.position[i], targets.point[i]));
  }
}

// Three-point mode: the pelvis and the feet are inferred from the head (the foot planner steps).
void TaskWriter::setInferredLowerBody() {
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  const Eigen::Quaterniond& headTurn = head_.turn;
  const double time = sample.pose.time;
  const Eigen::Vector3d& headPivot = head_.pivot;
  const InferredTrunk trunk = inferTrunk(head_.drop, head_.pitchDown, r.restHeadToHips.norm());
  const double neckTurn = kBentNeckTurn * smoothstep(trunk.bend / kBentNeckTurn);
  // The previous frame's travel: the planner is updated below, under this heading.
  const double yaw = job_.heading->facingTravel(job_.heading->update(faceHeadingOf(headTurn, r.up, r.forward), neckTurn, time),
                                                planner.travel(), planner.initialised() ? planner.walking() : 0.0, r.up,
                                                r.forward, r.avatarHeight / 1.75);
  const Eigen::Quaterniond heading = yawRotation(yaw, r.up);
  const Eigen::Vector3d side = r.up.cross(heading * r.forward).normalized();
  const Eigen::Quaterniond lean(Eigen::AngleAxisd(trunk.lean, side));
  const Eigen::Vector3d restOffset = heading * r.restHeadToHips;
  const Eigen::Vector3d pelvis = headPivot + lean * restOffset;
  const size_t hipsIndex = size_t(tracking::index(TrackerId::Hips));
  setPose(r.tasks.hipsPosition, r.tasks.hipsRotation, pelvis, lean * heading * r.restRotation[hipsIndex], trunk.weight);
  // The feet step under the body's centre of mass for the bend alone. Bent over, the pelvis goes
  // behind the heels and the trunk ahead of the toes: with the legs about 0.35 of the body's mass
  // and the upper body's centre 0.45 of the way from hips to head, the mass balances over a point
  // about 0.4 of the way from the pelvis to the head (cmu_002_10: 0.42), so the feet stay 0.4 of
  // the way back from where the bend put the hips to where upright hips would be. Under the bent
  // pelvis itself the feet stepped 50 cm back each time the user reached down. The crouch's lean
  // is left out, or a head near the floor looking up (a user lying down) planted them behind it
  // and stood the body on its head (pelvis 0.79 m up instead of lying).
  constexpr double kBalancePoint = 0.4;
  const Eigen::Vector3d bentHips = headPivot + Eigen::AngleAxisd(trunk.bend, side) * restOffset;
  const Eigen::Vector3d behind = headPivot + restOffset - bentHips;
  const Eigen::Vector3d underFeet = bentHips + kBalancePoint * (behind - r.up * r.up.dot(behind));

  if (!planner.initialised()) planner.reset(underFeet, yaw, time);
  const Eigen::Vector3d com = job_.solvedOnce ? Eigen::Vector3d(d.centerOfMass()) : underFeet;
  const auto& feet = planner.update(time, underFeet, yaw, com);
  // A jump: a head higher than straight legs on the floor can hold it lifts both feet by the
  // difference (the planner keeps their places on the ground). Without it a jumping user's body
  // stayed planted and its head sank up to 26 cm below the HMD (cmu_131_03, docs/eval.md).
  const double headHeight = r.up.dot(headPivot) - r.floor;
  const double airborne = std::max(0.0, headHeight - r.restHeight[headIndex] - r.standingHeadRise);
  for (int f = 0; f < 2; ++f) {
    const size_t i = size_t(tracking::index(f == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot));
    targets.point[i] = feet[size_t(f)].position + r.up * airborne;
    const Eigen::Quaterniond turn = yawRotation(feet[size_t(f)].yaw, r.up);
    const Eigen::Quaterniond heelRise(Eigen::AngleAxisd(feet[size_t(f)].roll, r.up.cross(turn * r.forward).normalized()));
    targets.rotation[i] = heelRise * turn * r.restRotation[i];
    setPose(r.tasks.position[i], -1, targets.point[i], targets.rotation[i], 1.0);
  }
  // Balance as an inequality: only while the centre of mass is off the support polygon.
  if (r.tasks.balance >= 0) {
    const bool over = !job_.solvedOnce || planner.overSupport(com);
    require(d.setEnabled(r.tasks.balance, !over && job_.balanceRow));
    if (!over) require(d.setTarget(r.tasks.balance, planner.nearestSupportPoint(com, 0.01 * r.avatarHeight / 1.75)));
  }
}

void TaskWriter::setSeatedTargets() {
  const size_t headIndex = size_t(tracking::index(TrackerId::Head));
  if (!seat.placed && sample.status[headIndex] == TrackerStatus::Tracked && sample.pose[TrackerId::Head].valid) {
    // The seat goes under the first tracked head, facing where it looks.
    const double seatHeight = job_.seatHeight > 0.0f ? calibration.scale * double(job_.seatHeight) : -1.0;
    seat.pose = placeSeat(r.legs, targets.point[headIndex], faceHeadingOf(head_.turn, r.up, r.forward), seatHeight);
    seat.placed = true;
    if (!job_.solvedOnce) {
      // Start the cold solve with the hips over the seat: the legs then only fold.
      ik::kinematics(r.body.model, d, false);
      const ik::Model::Joint& root = r.body.model.joints[size_t(r.body.hips)];
      if (root.desc.type == ik::JointType::Free && root.desc.parent == ik::kNoParent) {
        const Eigen::Vector3d shift =
            0.5 * (seat.pose.hip[0] + seat.pose.hip[1] - jointPosition(r.hipJoint[0]) - jointPosition(r.hipJoint[1]));
        Eigen::VectorXd q = d.q();
        q.segment<3>(root.first_dof) += root.desc.rest.linear().transpose() * shift;
        require(d.setConfiguration(q));
      }
      // A cold start sits down and reaches the first targets outside the budget (once per
      // placement: the first frame and each recenter). Within a 1 ms budget the budgeted solve
      // otherwise folded the legs and raised the arms over dozens of frames (hand p95 35 cm over
      // the first 2 s of `embody xr --seated`).
      out.settleSeat = true;
    }
  }
  // Until then (no tracked head yet) the lower body is left to the warm start.
  const double w = seat.placed ? 1.0 : 0.0;
  const Eigen::Quaterniond none = Eigen::Quaterniond::Identity();
  for (size_t s = 0; s < 2; ++s) {
    setPose(r.tasks.seatHip[s], -1, seat.pose.hip[s], none, w);
    setPose(r.tasks.seatKnee[s], -1, seat.pose.knee[s], none, w);
    const size_t f = size_t(tracking::index(s == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot));
    targets.point[f] = seat.pose.ankle[s];
    targets.rotation[f] = seat.pose.footRotation[s];
    setPose(r.tasks.position[f], -1, targets.point[f], targets.rotation[f], w);
  }
  setPose(-1, r.tasks.seatPelvis, Eigen::Vector3d::Zero(), seat.pose.pelvisRotation, w);
}

// Each clavicle's rest turn on its parent (the task's target is relative to the parent:
// ik::TaskDesc::reference), let go as the hand's target nears the arm's reach from where the
// shoulder would be with the clavicle at rest: from 85 % of the reach to all of it. Held there,
// the arm met a far target straight, and a hand held beyond reach kept the two levels trading
// 1.4 mm a frame (tests/runtime/body_plausibility_tests.cpp).
void TaskWriter::setClavicleTargets() {
  constexpr double kLetGoFrom = 0.85;
  for (size_t s = 0; s < 2; ++s) {
    const ik::TaskId t = r.tasks.clavicle[s];
    if (t < 0) continue;
    const ik::JointId clavicle = r.clavicleJoint[s];
    const ik::Model::Joint& c = r.body.model.joints[size_t(clavicle)];
    const ik::JointId shoulder = s == 0 ? r.leftShoulder : r.rightShoulder;
    const ik::Model::Joint& arm = r.body.model.joints[size_t(shoulder)];
    const Eigen::Vector3d restShoulder = arm.desc.parent == clavicle
                                             ? Eigen::Vector3d(d.jointFrame(c.desc.parent) * c.desc.rest * arm.desc.rest.translation())
                                             : jointPosition(shoulder);
    const size_t hand = size_t(tracking::index(s == 0 ? TrackerId::LeftHand : TrackerId::RightHand));
    const double reach = (targets.point[hand] - restShoulder).norm() / r.armReach;
    const double weight = targets.weight[hand] > 0.0 ? 1.0 - smoothstep((reach - kLetGoFrom) / (1.0 - kLetGoFrom)) : 1.0;
    setPose(-1, t, Eigen::Vector3d::Zero(), Eigen::Quaterniond(c.desc.rest.linear()), weight);
  }
}

void TaskWriter::setPoleTargets() {
  const size_t hips = size_t(tracking::index(TrackerId::Hips));
  const Eigen::Quaterniond pelvisTurn = Eigen::Quaterniond(d.jointFrame(r.body.hips).rotation()) * r.restRotation[hips].conjugate();
  const Eigen::Vector3d fwd = yawRotation(headingOf(pelvisTurn, r.up, r.forward), r.up) * r.forward;
  const Eigen::Vector3d left = r.up.cross(fwd);
  for (size_t k = 0; k < 4; ++k) {
    if (r.tasks.pole[k] < 0) continue;
    const Eigen::Vector3d root = jointPosition(r.limbRoot[k]), end = jointPosition(r.limbEnd[k]);
    Eigen::Vector3d pole, fallback;
    if (k < 2) {  // the knee over the toes
      pole = footForward(r, d, int(k));
      fallback = fwd;
    } else {
      const bool leftArm = k == 2;
      const Eigen::Vector3d palm = d.jointFrame(r.limbEnd[k]).rotation() * Eigen::Vector3d::UnitX() * (leftArm ? 1.0 : -1.0);
      pole = elbowPole(r.up, fwd, leftArm ? left : Eigen::Vector3d(-left), palm, end - root);
      fallback = -r.up;
    }
    setPose(r.tasks.pole[k], -1, poleTarget(root, end, r.limb[k], pole, fallback), Eigen::Quaterniond::Identity(), 1.0);
  }
}

void TaskWriter::setPose(ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p, const Eigen::Quaterniond& q,
                         double weight) {
  setTaskPose(r.body.model, d, position, orientation, p, q, weight, out.refusedCalls);
}

}  // namespace

void setTaskPose(const ik::Model& model, ik::Data& d, ik::TaskId position, ik::TaskId orientation, const Eigen::Vector3d& p,
                 const Eigen::Quaterniond& q, double weight, int& refusedCalls) {
  auto require = [&](const Status& s) {
    if (!s) ++refusedCalls;
  };
  for (ik::TaskId t : {position, orientation}) {
    if (t < 0) continue;
    if (!(weight > 0.0)) {
      require(d.setEnabled(t, false));
      continue;
    }
    require(d.setEnabled(t, true));
    require(d.setWeight(t, weight * model.tasks[size_t(t)].desc.weight));
    const ik::TaskType type = model.tasks[size_t(t)].desc.type;
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

bool TaskTargetsJob::Validate() const {
  if (!rig || !calibration || !sample || !targets || !planner || !heading || !seat || !data || !output) return false;
  if (data->q().size() != rig->body.model.dofs || !calibration->scaled() || !std::isfinite(sample->pose.time)) return false;
  for (size_t i = 0; i < tracking::kTrackerCount; ++i)
    if (!targets->point[i].allFinite() || !targets->rotation[i].coeffs().allFinite() || !std::isfinite(targets->weight[i]))
      return false;
  return true;
}

bool TaskTargetsJob::Run() const {
  if (!Validate()) return false;
  *output = TaskTargetsOutput{};
  TaskWriter(*this).setTargets();
  return true;
}

}  // namespace embody::runtime
