// The canonical walking clip and its rewriting into each convention (bvh_convention_writer.h).
#include "bvh_convention_writer.h"

#include <cmath>
#include <cstdio>
#include <glm/gtx/euler_angles.hpp>
#include <glm/gtx/quaternion.hpp>
#include <stdexcept>

namespace embody::test {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct RoleDef {
  int parent;
  glm::dvec3 offset;  // cm, Y up, facing +Z, the performer's left is +X; T-pose
  glm::dvec3 end;     // end site offset, zero for none
};

const std::array<RoleDef, kRoleCount>& roles() {
  static const std::array<RoleDef, kRoleCount> r = {{
      {-1, {0, 0, 0}, {}},                    // hips
      {kHips, {0, 10, -1}, {}},               // spine
      {kSpine, {0, 12, 0}, {}},               // chest
      {kChest, {0, 12, 1}, {}},               // upper chest
      {kUpperChest, {0, 14, 0}, {}},          // neck
      {kNeck, {0, 10, 1}, {0, 18, 1}},        // head, head top
      {kUpperChest, {3, 10, 0}, {}},          // left shoulder
      {kLShoulder, {15, 0, 0}, {}},           // left upper arm
      {kLUpperArm, {28, 0, 0}, {}},           // left lower arm
      {kLLowerArm, {26, 0, 0}, {18, 0, 0}},   // left hand
      {kUpperChest, {-3, 10, 0}, {}},         // right shoulder
      {kRShoulder, {-15, 0, 0}, {}},          // right upper arm
      {kRUpperArm, {-28, 0, 0}, {}},          // right lower arm
      {kRLowerArm, {-26, 0, 0}, {-18, 0, 0}}, // right hand
      {kHips, {9, -5, 0}, {}},                // left upper leg
      {kLUpperLeg, {0, -43, 0}, {}},          // left lower leg
      {kLLowerLeg, {0, -42, -1}, {}},         // left foot
      {kLFoot, {0, -4, 12}, {0, 0, 6}},       // left toes
      {kHips, {-9, -5, 0}, {}},               // right upper leg
      {kRUpperLeg, {0, -43, 0}, {}},          // right lower leg
      {kRLowerLeg, {0, -42, -1}, {}},         // right foot
      {kRFoot, {0, -4, 12}, {0, 0, 6}},       // right toes
  }};
  return r;
}

glm::dquat axisAngle(char axis, double degrees) {
  return glm::angleAxis(glm::radians(degrees), glm::dvec3(axis == 'X', axis == 'Y', axis == 'Z'));
}

// The canonical walk: local rotations per role and the root position (cm) at phase t in [0, 1).
void canonicalPose(double t, std::array<glm::dquat, kRoleCount>& local, glm::dvec3& root) {
  const double s = std::sin(2 * kPi * t), c2 = std::cos(4 * kPi * t);
  root = glm::dvec3(2 * s, 95 + 1.5 * c2, 60 * t);
  local.fill(glm::dquat(1, 0, 0, 0));
  local[kHips] = axisAngle('Y', 5 * s);
  local[kSpine] = axisAngle('X', 5 + 3 * c2);
  local[kChest] = axisAngle('Y', 6 * s);
  local[kNeck] = axisAngle('X', -5);
  local[kHead] = axisAngle('Y', 10 * s) * axisAngle('X', 4 * s);
  for (int side = 0; side < 2; ++side) {
    const double m = side == 0 ? 1 : -1, phase = side == 0 ? s : -s;
    const int o = side == 0 ? 0 : kRShoulder - kLShoulder;
    local[kLShoulder + o] = axisAngle('Z', -5 * m);
    local[kLUpperArm + o] = axisAngle('Z', -70 * m) * axisAngle('Y', -20 * phase * m);
    local[kLLowerArm + o] = axisAngle('Y', (-30 - 15 * phase) * m);
    local[kLHand + o] = axisAngle('X', 10 * phase) * axisAngle('Z', 5 * m);
    const int l = side == 0 ? 0 : kRUpperLeg - kLUpperLeg;
    local[kLUpperLeg + l] = axisAngle('X', -25 * phase);
    local[kLLowerLeg + l] = axisAngle('X', 20 + 20 * phase);
    local[kLFoot + l] = axisAngle('X', -10 * phase);
  }
}

// One joint of the written file.
struct OutJoint {
  std::string name;
  int parent = -1;
  int role = -1;            // -1 for helpers
  glm::dvec3 offset{0.0};   // canonical cm, Y up
  glm::dvec3 end{0.0};
  glm::dquat orient{1, 0, 0, 0};  // bone-axis frame in the file's world
};

std::vector<OutJoint> layout(const BvhConvention& c) {
  std::vector<OutJoint> js;
  std::array<int, kRoleCount> at{};                // where each role's children hang
  std::array<glm::dvec3, kRoleCount> inChainOffset{};  // of the in-chain helper they hang below
  for (int r = 0; r < kRoleCount; ++r) {
    if (!c.toes && (r == kLToes || r == kRToes)) continue;
    OutJoint j;
    j.name = c.names[r];
    j.role = r;
    const int parentRole = roles()[r].parent;
    j.parent = parentRole < 0 ? -1 : at[parentRole];
    j.offset = roles()[r].offset - (parentRole < 0 ? glm::dvec3(0.0) : inChainOffset[parentRole]);
    j.end = roles()[r].end;
    if (r == kLToes || r == kRToes) {
      j.offset = c.toesCm;
      j.end = c.toesEndCm;
    }
    at[r] = static_cast<int>(js.size());
    js.push_back(j);
    for (const auto& h : c.helpers)
      if (h.parent == r) {
        OutJoint hj;
        hj.name = h.name;
        hj.parent = at[r];
        hj.offset = h.offset;
        js.push_back(hj);
        if (h.inChain) {
          at[r] = static_cast<int>(js.size()) - 1;
          inChainOffset[r] = h.offset;
        }
      }
  }
  if (glm::length(c.boneAxis) > 0.0)
    for (size_t i = 0; i < js.size(); ++i) {
      if (js[i].role < 0) continue;  // helpers keep the parent's frame
      glm::dvec3 dir = js[i].end;
      for (size_t k = i + 1; k < js.size() && glm::length(dir) == 0.0; ++k)
        if (js[k].parent == static_cast<int>(i) && js[k].role >= 0) dir = js[k].offset;
      if (glm::length(dir) == 0.0) dir = glm::dvec3(0, 1, 0);
      // The bone axis along the bone, plus a twist so that no two conventions agree by chance.
      js[i].orient = glm::rotation(c.boneAxis, glm::normalize(c.world * dir)) *
                     glm::angleAxis(0.3 + 0.1 * static_cast<double>(i), c.boneAxis);
    }
  return js;
}

glm::dvec3 eulerDegrees(const glm::dquat& q, const std::string& order) {
  const glm::dmat4 m = glm::mat4_cast(q);
  double a = 0, b = 0, d = 0;
  if (order == "XYZ") glm::extractEulerAngleXYZ(m, a, b, d);
  else if (order == "XZY") glm::extractEulerAngleXZY(m, a, b, d);
  else if (order == "YXZ") glm::extractEulerAngleYXZ(m, a, b, d);
  else if (order == "YZX") glm::extractEulerAngleYZX(m, a, b, d);
  else if (order == "ZXY") glm::extractEulerAngleZXY(m, a, b, d);
  else if (order == "ZYX") glm::extractEulerAngleZYX(m, a, b, d);
  else throw std::invalid_argument("rotation order " + order);
  return glm::degrees(glm::dvec3(a, b, d));
}

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", std::abs(v) < 5e-7 ? 0.0 : v);
  return buf;
}

