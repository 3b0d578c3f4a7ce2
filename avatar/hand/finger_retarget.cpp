// Finger rig (rest geometry of the humanoid finger bones) and the per-frame retargeting job.
#include "avatar/hand/finger_retarget.h"

#include "core/angles.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace embody::avatar {
namespace {

constexpr float kDegF = float(embody::kDeg);

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const glm::quat& q) {
  return std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

// Rotation of the joint's frame in model space, composed from the pose's local rotations.
glm::quat globalRotation(const Skeleton& skeleton, const SkeletonPose& pose, int joint) {
  glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
  for (int j = joint; j >= 0; j = skeleton.joints[static_cast<size_t>(j)].parent)
    q = pose.local[static_cast<size_t>(j)].rotation * q;
  return glm::normalize(q);
}

// The same for a joint at or below `hand`, whose model-space rotation is already known: walks up
// to the hand only (the chain above it, often 30 vertebrae deep, is composed once per hand).
glm::quat rotationBelowHand(const Skeleton& skeleton, const SkeletonPose& pose, int joint, int hand,
                            const glm::quat& handGlobal) {
  glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
  int j = joint;
  for (; j >= 0 && j != hand; j = skeleton.joints[static_cast<size_t>(j)].parent)
    q = pose.local[static_cast<size_t>(j)].rotation * q;
  return glm::normalize(j == hand ? handGlobal * q : q);
}

// The smallest rotation taking unit vector a onto unit vector b (any axis when they are opposite).
glm::quat fromTo(const glm::vec3& a, const glm::vec3& b) {
  const float c = glm::dot(a, b);
  if (c < -0.99999f) {
    glm::vec3 axis = glm::cross(glm::vec3(1.0f, 0.0f, 0.0f), a);
    if (glm::dot(axis, axis) < 1e-6f) axis = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), a);
    return glm::angleAxis(std::numbers::pi_v<float>, glm::normalize(axis));
  }
  const glm::vec3 x = glm::cross(a, b);
  return glm::normalize(glm::quat(1.0f + c, x.x, x.y, x.z));
}

float angleBetween(const glm::vec3& a, const glm::vec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b));
}

// Tracked joints of the segment a finger bone stands for.
void trackedSegment(int finger, int segment, HandJoint& from, HandJoint& to) {
  const int base = finger == 0 ? static_cast<int>(HandJoint::ThumbMetacarpal)
                               : static_cast<int>(HandJoint::IndexProximal) + (finger - 1) * 5;
  from = static_cast<HandJoint>(base + segment);
  to = static_cast<HandJoint>(base + segment + 1);
}

constexpr std::array<HandJoint, 4> kKnuckles = {HandJoint::IndexProximal, HandJoint::MiddleProximal,
                                                HandJoint::RingProximal, HandJoint::LittleProximal};

}  // namespace

FingerLimits defaultFingerLimits(int finger, int segment) {
  // Degrees, from hand anatomy ranges (MCP, PIP, DIP; thumb CMC, MCP, IP), a little generous so
  // that tracking noise near the ends is not flattened. The thumb's ranges are wide on both axes:
  // measured against the hand's back its flexion is mostly sideways across the palm.
  struct L {
    float minFlex, maxFlex, spread, twist;
  };
  static constexpr L kThumb[3] = {{-35, 65, 55, 0}, {-25, 80, 35, 0}, {-25, 95, 20, 0}};
  static constexpr L kFinger[3] = {{-30, 95, 25, 10}, {-5, 115, 8, 5}, {-15, 95, 8, 5}};
  const L& l = finger == 0 ? kThumb[segment] : kFinger[segment];
  return {l.minFlex * kDegF, l.maxFlex * kDegF, l.spread * kDegF, l.twist * kDegF};
}

HumanBone fingerHumanBone(bool left, int finger, int segment) {
  const int first = static_cast<int>(left ? HumanBone::leftThumbMetacarpal : HumanBone::rightThumbMetacarpal);
  return static_cast<HumanBone>(first + finger * kFingerSegments + segment);
}

int countFingerBones(const HumanoidMap& map) {
  int n = 0;
  for (bool left : {true, false})
    for (int f = 0; f < kFingerCount; ++f)
      for (int s = 0; s < kFingerSegments; ++s) n += map.has(fingerHumanBone(left, f, s)) ? 1 : 0;
  return n;
}

