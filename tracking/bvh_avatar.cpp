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
constexpr double kMaxRestTilt = 0.20943951023931953;  // 12 degrees
constexpr double kAxisSnap = 0.3490658503988659;     // 20 degrees

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
// zero-channel pose is upside down) would give an avatar that scores garbage. Standing means
// upright in tracking space too: the head over the feet within kMaxRestTilt of +Y. A rest that
// lies along another axis than the motion stands on (a Z-up world rotating a Y-up skeleton in
// its root) once passed the looser test and scored 27-41 cm at exit 0.
Status checkStanding(const avatar::AvatarAsset& asset) {
  const avatar::HumanoidMap& map = asset.humanoid;
  if (!map.missingRequired.empty()) {
    std::string missing;
    for (auto b : map.missingRequired) missing += (missing.empty() ? "" : ", ") + std::string(avatar::humanBoneName(b));
    return Error{"not mappable to a humanoid (missing: " + missing + ")"};
  }
  std::vector<glm::mat4> g;
  avatar::computeGlobals(asset.skeleton, avatar::SkeletonPose::rest(asset.skeleton), g);
  auto at = [&](HumanBone b) { return glm::dvec3(g[size_t(map.joint(b))][3]); };
  auto y = [&](HumanBone b) { return at(b).y; };
  const double hips = y(HumanBone::hips), head = y(HumanBone::head);
  const double height = head - std::min(y(HumanBone::leftFoot), y(HumanBone::rightFoot));
  if (!(head > hips && height > 0.0) || y(HumanBone::leftFoot) > hips - 0.2 * height ||
      y(HumanBone::rightFoot) > hips - 0.2 * height)
    return Error{"not a standing body (head above the hips, feet below them)"};
  const glm::dvec3 body = at(HumanBone::head) - 0.5 * (at(HumanBone::leftFoot) + at(HumanBone::rightFoot));
  if (body.y < std::cos(kMaxRestTilt) * glm::length(body))
    return Error{"not a standing body (tilted more than 12 degrees from the motion's up)"};
  return Status::success();
}

// The nearest of the 24 turns between axes (a signed permutation matrix of determinant 1) when
// `r` is within kAxisSnap of it; `r` otherwise.
glm::dmat3 snapToAxes(const glm::dmat3& r, bool& snapped) {
  snapped = false;
  glm::dmat3 a(0.0);
  for (int c = 0; c < 3; ++c) {
    int k = 0;
    for (int i = 1; i < 3; ++i)
      if (std::abs(r[c][i]) > std::abs(r[c][k])) k = i;
    a[c][k] = r[c][k] > 0.0 ? 1.0 : -1.0;
  }
  if (std::abs(glm::determinant(a) - 1.0) > 1e-9) return r;
  const glm::dmat3 between = glm::transpose(a) * r;  // the turn left over after the snap
  const double cosAngle = 0.5 * (between[0][0] + between[1][1] + between[2][2] - 1.0);
  snapped = cosAngle >= std::cos(kAxisSnap);
  return snapped ? a : r;
}

