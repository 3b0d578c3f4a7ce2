// The body's per-frame jobs (docs/runtime.md, "The body's per-frame jobs") on the built-in
// mannequin, one at a time: the rig and the calibration they read, each job's Validate() against
// bad inputs and its Run() on inputs whose outputs are known.
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <limits>

#include "avatar/body/anthropometry.h"
#include "runtime/body_calibration.h"
#include "runtime/body_rig.h"
#include "runtime/budgeted_solve_job.h"
#include "runtime/residuals_job.h"
#include "runtime/skeleton_pose_job.h"
#include "runtime/task_targets_job.h"
#include "runtime/tracker_targets_job.h"
#include "tracking/body_dimensions.h"
#include "runtime/runtime_test_support.h"

using namespace embody;
using namespace embody::runtime;
using tracking::TrackerId;
using tracking::TrackerStatus;

namespace {

using embody::test::defaultAvatar;

size_t at(TrackerId id) { return size_t(tracking::index(id)); }

BodyRig rigFor(const AvatarBodyOptions& options) {
  int refused = 0;
  auto rig = buildBodyRig(defaultAvatar(), options, refused);
  REQUIRE(rig.ok());
  CHECK(refused == 0);
  return std::move(rig).value();
}

BodyRig rigFor(tracking::TrackerMask trackers, bool seated = false) {
  AvatarBodyOptions o;
  o.trackers = trackers;
  o.seat.enabled = seated;
  return rigFor(o);
}

// A standing user, every tracker live: eyes at 1.62 m, hands at the sides, pelvis at 1 m, ankles
// 8 cm above the floor; identity orientations (the hands' grip poses pointing down).
tracking::GuardedSample standingSample() {
  tracking::GuardedSample g;
  g.pose.time = 0.5;
  auto& s = g.pose;
  s[TrackerId::Head] = {{0.0f, 1.62f, 0.0f}, glm::quat(1, 0, 0, 0), true};
  s[TrackerId::LeftHand] = {{-0.25f, 0.85f, 0.0f}, tracking::gripOrientation(tracking::Side::Left, {0, -1, 0}, {1, 0, 0}), true};
  s[TrackerId::RightHand] = {{0.25f, 0.85f, 0.0f}, tracking::gripOrientation(tracking::Side::Right, {0, -1, 0}, {-1, 0, 0}), true};
  s[TrackerId::Hips] = {{0.0f, 1.0f, 0.0f}, glm::quat(1, 0, 0, 0), true};
  s[TrackerId::LeftFoot] = {{-0.1f, 0.08f, 0.0f}, glm::quat(1, 0, 0, 0), true};
  s[TrackerId::RightFoot] = {{0.1f, 0.08f, 0.0f}, glm::quat(1, 0, 0, 0), true};
  g.status.fill(TrackerStatus::Tracked);
  return g;
}

double angle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

// The targets of `sample` for `rig` at `calibration`.
BodyTargets targetsOf(const BodyRig& rig, const BodyCalibration& calibration, const tracking::GuardedSample& sample,
                      bool pelvisRow = true) {
  BodyTargets t;
  TrackerTargetsJob job;
  job.rig = &rig;
  job.calibration = &calibration;
  job.sample = &sample;
  job.pelvisRow = pelvisRow;
  job.targets = &t;
  REQUIRE(job.Run());
  return t;
}

// Everything a TaskTargetsJob writes, for one rig.
struct TaskState {
  const BodyRig& rig;
  BodyCalibration calibration;
  BodyTargets targets;
  FootPlanner planner;
  BodyHeading heading;
  SeatState seat;
  ik::Data data;
  TaskTargetsOutput out;

  explicit TaskState(const BodyRig& r) : rig(r), calibration(BodyCalibration::fromUserHeight(r, 1.75f)), data(r.body.model) {
    planner.configure({}, FootShape{}, r.up, r.forward, r.stance, r.avatarHeight / 1.75);
    REQUIRE(data.setConfiguration(r.restQ));
    ik::kinematics(r.body.model, data, false);
  }
  TaskTargetsJob job(const tracking::GuardedSample& sample, bool solvedOnce = false) {
    TaskTargetsJob j;
    j.rig = &rig;
    j.calibration = &calibration;
    j.sample = &sample;
    j.solvedOnce = solvedOnce;
    j.targets = &targets;
    j.planner = &planner;
    j.heading = &heading;
    j.seat = &seat;
    j.data = &data;
    j.output = &out;
    return j;
  }
};

}  // namespace

