#include "tracking/bvh_export.h"

#include "avatar/bvh/bvh_writer.h"

namespace embody::tracking {

using avatar::BvhChannel;

SolvedMotionBvh SolvedMotionBvh::forBvhAvatar(const BvhAvatar& avatar) {
  SolvedMotionBvh out(avatar.asset.skeleton);
  out.clip_.joints = avatar.clip.joints;
  out.clip_.channelCount = avatar.clip.channelCount;
  out.clip_.frameTime = avatar.clip.frameTime;
  out.toAvatar_ = avatar.mapping.toXr;
  out.scale_ = avatar.mapping.scale;
  out.shift_ = avatar.mapping.shift;
  out.bvhOfJoint_.resize(avatar.asset.skeleton.joints.size());
  for (size_t j = 0; j < out.bvhOfJoint_.size(); ++j) out.bvhOfJoint_[j] = int(j);  // joint i = clip joint i
  out.restRotation_.assign(out.bvhOfJoint_.size(), glm::dquat(1, 0, 0, 0));
  return out;
}

SolvedMotionBvh SolvedMotionBvh::forAvatar(const avatar::AvatarAsset& asset, double frameTime) {
  const avatar::Skeleton& sk = asset.skeleton;
  SolvedMotionBvh out(sk);
  out.clip_.frameTime = frameTime;
  std::vector<glm::mat4> g;
  avatar::computeGlobals(sk, avatar::SkeletonPose::rest(sk), g);
  out.bvhOfJoint_.resize(sk.joints.size());
  out.restRotation_.resize(sk.joints.size());
  for (size_t j = 0; j < sk.joints.size(); ++j) {
    avatar::BvhJoint b;
    b.name = sk.joints[j].name;
    b.parent = sk.joints[j].parent;
    const glm::dvec3 p(g[j][3]);
    b.offset = (b.parent < 0 ? p : p - glm::dvec3(g[size_t(b.parent)][3])) / out.scale_;
    if (b.parent < 0) b.channels = {BvhChannel::Xposition, BvhChannel::Yposition, BvhChannel::Zposition};
    b.channels.insert(b.channels.end(), {BvhChannel::Zrotation, BvhChannel::Xrotation, BvhChannel::Yrotation});
    b.firstChannel = out.clip_.channelCount;
    out.clip_.channelCount += int(b.channels.size());
    out.clip_.joints.push_back(std::move(b));
    out.bvhOfJoint_[j] = int(j);
    out.restRotation_[j] = glm::normalize(glm::quat_cast(glm::dmat3(glm::mat3(g[j]))));
  }
  return out;
}

namespace {
bool hasPositionChannel(const avatar::BvhJoint& joint) {
  for (BvhChannel c : joint.channels)
    if (c < BvhChannel::Xrotation) return true;
  return false;
}
}  // namespace

// A joint the body moves that has no position channels of its own keeps its file offset when read
// back. CC_Base clips carry the body's motion on the root (RL_BoneRoot, position channels) and
// turn CC_Base_Hip under it (rotation channels only), while the solver moves the hips: written
// as they were, the solved body walked on the spot (the root frozen where the clip began). Such a
// joint's displacement goes to the root's position: the whole hierarchy moves with it, as in the
// clip. One floating joint is expected (the hips); a second, independent one could not be kept.
void SolvedMotionBvh::carryTranslationsToRoot() {
  const size_t n = clip_.joints.size();
  for (size_t b = 0; b < n; ++b) {
    const avatar::BvhJoint& joint = clip_.joints[b];
    const int p = joint.parent;
    if (p < 0 || joint.endSite || !posed_[b] || !posed_[size_t(p)]) continue;
    if (hasPositionChannel(joint)) continue;
    const glm::dvec3 readBack = position_[size_t(p)] + world_[size_t(p)] * joint.offset;
    const glm::dvec3 moved = position_[b] - readBack;
    if (glm::length(moved) < 1e-6 * (1.0 + glm::length(joint.offset))) continue;
    int root = int(b);
    while (clip_.joints[size_t(root)].parent >= 0) root = clip_.joints[size_t(root)].parent;
    if (!hasPositionChannel(clip_.joints[size_t(root)])) return;
    // Every joint between the root and this one (and the root) moves by the same amount: they stay
    // where their offsets put them above it.
    for (int a = p; a >= 0; a = clip_.joints[size_t(a)].parent) position_[size_t(a)] += moved;
    return;
  }
}

void SolvedMotionBvh::reserve(size_t frames) { clip_.values.reserve(frames * size_t(clip_.channelCount)); }

void SolvedMotionBvh::add(const avatar::SkeletonPose& pose) {
  avatar::computeGlobals(*skeleton_, pose, globals_);
  const size_t n = clip_.joints.size();
  world_.assign(n, glm::dquat(1, 0, 0, 0));
  position_.assign(n, glm::dvec3(0.0));
  posed_.assign(n, 0);
  const glm::dmat3 toFile = glm::transpose(toAvatar_);
  const glm::dquat qToFile = glm::quat_cast(toFile);
  for (size_t j = 0; j < bvhOfJoint_.size(); ++j) {
    const int b = bvhOfJoint_[j];
    if (b < 0) continue;
    const glm::dmat3 m = glm::dmat3(glm::mat3(globals_[j]));  // not m(glm::mat3(x[j])): clang reads a declaration
    // Columns may carry scale: normalise before taking the rotation.
    const glm::dmat3 r(glm::normalize(m[0]), glm::normalize(m[1]), glm::normalize(m[2]));
    const glm::dquat delta = glm::quat_cast(r) * glm::conjugate(restRotation_[j]);
    world_[size_t(b)] = glm::normalize(qToFile * delta * glm::conjugate(qToFile));
    position_[size_t(b)] = toFile * (glm::dvec3(globals_[j][3]) - shift_) / scale_;
    posed_[size_t(b)] = 1;
  }
  carryTranslationsToRoot();
  const size_t base = clip_.values.size();
  clip_.values.resize(base + size_t(clip_.channelCount), 0.0f);
  for (size_t b = 0; b < n; ++b) {
    const avatar::BvhJoint& joint = clip_.joints[b];
    if (joint.channels.empty()) continue;
    const int p = joint.parent;
    const glm::dquat parentWorld = p >= 0 ? world_[size_t(p)] : glm::dquat(1, 0, 0, 0);
    const glm::dquat local = glm::conjugate(parentWorld) * world_[b];
    const glm::dvec3 offsetNow =
        p >= 0 ? glm::conjugate(parentWorld) * (position_[b] - position_[size_t(p)]) : position_[b];
    BvhChannel rot[3] = {BvhChannel::Zrotation, BvhChannel::Xrotation, BvhChannel::Yrotation};
    int r = 0;
    for (BvhChannel c : joint.channels)
      if (c >= BvhChannel::Xrotation && r < 3) rot[r++] = c;
    double deg[3] = {0, 0, 0};
    if (r == 3) avatar::eulerForChannels(local, rot, deg);
    r = 0;
    for (size_t k = 0; k < joint.channels.size(); ++k) {
      const BvhChannel c = joint.channels[k];
      float& v = clip_.values[base + size_t(joint.firstChannel) + k];
      if (c >= BvhChannel::Xrotation) v = float(deg[r++]);
      else v = float(offsetNow[int(c)] - joint.offset[int(c)]);
    }
  }
  ++clip_.frameCount;
}

Status SolvedMotionBvh::write(const std::string& path) const { return avatar::writeBvh(clip_, path); }

}  // namespace embody::tracking
