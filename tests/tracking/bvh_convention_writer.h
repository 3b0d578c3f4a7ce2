#pragma once
// Test-only: one walking clip (a canonical humanoid, Y up, facing +Z, centimetres) written as BVH
// text in the conventions of the common mocap tools: their joint names and helper bones, world
// axes, bones along a local axis (joint orients in the rotations), units, channel orders, frame
// times and an optional T-pose first frame. The conversions are exact rigid re-expressions of
// the same motion, so every convention must give the same trackers.
#include <array>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace embody::test {

enum Role {
  kHips, kSpine, kChest, kUpperChest, kNeck, kHead,
  kLShoulder, kLUpperArm, kLLowerArm, kLHand,
  kRShoulder, kRUpperArm, kRLowerArm, kRHand,
  kLUpperLeg, kLLowerLeg, kLFoot, kLToes,
  kRUpperLeg, kRLowerLeg, kRFoot, kRToes,
  kRoleCount
};

struct HelperBone {
  std::string name;
  Role parent;
  glm::dvec3 offset;  // canonical centimetres, Y up
  // false: a leaf. true: inside the limb, between `parent` and its role children (Daz Genesis 3's
  // lShldrTwist between lShldrBend and lForearmBend), never rotated; the children hang below it.
  bool inChain = false;
};

struct BvhConvention {
  std::string name;
  std::array<std::string, kRoleCount> names;
  std::vector<HelperBone> helpers;  // twist, roll, finger, IK bones that must not be mapped
  glm::dquat world{1, 0, 0, 0};     // canonical world -> the file's world
  glm::dvec3 boneAxis{0.0};         // non-zero: bones run along this local axis (joint orients)
  double unitsPerCm = 1.0;
  std::string rotationOrder = "ZYX";  // as listed in CHANNELS
  std::string positionOrder = "XYZ";
  double frameTime = 1.0 / 120.0;
  bool tposeFirst = false;
  bool toes = true;      // false: the feet end at their joints (no toe joints, no End Site)
  glm::dvec3 toesCm{0, -4, 12}, toesEndCm{0, 0, 6};  // the toe joints from the ankles, their End Sites
};

// The canonical clip's frames (no T-pose) and its conventions.
constexpr int kConventionClipFrames = 48;
const std::vector<BvhConvention>& bvhConventions();
// The clip in a convention as BVH text; `frames` motion frames (a T-pose is added before them).
std::string writeConventionClip(const BvhConvention& c, int frames = kConventionClipFrames);

}  // namespace embody::test