TEST_CASE("the body rig: built once, every tracker bound, rest heights in order", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  for (auto id : tracking::kAllTrackers) {
    CHECK(rig.joint[at(id)] >= 0);
    CHECK(rig.tasks.position[at(id)] >= 0);
  }
  CHECK(rig.restHeight[at(TrackerId::Head)] > rig.restHeight[at(TrackerId::Hips)]);
  CHECK(rig.restHeight[at(TrackerId::Hips)] > rig.restHeight[at(TrackerId::LeftFoot)]);
  CHECK(rig.restHeight[at(TrackerId::LeftFoot)] > 0.0);
  CHECK(rig.avatarEyeHeight > rig.restHeight[at(TrackerId::Hips)]);
  CHECK(rig.avatarEyeHeight < rig.avatarHeight);
  CHECK(rig.restQ.size() == rig.body.model.dofs);
  CHECK(rig.armReach > 0.4);
  CHECK(rig.tasks.hipsPosition < 0);  // tracked hips: no inferred pelvis

  const BodyRig three = rigFor(tracking::TrackerMask::threePoint());
  CHECK(three.layout.inferLowerBody);
  CHECK(three.body.model.tasks[size_t(three.tasks.position[at(TrackerId::LeftFoot)])].desc.type == ik::TaskType::Pose);
}

TEST_CASE("BodyCalibration: the scale from the user's height or the first live head, the heights on the first tracked head",
          "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  const BodyCalibration none;
  CHECK_FALSE(none.scaled());
  const BodyCalibration given = BodyCalibration::fromUserHeight(rig, 1.80f);
  CHECK(given.scale == Approx(rig.avatarEyeHeight / double(tracking::BodyDimensions::fromHeight(1.80f).eyeHeight)));
  CHECK_FALSE(given.fromHead);

  tracking::GuardedSample sample = standingSample();
  const BodyCalibration fromHead = BodyCalibration::fromFirstSample(rig, sample);
  CHECK(fromHead.fromHead);
  const float stature = 1.62f / float(avatar::kEyeHeightRatio);
  CHECK(fromHead.scale == Approx(rig.avatarEyeHeight / double(tracking::BodyDimensions::fromHeight(stature).eyeHeight)));
  CHECK_FALSE(fromHead.heightsCalibrated);

  // A head on the floor is no standing eye height: a 1.75 m user.
  sample.pose[TrackerId::Head].position.y = 0.3f;
  const BodyCalibration low = BodyCalibration::fromFirstSample(rig, sample);
  CHECK_FALSE(low.fromHead);
  CHECK(low.scale == Approx(BodyCalibration::fromUserHeight(rig, 1.75f).scale));

  // Heights: the lowest ankle and the pelvis stand at the avatar's rest heights.
  const BodyCalibration heights = given.withHeights(rig, standingSample());
  CHECK(heights.heightsCalibrated);
  CHECK(heights.scale == given.scale);
  const size_t hips = at(TrackerId::Hips), left = at(TrackerId::LeftFoot);
  CHECK(heights.heightOffset[left] == Approx(rig.restHeight[left] - given.scale * 0.08));
  CHECK(heights.heightOffset[hips] == Approx(rig.restHeight[hips] - given.scale * 1.0));
  CHECK(heights.heightOffset[at(TrackerId::Head)] == 0.0);
  const double userLeg = given.scale * (1.0 - 0.08), avatarLeg = rig.restHeight[hips] - rig.restHeight[left];
  CHECK(heights.legRatio == Approx(std::clamp(avatarLeg / userLeg, 0.5, 2.0)));
  // resetWarmStart forgets the heights, keeps the scale.
  const BodyCalibration reset = heights.withoutHeights();
  CHECK_FALSE(reset.heightsCalibrated);
  CHECK(reset.scale == given.scale);
  CHECK(reset.heightOffset[hips] == 0.0);
  CHECK(reset.legRatio == 1.0);
}