std::string vec(const glm::dvec3& v) {
  return num(v.x) + " " + num(v.y) + " " + num(v.z);
}

void writeHierarchy(const BvhConvention& c, const std::vector<OutJoint>& js, int j, int depth, std::string& out) {
  const std::string pad(static_cast<size_t>(depth) * 2, ' ');
  const OutJoint& jt = js[static_cast<size_t>(j)];
  const glm::dquat parentOrient = jt.parent < 0 ? glm::dquat(1, 0, 0, 0) : js[static_cast<size_t>(jt.parent)].orient;
  const glm::dvec3 offset = glm::inverse(parentOrient) * (c.world * jt.offset) * c.unitsPerCm;
  out += pad + (jt.parent < 0 ? "ROOT " : "JOINT ") + jt.name + "\n" + pad + "{\n";
  out += pad + "  OFFSET " + vec(jt.parent < 0 ? glm::dvec3(0.0) : offset) + "\n";
  out += pad + "  CHANNELS " + (jt.parent < 0 ? "6" : "3");
  if (jt.parent < 0)
    for (char a : c.positionOrder) out += std::string(" ") + a + "position";
  for (char a : c.rotationOrder) out += std::string(" ") + a + "rotation";
  out += "\n";
  bool children = false;
  for (size_t k = 0; k < js.size(); ++k)
    if (js[k].parent == j) {
      writeHierarchy(c, js, static_cast<int>(k), depth + 1, out);
      children = true;
    }
  const bool bareFoot = !c.toes && (jt.role == kLFoot || jt.role == kRFoot);
  if (!children && !bareFoot) {
    const glm::dvec3 end = glm::inverse(jt.orient) * (c.world * jt.end) * c.unitsPerCm;
    out += pad + "  End Site\n" + pad + "  {\n" + pad + "    OFFSET " + vec(end) + "\n" + pad + "  }\n";
  }
  out += pad + "}\n";
}

