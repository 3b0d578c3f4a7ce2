// Humanoid mapping by user bone map, VRM extensions and names; spine vertebra assignment.
#include "avatar/humanoid/humanoid_map.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <tuple>
#include <nlohmann/json.hpp>

namespace embody::avatar {
namespace {

constexpr std::array<std::string_view, kHumanBoneCount> kBoneNames = {"hips",
                                                                      "spine",
                                                                      "chest",
                                                                      "upperChest",
                                                                      "neck",
                                                                      "head",
                                                                      "leftEye",
                                                                      "rightEye",
                                                                      "jaw",
                                                                      "leftUpperLeg",
                                                                      "leftLowerLeg",
                                                                      "leftFoot",
                                                                      "leftToes",
                                                                      "rightUpperLeg",
                                                                      "rightLowerLeg",
                                                                      "rightFoot",
                                                                      "rightToes",
                                                                      "leftShoulder",
                                                                      "leftUpperArm",
                                                                      "leftLowerArm",
                                                                      "leftHand",
                                                                      "rightShoulder",
                                                                      "rightUpperArm",
                                                                      "rightLowerArm",
                                                                      "rightHand",
                                                                      "leftThumbMetacarpal",
                                                                      "leftThumbProximal",
                                                                      "leftThumbDistal",
                                                                      "leftIndexProximal",
                                                                      "leftIndexIntermediate",
                                                                      "leftIndexDistal",
                                                                      "leftMiddleProximal",
                                                                      "leftMiddleIntermediate",
                                                                      "leftMiddleDistal",
                                                                      "leftRingProximal",
                                                                      "leftRingIntermediate",
                                                                      "leftRingDistal",
                                                                      "leftLittleProximal",
                                                                      "leftLittleIntermediate",
                                                                      "leftLittleDistal",
                                                                      "rightThumbMetacarpal",
                                                                      "rightThumbProximal",
                                                                      "rightThumbDistal",
                                                                      "rightIndexProximal",
                                                                      "rightIndexIntermediate",
                                                                      "rightIndexDistal",
                                                                      "rightMiddleProximal",
                                                                      "rightMiddleIntermediate",
                                                                      "rightMiddleDistal",
                                                                      "rightRingProximal",
                                                                      "rightRingIntermediate",
                                                                      "rightRingDistal",
                                                                      "rightLittleProximal",
                                                                      "rightLittleIntermediate",
                                                                      "rightLittleDistal"};

constexpr std::array<std::string_view, kVertebralJointCount> kVertebralNames = {
    "vl5", "vl4", "vl3", "vl2", "vl1", "vt12", "vt11", "vt10", "vt9", "vt8", "vt7", "vt6",      "vt5",
    "vt4", "vt3", "vt2", "vt1", "vc7", "vc6",  "vc5",  "vc4",  "vc3", "vc2", "vc1", "skullbase"};

// Where each spine bone's range begins (spine.md §5 "pivot").
constexpr int kLevelSpine = 0, kLevelChest = 5, kLevelUpperChest = 11, kLevelNeck = 17, kLevelHead = 24;

HumanBone bone(int i) {
  return static_cast<HumanBone>(i);
}

// Lower-case alphanumerics of the part after the last ':' or '|', known rig prefixes removed.
std::string normalizeName(std::string_view raw) {
  const size_t cut = raw.find_last_of(":|");
  if (cut != std::string_view::npos) raw = raw.substr(cut + 1);
  std::string s;
  for (char c : raw)
    if (std::isalnum(static_cast<unsigned char>(c)))
      s.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  for (std::string_view prefix : {"mixamorig", "bip001", "bip01", "jbipc", "jbip", "def", "ccbase"})
    if (s.size() > prefix.size() && s.compare(0, prefix.size(), prefix) == 0) {
      s.erase(0, prefix.size());
      break;
    }
  return s;
}

// The name without its leading separated words, longest first: "Skeleton1_LHand" -> "lhand",
// "Character1_Spine_01" -> {"spine01", "01"}. Rig and asset prefixes (OptiTrack's skeleton name,
// HumanIK's character name) are matched after the full name, never instead of it.
std::vector<std::string> nameSuffixes(std::string_view raw) {
  const size_t cut = raw.find_last_of(":|");
  if (cut != std::string_view::npos) raw = raw.substr(cut + 1);
  std::vector<std::string> out;
  for (size_t i = 1; i < raw.size(); ++i) {
    const char c = raw[i - 1];
    if (c == '_' || c == ' ' || c == '.' || c == '-') {
      std::string s = normalizeName(raw.substr(i));
      if (!s.empty()) out.push_back(std::move(s));
    }
  }
  return out;
}

struct SidedAlias {
  HumanBone left, right;
  std::vector<std::string> bases;
};

// Generic (Mixamo, CMU/BVH, Unreal, Biped, VRoid, Rigify) names. Center bones are assigned in
// this order, each taking its first alias present and not yet taken: upperChest before chest so
// that Unreal's spine_03 is the chest when spine_05 exists and the upper chest otherwise.
const std::vector<std::pair<HumanBone, std::vector<std::string>>>& genericCenter() {
  static const std::vector<std::pair<HumanBone, std::vector<std::string>>> t = {
      {HumanBone::hips, {"hips", "hip", "pelvis"}},  // CC_Base_Hip is the root above CC_Base_Pelvis
      {HumanBone::head, {"head"}},
      {HumanBone::neck, {"neck", "neck01", "necktwist01", "lowerneck", "necklower"}},
      {HumanBone::upperChest, {"spine2", "upperchest", "chest2", "spine05", "spine03", "t8", "chestupper"}},
      {HumanBone::chest, {"spine1", "chest", "spine03", "spine02", "t12", "l3", "chestlower"}},
      {HumanBone::spine, {"spine", "spine01", "lowerback", "abdomen", "ab", "waist", "l5", "abdomenlower"}},
      {HumanBone::jaw, {"jaw"}},
  };
  return t;
}

const std::vector<SidedAlias>& genericSided() {
  static const std::vector<SidedAlias> t = [] {
    std::vector<SidedAlias> v = {
        // Joint-named rigs (cgspeed's LeftCollar, LeftShoulder, LeftElbow, LeftWrist) call the
        // clavicle the collar and the upper arm the shoulder: collar first, shoulder as a fallback.
        {HumanBone::leftShoulder, HumanBone::rightShoulder, {"collar", "clavicle", "shoulder"}},
        // Daz Genesis 3/8 (lShldrBend, lForearmBend, lThighBend; their Twist bones stay unmapped)
        // and Genesis 1/2 (lShldr, lForeArm, lThigh).
        {HumanBone::leftUpperArm, HumanBone::rightUpperArm, {"arm", "upperarm", "uparm", "uarm", "shldrbend", "shldr", "shoulder"}},
        {HumanBone::leftLowerArm, HumanBone::rightLowerArm, {"forearm", "lowerarm", "farm", "forearmbend", "elbow"}},
        {HumanBone::leftHand, HumanBone::rightHand, {"wrist", "hand"}},  // cgspeed: LeftWrist above lhand
        {HumanBone::leftUpperLeg, HumanBone::rightUpperLeg, {"upleg", "thigh", "upperleg", "thighbend", "hip"}},
        {HumanBone::leftLowerLeg, HumanBone::rightLowerLeg, {"leg", "calf", "shin", "lowerleg", "knee"}},
        {HumanBone::leftFoot, HumanBone::rightFoot, {"foot", "ankle"}},
        {HumanBone::leftToes, HumanBone::rightToes, {"toebase", "toe", "toes", "toe0", "ball"}},
        {HumanBone::leftEye, HumanBone::rightEye, {"eye"}},
    };
    // Fingers: Mixamo HandThumb1..3, VRoid Thumb1..3, Unreal thumb_01..03, Daz lMid1..3.
    const std::vector<std::vector<std::string>> fingers = {{"thumb"}, {"index"}, {"middle", "mid"}, {"ring"}, {"little", "pinky"}};
    for (int f = 0; f < 5; ++f)
      for (int k = 0; k < 3; ++k) {
        const int l = static_cast<int>(HumanBone::leftThumbMetacarpal) + f * 3 + k;
        const int r = static_cast<int>(HumanBone::rightThumbMetacarpal) + f * 3 + k;
        std::vector<std::string> bases;
        for (const std::string& name : fingers[size_t(f)]) {
          bases.push_back("hand" + name + std::to_string(k + 1));
          bases.push_back(name + std::to_string(k + 1));
          bases.push_back(name + "0" + std::to_string(k + 1));
        }
        v.push_back({bone(l), bone(r), bases});
      }
    return v;
  }();
  return t;
}

// H-Anim (ISO/IEC 19774) joint names; spine bones sit at their spine.md §5 pivots.
const std::vector<std::pair<HumanBone, std::vector<std::string>>>& hanimTable() {
  static const std::vector<std::pair<HumanBone, std::vector<std::string>>> t = [] {
    std::vector<std::pair<HumanBone, std::vector<std::string>>> v = {
        {HumanBone::hips, {"humanoidroot"}},          {HumanBone::spine, {"vl5", "vl4", "vl3"}},
        {HumanBone::chest, {"vt12", "vt11", "vt10"}}, {HumanBone::upperChest, {"vt6", "vt5"}},
        {HumanBone::neck, {"vc7", "vc6", "vc4"}},     {HumanBone::head, {"skullbase"}},
        {HumanBone::jaw, {"temporomandibular"}},
    };
    struct S {
      HumanBone l, r;
      const char* name;
    };
    for (const S& s : {S{HumanBone::leftUpperLeg, HumanBone::rightUpperLeg, "hip"},
                       S{HumanBone::leftLowerLeg, HumanBone::rightLowerLeg, "knee"},
                       S{HumanBone::leftFoot, HumanBone::rightFoot, "ankle"},
                       S{HumanBone::leftToes, HumanBone::rightToes, "metatarsal"},
                       S{HumanBone::leftShoulder, HumanBone::rightShoulder, "sternoclavicular"},
                       S{HumanBone::leftUpperArm, HumanBone::rightUpperArm, "shoulder"},
                       S{HumanBone::leftLowerArm, HumanBone::rightLowerArm, "elbow"},
                       S{HumanBone::leftHand, HumanBone::rightHand, "wrist"},
                       S{HumanBone::leftEye, HumanBone::rightEye, "eyeballjoint"}}) {
      v.push_back({s.l, {std::string("l") + s.name}});
      v.push_back({s.r, {std::string("r") + s.name}});
    }
    const char* fingers[] = {"thumb", "index", "middle", "ring", "pinky"};
    for (int f = 0; f < 5; ++f)
      for (int k = 0; k < 3; ++k) {
        const std::string n = fingers[f] + std::to_string(k + 1);
        v.push_back({bone(static_cast<int>(HumanBone::leftThumbMetacarpal) + f * 3 + k), {"l" + n}});
        v.push_back({bone(static_cast<int>(HumanBone::rightThumbMetacarpal) + f * 3 + k), {"r" + n}});
      }
    return v;
  }();
  return t;
}

void addNote(HumanoidMap& m, std::string note) {
  m.notes.push_back(std::move(note));
}

}  // namespace

std::string_view humanBoneName(HumanBone b) {
  const int i = static_cast<int>(b);
  return i >= 0 && i < kHumanBoneCount ? kBoneNames[i] : std::string_view("?");
}

bool parseHumanBone(std::string_view name, HumanBone& out) {
  for (int i = 0; i < kHumanBoneCount; ++i)
    if (kBoneNames[i] == name) {
      out = bone(i);
      return true;
    }
  return false;
}

const std::vector<HumanBone>& requiredHumanBones() {
  static const std::vector<HumanBone> r = {
      HumanBone::hips,          HumanBone::spine,         HumanBone::head,          HumanBone::leftUpperLeg,
      HumanBone::leftLowerLeg,  HumanBone::leftFoot,      HumanBone::rightUpperLeg, HumanBone::rightLowerLeg,
      HumanBone::rightFoot,     HumanBone::leftUpperArm,  HumanBone::leftLowerArm,  HumanBone::leftHand,
      HumanBone::rightUpperArm, HumanBone::rightLowerArm, HumanBone::rightHand};
  return r;
}

std::string_view mappingMethodName(MappingMethod m) {
  switch (m) {
    case MappingMethod::BoneMap:
      return "bone-map";
    case MappingMethod::Vrm:
      return "vrm";
    case MappingMethod::Names:
      return "names";
    case MappingMethod::Topology:
      return "topology";
    default:
      return "none";
  }
}

std::string_view vertebralJointName(int level) {
  return level >= 0 && level < kVertebralJointCount ? kVertebralNames[level] : std::string_view("?");
}

int vertebralJointLevel(std::string_view name) {
  for (int i = 0; i < kVertebralJointCount; ++i)
    if (kVertebralNames[i] == name) return i;
  return -1;
}

std::vector<SpineBone> assignVertebrae(const Skeleton& skeleton, const HumanoidMap& map) {
  const int hips = map.joint(HumanBone::hips), head = map.joint(HumanBone::head);
  if (hips < 0 || head < 0 || hips == head || !skeleton.isAncestor(hips, head)) return {};
  std::vector<int> chain;
  for (int j = head; j != hips; j = skeleton.joints[j].parent) chain.push_back(j);
  std::reverse(chain.begin(), chain.end());
  const int n = static_cast<int>(chain.size());
  std::vector<int> anchor(n, -1);
  for (int i = 0; i < n; ++i) {
    const int j = chain[i];
    int level = vertebralJointLevel(normalizeName(skeleton.joints[j].name));
    if (level < 0) {
      if (j == map.joint(HumanBone::spine))
        level = kLevelSpine;
      else if (j == map.joint(HumanBone::chest))
        level = kLevelChest;
      else if (j == map.joint(HumanBone::upperChest))
        level = kLevelUpperChest;
      else if (j == map.joint(HumanBone::neck))
        level = kLevelNeck;
    }
    anchor[i] = level;
  }
  anchor[n - 1] = kLevelHead;  // the head bone is the Occ-C1 joint whatever it is called
  if (n > 1 && anchor[0] < 0) anchor[0] = kLevelSpine;
  // Anchors must rise strictly; one that does not is dropped and interpolated instead.
  int last = -1;
  for (int i = 0; i < n - 1; ++i) {
    if (anchor[i] < 0) continue;
    if (anchor[i] <= last || anchor[i] >= kLevelHead)
      anchor[i] = -1;
    else
      last = anchor[i];
  }
  std::vector<int> level(n);
  int prev = 0;
  for (int i = 0; i < n; ++i) {
    if (anchor[i] >= 0) {
      level[i] = anchor[i];
      prev = i;
      continue;
    }
    int next = i + 1;
    while (anchor[next] < 0) ++next;  // the head always anchors
    const double a = level[prev], b = anchor[next];
    level[i] = static_cast<int>(std::lround(a + (b - a) * (i - prev) / double(next - prev)));
  }
  std::vector<SpineBone> out(n);
  for (int i = 0; i < n; ++i) {
    out[i].joint = chain[i];
    out[i].firstLevel = level[i];
    out[i].endLevel = i + 1 < n ? std::max(level[i], level[i + 1]) : kVertebralJointCount;
  }
  return out;
}

void finishHumanoidMap(const Skeleton& skeleton, HumanoidMap& map) {
  map.missingRequired.clear();
  for (HumanBone b : requiredHumanBones())
    if (!map.has(b)) map.missingRequired.push_back(b);
  map.spine = assignVertebrae(skeleton, map);
  // Facing from the rest pose: left = (left limb - right limb), forward = left x up.
  std::vector<glm::mat4> globals;
  computeGlobals(skeleton, SkeletonPose::rest(skeleton), globals);
  for (auto [l, r] : {std::pair{HumanBone::leftUpperArm, HumanBone::rightUpperArm},
                      std::pair{HumanBone::leftUpperLeg, HumanBone::rightUpperLeg}}) {
    if (!map.has(l) || !map.has(r)) continue;
    glm::vec3 left = glm::vec3(globals[map.joint(l)][3] - globals[map.joint(r)][3]);
    left -= glm::dot(left, map.up) * map.up;
    if (glm::length(left) < 1e-6f) continue;
    map.forward = glm::normalize(glm::cross(glm::normalize(left), map.up));
    break;
  }
}

HumanoidMap mapByNames(const Skeleton& skeleton) {
  HumanoidMap map;
  std::map<std::string, int> byName;  // full names first, then names without leading words
  for (size_t j = 0; j < skeleton.joints.size(); ++j)
    byName.emplace(normalizeName(skeleton.joints[j].name), static_cast<int>(j));
  const bool hanim = byName.count("humanoidroot") || byName.count("sacroiliac") ||
                     byName.count("skullbase") || byName.count("vl5");
  for (size_t j = 0; j < skeleton.joints.size(); ++j)
    for (auto& suffix : nameSuffixes(skeleton.joints[j].name)) byName.emplace(std::move(suffix), static_cast<int>(j));
  std::vector<bool> taken(skeleton.joints.size(), false);
  auto take = [&](HumanBone b, const std::vector<std::string>& aliases) {
    if (map.has(b)) return;
    for (const auto& a : aliases) {
      auto it = byName.find(a);
      if (it != byName.end() && !taken[it->second]) {
        map.bones[static_cast<int>(b)] = it->second;
        taken[it->second] = true;
        return;
      }
    }
  };
  if (hanim) {
    for (const auto& [b, aliases] : hanimTable()) take(b, aliases);
  } else {
    for (const auto& [b, aliases] : genericCenter()) take(b, aliases);
    for (const auto& s : genericSided()) {
      std::vector<std::string> l, r;
      for (const auto& base : s.bases) {
        l.insert(l.end(), {"left" + base, "l" + base, base + "l", base + "left"});
        r.insert(r.end(), {"right" + base, "r" + base, base + "r", base + "right"});
      }
      take(s.left, l);
      take(s.right, r);
    }
    // Without a collar, a "shoulder" directly above the elbow is the upper arm.
    for (auto [shoulder, upper, lower] : {std::tuple{HumanBone::leftShoulder, HumanBone::leftUpperArm, HumanBone::leftLowerArm},
                                          std::tuple{HumanBone::rightShoulder, HumanBone::rightUpperArm, HumanBone::rightLowerArm}})
      if (!map.has(upper) && map.has(shoulder) && map.has(lower) &&
          skeleton.joints[map.joint(lower)].parent == map.joint(shoulder)) {
        map.bones[static_cast<int>(upper)] = map.joint(shoulder);
        map.bones[static_cast<int>(shoulder)] = -1;
      }
    // The spine is required; a rig with one torso bone between hips and neck names it like a
    // chest (CMU's Hips -> Spine1 -> Neck): the lowest torso bone found is the spine.
    if (!map.has(HumanBone::spine))
      for (HumanBone b : {HumanBone::chest, HumanBone::upperChest})
        if (map.has(b)) {
          map.bones[static_cast<int>(HumanBone::spine)] = map.joint(b);
          map.bones[static_cast<int>(b)] = -1;
          break;
        }
  }
  map.method = MappingMethod::Names;
  finishHumanoidMap(skeleton, map);
  return map;
}

namespace {

// obj[key], or null when obj is not an object or lacks the key (json::value() throws on a
// non-object, and a file may put any type anywhere).
nlohmann::json memberOrNull(const nlohmann::json& obj, const char* key) {
  if (!obj.is_object()) return nullptr;
  const auto it = obj.find(key);
  return it == obj.end() ? nlohmann::json() : *it;
}

HumanoidMap mapByVrm(const nlohmann::json& doc, const Skeleton& skeleton, const std::vector<int>& nodeToJoint,
                     bool& present) {
  HumanoidMap map;
  present = false;
  auto jointOf = [&](const nlohmann::json& node) -> int {
    if (!node.is_number_integer()) return -1;
    const auto i = node.get<int64_t>();
    return i >= 0 && static_cast<size_t>(i) < nodeToJoint.size() ? nodeToJoint[static_cast<size_t>(i)] : -1;
  };
  if (!doc.is_object() || !doc.contains("extensions") || !doc["extensions"].is_object()) return map;
  const auto& ext = doc["extensions"];
  if (ext.contains("VRMC_vrm") && ext["VRMC_vrm"].is_object()) {
    const nlohmann::json hb = memberOrNull(memberOrNull(ext["VRMC_vrm"], "humanoid"), "humanBones");
    if (hb.is_object() && !hb.empty()) {
      present = true;
      for (const auto& [name, entry] : hb.items()) {
        HumanBone b;
        if (!parseHumanBone(name, b)) {
          addNote(map, "VRM 1.0 humanBones: unknown bone '" + name + "' ignored");
          continue;
        }
        const int j = entry.is_object() && entry.contains("node") ? jointOf(entry["node"]) : -1;
        if (j < 0)
          addNote(map, "VRM 1.0 humanBones: '" + name + "' has no valid node");
        else
          map.bones[static_cast<int>(b)] = j;
      }
    }
  } else if (ext.contains("VRM") && ext["VRM"].is_object()) {
    const nlohmann::json hb = memberOrNull(memberOrNull(ext["VRM"], "humanoid"), "humanBones");
    if (hb.is_array() && !hb.empty()) {
      present = true;
      for (const auto& entry : hb) {
        if (!entry.is_object() || !entry.contains("bone") || !entry["bone"].is_string()) continue;
        std::string name = entry["bone"].get<std::string>();
        // VRM 0.x thumbs are Proximal/Intermediate/Distal where VRM 1.0 says Metacarpal/Proximal/Distal.
        for (const char* side : {"left", "right"}) {
          const std::string s = side;
          if (name == s + "ThumbProximal")
            name = s + "ThumbMetacarpal";
          else if (name == s + "ThumbIntermediate")
            name = s + "ThumbProximal";
        }
        HumanBone b;
        if (!parseHumanBone(name, b)) {
          addNote(map, "VRM 0.x humanBones: unknown bone '" + name + "' ignored");
          continue;
        }
        const int j = entry.contains("node") ? jointOf(entry["node"]) : -1;
        if (j < 0)
          addNote(map, "VRM 0.x humanBones: '" + name + "' has no valid node");
        else
          map.bones[static_cast<int>(b)] = j;
      }
    }
  }
  map.method = MappingMethod::Vrm;
  finishHumanoidMap(skeleton, map);
  return map;
}

}  // namespace

Status applyBoneMap(const std::string& text, const Skeleton& skeleton, const std::vector<int>& nodeToJoint,
                    HumanoidMap& map) {
  const auto doc = nlohmann::json::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object())
    return Error{"bone map: not a JSON object of bone name -> node name"};
  const bool byIndex = !nodeToJoint.empty();  // glTF node indices; a BVH clip has names only
  std::vector<std::string> boneOfJoint(skeleton.joints.size());  // the user's bone per joint
  for (const auto& [name, value] : doc.items()) {
    HumanBone b;
    if (!parseHumanBone(name, b))
      return Error{"bone map: '" + name + "' is not a VRM 1.0 humanoid bone name"};
    int j = -1;
    if (value.is_string()) {
      j = skeleton.find(value.get<std::string>());
      if (j < 0)
        return Error{"bone map: " + name + " -> '" + value.get<std::string>() + "': no node has that name"};
    } else if (value.is_number_integer() && byIndex) {
      const auto i = value.get<int64_t>();
      if (i < 0 || static_cast<size_t>(i) >= nodeToJoint.size())
        return Error{"bone map: " + name + " -> node " + std::to_string(i) + " out of range"};
      j = nodeToJoint[static_cast<size_t>(i)];
    } else if (value.is_null()) {
      j = -1;  // explicitly unmapped
    } else if (byIndex) {
      return Error{"bone map: " + name + ": expected a node name (a string) or a glTF node index"};
    } else {
      return Error{"bone map: " + name + ": expected a joint name (a string)"};
    }
    if (j >= 0) {
      std::string& other = boneOfJoint[static_cast<size_t>(j)];
      if (!other.empty())
        return Error{"bone map: " + other + " and " + name + " both map to '" +
                     skeleton.joints[static_cast<size_t>(j)].name + "' (one joint plays one bone)"};
      other = name;
    }
    // A joint plays one bone: the user's choice takes it away from whatever bone had it.
    for (auto& other : map.bones)
      if (j >= 0 && other == j) other = -1;
    map.bones[static_cast<int>(b)] = j;
  }
  return {};
}