TEST_CASE("TrackerTargetsJob: Validate rejects missing, uncalibrated and non-finite inputs", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  const BodyCalibration calibration = BodyCalibration::sameBody();
  const tracking::GuardedSample sample = standingSample();
  BodyTargets targets;
  TrackerTargetsJob job;
  job.rig = &rig;
  job.calibration = &calibration;
  job.sample = &sample;
  job.targets = &targets;
  CHECK(job.Validate());
  for (int missing = 0; missing < 4; ++missing) {
    TrackerTargetsJob bad = job;
    if (missing == 0) bad.rig = nullptr;
    if (missing == 1) bad.calibration = nullptr;
    if (missing == 2) bad.sample = nullptr;
    if (missing == 3) bad.targets = nullptr;
    CHECK_FALSE(bad.Validate());
    CHECK_FALSE(bad.Run());
  }
  const BodyCalibration uncalibrated;
  TrackerTargetsJob bad = job;
  bad.calibration = &uncalibrated;
  CHECK_FALSE(bad.Validate());
  tracking::GuardedSample nan = sample;
  nan.pose[TrackerId::RightHand].position.x = std::numeric_limits<float>::quiet_NaN();
  bad = job;
  bad.sample = &nan;
  CHECK_FALSE(bad.Validate());
  BodyCalibration nanOffset = calibration;
  nanOffset.heightOffset[0] = std::numeric_limits<double>::infinity();
  bad = job;
  bad.calibration = &nanOffset;
  CHECK_FALSE(bad.Validate());
}

TEST_CASE("TrackerTargetsJob maps a known tracker pose to a known avatar-space target", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  // The mannequin faces +Z with +Y up: tracking space (-Z forward) turns half a turn about up.
  REQUIRE(rig.up.isApprox(Eigen::Vector3d::UnitY()));
  REQUIRE(rig.forward.isApprox(Eigen::Vector3d::UnitZ()));
  BodyCalibration calibration = BodyCalibration::fromUserHeight(rig, 1.75f);
  calibration.scale = 2.0;
  calibration.heightOffset[at(TrackerId::LeftFoot)] = 0.05;
  tracking::GuardedSample sample = standingSample();
  sample.pose[TrackerId::Head].position = {0.3f, 1.2f, -0.5f};
  sample.status[at(TrackerId::RightHand)] = TrackerStatus::Neutral;
  sample.pose[TrackerId::LeftHand].valid = false;
  const BodyTargets t = targetsOf(rig, calibration, sample, false);

  const size_t head = at(TrackerId::Head), foot = at(TrackerId::LeftFoot);
  const Eigen::Vector3d expectedHead(-0.6, 2.4 + rig.floor, 1.0);
  CHECK((t.point[head] - expectedHead).norm() < 1e-6);
  // The left ankle at (-0.1, 0.08, 0): x turned, scaled, lifted by its offset.
  const Eigen::Vector3d expectedFoot(0.2, 0.16 + rig.floor + 0.05, 0.0);
  CHECK((t.point[foot] - expectedFoot).norm() < 1e-6);
  // A tracker held at its rest reference (identity for head and feet) targets its joint's rest rotation.
  CHECK(angle(t.rotation[head], rig.restRotation[head]) < 1e-6);
  CHECK(angle(t.rotation[foot], rig.restRotation[foot]) < 1e-6);
  // Weights: tracked 1, neutral 0.3, invalid 0, the pelvis 0 without its row.
  CHECK(t.weight[head] == 1.0);
  CHECK(t.weight[at(TrackerId::RightHand)] == Approx(0.3));
  CHECK(t.weight[at(TrackerId::LeftHand)] == 0.0);
  CHECK(t.weight[at(TrackerId::Hips)] == 0.0);
}