// One frame's values in the file's channel order (depth-first, as written).
void writeFrame(const BvhConvention& c, const std::vector<OutJoint>& js, const std::array<glm::dquat, kRoleCount>& local,
                const glm::dvec3& root, int j, std::string& line) {
  const OutJoint& jt = js[static_cast<size_t>(j)];
  const glm::dquat parentOrient = jt.parent < 0 ? glm::dquat(1, 0, 0, 0) : js[static_cast<size_t>(jt.parent)].orient;
  const glm::dquat canonical = jt.role >= 0 ? local[static_cast<size_t>(jt.role)] : glm::dquat(1, 0, 0, 0);
  const glm::dquat r = glm::inverse(parentOrient) * c.world * canonical * glm::inverse(c.world) * jt.orient;
  if (jt.parent < 0) {
    const glm::dvec3 p = c.world * root * c.unitsPerCm;
    for (char a : c.positionOrder) line += num(p[a - 'X']) + " ";
  }
  const glm::dvec3 e = eulerDegrees(r, c.rotationOrder);
  line += num(e.x) + " " + num(e.y) + " " + num(e.z) + " ";
  for (size_t k = 0; k < js.size(); ++k)
    if (js[k].parent == j) writeFrame(c, js, local, root, static_cast<int>(k), line);
}

// Left and right versions of "L"/"R" name patterns: {prefix, left, right, suffix} per role.
std::array<std::string, kRoleCount> sided(const std::array<std::string, 6>& center, const std::string& lfmt,
                                          const std::string& rfmt, const std::array<std::string, 8>& limb) {
  std::array<std::string, kRoleCount> a;
  for (int i = 0; i < 6; ++i) a[static_cast<size_t>(i)] = center[static_cast<size_t>(i)];
  auto fill = [&](const std::string& f, int arm, int leg) {
    auto put = [&](int at, const std::string& base) {
      std::string s = f;
      s.replace(s.find("%"), 1, base);
      a[static_cast<size_t>(at)] = s;
    };
    for (int k = 0; k < 4; ++k) put(arm + k, limb[static_cast<size_t>(k)]);
    for (int k = 0; k < 4; ++k) put(leg + k, limb[static_cast<size_t>(4 + k)]);
  };
  fill(lfmt, kLShoulder, kLUpperLeg);
  fill(rfmt, kRShoulder, kRUpperLeg);
  return a;
}

const glm::dquat kZUp = glm::angleAxis(kPi / 2, glm::dvec3(1, 0, 0));  // Y -> Z, facing +Z -> -Y

