// Humanoid mapping from the skeleton's shape alone, for rigs whose names say nothing
// (CesiumMan's leg_joint_R_1, Skeleton_arm_joint_R__2_). Works on rest-pose joint positions with
// +Y up; all thresholds are fractions of the skeleton's height so the scale does not matter.
#include <algorithm>
#include <array>
#include <cmath>

#include "avatar/humanoid/humanoid_map.h"

namespace embody::avatar {
namespace {

struct Shape {
  const Skeleton& skeleton;
  std::vector<glm::vec3> pos;
  std::vector<std::vector<int>> children;
  std::vector<float> minY, maxY;  // over each joint's subtree, itself included
  float height = 0.0f;

  explicit Shape(const Skeleton& s) : skeleton(s) {
    std::vector<glm::mat4> globals;
    computeGlobals(s, SkeletonPose::rest(s), globals);
    const size_t n = s.joints.size();
    pos.resize(n);
    children.resize(n);
    for (size_t j = 0; j < n; ++j) {
      pos[j] = glm::vec3(globals[j][3]);
      if (s.joints[j].parent >= 0) children[s.joints[j].parent].push_back(static_cast<int>(j));
    }
    minY.resize(n);
    maxY.resize(n);
    for (size_t j = n; j-- > 0;) {  // children come after parents: reverse order is bottom-up
      minY[j] = maxY[j] = pos[j].y;
      for (int c : children[j]) {
        minY[j] = std::min(minY[j], minY[c]);
        maxY[j] = std::max(maxY[j], maxY[c]);
      }
    }
    float lo = 0.0f, hi = 0.0f;
    for (size_t j = 0; j < n; ++j) {
      lo = j ? std::min(lo, pos[j].y) : pos[j].y;
      hi = j ? std::max(hi, pos[j].y) : pos[j].y;
    }
    height = hi - lo;
  }

  bool goesDown(int child, int from) const { return minY[child] < pos[from].y - 0.25f * height; }
  bool goesUp(int child, int from) const { return maxY[child] > pos[from].y + 0.12f * height; }

  // Farthest horizontal reach of a subtree from a point (iterative: hostile files can be deep).
  float reach(int j, const glm::vec3& from) const {
    float r = 0.0f;
    std::vector<int> stack{j};
    while (!stack.empty()) {
      const int k = stack.back();
      stack.pop_back();
      const glm::vec3 d = pos[k] - from;
      r = std::max(r, std::hypot(d.x, d.z));
      stack.insert(stack.end(), children[k].begin(), children[k].end());
    }
    return r;
  }

