#pragma once
// Humanoid bone mapping: which skeleton joint plays which VRM 1.0 humanoid bone, how that was
// decided, and which vertebrae each spine bone between hips and head stands for.
//
// Mapping order, first match wins (mapHumanoid):
//   1. a user bone map (JSON object {"hips": "NodeName", ...}, VRM 1.0 bone names): its entries
//      always win; bones it leaves out are filled by the next method that maps the rest;
//   2. VRM 1.0 VRMC_vrm.humanoid.humanBones (object bone -> {"node": i});
//   3. VRM 0.x VRM.humanoid.humanBones (array of {"bone", "node"}; the model faces -Z);
//   4. names: H-Anim (humanoid_root, sacroiliac, l_hip ... skullbase) when the skeleton uses
//      H-Anim names, else one table for Mixamo (mixamorig:Hips ...), CMU (original and cgspeed),
//      MotionBuilder/HumanIK, 3ds Max Biped, Reallusion CC_Base/CC3, Bandai-Namco, Rokoko,
//      Perception Neuron, Xsens MVN, OptiTrack Motive, Unreal, VRM/VRoid and Rigify names.
//      Namespaces (`ns:`), rig prefixes and leading asset words (`Skeleton1_`, `Character1_`)
//      are dropped; twist, roll, share and helper bones match nothing and stay unmapped;
//   5. topology and rest-pose geometry (names ignored): the hips are the joint whose branches
//      are two legs going down and a spine going up; the spine branches into two arms and a neck;
//      left and right come from the rest pose (left = up x forward, forward from the toes, else +Z).
// Depends only on the Skeleton; no glTF types.
#include <array>
#include <glm/glm.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "avatar/skeleton.h"
#include "core/result.h"

namespace embody::avatar {

// VRM 1.0 humanoid bones (https://github.com/vrm-c/vrm-specification, VRMC_vrm-1.0/humanoid.md).
enum class HumanBone : int {
  hips,
  spine,
  chest,
  upperChest,
  neck,
  head,
  leftEye,
  rightEye,
  jaw,
  leftUpperLeg,
  leftLowerLeg,
  leftFoot,
  leftToes,
  rightUpperLeg,
  rightLowerLeg,
  rightFoot,
  rightToes,
  leftShoulder,
  leftUpperArm,
  leftLowerArm,
  leftHand,
  rightShoulder,
  rightUpperArm,
  rightLowerArm,
  rightHand,
  leftThumbMetacarpal,
  leftThumbProximal,
  leftThumbDistal,
  leftIndexProximal,
  leftIndexIntermediate,
  leftIndexDistal,
  leftMiddleProximal,
  leftMiddleIntermediate,
  leftMiddleDistal,
  leftRingProximal,
  leftRingIntermediate,
  leftRingDistal,
  leftLittleProximal,
  leftLittleIntermediate,
  leftLittleDistal,
  rightThumbMetacarpal,
  rightThumbProximal,
  rightThumbDistal,
  rightIndexProximal,
  rightIndexIntermediate,
  rightIndexDistal,
  rightMiddleProximal,
  rightMiddleIntermediate,
  rightMiddleDistal,
  rightRingProximal,
  rightRingIntermediate,
  rightRingDistal,
  rightLittleProximal,
  rightLittleIntermediate,
  rightLittleDistal,
  count
};
constexpr int kHumanBoneCount = static_cast<int>(HumanBone::count);

std::string_view humanBoneName(HumanBone b);                 // the VRM 1.0 name, e.g. "leftUpperArm"
bool parseHumanBone(std::string_view name, HumanBone& out);  // accepts VRM 1.0 names
// Required for a usable avatar: hips, spine, head, upper/lower legs, feet, upper/lower arms, hands.
const std::vector<HumanBone>& requiredHumanBones();

enum class MappingMethod { None, BoneMap, Vrm, Names, Topology };
std::string_view mappingMethodName(MappingMethod m);  // "none", "bone-map", "vrm", "names", "topology"

// The intervertebral joints of the coupled spine in H-Anim order, bottom to top: index 0 = vl5
// (L5-S1) ... 23 = vc1 (C1-C2), 24 = skullbase (Occ-C1).
constexpr int kVertebralJointCount = 25;
std::string_view vertebralJointName(int level);  // "vl5" ... "vc1", "skullbase"
int vertebralJointLevel(std::string_view name);  // -1 when not an H-Anim vertebral joint name

// One avatar bone on the path hips -> head, with the vertebral joints it stands for
// ([firstLevel, endLevel), possibly empty for a bone the spine model keeps rigid). A render bone
// that stands for several vertebrae takes their composed rotation (spine.md §5).
struct SpineBone {
  int joint = -1;
  int firstLevel = 0;
  int endLevel = 0;
  bool standsFor(int level) const { return level >= firstLevel && level < endLevel; }
  int levelCount() const { return endLevel - firstLevel; }
};

struct HumanoidMap {
  std::array<int, kHumanBoneCount> bones;  // skeleton joint per bone, -1 when unmapped
  MappingMethod method = MappingMethod::None;
  std::vector<HumanBone> missingRequired;  // empty when the avatar can be driven
  std::vector<SpineBone> spine;            // hips (exclusive) up to head (inclusive), bottom first
  glm::vec3 forward{0.0f, 0.0f, 1.0f};     // the way the rest pose faces (VRM 0.x: -Z)
  glm::vec3 up{0.0f, 1.0f, 0.0f};
  std::vector<std::string> notes;  // why a method was skipped, conflicts resolved

  HumanoidMap() { bones.fill(-1); }
  int joint(HumanBone b) const { return bones[static_cast<int>(b)]; }
  bool has(HumanBone b) const { return joint(b) >= 0; }
  bool usable() const { return method != MappingMethod::None && missingRequired.empty(); }
};

// Assigns vertebral levels to the hips->head chain (spine.md §5): H-Anim vertebra names stand
// for themselves; otherwise spine anchors at vl5, chest at vt12, upperChest at vt6, neck at vc7,
// head at skullbase, and unmapped bones between two anchors share the levels evenly.
std::vector<SpineBone> assignVertebrae(const Skeleton& skeleton, const HumanoidMap& map);

struct HumanoidInputs {
  const Skeleton* skeleton = nullptr;
  std::string gltfJson;               // "" when not from glTF (no VRM extensions then)
  std::vector<int> gltfNodeToJoint;   // glTF node index -> joint
  std::string boneMapJson;            // the user's --bone-map contents, "" for none
  std::vector<bool> jointHasWeights;  // per joint: some vertex is weighted to it (may be empty)
};

// Maps the humanoid. Only a malformed user bone map (bad JSON, unknown bone or node names) is an
// Error; an avatar that cannot be mapped returns a map with missingRequired filled.
Result<HumanoidMap> mapHumanoid(const HumanoidInputs& in);

// Building blocks, exposed for tests.
HumanoidMap mapByNames(const Skeleton& skeleton);
HumanoidMap mapByTopology(const Skeleton& skeleton, const std::vector<bool>& jointHasWeights);
// Applies a user bone map (JSON object VRM-bone-name -> node name or index into nodeToJoint) on
// top of `map`: its entries win, null unmaps. An empty nodeToJoint (a BVH clip) takes names only.
// Errors name the bad entry; two bones on one joint are an error.
Status applyBoneMap(const std::string& text, const Skeleton& skeleton, const std::vector<int>& nodeToJoint,
                    HumanoidMap& map);
// Fills missingRequired, spine and forward for a map whose bones are set.
void finishHumanoidMap(const Skeleton& skeleton, HumanoidMap& map);

}  // namespace embody::avatar