TEST_CASE("TrackerTargetsJob: an arm scale moves the hands towards the shoulders the head implies, nothing else",
          "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  const BodyCalibration calibration = BodyCalibration::fromUserHeight(rig, 1.75f);
  tracking::GuardedSample sample = standingSample();
  sample.pose[TrackerId::LeftHand].position = {-0.2f, 1.4f, -0.6f};  // reaching forward
  const BodyTargets plain = targetsOf(rig, calibration, sample);
  BodyTargets scaled;
  TrackerTargetsJob job;
  job.rig = &rig;
  job.calibration = &calibration;
  job.sample = &sample;
  job.armScale = 1.25;  // the user's arms 25 % longer than the avatar's proportions
  job.targets = &scaled;
  REQUIRE(job.Run());
  // The user's shoulder as the head implies it, in avatar space: the scaled hand is on the line
  // from it to the unscaled hand, at 1 / 1.25 of the distance.
  const auto dims = tracking::BodyDimensions::fromHeight(float(rig.avatarHeight / calibration.scale));
  const glm::vec3 s = dims.shoulderFromHead(sample.pose[TrackerId::Head], tracking::Side::Left);
  const Eigen::Vector3d shoulder = rig.toAvatar(calibration.scale, Eigen::Vector3d(s.x, s.y, s.z));
  const size_t left = at(TrackerId::LeftHand);
  CHECK((scaled.point[left] - shoulder).norm() == Approx((plain.point[left] - shoulder).norm() / 1.25).epsilon(1e-6));
  CHECK((scaled.point[left] - shoulder).normalized().isApprox((plain.point[left] - shoulder).normalized(), 1e-6));
  for (auto id : {TrackerId::Head, TrackerId::Hips, TrackerId::LeftFoot, TrackerId::RightFoot}) {
    CHECK((scaled.point[at(id)] - plain.point[at(id)]).norm() < 1e-12);
  }
  CHECK(angle(scaled.rotation[left], plain.rotation[left]) < 1e-12);
  // Outside [0.5, 2]: refused.
  job.armScale = 3.0;
  CHECK_FALSE(job.Validate());
  job.armScale = std::nan("");
  CHECK_FALSE(job.Validate());
}

TEST_CASE("TaskTargetsJob: Validate rejects missing pointers, a data of another model and non-finite targets",
          "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  TaskState state(rig);
  const tracking::GuardedSample sample = standingSample();
  state.targets = targetsOf(rig, state.calibration, sample);
  const TaskTargetsJob job = state.job(sample);
  CHECK(job.Validate());
  TaskTargetsJob bad = job;
  bad.planner = nullptr;
  CHECK_FALSE(bad.Validate());
  bad = job;
  bad.heading = nullptr;
  CHECK_FALSE(bad.Validate());
  bad = job;
  bad.output = nullptr;
  CHECK_FALSE(bad.Run());
  AvatarBodyOptions uncoupled;
  uncoupled.coupledSpine = false;
  const BodyRig other = rigFor(uncoupled);
  REQUIRE(other.body.model.dofs != rig.body.model.dofs);
  ik::Data otherData(other.body.model);
  bad = job;
  bad.data = &otherData;
  CHECK_FALSE(bad.Validate());
  BodyCalibration uncalibrated;
  bad = job;
  bad.calibration = &uncalibrated;
  CHECK_FALSE(bad.Validate());
  state.targets.point[at(TrackerId::Head)].x() = std::numeric_limits<double>::quiet_NaN();
  CHECK_FALSE(job.Validate());
}

TEST_CASE("TaskTargetsJob writes the trackers' tasks: targets set where weighted, off where not", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  TaskState state(rig);
  const tracking::GuardedSample sample = standingSample();
  state.targets = targetsOf(rig, state.calibration, sample);
  state.targets.weight[at(TrackerId::LeftHand)] = 0.0;
  REQUIRE(state.job(sample, true).Run());
  CHECK(state.out.refusedCalls == 0);
  CHECK_FALSE(state.out.settleSeat);
  const size_t head = at(TrackerId::Head), left = at(TrackerId::LeftHand), right = at(TrackerId::RightHand);
  CHECK(state.data.enabled(rig.tasks.position[head]));
  CHECK(state.data.targetPosition(rig.tasks.position[head]) == state.targets.point[head]);
  CHECK(angle(state.data.targetOrientation(rig.tasks.orientation[head]), state.targets.rotation[head]) < 1e-12);
  CHECK(state.data.enabled(rig.tasks.position[right]));
  CHECK_FALSE(state.data.enabled(rig.tasks.position[left]));
  CHECK_FALSE(state.data.enabled(rig.tasks.orientation[left]));
}