  std::vector<int> followDown(int j) const {
    std::vector<int> chain{j};
    while (!children[j].empty()) {
      j = *std::min_element(children[j].begin(), children[j].end(),
                            [&](int a, int b) { return minY[a] < minY[b]; });
      chain.push_back(j);
    }
    return chain;
  }
  std::vector<int> followUp(int j) const {
    std::vector<int> chain{j};
    while (!children[j].empty()) {
      j = *std::max_element(children[j].begin(), children[j].end(),
                            [&](int a, int b) { return maxY[a] < maxY[b]; });
      chain.push_back(j);
    }
    return chain;
  }
  std::vector<int> followOut(int j, const glm::vec3& from) const {
    std::vector<int> chain{j};
    while (!children[j].empty()) {
      j = *std::max_element(children[j].begin(), children[j].end(),
                            [&](int a, int b) { return reach(a, from) < reach(b, from); });
      chain.push_back(j);
    }
    return chain;
  }
  float dist(int a, int b) const { return glm::length(pos[a] - pos[b]); }
};

// Index where the limb proper starts: skips one leading offset bone (a clavicle, a hip-offset
// bone) when it is clearly shorter than the next segment and the chain is long enough.
// The next segment is measured past a twist: when chain[2] continues chain[1]'s line (within 10
// degrees) into a segment of about its length (0.7-1.4), as a twist halfway along the upper arm
// does (Daz's ShldrTwist), the segment runs on to chain[3].
int limbStart(const Shape& s, const std::vector<int>& chain, float ratio) {
  if (chain.size() < 4) return 0;
  float next = s.dist(chain[1], chain[2]);
  const glm::vec3 a = s.pos[chain[2]] - s.pos[chain[1]], b = s.pos[chain[3]] - s.pos[chain[2]];
  const float la = glm::length(a), lb = glm::length(b);
  if (la > 0.0f && lb > 0.0f && glm::dot(a, b) > std::cos(glm::radians(10.0f)) * la * lb && lb > 0.7f * la && lb < 1.4f * la &&
      s.children[static_cast<size_t>(chain[2])].size() == 1)
    next = la + lb;
  return s.dist(chain[0], chain[1]) < ratio * next ? 1 : 0;
}

void setBone(HumanoidMap& map, HumanBone b, int j) { map.bones[static_cast<int>(b)] = j; }

// Twist bones inside a limb (Daz's ShldrTwist and ForearmTwist, ThighTwist): a chain with more
// joints between the limb's root and its end than the two segments a limb has. In a straight rest
// pose nothing tells the middle joint from a twist but where it sits, so the middle joint is the
// one nearest `middleShare` of the way along the chain to the end (the elbow at 0.55, the knee at
// 0.5; a twist sits halfway along its segment, at about 0.27 and 0.78 of the arm). `end` is the
// index of the limb's end joint in `chain`, `start` of its root.
constexpr float kTwistSegment = 0.4f;  // a twist's segment against the limb's first segment

int middleJoint(const Shape& s, const std::vector<int>& chain, size_t start, size_t end, float middleShare) {
  std::vector<float> along{0.0f};
  for (size_t i = start + 1; i <= end; ++i) along.push_back(along.back() + s.dist(chain[i - 1], chain[i]));
  size_t best = start + 1;
  for (size_t i = start + 1; i < end; ++i)
    if (std::abs(along[i - start] - middleShare * along.back()) < std::abs(along[best - start] - middleShare * along.back()))
      best = i;
  return chain[best];
}

bool weightedJoint(const std::vector<bool>& jointHasWeights, int j) {
  return jointHasWeights.empty() || (static_cast<size_t>(j) < jointHasWeights.size() && jointHasWeights[j]);
}



// Hips: the first joint (closest to the root) with two branches going down and one going up.
// A single down branch that itself splits into two legs (a pelvis bone) also counts.
struct HipsBranch {
  int hips = -1, spineRoot = -1;
  std::array<int, 2> legRoots{-1, -1};  // the lower-reaching first
};

HipsBranch findHips(const Shape& s) {
  HipsBranch r;
  const int n = static_cast<int>(s.skeleton.joints.size());
  for (int j = 0; j < n; ++j) {
    std::vector<int> down, up;
    for (int c : s.children[j]) {
      if (s.goesDown(c, j))
        down.push_back(c);
      else if (s.goesUp(c, j))
        up.push_back(c);
    }
    if (down.size() == 1) {
      std::vector<int> inner;
      for (int c : s.children[down[0]])
        if (s.goesDown(c, down[0])) inner.push_back(c);
      if (inner.size() >= 2) down = inner;
    }
    if (down.size() < 2 || up.empty()) continue;
    std::sort(down.begin(), down.end(), [&](int a, int b) { return s.minY[a] < s.minY[b]; });
    r.hips = j;
    r.legRoots = {down[0], down[1]};
    r.spineRoot = *std::max_element(up.begin(), up.end(), [&](int a, int b) { return s.maxY[a] < s.maxY[b]; });
    return r;
  }
  return r;
}

// The ankle's index in a leg chain from its root `a`: the first joint from a + 2 on (at most two
// twists further, each segment at least kTwistSegment of the first) whose next segment runs
// forward more than down (the foot), else a + 2. A thigh or shin twist pushes it on.
size_t ankleIndex(const Shape& s, const std::vector<int>& leg, size_t a) {
  const float first = s.dist(leg[a], leg[a + 1]);
  for (size_t i = a + 2; i + 1 < leg.size() && i <= a + 4; ++i) {
    if (s.dist(leg[i - 1], leg[i]) < kTwistSegment * first) break;
    const glm::vec3 d = s.pos[leg[i + 1]] - s.pos[leg[i]];
    if (std::hypot(d.x, d.z) > std::abs(d.y)) return i;
  }
  return a + 2;
}

// Legs and the facing they imply: lateral axis between the hip joints, forward from the toes
// (ankle -> toe), else the glTF convention +Z. Returns the avatar's left direction.
glm::vec3 mapLegs(const Shape& s, const HipsBranch& h, HumanoidMap& map) {
  std::vector<int> legs[2] = {s.followDown(h.legRoots[0]), s.followDown(h.legRoots[1])};
  int legStart[2] = {limbStart(s, legs[0], 0.5f), limbStart(s, legs[1], 0.5f)};
  glm::vec3 lateral = s.pos[legs[0][legStart[0]]] - s.pos[legs[1][legStart[1]]];
  lateral.y = 0.0f;
  glm::vec3 forward(0.0f, 0.0f, 1.0f);
  if (glm::length(lateral) > 1e-6f) {
    glm::vec3 f = glm::normalize(glm::cross(glm::normalize(lateral), map.up));
    float cue = f.z;  // without toes: the side nearer +Z
    const auto& leg = legs[0];
    const size_t foot = leg.size() >= static_cast<size_t>(legStart[0]) + 3 ? ankleIndex(s, leg, static_cast<size_t>(legStart[0]))
                                                                          : static_cast<size_t>(legStart[0]) + 2;
    if (foot + 1 < leg.size()) {
      glm::vec3 toe = s.pos[leg[foot + 1]] - s.pos[leg[foot]];
      toe.y = 0.0f;
      if (glm::length(toe) > 0.01f * s.height) cue = glm::dot(f, toe);
    }
    forward = cue >= 0.0f ? f : -f;
  }
  const glm::vec3 left = glm::cross(map.up, forward);
  for (int k = 0; k < 2; ++k) {
    const auto& leg = legs[k];
    const size_t a = static_cast<size_t>(legStart[k]);
    if (leg.size() < a + 3) continue;
    const size_t foot = ankleIndex(s, leg, a);
    const bool l = glm::dot(s.pos[leg[a]] - s.pos[h.hips], left) > 0.0f;
    setBone(map, l ? HumanBone::leftUpperLeg : HumanBone::rightUpperLeg, leg[a]);
    setBone(map, l ? HumanBone::leftLowerLeg : HumanBone::rightLowerLeg, foot == a + 2 ? leg[a + 1] : middleJoint(s, leg, a, foot, 0.5f));
    setBone(map, l ? HumanBone::leftFoot : HumanBone::rightFoot, leg[foot]);
    if (leg.size() > foot + 1) setBone(map, l ? HumanBone::leftToes : HumanBone::rightToes, leg[foot + 1]);
  }
  return left;
}

// Spine: climb from the hips to the junction where two arms and a neck leave.
struct ShoulderJunction {
  std::vector<int> torso;  // spine joints from the hips up to the junction
  int junction = -1, neckRoot = -1;
  std::array<int, 2> arms{-1, -1};
};

ShoulderJunction findShoulders(const Shape& s, int spineRoot) {
  ShoulderJunction r;
  for (int j = spineRoot; j >= 0;) {
    r.torso.push_back(j);
    // The neck is the child that climbs highest; arms are other children reaching out sideways.
    int upKid = -1;
    for (int c : s.children[j])
      if (s.maxY[c] > s.pos[j].y + 0.03f * s.height && (upKid < 0 || s.maxY[c] > s.maxY[upKid])) upKid = c;
    std::vector<int> lateralKids;
    for (int c : s.children[j])
      if (c != upKid && s.reach(c, s.pos[j]) > 0.12f * s.height) lateralKids.push_back(c);
    if (lateralKids.size() >= 2 && upKid >= 0) {
      r.junction = j;
      std::sort(lateralKids.begin(), lateralKids.end(),
                [&](int a, int b) { return s.reach(a, s.pos[j]) > s.reach(b, s.pos[j]); });
      r.arms = {lateralKids[0], lateralKids[1]};
      r.neckRoot = upKid;
      return r;
    }
    if (s.children[j].empty()) break;
    j = *std::max_element(s.children[j].begin(), s.children[j].end(),
                          [&](int a, int b) { return s.maxY[a] < s.maxY[b]; });
  }
  return r;
}

// Spine bones along the torso; neck and head: the chain above the junction, where trailing
// unweighted end joints are not the head.
void mapSpineAndHead(const Shape& s, const ShoulderJunction& t, const std::vector<bool>& jointHasWeights,
                     HumanoidMap& map) {
  setBone(map, HumanBone::spine, t.torso.front());
  if (t.torso.size() == 2) setBone(map, HumanBone::chest, t.torso[1]);
  if (t.torso.size() >= 3) {
    setBone(map, HumanBone::chest, t.torso[(t.torso.size() - 1) / 2]);
    setBone(map, HumanBone::upperChest, t.torso.back());
  }
  std::vector<int> neck = s.followUp(t.neckRoot);
  while (neck.size() > 1 && !weightedJoint(jointHasWeights, neck.back())) neck.pop_back();
  setBone(map, HumanBone::head, neck.back());
  if (neck.size() >= 2) setBone(map, HumanBone::neck, neck.front());
}

// The hand's index in an arm chain from its upper arm `k`: k + 2, or up to two joints further
// along when the joints between are twists (weighted, each segment at least kTwistSegment of the
// first: finger and end joints are shorter or unweighted), stopping where the fingers branch.
size_t handIndex(const Shape& s, const std::vector<int>& chain, size_t k, const std::vector<bool>& jointHasWeights) {
  size_t hand = k + 2;
  const float first = s.dist(chain[k], chain[k + 1]);
  for (size_t i = k + 3; i < chain.size() && i <= k + 4; ++i) {
    if (s.children[static_cast<size_t>(chain[i - 1])].size() >= 2) break;
    if (!weightedJoint(jointHasWeights, chain[i]) || s.dist(chain[i - 1], chain[i]) < kTwistSegment * first) break;
    hand = i;
  }
  return hand;
}

void mapArms(const Shape& s, const ShoulderJunction& t, int hips, const glm::vec3& left,
             const std::vector<bool>& jointHasWeights, HumanoidMap& map) {
  for (int a : t.arms) {
    const auto chain = s.followOut(a, s.pos[t.junction]);
    // A first joint at the junction's own pivot is a clavicle whatever its length (CMU's
    // LeftShoulder, 0 offset from Spine1, 3.8 units to LeftArm against a 4.9 upper arm).
    const bool atJunction = chain.size() >= 4 && s.dist(chain[0], t.junction) < 0.01f * s.height;
    const size_t k = atJunction ? 1 : static_cast<size_t>(limbStart(s, chain, 0.75f));
    if (chain.size() < k + 3) continue;
    const size_t hand = handIndex(s, chain, k, jointHasWeights);
    const bool l = glm::dot(s.pos[chain[hand]] - s.pos[hips], left) > 0.0f;
    if (k == 1) setBone(map, l ? HumanBone::leftShoulder : HumanBone::rightShoulder, chain[0]);
    setBone(map, l ? HumanBone::leftUpperArm : HumanBone::rightUpperArm, chain[k]);
    setBone(map, l ? HumanBone::leftLowerArm : HumanBone::rightLowerArm, hand == k + 2 ? chain[k + 1] : middleJoint(s, chain, k, hand, 0.55f));
    setBone(map, l ? HumanBone::leftHand : HumanBone::rightHand, chain[hand]);
  }
}

}  // namespace

HumanoidMap mapByTopology(const Skeleton& skeleton, const std::vector<bool>& jointHasWeights) {
  HumanoidMap map;
  map.method = MappingMethod::Topology;
  auto give = [&](const std::string& note) {
    map.notes.push_back(note);
    finishHumanoidMap(skeleton, map);
    return map;
  };
  // Reach queries make this quadratic in the worst case; real rigs have well under 4096 nodes.
  if (skeleton.joints.size() < 10 || skeleton.joints.size() > 4096)
    return give("topology: needs 10 to 4096 joints, the skeleton has " + std::to_string(skeleton.joints.size()));
  const Shape s(skeleton);
  const HipsBranch hips = findHips(s);
  if (hips.hips < 0) return give("topology: no joint branches into two legs and a spine");
  setBone(map, HumanBone::hips, hips.hips);
  const glm::vec3 left = mapLegs(s, hips, map);
  const ShoulderJunction shoulders = findShoulders(s, hips.spineRoot);
  if (shoulders.junction < 0) return give("topology: the spine never branches into two arms and a neck");
  mapSpineAndHead(s, shoulders, jointHasWeights, map);
  mapArms(s, shoulders, hips.hips, left, jointHasWeights, map);
  finishHumanoidMap(skeleton, map);
  return map;
}

}  // namespace embody::avatar