// The turn that stands a rest pose upright and facing forward in tracking space (+Y up, facing
// -Z): its up from the feet to the head, its left from the right foot and hand to the left ones.
// A skeleton authored in other axes than its motion is off by a turn between axes, and a standing
// body is not exactly straight over its feet (the CMU rest leans 4 degrees), so a turn within
// kAxisSnap of one between axes is taken as that one (`betweenAxes`): the rest then stands as the
// skeleton was authored. Identity when the joints are missing or degenerate.
glm::dquat uprightTurn(const std::vector<glm::dvec3>& restXr, const BvhMapping& m, bool& betweenAxes) {
  betweenAxes = false;
  auto at = [&](TrackerId id, glm::dvec3& p) {
    const int j = m.joint[size_t(index(id))];
    if (j >= 0) p = restXr[size_t(j)];
    return j >= 0;
  };
  glm::dvec3 head, lf, rf, lh, rh;
  if (!at(TrackerId::Head, head) || !at(TrackerId::LeftFoot, lf) || !at(TrackerId::RightFoot, rf) ||
      !at(TrackerId::LeftHand, lh) || !at(TrackerId::RightHand, rh))
    return glm::dquat(1.0, 0.0, 0.0, 0.0);
  const glm::dvec3 up = head - 0.5 * (lf + rf);
  glm::dvec3 left = (lf - rf) + (lh - rh);
  left -= up * (glm::dot(left, up) / std::max(glm::dot(up, up), 1e-300));
  if (!(glm::length(up) > 1e-9 && glm::length(left) > 1e-3 * glm::length(up))) return glm::dquat(1.0, 0.0, 0.0, 0.0);
  const glm::dvec3 u = glm::normalize(up), l = glm::normalize(left), back = glm::cross(-l, u);
  // The rest's right, up and back as columns; the turn takes them to +X, +Y, +Z.
  const glm::dmat3 restAxes(-l, u, back);
  return glm::normalize(glm::quat_cast(snapToAxes(glm::transpose(restAxes), betweenAxes)));
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
double restLift(const std::vector<glm::dvec3>& restXr, const BvhMapping& m, double lowest, double standingAnkle) {
  const int left = m.joint[size_t(index(TrackerId::LeftFoot))], right = m.joint[size_t(index(TrackerId::RightFoot))];
  if (left < 0 || right < 0 || !std::isfinite(standingAnkle)) return 0.0;
  const double ankle = std::min(restXr[size_t(left)].y, restXr[size_t(right)].y) - lowest;
  const double lift = standingAnkle - ankle;
  return std::abs(lift) <= kMaxRestLift ? lift : 0.0;
}

// The clip's rest pose: its joints at `frame` (empty: every channel zero) in tracking space (world
// positions and rotations), turned by `turn` about the origin.
struct RestPose {
  std::vector<BvhGlobal> file;     // the clip's globals, file axes and units
  std::vector<glm::dvec3> position;  // tracking space, metres, turned
};

RestPose restPose(const avatar::BvhClip& clip, const BvhMapping& m, std::span<const float> frame, const glm::dquat& turn) {
  RestPose r;
  avatar::bvhGlobals(clip, frame, r.file);
  r.position.reserve(r.file.size());
  for (const auto& g : r.file) r.position.push_back(turn * (m.toXr * g.position * m.scale));
  return r;
}

// The avatar from the clip's joints with the rest pose of `frame` (empty: every channel zero),
// turned by `turn` (the identity, or uprightTurn for a rest lying along another axis than the
// motion's up): rotations and offsets turned into tracking axes, standing over the origin with its
// ankles at `standingAnkle` (restLift), a capsule per bone, mapped, and checked to be a standing body.
Status buildSkeleton(const avatar::BvhClip& clip, const BvhMapping& m, std::span<const float> frame, const glm::dquat& turn,
                     double standingAnkle, avatar::AvatarAsset& asset, double& lift) {
  asset = avatar::AvatarAsset();
  asset.format = avatar::AvatarFormat::Procedural;
  const RestPose rest = restPose(clip, m, frame, turn);
  const glm::dquat q = glm::quat_cast(m.toXr);
  double lowest = 1e300;
  for (const auto& p : rest.position) lowest = std::min(lowest, p.y);
  lowest = m.body.lowestWithBareSoles(lowest, m.scale, [&](size_t, int foot) { return rest.position[size_t(foot)].y; });
  lift = restLift(rest.position, m, lowest, standingAnkle);
  lowest -= lift;
  for (size_t j = 0; j < clip.joints.size(); ++j) {
    const avatar::BvhJoint& b = clip.joints[j];
    avatar::Joint joint;
    joint.name = b.name;
    joint.parent = b.parent;
    glm::dvec3 t = m.toXr * b.offset * m.scale;
    if (b.parent < 0) t = glm::dvec3(0.0, rest.position[j].y - lowest, 0.0);
    const glm::dquat local =
        b.parent < 0 ? rest.file[j].rotation : glm::conjugate(rest.file[size_t(b.parent)].rotation) * rest.file[j].rotation;
    const glm::dquat inXr = q * local * glm::conjugate(q);
    joint.rest.translation = glm::vec3(t);
    joint.rest.rotation = glm::quat(glm::normalize(b.parent < 0 ? turn * inXr : inXr));
    asset.skeleton.joints.push_back(std::move(joint));
  }
  if (const std::string bad = asset.skeleton.validate(); !bad.empty()) return Error{"BVH skeleton: " + bad};
  avatar::buildCapsuleMesh(asset, float(m.heightUnits * m.scale), m.joint[size_t(index(TrackerId::Hips))]);
  if (auto s = avatar::prepareAvatar(asset, ""); !s) return Error{s.error()};
  return checkStanding(asset);
}

// The mapping's references were taken at zero channels, where every joint's world rotation is the
// identity; at the rest pose of `frame` turned by `restTurn` each tracker joint is turned by its
// world rotation there.
void turnReferences(const avatar::BvhClip& clip, std::span<const float> frame, const glm::dquat& restTurn, BvhMapping& m) {
  std::vector<BvhGlobal> g;
  avatar::bvhGlobals(clip, frame, g);
  const glm::dquat q = glm::quat_cast(m.toXr);
  for (auto id : kAllTrackers) {
    const size_t i = size_t(index(id));
    if (m.joint[i] < 0) continue;
    const glm::dquat turn = glm::normalize(restTurn * q * g[size_t(m.joint[i])].rotation * glm::conjugate(q));
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
  // stood up and faced forward first when it is authored in other axes than the motion (a Z-up
  // world turning a Y-up skeleton in the root's channels lays it on its back or side at zero
  // channels: scored 27-41 cm, or refused, where the same clip authored in one set of axes scores
  // 6.3); else the clip's first frame (CC_Base exports point the legs up at zero channels; their
  // first frame is the performer standing or a T-pose); else the zero-channel pose stood up by
  // the turn that puts its head over its feet. A clip standing in none is refused.
  const double standingAnkle = standingAnkleHeight(*trace);
  const glm::dquat none(1.0, 0.0, 0.0, 0.0);
  bool betweenAxes = false;
  const glm::dquat upright = uprightTurn(restPose(clip, m, {}, none).position, m, betweenAxes);
  const glm::dquat authored = betweenAxes ? upright : none;
  auto useTurn = [&](const glm::dquat& turn) {
    out.restTurn = turn;
    turnReferences(clip, {}, turn, out.mapping);
    char note[200];
    std::snprintf(note, sizeof note,
                  "rest pose turned %.0f degrees to stand upright, facing forward: the skeleton is authored in other axes "
                  "than its motion",
                  glm::degrees(2.0 * std::acos(std::min(1.0, std::abs(turn.w)))));
    out.mapping.notes.push_back(note);
  };
  Status built = buildSkeleton(clip, m, {}, authored, standingAnkle, out.asset, out.restLift);
  if (built && betweenAxes && std::abs(std::abs(authored.w) - 1.0) > 1e-12) useTurn(authored);
  if (!built && clip.frameCount > 0) {
    const std::string zeroChannels = built.error();
    built = buildSkeleton(clip, m, clip.frame(0), none, standingAnkle, out.asset, out.restLift);
    if (built) {
      out.restFromFirstFrame = true;
      turnReferences(clip, clip.frame(0), none, out.mapping);
    } else {
      const std::string firstFrame = built.error();
      built = buildSkeleton(clip, m, {}, upright, standingAnkle, out.asset, out.restLift);
      if (!built)
        return Error{"the clip cannot be an avatar: its zero-channel pose is " + zeroChannels + ", its first frame is " +
                     firstFrame + ", and stood upright its zero-channel pose is " + built.error()};
      useTurn(upright);
    }
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