// The canonical names, CMU and its conversions, and the DCC tools' rigs.
void addToolConventions(std::vector<BvhConvention>& v) {
  BvhConvention c;
  c.name = "canonical";
  c.names = sided({"Hips", "Spine", "Spine1", "Spine2", "Neck", "Head"}, "Left%", "Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"});
  v.push_back(c);

  c = {};
  c.name = "cmu";  // CMU's own BVH: CMU units (1/0.45 inch), T-pose first frame
  c.names = sided({"Hips", "LowerBack", "Spine", "Spine1", "Neck1", "Head"}, "Left%", "Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"});
  c.helpers = {{"LeftFingerBase", kLHand, {6, 0, 0}}, {"LThumb", kLHand, {3, 0, 3}},
               {"RightFingerBase", kRHand, {-6, 0, 0}}, {"RThumb", kRHand, {-3, 0, 3}}};
  c.unitsPerCm = 0.45 / 2.54;
  c.tposeFirst = true;
  v.push_back(c);

  c = {};
  c.name = "cgspeed";  // CMU converted for 3ds Max/MotionBuilder by cgspeed: joint-named limbs
  c.names = sided({"Hips", "lowerback", "Chest", "Chest2", "Neck", "Head"}, "Left%", "Right%",
                  {"Collar", "Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Toe"});
  c.helpers = {{"lhand", kLHand, {4, 0, 0}}, {"LThumb", kLHand, {2, 0, 3}}, {"rhand", kRHand, {-4, 0, 0}},
               {"RThumb", kRHand, {-2, 0, 3}}};
  c.unitsPerCm = 0.45 / 2.54;
  c.frameTime = 1.0 / 120.0;
  v.push_back(c);

  c = {};
  c.name = "humanik";  // MotionBuilder / HumanIK: character namespace, roll bones
  c.names = sided({"Character1_Hips", "Character1_Spine", "Character1_Spine1", "Character1_Spine2",
                   "Character1_Neck", "Character1_Head"},
                  "Character1_Left%", "Character1_Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"});
  c.helpers = {{"Character1_LeftArmRoll", kLUpperArm, {14, 0, 0}}, {"Character1_LeftForeArmRoll", kLLowerArm, {13, 0, 0}},
               {"Character1_LeftHandThumb1", kLHand, {3, 0, 3}}, {"Character1_RightArmRoll", kRUpperArm, {-14, 0, 0}},
               {"Character1_RightForeArmRoll", kRLowerArm, {-13, 0, 0}}, {"Character1_LeftUpLegRoll", kLUpperLeg, {0, -20, 0}}};
  c.rotationOrder = "ZXY";
  c.frameTime = 1.0 / 30.0;
  v.push_back(c);

  c = {};
  c.name = "biped";  // 3ds Max Biped: Z up, bones along +X, inches
  c.names = sided({"Bip01 Pelvis", "Bip01 Spine", "Bip01 Spine1", "Bip01 Spine2", "Bip01 Neck", "Bip01 Head"},
                  "Bip01 L %", "Bip01 R %", {"Clavicle", "UpperArm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "Toe0"});
  c.helpers = {{"Bip01 L ForeTwist", kLLowerArm, {13, 0, 0}}, {"Bip01 L Finger0", kLHand, {3, 0, 3}},
               {"Bip01 R ForeTwist", kRLowerArm, {-13, 0, 0}}, {"Bip01 R Finger0", kRHand, {-3, 0, 3}}};
  c.world = kZUp;
  c.boneAxis = {1, 0, 0};
  c.unitsPerCm = 1 / 2.54;
  c.rotationOrder = "ZXY";
  c.frameTime = 1.0 / 30.0;
  v.push_back(c);

  c = {};
  c.name = "mixamo";
  c.names = sided({"mixamorig:Hips", "mixamorig:Spine", "mixamorig:Spine1", "mixamorig:Spine2", "mixamorig:Neck",
                   "mixamorig:Head"},
                  "mixamorig:Left%", "mixamorig:Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"});
  c.helpers = {{"mixamorig:LeftHandIndex1", kLHand, {8, 0, 1}}, {"mixamorig:RightHandIndex1", kRHand, {-8, 0, 1}}};
  c.rotationOrder = "XYZ";
  c.frameTime = 1.0 / 30.0;
  v.push_back(c);
}