bool handFrameFromKnuckles(const glm::vec3& wrist, const std::array<glm::vec3, 4>& knuckles,
                           const std::array<bool, 4>& use, bool left, glm::quat& frame) {
  glm::vec3 mean(0.0f);
  int n = 0, first = -1, last = -1;
  for (int i = 0; i < 4; ++i) {
    if (!use[static_cast<size_t>(i)]) continue;
    mean += knuckles[static_cast<size_t>(i)];
    ++n;
    if (first < 0) first = i;
    last = i;
  }
  if (n < 2 || first == last) return false;
  glm::vec3 f = mean / float(n) - wrist;  // towards the fingers
  if (!finite(f) || glm::length(f) < 1e-6f) return false;
  f = glm::normalize(f);
  glm::vec3 s =
      knuckles[static_cast<size_t>(first)] - knuckles[static_cast<size_t>(last)];  // little -> index
  s -= glm::dot(s, f) * f;
  if (!finite(s) || glm::length(s) < 1e-6f) return false;
  s = glm::normalize(s);  // the thumb side
  // OpenXR wrist axes: Z = -fingers; X = away from the thumb (right hand) / towards it (left);
  // Y = Z x X, out of the back of the hand.
  const glm::vec3 z = -f, x = left ? s : -s, y = glm::cross(z, x);
  frame = glm::normalize(glm::quat_cast(glm::mat3(x, y, z)));
  return true;
}

namespace {

// The rest skeleton in model space, as buildFingerRig measures it.
struct RestHand {
  const Skeleton& skeleton;
  const HumanoidMap& map;
  const SkeletonPose rest;
  std::vector<glm::mat4> globals;
  RestHand(const Skeleton& sk, const HumanoidMap& m) : skeleton(sk), map(m), rest(SkeletonPose::rest(sk)) {
    computeGlobals(sk, rest, globals);
  }
  glm::vec3 position(int j) const { return glm::vec3(globals[static_cast<size_t>(j)][3]); }
  int jointCount() const { return static_cast<int>(skeleton.joints.size()); }
};

// Where a finger bone points at rest (model space, not normalised; zero when it has no
// direction): the next mapped finger bone below it, else its first child apart from it, else on
// along the previous segment (or from the hand, for a lone bone).
glm::vec3 restBoneDirection(const RestHand& r, bool left, int f, int s, int j, int hand, const glm::vec3& previousDir) {
  glm::vec3 dir(0.0f);
  const int next = s + 1 < kFingerSegments ? r.map.joint(fingerHumanBone(left, f, s + 1)) : -1;
  if (next >= 0 && next < r.jointCount() && next != j && r.skeleton.isAncestor(j, next))
    dir = r.position(next) - r.position(j);
  if (glm::length(dir) < 1e-6f)
    for (int c : r.skeleton.children(j))
      if (glm::length(r.position(c) - r.position(j)) > 1e-6f) {
        dir = r.position(c) - r.position(j);
        break;
      }
  if (glm::length(dir) < 1e-6f) dir = glm::length(previousDir) > 0.0f ? previousDir : r.position(j) - r.position(hand);
  return dir;
}

// The finger bones of one hand whose frame (frameGlobal, model space) is known.
void rigFingerBones(const RestHand& r, const glm::quat& frameGlobal, FingerRigHand& rh, std::vector<std::string>& notes) {
  const bool left = rh.left;
  const int hand = rh.hand;
  auto below = [&](int j) { return j >= 0 && j < r.jointCount() && j != hand && r.skeleton.isAncestor(hand, j); };
  const glm::vec3 dorsalGlobal = frameGlobal * glm::vec3(0.0f, 1.0f, 0.0f);
  for (int f = 0; f < kFingerCount; ++f) {
    glm::vec3 previousDir = glm::vec3(0.0f);  // global rest direction of the previous segment
    for (int s = 0; s < kFingerSegments; ++s) {
      FingerBone& b = rh.bones[static_cast<size_t>(f * kFingerSegments + s)];
      trackedSegment(f, s, b.trackedFrom, b.trackedTo);
      b.limits = defaultFingerLimits(f, s);
      const int j = r.map.joint(fingerHumanBone(left, f, s));
      const std::string name(humanBoneName(fingerHumanBone(left, f, s)));
      if (!below(j)) {
        if (j >= 0) notes.push_back(name + ": not below the hand bone, not driven");
        previousDir = glm::vec3(0.0f);
        continue;
      }
      glm::vec3 dir = restBoneDirection(r, left, f, s, j, hand, previousDir);
      if (glm::length(dir) < 1e-6f) {
        notes.push_back(name + ": no direction (zero-length bone), not driven");
        continue;
      }
      dir = glm::normalize(dir);
      previousDir = dir;
      glm::vec3 dorsal = dorsalGlobal - glm::dot(dorsalGlobal, dir) * dir;
      if (glm::length(dorsal) < 1e-3f) {  // a bone along the back-of-hand normal
        const glm::vec3 x = frameGlobal * glm::vec3(1.0f, 0.0f, 0.0f);
        dorsal = x - glm::dot(x, dir) * dir;
      }
      dorsal = glm::normalize(dorsal);
      const glm::quat inv = glm::conjugate(globalRotation(r.skeleton, r.rest, j));
      b.joint = j;
      b.axis = glm::normalize(inv * dir);
      b.dorsal = glm::normalize(inv * dorsal);
      b.lateral = glm::cross(b.axis, b.dorsal);
      ++rh.mappedBones;
    }
  }
}

}  // namespace