namespace {

// Every chain the map names runs the right way down the skeleton: hips above spine above head,
// each limb's bones in order (a map filled from two methods must not cross them).
bool chainsInOrder(const Skeleton& skeleton, const HumanoidMap& m) {
  const std::vector<std::vector<HumanBone>> chains = {
      {HumanBone::hips, HumanBone::spine, HumanBone::chest, HumanBone::upperChest, HumanBone::neck, HumanBone::head},
      {HumanBone::hips, HumanBone::leftUpperLeg, HumanBone::leftLowerLeg, HumanBone::leftFoot, HumanBone::leftToes},
      {HumanBone::hips, HumanBone::rightUpperLeg, HumanBone::rightLowerLeg, HumanBone::rightFoot, HumanBone::rightToes},
      {HumanBone::spine, HumanBone::leftShoulder, HumanBone::leftUpperArm, HumanBone::leftLowerArm, HumanBone::leftHand},
      {HumanBone::spine, HumanBone::rightShoulder, HumanBone::rightUpperArm, HumanBone::rightLowerArm, HumanBone::rightHand}};
  for (const auto& chain : chains) {
    int above = -1;
    for (HumanBone b : chain) {
      const int j = m.joint(b);
      if (j < 0) continue;
      if (above >= 0 && (j == above || !skeleton.isAncestor(above, j))) return false;
      above = j;
    }
  }
  return true;
}

// The names' map with the bones it left out taken from the topology's, where the topology's joint
// plays no named bone and every chain stays in order. Names that were found are kept: replacing
// the whole map by the topology's when one required bone had no name mapped a CMU arm one joint
// off (its clavicle as the upper arm, the forearm as the hand).
HumanoidMap namesFilledByTopology(const Skeleton& skeleton, const HumanoidMap& byNames, const HumanoidMap& byTopology) {
  HumanoidMap merged = byNames;
  std::vector<std::string> filled;
  for (int b = 0; b < kHumanBoneCount; ++b) {
    const int j = byTopology.bones[static_cast<size_t>(b)];
    if (merged.bones[static_cast<size_t>(b)] >= 0 || j < 0 ||
        std::find(merged.bones.begin(), merged.bones.end(), j) != merged.bones.end())
      continue;
    merged.bones[static_cast<size_t>(b)] = j;
    if (!chainsInOrder(skeleton, merged)) {
      merged.bones[static_cast<size_t>(b)] = -1;
      continue;
    }
    filled.emplace_back(humanBoneName(static_cast<HumanBone>(b)));
  }
  finishHumanoidMap(skeleton, merged);
  std::string list;
  for (const auto& f : filled) list += (list.empty() ? "" : ", ") + f;
  if (!filled.empty()) addNote(merged, "names left " + std::to_string(byNames.missingRequired.size()) +
                                           " required bones unmapped; filled by topology: " + list);
  return merged;
}

}  // namespace

