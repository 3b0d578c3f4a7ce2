#include "tracking/bvh_avatar.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "avatar/avatar_loader.h"
#include "avatar/procedural/capsule_mesh.h"
#include "core/percentile.h"

namespace embody::tracking {

namespace {

using avatar::BvhGlobal;
using avatar::HumanBone;

constexpr double kMaxRestLift = 0.15;  // metres

// The clip's joints at one file frame, in tracking space.
void jointsAtFrame(const avatar::BvhClip& clip, const BvhMapping& m, size_t frame, std::vector<BvhGlobal>& out) {
  avatar::bvhGlobals(clip, clip.frame(frame), out);
  const glm::dquat q = glm::quat_cast(m.toXr);
  for (auto& g : out) {
    g.position = m.toXr * g.position * m.scale + m.shift;
    g.rotation = glm::normalize(q * g.rotation * glm::conjugate(q));
  }
}

// The rest pose must be a standing body: a mapper fed anything else (CC_Base exports, whose
// zero-channel pose points the legs up) would give an avatar that scores garbage.
Status checkStanding(const avatar::AvatarAsset& asset) {
  const avatar::HumanoidMap& map = asset.humanoid;
  if (!map.missingRequired.empty()) {
    std::string missing;
    for (auto b : map.missingRequired) missing += (missing.empty() ? "" : ", ") + std::string(avatar::humanBoneName(b));
    return Error{"not mappable to a humanoid (missing: " + missing + ")"};
  }
  std::vector<glm::mat4> g;
  avatar::computeGlobals(asset.skeleton, avatar::SkeletonPose::rest(asset.skeleton), g);
  auto y = [&](HumanBone b) { return double(g[size_t(map.joint(b))][3].y); };
  const double hips = y(HumanBone::hips), head = y(HumanBone::head);
  const double height = head - std::min(y(HumanBone::leftFoot), y(HumanBone::rightFoot));
  if (!(head > hips && height > 0.0) || y(HumanBone::leftFoot) > hips - 0.2 * height ||
      y(HumanBone::rightFoot) > hips - 0.2 * height)
    return Error{"not a standing body (head above the hips, feet below them)"};
  return Status::success();
}

// How high the clip's ankles stand: the lower ankle's height over the trace's frames, at the
// floor's percentile (its standing frames, as the floor's own estimate, bvh_source.cpp). NaN
// without both feet.
double standingAnkleHeight(const Trace& trace) {
  std::vector<double> lower;
  lower.reserve(trace.samples.size());
  if (trace.trackers.has(TrackerId::LeftFoot) && trace.trackers.has(TrackerId::RightFoot))
    for (const PoseSample& s : trace.samples)
      if (s[TrackerId::LeftFoot].valid && s[TrackerId::RightFoot].valid)
        lower.push_back(std::min(s[TrackerId::LeftFoot].position.y, s[TrackerId::RightFoot].position.y));
  return percentileByRank(lower, kFloorPercentile);  // NaN for none
}

// How far above the floor the rest pose stands (tracking/bvh_avatar.h): its lower ankle at the
// height the clip's ankles stand at (`standingAnkle`), where the body solver plants an ankle.
// Standing the rest's lowest joint on the floor instead trusts the clip's lowest joint to be the
// sole, and it is not: cgspeed's toe end sites hang 2.8 cm under the ankle at rest but 4-9 cm in
// the motion, so `cmu_131_02`'s ankles stand 10.2 cm above the floor and the rest's 2.8; a
// three-point body planted its feet 7 cm low and bent its trunk to make up the eyes' height
// (docs/eval.md, session 10). 0 without feet, or when the two differ by more than 15 cm.
double restLift(const std::vector<BvhGlobal>& rest, const BvhMapping& m, double lowest, double standingAnkle) {
  const int left = m.joint[size_t(index(TrackerId::LeftFoot))], right = m.joint[size_t(index(TrackerId::RightFoot))];
  if (left < 0 || right < 0 || !std::isfinite(standingAnkle)) return 0.0;
  const double ankle = std::min((m.toXr * rest[size_t(left)].position * m.scale).y,
                                (m.toXr * rest[size_t(right)].position * m.scale).y) - lowest;
  const double lift = standingAnkle - ankle;
  return std::abs(lift) <= kMaxRestLift ? lift : 0.0;
}

// The avatar from the clip's joints with the rest pose of `frame` (empty: every channel zero):
// rotations and offsets turned into tracking axes, standing over the origin with its ankles at
// `standingAnkle` (restLift), a capsule per bone, mapped, and checked to be a standing body.
Status buildSkeleton(const avatar::BvhClip& clip, const BvhMapping& m, std::span<const float> frame, double standingAnkle,
                     avatar::AvatarAsset& asset, double& lift) {
  asset = avatar::AvatarAsset();
  asset.format = avatar::AvatarFormat::Procedural;
  std::vector<BvhGlobal> rest;
  avatar::bvhGlobals(clip, frame, rest);
  const glm::dquat q = glm::quat_cast(m.toXr);
  double lowest = 1e300;
  for (const auto& g : rest) lowest = std::min(lowest, (m.toXr * g.position * m.scale).y);
  for (size_t i = 0; i < 2; ++i)  // the sole under a bare ankle, as the floor has it (BvhBody::soleBelowFoot)
    if (const int foot = m.body.joint(i == 0 ? HumanBone::leftFoot : HumanBone::rightFoot); foot >= 0 && m.body.soleBelowFoot[i] > 0.0)
      lowest = std::min(lowest, (m.toXr * rest[size_t(foot)].position * m.scale).y - m.body.soleBelowFoot[i] * m.scale);
  lift = restLift(rest, m, lowest, standingAnkle);
  lowest -= lift;
  for (size_t j = 0; j < clip.joints.size(); ++j) {
    const avatar::BvhJoint& b = clip.joints[j];
    avatar::Joint joint;
    joint.name = b.name;
    joint.parent = b.parent;
    glm::dvec3 t = m.toXr * b.offset * m.scale;
    if (b.parent < 0) t = glm::dvec3(0.0, (m.toXr * rest[j].position * m.scale).y - lowest, 0.0);
    const glm::dquat local = b.parent < 0 ? rest[j].rotation : glm::conjugate(rest[size_t(b.parent)].rotation) * rest[j].rotation;
    joint.rest.translation = glm::vec3(t);
    joint.rest.rotation = glm::quat(glm::normalize(q * local * glm::conjugate(q)));
    asset.skeleton.joints.push_back(std::move(joint));
  }
  if (const std::string bad = asset.skeleton.validate(); !bad.empty()) return Error{"BVH skeleton: " + bad};
  avatar::buildCapsuleMesh(asset, float(m.heightUnits * m.scale), m.joint[size_t(index(TrackerId::Hips))]);
  if (auto s = avatar::prepareAvatar(asset, ""); !s) return Error{s.error()};
  return checkStanding(asset);
}

// The mapping's references were taken at zero channels, where every joint's world rotation is the
// identity; at the rest pose of `frame` each tracker joint is turned by its world rotation there.
void turnReferences(const avatar::BvhClip& clip, std::span<const float> frame, BvhMapping& m) {
  std::vector<BvhGlobal> g;
  avatar::bvhGlobals(clip, frame, g);
  const glm::dquat q = glm::quat_cast(m.toXr);
  for (auto id : kAllTrackers) {
    const size_t i = size_t(index(id));
    if (m.joint[i] < 0) continue;
    const glm::dquat turn = glm::normalize(q * g[size_t(m.joint[i])].rotation * glm::conjugate(q));
    m.reference[i] = turn * m.reference[i];
    if (id == TrackerId::Head) m.eyeOffset = turn * m.eyeOffset;
  }
}

}  // namespace

Result<BvhAvatar> buildBvhAvatar(avatar::BvhClip clip, const BvhTrackerOptions& options) {
  if (clip.joints.empty() || clip.frameCount == 0) return Error{"the BVH clip has no joints or no frames"};
  // The clip's joints are what the solved body is scored against: repaired as the trace is.
  if (auto r = repairBvhGlitches(clip); !r) return Error{r.error()};
  // --bvh-mirror: the clip itself mirrored, so its joints beside the body are the trace's.
  BvhTrackerOptions o = options;
  if (options.body.mirror) {
    avatar::mirrorBvhClip(clip);
    o.body = avatar::mirroredBvhOptions(options.body);
  }
  BvhAvatar out;
  auto trace = bvhToTrace(clip, o, &out.mapping);
  if (!trace) return Error{trace.error()};
  if (options.body.mirror) {
    out.mapping.notes.push_back("--bvh-mirror: the clip read mirrored across its X axis");
    trace->notes.push_back(out.mapping.notes.back());
  }
  const BvhMapping& m = out.mapping;  // (turnReferences may update it below)

  // The skeleton's rest pose: the zero-channel pose when it is a standing body (CMU, most tools),
  // else the clip's first frame (CC_Base exports point the legs up at zero channels; their first
  // frame is the performer standing or a T-pose). A clip standing in neither is refused.
  const double standingAnkle = standingAnkleHeight(*trace);
  Status built = buildSkeleton(clip, m, {}, standingAnkle, out.asset, out.restLift);
  if (!built && clip.frameCount > 0) {
    const std::string zeroChannels = built.error();
    built = buildSkeleton(clip, m, clip.frame(0), standingAnkle, out.asset, out.restLift);
    if (!built)
      return Error{"the clip cannot be an avatar: its zero-channel pose is " + zeroChannels + ", its first frame is " +
                   built.error()};
    out.restFromFirstFrame = true;
    turnReferences(clip, clip.frame(0), out.mapping);
  }
  if (!built) return Error{"the clip cannot be an avatar: " + built.error()};
  if (std::abs(out.restLift) >= 0.005) {
    char note[160];
    std::snprintf(note, sizeof note, "rest pose %s %.1f cm: its ankles stand where the clip's do",
                  out.restLift > 0 ? "lifted" : "lowered", 100.0 * std::abs(out.restLift));
    out.mapping.notes.push_back(note);
  }
  out.trace = std::move(trace).value();
  out.clip = std::move(clip);
  return out;
}

Result<BvhAvatar> loadBvhAvatar(const std::string& path, const BvhTrackerOptions& options) {
  auto clip = avatar::loadBvh(path);
  if (!clip) return Error{clip.error()};
  auto built = buildBvhAvatar(std::move(clip).value(), options);
  if (!built) return Error{path + ": " + built.error()};
  built->asset.sourcePath = path;
  return built;
}

void bvhJointsAt(const avatar::BvhClip& clip, const BvhMapping& m, double t, std::vector<BvhGlobal>& out) {
  // Frame index in the file: the trace starts at m.firstFrame; clamp to the clip.
  const double last = double(clip.frameCount - 1);
  const double f = std::clamp(double(m.firstFrame) + (clip.frameTime > 0.0 ? t / clip.frameTime : 0.0), 0.0, last);
  const auto f0 = size_t(std::floor(f));
  const size_t f1 = std::min(f0 + 1, clip.frameCount - 1);
  const double a = f - double(f0);
  jointsAtFrame(clip, m, f0, out);
  if (a < 1e-12 || f1 == f0) return;
  thread_local std::vector<BvhGlobal> next;
  jointsAtFrame(clip, m, f1, next);
  for (size_t j = 0; j < out.size(); ++j) {
    out[j].position = glm::mix(out[j].position, next[j].position, a);
    out[j].rotation = glm::slerp(out[j].rotation, next[j].rotation, a);
  }
}

void bvhPoseAt(const BvhAvatar& avatar, double t, avatar::SkeletonPose& pose) {
  thread_local std::vector<BvhGlobal> g;
  bvhJointsAt(avatar.clip, avatar.mapping, t, g);
  const auto& joints = avatar.asset.skeleton.joints;
  pose = avatar::SkeletonPose::rest(avatar.asset.skeleton);
  for (size_t j = 0; j < joints.size(); ++j) {
    const int p = joints[j].parent;
    glm::dquat r = g[j].rotation;
    glm::dvec3 x = g[j].position;
    if (p >= 0) {
      const glm::dquat inv = glm::conjugate(g[size_t(p)].rotation);
      r = inv * r;
      x = inv * (x - g[size_t(p)].position);
    }
    pose.local[j].rotation = glm::normalize(glm::quat(r));
    pose.local[j].translation = glm::vec3(x);
  }
}

}  // namespace embody::tracking