FingerRig buildFingerRig(const Skeleton& skeleton, const HumanoidMap& map) {
  FingerRig rig;
  const RestHand r(skeleton, map);
  for (int h = 0; h < 2; ++h) {
    const bool left = h == 0;
    FingerRigHand& rh = rig.hands[static_cast<size_t>(h)];
    rh.left = left;
    const int hand = map.joint(left ? HumanBone::leftHand : HumanBone::rightHand);
    if (hand < 0 || hand >= r.jointCount()) continue;
    std::array<glm::vec3, 4> knuckles{};
    std::array<bool, 4> use{};
    for (int f = 1; f < kFingerCount; ++f) {
      const int j = map.joint(fingerHumanBone(left, f, 0));
      if (!(j >= 0 && j < r.jointCount() && j != hand && skeleton.isAncestor(hand, j))) continue;
      knuckles[static_cast<size_t>(f - 1)] = r.position(j);
      use[static_cast<size_t>(f - 1)] = true;
      rh.frameFinger[static_cast<size_t>(f)] = true;
    }
    glm::quat frameGlobal;
    if (!handFrameFromKnuckles(r.position(hand), knuckles, use, left, frameGlobal)) {
      if (countFingerBones(map) > 0)
        rig.notes.push_back(std::string(left ? "left" : "right") +
                            " hand: fingers not driven (needs two of the index..little proximal bones "
                            "under the hand bone, apart from each other)");
      rh.frameFinger.fill(false);
      continue;
    }
    rh.hand = hand;
    rh.handFrame = glm::normalize(glm::conjugate(globalRotation(skeleton, r.rest, hand)) * frameGlobal);
    rigFingerBones(r, frameGlobal, rh, rig.notes);
  }
  return rig;
}

bool FingerRetargetJob::Validate() const {
  if (!skeleton || !rig || !state || !pose) return false;
  if (pose->local.size() != skeleton->joints.size()) return false;
  if (!std::isfinite(deltaTime) || deltaTime < 0.0f || !std::isfinite(blendTime) || !(blendTime > 0.0f))
    return false;
  const int n = static_cast<int>(skeleton->joints.size());
  for (const FingerRigHand& rh : rig->hands) {
    if (rh.hand >= n) return false;
    for (const FingerBone& b : rh.bones)
      if (b.joint >= n) return false;
  }
  return true;
}

