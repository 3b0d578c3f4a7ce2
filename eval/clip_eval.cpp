#include "eval/clip_eval.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <glm/gtc/constants.hpp>

#include "core/enum_names.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/ik_stage.h"
#include "tracking/pose_source.h"
#include "tracking/trace.h"

namespace embody::eval {

namespace {

using avatar::HumanBone;
using tracking::TrackerId;

glm::dquat worldRotation(const glm::mat4& m) {
  const glm::dmat3 r(glm::normalize(glm::dvec3(m[0])), glm::normalize(glm::dvec3(m[1])), glm::normalize(glm::dvec3(m[2])));
  return glm::normalize(glm::quat_cast(r));
}

void appendPose(const avatar::Skeleton& sk, const avatar::SkeletonPose& pose, std::vector<glm::mat4>& globals, JointTrack& out) {
  avatar::computeGlobals(sk, pose, globals);
  for (const auto& g : globals) {
    out.position.emplace_back(glm::dvec3(g[3]));
    out.rotation.push_back(worldRotation(g));
  }
}

// The clip's joints at every evaluated frame.
JointTrack truthTrack(const tracking::BvhAvatar& avatar, double fps, int frames) {
  JointTrack t;
  t.joints = int(avatar.clip.joints.size());
  std::vector<avatar::BvhGlobal> g;
  for (int f = 0; f < frames; ++f) {
    tracking::bvhJointsAt(avatar.clip, avatar.mapping, double(f) / fps, g);
    for (const auto& x : g) t.position.push_back(x.position), t.rotation.push_back(x.rotation);
  }
  return t;
}

std::unique_ptr<tracking::PoseSource> sourceFor(const tracking::BvhAvatar& avatar, TrackerSet set) {
  auto trace = std::make_unique<tracking::TraceSource>(avatar.trace, avatar.asset.sourcePath);
  return tracking::maskTrackers(std::move(trace), trackerMask(set));
}

Result<JointTrack> runtimeTrack(const tracking::BvhAvatar& avatar, const EvalOptions& o, bool coupled, double fps,
                                const JointTrack& truth, tracking::SolvedMotionBvh* bvh, MethodRun& run) {
  const int frames = truth.frames();
  runtime::AvatarBodyOptions bo;
  bo.coupledSpine = coupled;
  bo.trackers = trackerMask(o.trackers);
  bo.sameBody.enabled = true;
  bo.jointMarkers = o.trackers == TrackerSet::Full;
  bo.sameBody.eyeOffset = Eigen::Vector3d(avatar.mapping.eyeOffset.x, avatar.mapping.eyeOffset.y, avatar.mapping.eyeOffset.z);
  for (size_t i = 0; i < tracking::kTrackerCount; ++i) {
    const glm::dquat& q = avatar.mapping.reference[i];
    bo.sameBody.reference[i] = Eigen::Quaterniond(q.w, q.x, q.y, q.z);
  }
  auto solver = runtime::AvatarBodySolver::create(avatar.asset, bo);
  if (!solver) return Error{"body solver: " + solver.error()};
  runtime::IkStageConfig cfg;
  cfg.fixedIterations = o.ikIterations;
  // Full markers are the clip's own joints, exact: a check that import, solve and export agree,
  // not a tracking scenario, so no One Euro filter (its lag alone is about 1 cm on a walk).
  cfg.filter = o.trackers != TrackerSet::Full;
  cfg.guard.userHeight = float(avatar.mapping.heightUnits * avatar.mapping.scale);
  runtime::IkStage stage(**solver, runtime::steadyClock(), cfg);
  auto source = sourceFor(avatar, o.trackers);
  runtime::SolvedFrame frame;
  frame.pose = avatar::SkeletonPose::rest(avatar.asset.skeleton);
  JointTrack track;
  track.joints = int(avatar.asset.skeleton.joints.size());
  std::vector<glm::mat4> globals;
  std::vector<glm::dvec3> markerPosition;
  std::vector<glm::dquat> markerRotation;
  // The clip's rotations are world rotations from its zero-channel pose; markers turn joints from
  // the avatar's rest, which is the clip's first frame when its zero-channel pose does not stand.
  std::vector<glm::dquat> restInverse;
  avatar::computeGlobals(avatar.asset.skeleton, avatar::SkeletonPose::rest(avatar.asset.skeleton), globals);
  for (const auto& g : globals) restInverse.push_back(glm::conjugate(worldRotation(g)));
  for (int f = 0; f < frames; ++f) {
    if (bo.jointMarkers) {
      const auto first = size_t(f) * size_t(truth.joints), last = first + size_t(truth.joints);
      markerPosition.assign(truth.position.begin() + std::ptrdiff_t(first), truth.position.begin() + std::ptrdiff_t(last));
      markerRotation.assign(truth.rotation.begin() + std::ptrdiff_t(first), truth.rotation.begin() + std::ptrdiff_t(last));
      for (size_t j = 0; j < markerRotation.size() && j < restInverse.size(); ++j)
        markerRotation[j] = glm::normalize(markerRotation[j] * restInverse[j]);
      (*solver)->setMarkers(markerPosition, markerRotation);
    }
    stage.process(source->sample(double(f) / fps), frame);
    appendPose(avatar.asset.skeleton, frame.pose, globals, track);
    if (bvh) bvh->add(frame.pose);
    const int keep = coupled ? o.keepPoses : 0;
    if (keep > 0 && (f * keep) / frames != ((f + 1) * keep) / frames) run.kept.emplace_back(f, frame.pose);
  }
  return track;
}

// --- the naive baseline ---------------------------------------------------------------------

glm::dquat between(const glm::dvec3& from, const glm::dvec3& to) {
  const glm::dvec3 a = glm::normalize(from), b = glm::normalize(to);
  const double d = glm::dot(a, b);
  if (d > 1.0 - 1e-12) return glm::dquat(1, 0, 0, 0);
  if (d < -1.0 + 1e-12) {
    glm::dvec3 axis = glm::cross(a, glm::dvec3(1, 0, 0));
    if (glm::length(axis) < 1e-6) axis = glm::cross(a, glm::dvec3(0, 1, 0));
    return glm::angleAxis(glm::pi<double>(), glm::normalize(axis));
  }
  return glm::normalize(glm::dquat(1.0 + d, glm::cross(a, b)));
}

struct NaiveBody {
  const avatar::Skeleton* sk = nullptr;
  std::vector<glm::dvec3> rest;  // rest joint positions, standing on the floor
  int head = -1;
  std::array<std::array<int, 3>, 2> arm{};  // upper arm, forearm, hand (0 = left)
  glm::dvec3 eyeOffset{0.0};
  std::array<glm::dquat, tracking::kTrackerCount> reference{};
};

// Moves joint j and everything below it rigidly: about `pivot0` (rest) to `pivot`, turned by r.
void moveSubtree(const NaiveBody& b, int root, const glm::dvec3& pivot0, const glm::dvec3& pivot, const glm::dquat& r,
                 std::vector<glm::dvec3>& p, std::vector<glm::dquat>& q) {
  for (size_t j = size_t(root); j < b.sk->joints.size(); ++j)
    if (b.sk->isAncestor(root, int(j))) {
      p[j] = pivot + r * (b.rest[j] - pivot0);
      q[j] = r;
    }
}

void naivePose(const NaiveBody& b, const tracking::PoseSample& s, std::vector<glm::dvec3>& p, std::vector<glm::dquat>& q) {
  const size_t n = b.rest.size();
  p.assign(n, glm::dvec3(0.0));
  q.assign(n, glm::dquat(1, 0, 0, 0));
  const auto& head = s[TrackerId::Head];
  const glm::dquat headTurn = glm::dquat(head.orientation) * glm::conjugate(b.reference[0]);
  glm::dvec3 fwd = headTurn * glm::dvec3(0, 0, -1);
  fwd.y = 0.0;
  const double yaw = glm::length(fwd) > 1e-6 ? std::atan2(-fwd.x, -fwd.z) : 0.0;
  const glm::dquat turn = glm::angleAxis(yaw, glm::dvec3(0, 1, 0));
  // Stand the rest body under the eyes, turned to the heading.
  const glm::dvec3 eye0 = b.rest[size_t(b.head)] + b.eyeOffset;
  glm::dvec3 eye = glm::dvec3(head.position);
  eye.y = eye0.y;
  moveSubtree(b, 0, eye0, eye, turn, p, q);
  const glm::dvec3 headPivot = p[size_t(b.head)];
  moveSubtree(b, b.head, b.rest[size_t(b.head)], headPivot, headTurn, p, q);
  // Arms: two-bone IK, elbows down and back.
  for (size_t side = 0; side < 2; ++side) {
    const auto [u, l, h] = b.arm[side];
    const auto& hand = s[side == 0 ? TrackerId::LeftHand : TrackerId::RightHand];
    if (u < 0 || l < 0 || h < 0 || !hand.valid) continue;
    const glm::dvec3 shoulder = p[size_t(u)], target(hand.position);
    const double a = glm::length(b.rest[size_t(l)] - b.rest[size_t(u)]), c = glm::length(b.rest[size_t(h)] - b.rest[size_t(l)]);
    glm::dvec3 toTarget = target - shoulder;
    const double d = std::clamp(glm::length(toTarget), std::abs(a - c) + 1e-6, a + c - 1e-6);
    const glm::dvec3 dir = glm::length(toTarget) > 1e-9 ? glm::normalize(toTarget) : glm::dvec3(0, -1, 0);
    glm::dvec3 pole = glm::dvec3(0, -1, 0) + 0.3 * (turn * glm::dvec3(0, 0, 1));
    pole -= dir * glm::dot(pole, dir);
    pole = glm::length(pole) > 1e-9 ? glm::normalize(pole) : glm::dvec3(0, 0, 1);
    const double cosA = std::clamp((a * a + d * d - c * c) / (2.0 * a * d), -1.0, 1.0);
    const glm::dvec3 elbow = shoulder + a * (cosA * dir + std::sqrt(1.0 - cosA * cosA) * pole);
    const glm::dvec3 wrist = shoulder + dir * d;
    const glm::dquat upper = between(turn * (b.rest[size_t(l)] - b.rest[size_t(u)]), elbow - shoulder) * turn;
    moveSubtree(b, u, b.rest[size_t(u)], shoulder, upper, p, q);
    const glm::dquat fore = between(upper * (b.rest[size_t(h)] - b.rest[size_t(l)]), wrist - elbow) * upper;
    moveSubtree(b, l, b.rest[size_t(l)], elbow, fore, p, q);
    const size_t ti = size_t(tracking::index(side == 0 ? TrackerId::LeftHand : TrackerId::RightHand));
    moveSubtree(b, h, b.rest[size_t(h)], wrist, glm::dquat(hand.orientation) * glm::conjugate(b.reference[ti]), p, q);
  }
}

JointTrack naiveTrack(const tracking::BvhAvatar& avatar, double fps, int frames) {
  NaiveBody b;
  b.sk = &avatar.asset.skeleton;
  std::vector<glm::mat4> g;
  avatar::computeGlobals(*b.sk, avatar::SkeletonPose::rest(*b.sk), g);
  double lowest = 1e300;
  for (const auto& m : g) lowest = std::min(lowest, double(m[3].y));
  // The sole under a bare ankle, where the avatar's foot is the clip's.
  lowest = avatar.mapping.body.lowestWithBareSoles(lowest, avatar.mapping.scale, [&](size_t side, int foot) {
    return foot == avatar.asset.humanoid.joint(side == 0 ? HumanBone::leftFoot : HumanBone::rightFoot)
               ? double(g[size_t(foot)][3].y)
               : std::numeric_limits<double>::infinity();
  });
  for (const auto& m : g) b.rest.push_back(glm::dvec3(m[3]) - glm::dvec3(0, lowest, 0));
  const avatar::HumanoidMap& map = avatar.asset.humanoid;
  b.head = map.joint(HumanBone::head);
  b.arm[0] = {map.joint(HumanBone::leftUpperArm), map.joint(HumanBone::leftLowerArm), map.joint(HumanBone::leftHand)};
  b.arm[1] = {map.joint(HumanBone::rightUpperArm), map.joint(HumanBone::rightLowerArm), map.joint(HumanBone::rightHand)};
  b.eyeOffset = avatar.mapping.eyeOffset;
  b.reference = avatar.mapping.reference;
  auto source = sourceFor(avatar, TrackerSet::Three);  // the baseline uses the HMD and controllers only
  JointTrack t;
  t.joints = int(b.rest.size());
  std::vector<glm::dvec3> p;
  std::vector<glm::dquat> q;
  for (int f = 0; f < frames; ++f) {
    naivePose(b, source->sample(double(f) / fps), p, q);
    t.position.insert(t.position.end(), p.begin(), p.end());
    t.rotation.insert(t.rotation.end(), q.begin(), q.end());
  }
  return t;
}

}  // namespace

ScoredSkeleton scoredSkeleton(const tracking::BvhAvatar& avatar) {
  const avatar::Skeleton& sk = avatar.asset.skeleton;
  const avatar::HumanoidMap& map = avatar.asset.humanoid;
  ScoredSkeleton s;
  auto joint = [&](HumanBone b) { return map.joint(b); };
  auto below = [&](int ancestor, int j) { return ancestor >= 0 && sk.isAncestor(ancestor, j); };
  const int hips = joint(HumanBone::hips), head = joint(HumanBone::head);
  s.pelvis = hips;
  std::vector<int> spine;  // hips up to the head
  for (int j = head; j >= 0; j = sk.joints[size_t(j)].parent) {
    spine.insert(spine.begin(), j);
    if (j == hips) break;
  }
  std::vector<glm::mat4> g;
  avatar::computeGlobals(sk, avatar::SkeletonPose::rest(sk), g);
  auto restPos = [&](int j) { return glm::dvec3(g[size_t(j)][3]); };
  // Regions: the trunk up to the neck bone, the neck up to the head (one region without a neck).
  const int neck = joint(HumanBone::neck);
  const auto split = std::find(spine.begin(), spine.end(), neck);
  std::vector<std::vector<int>> chains;
  if (split == spine.end()) chains = {spine};
  else chains = {std::vector<int>(spine.begin(), split + 1), std::vector<int>(split, spine.end())};
  for (auto& chain : chains) {
    ScoredSkeleton::SpineRegion r;
    r.axis.assign(chain.size(), glm::dvec3(0, 1, 0));
    for (size_t k = 1; k < chain.size(); ++k) {
      const glm::dvec3 d = restPos(chain[k]) - restPos(chain[k - 1]);
      if (glm::length(d) > 1e-6) r.axis[k] = glm::normalize(d);
    }
    r.chain = std::move(chain);
    if (r.chain.size() > 2) s.spineRegions.push_back(std::move(r));
  }
  const int spineRoot = spine.size() > 1 ? spine[1] : -1;  // the first joint above the hips
  const std::array<HumanBone, 2> hands{HumanBone::leftHand, HumanBone::rightHand};
  for (size_t j = 0; j < sk.joints.size(); ++j) {
    const int ji = int(j);
    // The body is the hips and what hangs below them: a root bone above the hips (Reallusion's
    // RL_BoneRoot) carries no body part and stays where the rest put it in a solution.
    if (avatar.clip.joints[j].endSite || !below(hips, ji)) continue;
    s.groups[kAll].push_back(ji);
    const bool inHand = below(joint(hands[0]), ji) || below(joint(hands[1]), ji);
    const bool handItself = ji == joint(hands[0]) || ji == joint(hands[1]);
    const bool belowHead = below(head, ji) && ji != head;
    if (ji == hips) s.groups[kRoot].push_back(ji);
    if (ji == head) s.groups[kHead].push_back(ji);
    if (handItself) s.groups[kHands].push_back(ji);
    if (below(joint(HumanBone::leftFoot), ji) || below(joint(HumanBone::rightFoot), ji)) s.groups[kFeet].push_back(ji);
    if (below(spineRoot, ji) && (!inHand || handItself) && !belowHead) s.groups[kUpper].push_back(ji);
    else if (below(hips, ji) && ji != hips && !below(spineRoot, ji)) s.groups[kLower].push_back(ji);
  }
  const std::array<HumanBone, 2> upperLegs{HumanBone::leftUpperLeg, HumanBone::rightUpperLeg};
  for (size_t side = 0; side < 2; ++side) {
    const bool left = side == 0;
    s.legs[side] = {joint(upperLegs[side]), joint(left ? HumanBone::leftLowerLeg : HumanBone::rightLowerLeg),
                    joint(left ? HumanBone::leftFoot : HumanBone::rightFoot)};
    s.arms[side] = {joint(left ? HumanBone::leftUpperArm : HumanBone::rightUpperArm),
                    joint(left ? HumanBone::leftLowerArm : HumanBone::rightLowerArm), joint(hands[side])};
    const int ankle = s.legs[side][2];
    if (ankle >= 0)
      for (size_t j = size_t(ankle); j < sk.joints.size(); ++j)
        if (sk.isAncestor(ankle, int(j))) s.soles[side].push_back(int(j));  // the ankle first
    // The sole under a bare ankle, as the clip's floor has it (avatar::BvhBody::soleBelowFoot).
    if (ankle >= 0 && ankle == avatar.mapping.body.joint(left ? HumanBone::leftFoot : HumanBone::rightFoot))
      s.soleBelowAnkle[side] = avatar.mapping.body.soleBelowFoot[side] * avatar.mapping.scale;
  }
  // Standing pelvis height: the rest pelvis above the rest soles.
  if (hips >= 0) {
    double sole = 1e300;
    for (size_t side = 0; side < 2; ++side)
      for (int j : s.soles[side]) sole = std::min(sole, restPos(j).y - (j == s.soles[side][0] ? s.soleBelowAnkle[side] : 0.0));
    if (sole < 1e299) s.standingPelvisHeight = restPos(hips).y - sole;
  }
  return s;
}

constexpr EnumName<TrackerSet> kTrackerSetNames[] = {
    {TrackerSet::Three, "3"}, {TrackerSet::Four, "4"}, {TrackerSet::Six, "6"}, {TrackerSet::Full, "full"}};

bool parseTrackerSet(std::string_view text, TrackerSet& out) {
  return parseEnumName(kTrackerSetNames, text, out);
}

const char* trackerSetName(TrackerSet set) {
  return enumName(kTrackerSetNames, set);
}

tracking::TrackerMask trackerMask(TrackerSet set) {
  switch (set) {
    case TrackerSet::Three: return tracking::TrackerMask::threePoint();
    case TrackerSet::Four: return {TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand, TrackerId::Hips};
    case TrackerSet::Six:
    case TrackerSet::Full: return tracking::TrackerMask::all();
  }
  return tracking::TrackerMask::all();
}

constexpr EnumName<Method> kMethodNames[] = {
    {Method::Coupled, "coupled"}, {Method::Uncoupled, "uncoupled"}, {Method::Naive, "naive"}};

const char* methodName(Method m) {
  return enumName(kMethodNames, m);
}

Result<ClipEval> evaluateClip(const tracking::BvhAvatar& avatar, const EvalOptions& o, tracking::SolvedMotionBvh* solvedBvh) {
  ClipEval e;
  e.clip = avatar.asset.sourcePath;
  e.fps = o.fps > 0.0 ? o.fps : 1.0 / avatar.clip.frameTime;
  if (!(e.fps > 0.0 && std::isfinite(e.fps))) return Error{"the clip has no frame time"};
  const tracking::TrackerMask need = trackerMask(o.trackers);
  for (auto id : tracking::kAllTrackers)
    if (need.has(id) && !avatar.trace.trackers.has(id))
      return Error{"the clip has no joint for the " + std::string(tracking::trackerKey(id)) + " tracker"};
  // Every evaluated time lies inside the clip (the source is invalid past its last sample).
  const double duration = avatar.trace.samples.size() > 1 ? avatar.trace.samples.back().time - avatar.trace.samples.front().time : 0.0;
  e.frames = int(std::floor(duration * e.fps - 1e-9)) + 1;
  if (duration <= 0.0 || e.frames < 4) return Error{"the clip is too short to score (fewer than 4 frames at the chosen rate)"};
  e.truth = truthTrack(avatar, e.fps, e.frames);
  e.skeleton = scoredSkeleton(avatar);
  for (const auto& j : avatar.clip.joints) e.jointNames.push_back(j.name);
  e.notes = avatar.mapping.notes;
  for (Method m : kMethods) {
    const auto started = std::chrono::steady_clock::now();
    MethodRun run;
    run.method = m;
    if (m == Method::Naive) {
      run.solved = naiveTrack(avatar, e.fps, e.frames);
    } else {
      auto t = runtimeTrack(avatar, o, m == Method::Coupled, e.fps, e.truth, m == Method::Coupled ? solvedBvh : nullptr, run);
      if (!t) return Error{t.error()};
      run.solved = std::move(t).value();
    }
    run.metrics = score(run.solved, e.truth, e.skeleton, e.fps);
    run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    e.runs.push_back(std::move(run));
  }
  return e;
}

}  // namespace embody::eval