TEST_CASE("TaskTargetsJob, three-point: both feet planted under the pelvis inferred from the head", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::threePoint());
  TaskState state(rig);
  const tracking::GuardedSample sample = standingSample();
  state.targets = targetsOf(rig, state.calibration, sample);
  const size_t head = at(TrackerId::Head);
  REQUIRE(state.job(sample).Run());
  CHECK(state.out.refusedCalls == 0);
  // The head at its rest orientation (no turn): the pelvis at the rest head-to-hips offset from
  // the head joint, the first frame plants both feet at their rest stance around its ground point.
  const Eigen::Vector3d hips = state.targets.point[head] - state.targets.rotation[head] * rig.eyeInHead + rig.restHeadToHips;
  auto ground = [&](const Eigen::Vector3d& p) { return Eigen::Vector3d(p - rig.up * rig.up.dot(p)); };
  REQUIRE(state.planner.initialised());
  for (int f = 0; f < 2; ++f) {
    const size_t i = at(f == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot);
    const Eigen::Vector3d expected = ground(hips) + ground(rig.stance[size_t(f)]) + rig.up * rig.up.dot(rig.stance[0]);
    CHECK((state.targets.point[i] - expected).norm() < 1e-9);
    CHECK(angle(state.targets.rotation[i], rig.restRotation[i]) < 1e-9);
    CHECK(state.data.enabled(rig.tasks.position[i]));
    CHECK(state.data.targetPosition(rig.tasks.position[i]) == state.targets.point[i]);
  }
}

TEST_CASE("TaskTargetsJob, three-point: the pelvis row stands under the head, leans back when bending over, lets go in a squat",
          "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::threePoint());
  REQUIRE(rig.tasks.hipsPosition >= 0);
  REQUIRE(rig.tasks.hipsRotation >= 0);
  const size_t head = at(TrackerId::Head);
  const Eigen::Vector3d forward = rig.forward;  // the head is not turned: the heading is the rest's
  struct Row {
    bool enabled;
    Eigen::Vector3d offset;  // target - head pivot
  };
  auto rowFor = [&](float headHeight, float pitchDownDegrees) {
    tracking::GuardedSample sample = standingSample();
    sample.pose[TrackerId::Head].position.y = headHeight;
    sample.pose[TrackerId::Head].orientation = glm::angleAxis(glm::radians(-pitchDownDegrees), glm::vec3(1, 0, 0));
    TaskState state(rig);
    state.targets = targetsOf(rig, state.calibration, sample);
    REQUIRE(state.job(sample).Run());
    CHECK(state.out.refusedCalls == 0);
    const Eigen::Vector3d pivot = state.targets.point[head] - state.targets.rotation[head] * rig.eyeInHead;
    return Row{state.data.enabled(rig.tasks.hipsPosition), state.data.targetPosition(rig.tasks.hipsPosition) - pivot};
  };
  // Standing, looking ahead or down at the floor: the rest offset exactly, enabled.
  for (float pitch : {0.0f, 60.0f}) {
    const Row standing = rowFor(1.62f, pitch);
    CHECK(standing.enabled);
    CHECK((standing.offset - rig.restHeadToHips).norm() < 1e-9);
  }
  const double trunk = rig.restHeadToHips.norm();
  // The head 40 cm lower looking 70 degrees down: bent over at the hips, the pelvis behind the
  // head and hardly lower than standing (the legs straight).
  const Row bent = rowFor(1.22f, 70.0f);
  CHECK(bent.enabled);
  CHECK(bent.offset.dot(forward) < -0.5 * trunk);
  CHECK(std::abs(bent.offset.norm() - trunk) < 1e-9);
  // The same depth looking ahead: a squat, deep enough that the row lets the pelvis go.
  CHECK_FALSE(rowFor(1.22f, 0.0f).enabled);
  // A shallow crouch (12 cm): still held, leaning a little forward (the pelvis behind the head).
  const Row shallow = rowFor(1.50f, 0.0f);
  CHECK(shallow.enabled);
  CHECK(shallow.offset.dot(forward) < -0.01);
  CHECK(shallow.offset.dot(forward) > -0.2 * trunk);
}