// Character-creator and capture-suit rigs.
void addCaptureConventions(std::vector<BvhConvention>& v) {
  BvhConvention c;
  c.name = "ccbase";  // Reallusion CC_Base / CC3: bones along +Y, twist and share bones
  c.names = sided({"CC_Base_Hip", "CC_Base_Waist", "CC_Base_Spine01", "CC_Base_Spine02", "CC_Base_NeckTwist01",
                   "CC_Base_Head"},
                  "CC_Base_L_%", "CC_Base_R_%", {"Clavicle", "Upperarm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "ToeBase"});
  c.helpers = {{"CC_Base_L_UpperarmTwist01", kLUpperArm, {10, 0, 0}}, {"CC_Base_L_ForearmTwist01", kLLowerArm, {10, 0, 0}},
               {"CC_Base_L_ElbowShareBone", kLLowerArm, {0, 0, 0}}, {"CC_Base_R_UpperarmTwist01", kRUpperArm, {-10, 0, 0}},
               {"CC_Base_R_ForearmTwist01", kRLowerArm, {-10, 0, 0}}, {"CC_Base_L_Mid1", kLHand, {9, 0, 0}},
               {"CC_Base_L_ThighTwist01", kLUpperLeg, {0, -15, 0}}, {"CC_Base_R_RibsTwist", kUpperChest, {-5, 5, 5}}};
  c.boneAxis = {0, 1, 0};
  c.frameTime = 1.0 / 60.0;
  v.push_back(c);

  c = {};
  c.name = "bandai";  // Bandai-Namco Research motion dataset: Hand_L, bones along +X
  c.names = sided({"Hips", "Spine", "Chest", "Chest2", "Neck", "Head"}, "%_L", "%_R",
                  {"Shoulder", "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes"});
  c.boneAxis = {1, 0, 0};
  c.rotationOrder = "XZY";
  c.frameTime = 1.0 / 30.0;
  v.push_back(c);

  c = {};
  c.name = "rokoko";
  c.names = sided({"Hips", "Spine", "Spine1", "Spine2", "Neck", "Head"}, "Left%", "Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "Toe"});
  c.helpers = {{"LeftFinger1Metacarpal", kLHand, {3, 0, 2}}, {"RightFinger1Metacarpal", kRHand, {-3, 0, 2}}};
  c.unitsPerCm = 0.01;  // metres
  c.rotationOrder = "YZX";
  c.frameTime = 1.0 / 100.0;
  v.push_back(c);

  c = {};
  c.name = "neuron";  // Perception Neuron: YXZ, in-hand helper bones
  c.names = sided({"Hips", "Spine", "Spine1", "Spine2", "Neck", "Head"}, "Left%", "Right%",
                  {"Shoulder", "Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"});
  c.helpers = {{"LeftInHandIndex", kLHand, {4, 0, 1}}, {"LeftHandThumb1", kLHand, {3, 0, 3}},
               {"RightInHandIndex", kRHand, {-4, 0, 1}}, {"RightHandThumb1", kRHand, {-3, 0, 3}}};
  c.rotationOrder = "YXZ";
  c.frameTime = 1.0 / 60.0;
  v.push_back(c);
}

// Motion-capture systems, the Unreal mannequin and VRM.
void addSystemConventions(std::vector<BvhConvention>& v) {
  BvhConvention c;
  c.name = "xsens";  // Xsens MVN: Pelvis, L5, L3, T12, T8; 240 Hz
  c.names = sided({"Pelvis", "L5", "L3", "T8", "Neck", "Head"}, "Left%", "Right%",
                  {"Shoulder", "UpperArm", "ForeArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toe"});
  c.rotationOrder = "ZXY";
  c.frameTime = 1.0 / 240.0;
  v.push_back(c);

  c = {};
  c.name = "optitrack";  // OptiTrack Motive: asset-name prefix, LUArm/LFArm, metres
  c.names = sided({"Skeleton1_Hip", "Skeleton1_Ab", "Skeleton1_Chest", "Skeleton1_UpperChest", "Skeleton1_Neck",
                   "Skeleton1_Head"},
                  "Skeleton1_L%", "Skeleton1_R%", {"Shoulder", "UArm", "FArm", "Hand", "Thigh", "Shin", "Foot", "Toe"});
  c.unitsPerCm = 0.01;
  c.rotationOrder = "ZXY";
  c.frameTime = 1.0 / 120.0;
  v.push_back(c);

  c = {};
  c.name = "unreal";  // Unreal mannequin: Z up, facing +X, twist and IK bones, 1/24 s
  c.names = sided({"pelvis", "spine_01", "spine_02", "spine_03", "neck_01", "head"}, "%_l", "%_r",
                  {"clavicle", "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball"});
  c.helpers = {{"upperarm_twist_01_l", kLUpperArm, {10, 0, 0}}, {"lowerarm_twist_01_l", kLLowerArm, {10, 0, 0}},
               {"upperarm_twist_01_r", kRUpperArm, {-10, 0, 0}}, {"calf_twist_01_l", kLLowerLeg, {0, -20, 0}},
               {"ik_hand_root", kHips, {0, 5, 0}}, {"ik_foot_l", kHips, {5, -5, 0}}};
  c.world = glm::angleAxis(kPi / 2, glm::dvec3(0, 0, 1)) * kZUp;
  c.frameTime = 1.0 / 24.0;
  v.push_back(c);

  c = {};
  c.name = "daz_genesis3";  // Daz Studio Genesis 3/8: twist bones inside the limbs, lMid/lPinky
  c.names = sided({"hip", "abdomenLower", "abdomenUpper", "chestUpper", "neckLower", "head"}, "l%", "r%",
                  {"Collar", "ShldrBend", "ForearmBend", "Hand", "ThighBend", "Shin", "Foot", "Toe"});
  c.helpers = {{"lShldrTwist", kLUpperArm, {14, 0, 0}, true}, {"lForearmTwist", kLLowerArm, {12, 0, 0}, true},
               {"rShldrTwist", kRUpperArm, {-14, 0, 0}, true}, {"rForearmTwist", kRLowerArm, {-12, 0, 0}, true},
               {"lThighTwist", kLUpperLeg, {0, -20, 0}, true}, {"rThighTwist", kRUpperLeg, {0, -20, 0}, true},
               {"lMid1", kLHand, {9, 0, 0}}, {"rMid1", kRHand, {-9, 0, 0}}, {"neckUpper", kNeck, {0, 4, 0}, true}};
  v.push_back(c);

  c = {};
  c.name = "daz_genesis2";  // Genesis 1/2: lShldr, lForeArm, lThigh
  c.names = sided({"hip", "abdomen", "abdomen2", "chest", "neck", "head"}, "l%", "r%",
                  {"Collar", "Shldr", "ForeArm", "Hand", "Thigh", "Shin", "Foot", "Toe"});
  v.push_back(c);

  c = {};
  c.name = "vrm";  // VRM humanoid bone names, metres, facing -Z
  c.names = sided({"hips", "spine", "chest", "upperChest", "neck", "head"}, "left%", "right%",
                  {"Shoulder", "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes"});
  c.world = glm::angleAxis(kPi, glm::dvec3(0, 1, 0));
  c.unitsPerCm = 0.01;
  c.rotationOrder = "YXZ";
  c.frameTime = 1.0 / 60.0;
  c.tposeFirst = true;
  v.push_back(c);
}

}  // namespace

const std::vector<BvhConvention>& bvhConventions() {
  static const std::vector<BvhConvention> all = [] {
    std::vector<BvhConvention> v;
    addToolConventions(v);
    addCaptureConventions(v);
    addSystemConventions(v);
    return v;
  }();
  return all;
}

std::string writeConventionClip(const BvhConvention& c, int frames) {
  const std::vector<OutJoint> js = layout(c);
  std::string out = "HIERARCHY\n";
  writeHierarchy(c, js, 0, 0, out);
  const int total = frames + (c.tposeFirst ? 1 : 0);
  char buf[80];
  std::snprintf(buf, sizeof buf, "MOTION\nFrames: %d\nFrame Time: %.8f\n", total, c.frameTime);
  out += buf;
  std::array<glm::dquat, kRoleCount> local;
  glm::dvec3 root;
  for (int f = 0; f < total; ++f) {
    const int k = c.tposeFirst ? f - 1 : f;
    canonicalPose(static_cast<double>(std::max(k, 0)) / kConventionClipFrames, local, root);
    if (k < 0) local.fill(glm::dquat(1, 0, 0, 0));  // the T-pose, where the motion starts
    std::string line;
    writeFrame(c, js, local, root, 0, line);
    line.back() = '\n';
    out += line;
  }
  return out;
}

}  // namespace embody::test