Result<HumanoidMap> mapHumanoid(const HumanoidInputs& in) {
  const Skeleton& skeleton = *in.skeleton;
  HumanoidMap best;
  std::vector<std::string> notes;
  bool vrmPresent = false;
  if (!in.gltfJson.empty()) {
    const auto doc = nlohmann::json::parse(in.gltfJson, nullptr, false);
    if (!doc.is_discarded()) {
      HumanoidMap vrm = mapByVrm(doc, skeleton, in.gltfNodeToJoint, vrmPresent);
      if (vrmPresent) best = std::move(vrm);
    }
  }
  if (!vrmPresent) {
    HumanoidMap byNames = mapByNames(skeleton);
    if (byNames.missingRequired.empty()) {
      best = std::move(byNames);
    } else {
      HumanoidMap byTopology = mapByTopology(skeleton, in.jointHasWeights);
      const bool named = std::any_of(byNames.bones.begin(), byNames.bones.end(), [](int j) { return j >= 0; });
      HumanoidMap merged = named ? namesFilledByTopology(skeleton, byNames, byTopology) : byNames;
      if (merged.missingRequired.size() < byNames.missingRequired.size() &&
          merged.missingRequired.size() <= byTopology.missingRequired.size()) {
        best = std::move(merged);
      } else if (byTopology.missingRequired.size() < byNames.missingRequired.size()) {
        addNote(byTopology, "names left " + std::to_string(byNames.missingRequired.size()) +
                                " required bones unmapped; mapped by topology");
        best = std::move(byTopology);
      } else {
        best = std::move(byNames);
      }
    }
  }
  if (!in.boneMapJson.empty()) {
    if (auto s = applyBoneMap(in.boneMapJson, skeleton, in.gltfNodeToJoint, best); !s.ok())
      return Error{s.error()};
    best.method = MappingMethod::BoneMap;
    finishHumanoidMap(skeleton, best);
  }
  if (std::all_of(best.bones.begin(), best.bones.end(), [](int j) { return j < 0; }))
    best.method = MappingMethod::None;
  return best;
}

}  // namespace embody::avatar