TEST_CASE("TaskTargetsJob, seated: the seat goes under the first tracked head and asks for one settle", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::threePoint(), true);
  TaskState state(rig);
  tracking::GuardedSample sample = standingSample();
  sample.pose[TrackerId::Head].position.y = 1.2f;
  sample.status[at(TrackerId::Head)] = TrackerStatus::Held;
  state.targets = targetsOf(rig, state.calibration, sample);
  REQUIRE(state.job(sample).Run());
  CHECK_FALSE(state.seat.placed);
  CHECK_FALSE(state.out.settleSeat);
  CHECK_FALSE(state.data.enabled(rig.tasks.seatHip[0]));

  sample.status[at(TrackerId::Head)] = TrackerStatus::Tracked;
  state.targets = targetsOf(rig, state.calibration, sample);
  REQUIRE(state.job(sample).Run());
  CHECK(state.seat.placed);
  CHECK(state.out.settleSeat);  // placed before the first solve
  CHECK(state.data.enabled(rig.tasks.seatHip[0]));
  CHECK(state.data.targetPosition(rig.tasks.seatHip[1]) == state.seat.pose.hip[1]);
  // The seat is below the head: the hips under the eyes, the ankles on the floor.
  CHECK(rig.up.dot(state.seat.pose.hip[0]) < rig.up.dot(state.targets.point[at(TrackerId::Head)]) - 0.4);
  CHECK(state.targets.point[at(TrackerId::LeftFoot)] == state.seat.pose.ankle[0]);

  REQUIRE(state.job(sample, true).Run());
  CHECK_FALSE(state.out.settleSeat);  // placed once
}

TEST_CASE("BudgetedSolveJob: Validate, the fixed count, the cold start's four times, a passed deadline", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  TaskState state(rig);
  const tracking::GuardedSample sample = standingSample();
  state.targets = targetsOf(rig, state.calibration, sample);
  REQUIRE(state.job(sample).Run());
  ManualClock clock(10.0);
  IterationCostModel cost;
  BudgetedSolveOutput out;
  BudgetedSolveJob job;
  job.model = &rig.body.model;
  job.clock = &clock;
  job.deadline = clock.now() + std::chrono::milliseconds(2);
  job.iterationCost = &cost;
  job.data = &state.data;
  job.output = &out;
  CHECK(job.Validate());
  for (int k = 0; k < 4; ++k) {
    BudgetedSolveJob bad = job;
    if (k == 0) bad.model = nullptr;
    if (k == 1) bad.maxIterations = 0;
    if (k == 2) bad.maxLevelStep = std::numeric_limits<double>::quiet_NaN();
    if (k == 3) bad.fixedIterations = -1;
    CHECK_FALSE(bad.Validate());
    CHECK_FALSE(bad.Run());
  }

  // The deadline already passed: not one iteration, the configuration unchanged.
  const Eigen::VectorXd before = state.data.q();
  BudgetedSolveJob late = job;
  late.deadline = clock.now() - std::chrono::milliseconds(1);
  REQUIRE(late.Run());
  CHECK(out.iterations == 0);
  CHECK(state.data.q() == before);

  // From the rest pose the targets are far: a cold fixed count of 2 runs 4 x 2 iterations, warm 2.
  BudgetedSolveJob cold = job;
  cold.fixedIterations = 2;
  cold.cold = true;
  REQUIRE(cold.Run());
  CHECK(out.iterations == 8);
  CHECK_FALSE(out.broken);
  CHECK(state.data.q() != before);
  BudgetedSolveJob warm = cold;
  warm.cold = false;
  REQUIRE(warm.Run());
  CHECK((out.iterations == 2 || out.converged));
  // Under a deadline on a clock that does not move, the cap rules.
  BudgetedSolveJob capped = job;
  capped.maxIterations = 3;
  REQUIRE(capped.Run());
  CHECK((out.iterations == 3 || out.converged));

  // The first live solve settles, with a fixed count too (embody eval scores the live path): from
  // the rest pose it runs past the cold start's 4 x 2 iterations, the same count and
  // configuration every time.
  BudgetedSolveJob settling = cold;
  settling.settleFirst = true;
  Eigen::VectorXd settled[2];
  int iterations[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    REQUIRE(state.data.setConfiguration(before));
    REQUIRE(settling.Run());
    CHECK_FALSE(out.broken);
    settled[k] = state.data.q();
    iterations[k] = out.iterations;
  }
  CHECK(iterations[0] > 8);
  CHECK(iterations[0] == iterations[1]);
  CHECK(settled[0] == settled[1]);
}