namespace {

bool jointOk(const TrackedHandJoints& t, HandJoint j) {
  const auto i = static_cast<size_t>(j);
  return t.valid[i] && finite(t.position[i]) && finite(t.orientation[i]);
}

// The tracked hand frame, from the same knuckles as the avatar's; false when not tracked.
bool trackedHandFrame(const FingerRigHand& rh, const TrackedHandJoints* t, glm::quat& frame) {
  frame = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  if (!t || !t->active || !jointOk(*t, HandJoint::Wrist)) return false;
  std::array<glm::vec3, 4> knuckles{};
  std::array<bool, 4> use{};
  for (int f = 1; f < kFingerCount; ++f) {
    if (!rh.frameFinger[static_cast<size_t>(f)]) continue;
    const HandJoint k = kKnuckles[static_cast<size_t>(f - 1)];
    if (!jointOk(*t, k)) return false;
    knuckles[static_cast<size_t>(f - 1)] = t->position[static_cast<size_t>(k)];
    use[static_cast<size_t>(f - 1)] = true;
  }
  return handFrameFromKnuckles(t->position[static_cast<size_t>(HandJoint::Wrist)], knuckles, use, rh.left, frame);
}

// The bone's rotation from its rest frame to the tracked segment (`d`, unit, and `back` = the
// tracked back of the finger, both in the bone's rest frame), within its limits.
glm::quat limitedBoneDelta(const FingerBone& b, const glm::vec3& d, const glm::vec3& back) {
  const float xa = glm::dot(d, b.axis), xn = glm::dot(d, b.dorsal), xl = glm::dot(d, b.lateral);
  const float spread = std::clamp(std::asin(std::clamp(xl, -1.0f, 1.0f)), -b.limits.maxSpread, b.limits.maxSpread);
  const float flexion = std::clamp(std::atan2(-xn, xa), b.limits.minFlexion, b.limits.maxFlexion);
  const glm::vec3 clamped =
      std::cos(spread) * (std::cos(flexion) * b.axis - std::sin(flexion) * b.dorsal) + std::sin(spread) * b.lateral;
  glm::quat delta = fromTo(b.axis, glm::normalize(clamped));
  if (b.limits.maxTwist > 0.0f) {
    // Twist about the bone: the tracked back of the finger (+Y) against the rig's dorsal.
    const glm::vec3 a = glm::normalize(clamped);
    glm::vec3 p1 = delta * b.dorsal, p2 = back;
    p1 -= glm::dot(p1, a) * a;
    p2 -= glm::dot(p2, a) * a;
    if (glm::length(p1) > 1e-3f && glm::length(p2) > 1e-3f) {
      const float twist = std::clamp(std::atan2(glm::dot(glm::cross(p1, p2), a), glm::dot(p1, p2)),
                                     -b.limits.maxTwist, b.limits.maxTwist);
      delta = glm::angleAxis(twist, a) * delta;
    }
  }
  return delta;
}

// One hand's state for a frame: tracked joints -> the avatar's model space via the hand frames.
struct HandFrame {
  const FingerRigHand& rh;
  const TrackedHandJoints* tracked;
  bool ok = false;              // the tracked hand frame is known
  glm::quat handGlobal{1, 0, 0, 0};  // the avatar's hand joint, model space
  glm::quat toAvatar{1, 0, 0, 0};    // tracked directions -> avatar model space
};

// Pass 1 of a finger: the full-weight target rotations, outwards, each relative to its
// retargeted parent (written into the pose so the next segment sees it). A lost finger holds its
// last target while it blends out. `input` gets the pose's rotations as they came.
void writeFingerTargets(const Skeleton& sk, SkeletonPose& p, const HandFrame& hf, size_t first, bool fingerOk,
                        std::array<glm::quat, kFingerBonesPerHand>& last,
                        std::array<glm::quat, kFingerSegments>& input) {
  for (int s = 0; s < kFingerSegments; ++s) {
    const size_t bi = first + static_cast<size_t>(s);
    const FingerBone& b = hf.rh.bones[bi];
    if (b.joint < 0) continue;
    Transform& local = p.local[static_cast<size_t>(b.joint)];
    input[static_cast<size_t>(s)] = local.rotation;
    if (!fingerOk) {
      local.rotation = finite(last[bi]) && glm::length(last[bi]) > 0.5f ? last[bi] : local.rotation;
      continue;
    }
    const glm::quat restLocal = sk.joints[static_cast<size_t>(b.joint)].rest.rotation;
    const glm::quat parentGlobal =
        rotationBelowHand(sk, p, sk.joints[static_cast<size_t>(b.joint)].parent, hf.rh.hand, hf.handGlobal);
    const glm::quat restGlobal = glm::normalize(parentGlobal * restLocal);
    const TrackedHandJoints& t = *hf.tracked;
    const glm::vec3 seg = t.position[static_cast<size_t>(b.trackedTo)] - t.position[static_cast<size_t>(b.trackedFrom)];
    glm::quat delta(1.0f, 0.0f, 0.0f, 0.0f);  // in the bone's rest frame
    if (glm::length(seg) > 1e-6f) {
      const glm::quat toRest = glm::conjugate(restGlobal);
      const glm::vec3 back = t.orientation[static_cast<size_t>(b.trackedFrom)] * glm::vec3(0.0f, 1.0f, 0.0f);
      delta = limitedBoneDelta(b, toRest * (hf.toAvatar * glm::normalize(seg)), toRest * (hf.toAvatar * back));
    }
    const glm::quat target = glm::normalize(restLocal * delta);
    if (finite(target)) {
      local.rotation = target;
      last[bi] = target;
    }
  }
}

// Pass 2: blend each bone of the finger between its input rotation and the target.
void blendFinger(SkeletonPose& p, const FingerRigHand& rh, size_t first, float w,
                 const std::array<glm::quat, kFingerSegments>& input, float* bend) {
  for (int s = 0; s < kFingerSegments; ++s) {
    const size_t bi = first + static_cast<size_t>(s);
    const FingerBone& b = rh.bones[bi];
    if (b.joint < 0) continue;
    Transform& local = p.local[static_cast<size_t>(b.joint)];
    const glm::quat in = input[static_cast<size_t>(s)];
    glm::quat out = w >= 1.0f ? local.rotation : glm::slerp(in, local.rotation, w);
    if (!finite(out)) out = in;
    local.rotation = glm::normalize(out);
    if (bend) bend[bi] = angleBetween(in * b.axis, local.rotation * b.axis);
  }
}

}  // namespace