TEST_CASE("SkeletonPoseJob: Validate rejects a pose of another size, the rest configuration gives the rest pose",
          "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  ik::Data data(rig.body.model);
  REQUIRE(data.setConfiguration(rig.body.restConfiguration));
  ik::kinematics(rig.body.model, data, false);
  const avatar::SkeletonPose rest = avatar::SkeletonPose::rest(defaultAvatar().skeleton);
  avatar::SkeletonPose pose = rest;
  for (auto& t : pose.local) t.rotation = glm::angleAxis(1.0f, glm::vec3(0, 0, 1));  // anything but rest
  SkeletonPoseJob job{&rig.body, &defaultAvatar(), &data, &pose};
  CHECK(job.Validate());
  avatar::SkeletonPose small;
  SkeletonPoseJob bad = job;
  bad.pose = &small;
  CHECK_FALSE(bad.Validate());
  bad = job;
  bad.data = nullptr;
  CHECK_FALSE(bad.Run());

  REQUIRE(job.Run());
  REQUIRE(pose.local.size() == rest.local.size());
  for (size_t j = 0; j < rest.local.size(); ++j) {
    INFO(defaultAvatar().skeleton.joints[j].name);
    CHECK(std::abs(glm::dot(pose.local[j].rotation, rest.local[j].rotation)) > 1.0f - 1e-5f);
    CHECK(glm::length(pose.local[j].translation - rest.local[j].translation) < 1e-4f);
  }
}

TEST_CASE("ResidualsJob: each enabled tracker's distance to its body part and the hands' reach", "[runtime][jobs]") {
  const BodyRig rig = rigFor(tracking::TrackerMask::all());
  ik::Data data(rig.body.model);
  REQUIRE(data.setConfiguration(rig.restQ));
  ik::kinematics(rig.body.model, data, false);
  // Targets on the body parts themselves (the head's is the eye point), all but the hips enabled.
  BodyTargets targets;
  int refused = 0;
  for (auto id : tracking::kAllTrackers) {
    const size_t i = at(id);
    targets.point[i] = id == TrackerId::Head ? Eigen::Vector3d(data.jointFrame(rig.body.head) * rig.eyeInHead)
                                             : Eigen::Vector3d(data.jointFrame(rig.joint[i]).translation());
    setTaskPose(rig.body.model, data, rig.tasks.position[i], -1, targets.point[i], Eigen::Quaterniond::Identity(),
                id == TrackerId::Hips ? 0.0 : 1.0, refused);
  }
  REQUIRE(refused == 0);
  targets.point[at(TrackerId::LeftHand)] += 0.1 * rig.up;  // towards the shoulder: within reach
  targets.point[at(TrackerId::RightHand)] += Eigen::Vector3d(10.0, 0.0, 0.0);
  SolveResult result;
  ResidualsJob job{&rig, &data, &targets, &result};
  SolveResult untouched;
  ResidualsJob bad{&rig, &data, nullptr, &untouched};
  CHECK_FALSE(bad.Run());
  CHECK(untouched.residual[0] == -1.0f);
  REQUIRE(job.Run());
  CHECK(result.residual[at(TrackerId::Head)] == Approx(0.0).margin(1e-9));
  CHECK(result.residual[at(TrackerId::LeftFoot)] == Approx(0.0).margin(1e-9));
  CHECK(result.residual[at(TrackerId::LeftHand)] == Approx(0.1).epsilon(1e-6));
  CHECK(result.residual[at(TrackerId::RightHand)] == Approx(10.0).epsilon(1e-6));
  CHECK(result.residual[at(TrackerId::Hips)] == -1.0f);  // no enabled task
  CHECK(result.reachable[at(TrackerId::LeftHand)]);
  CHECK_FALSE(result.reachable[at(TrackerId::RightHand)]);
}