bool FingerRetargetJob::Run() const {
  const Skeleton& sk = *skeleton;
  SkeletonPose& p = *pose;
  const float step = std::min(1.0f, deltaTime / blendTime);
  for (int h = 0; h < 2; ++h) {
    const size_t hi = static_cast<size_t>(h);
    const FingerRigHand& rh = rig->hands[hi];
    if (output) {
      output->bend[hi].fill(0.0f);
      output->weight[hi].fill(0.0f);
      output->handTracked[hi] = false;
    }
    if (rh.hand < 0) continue;
    HandFrame hf{rh, hands[hi]};
    glm::quat trackedFrame;
    hf.ok = trackedHandFrame(rh, hf.tracked, trackedFrame);
    if (output) output->handTracked[hi] = hf.ok;
    // Tracked model-free directions -> the avatar's model space, through the two hand frames.
    hf.handGlobal = globalRotation(sk, p, rh.hand);
    hf.toAvatar = glm::normalize(hf.handGlobal * rh.handFrame * glm::conjugate(trackedFrame));
    for (int f = 0; f < kFingerCount; ++f) {
      const size_t first = static_cast<size_t>(f * kFingerSegments);
      bool any = false, fingerOk = hf.ok;
      for (int s = 0; s < kFingerSegments; ++s) {
        const FingerBone& b = rh.bones[first + static_cast<size_t>(s)];
        if (b.joint < 0) continue;
        any = true;
        fingerOk = fingerOk && jointOk(*hf.tracked, b.trackedFrom) && jointOk(*hf.tracked, b.trackedTo);
      }
      if (!any) continue;
      float& w = state->weight[hi][static_cast<size_t>(f)];
      w = fingerOk ? std::min(1.0f, w + step) : std::max(0.0f, w - step);
      if (output) output->weight[hi][static_cast<size_t>(f)] = w;
      if (w <= 0.0f) continue;  // the input pose as it is
      std::array<glm::quat, kFingerSegments> input{};
      writeFingerTargets(sk, p, hf, first, fingerOk, state->last[hi], input);
      blendFinger(p, rh, first, w, input, output ? output->bend[hi].data() : nullptr);
    }
  }
  return true;
}

}  // namespace embody::avatar
