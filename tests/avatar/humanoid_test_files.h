#pragma once
// A humanoid glTF written by hand for the mapping tests: 22 joints with non-identity rest
// rotations, a skinned "body" mesh made of one box per bone (boxes at the neck blend neck and
// head), a "hair" mesh on the head and an "eyes-inside" mesh. The caller chooses the node names
// (VRM-style meaningless names, Mixamo names ...) and may add VRM extensions to `doc`.
#include <algorithm>
#include <array>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <map>
#include <string>
#include <vector>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "core/result.h"
#include "gltf_test_files.h"

namespace embody::test {

struct HumanoidJointSpec {
  const char* bone;    // VRM 1.0 humanoid bone name
  const char* parent;  // VRM 1.0 bone name of the parent, nullptr for the root
  glm::vec3 pos;       // model-space rest position (metres, +Y up, facing +Z)
};

inline const std::vector<HumanoidJointSpec>& humanoidJointSpecs() {
  static const std::vector<HumanoidJointSpec> s = {
      {"hips", nullptr, {0, 0.95f, 0}},
      {"spine", "hips", {0, 1.05f, -0.01f}},
      {"chest", "spine", {0, 1.20f, -0.01f}},
      {"upperChest", "chest", {0, 1.33f, -0.02f}},
      {"neck", "upperChest", {0, 1.48f, -0.02f}},
      {"head", "neck", {0, 1.58f, 0.0f}},
      {"leftShoulder", "upperChest", {0.04f, 1.43f, 0}},
      {"leftUpperArm", "leftShoulder", {0.17f, 1.42f, -0.02f}},
      {"leftLowerArm", "leftUpperArm", {0.43f, 1.42f, -0.02f}},
      {"leftHand", "leftLowerArm", {0.68f, 1.42f, -0.02f}},
      {"rightShoulder", "upperChest", {-0.04f, 1.43f, 0}},
      {"rightUpperArm", "rightShoulder", {-0.17f, 1.42f, -0.02f}},
      {"rightLowerArm", "rightUpperArm", {-0.43f, 1.42f, -0.02f}},
      {"rightHand", "rightLowerArm", {-0.68f, 1.42f, -0.02f}},
      {"leftUpperLeg", "hips", {0.09f, 0.90f, 0}},
      {"leftLowerLeg", "leftUpperLeg", {0.10f, 0.48f, 0.01f}},
      {"leftFoot", "leftLowerLeg", {0.10f, 0.08f, -0.01f}},
      {"leftToes", "leftFoot", {0.10f, 0.02f, 0.12f}},
      {"rightUpperLeg", "hips", {-0.09f, 0.90f, 0}},
      {"rightLowerLeg", "rightUpperLeg", {-0.10f, 0.48f, 0.01f}},
      {"rightFoot", "rightLowerLeg", {-0.10f, 0.08f, -0.01f}},
      {"rightToes", "rightFoot", {-0.10f, 0.02f, 0.12f}},
  };
  return s;
}

// The 30 finger bones for the T-posed hands above (fingers along +-X, palms down, thumbs
// forward), VRM 1.0 names. Appended by HumanoidFile(..., fingers = true).
inline const std::vector<HumanoidJointSpec>& humanoidFingerSpecs() {
  static const std::vector<HumanoidJointSpec> s = [] {
    static const std::vector<std::string> names = [] {
      std::vector<std::string> n;
      for (const char* side : {"left", "right"}) {
        for (const char* seg : {"Metacarpal", "Proximal", "Distal"})
          n.push_back(std::string(side) + "Thumb" + seg);
        for (const char* f : {"Index", "Middle", "Ring", "Little"})
          for (const char* seg : {"Proximal", "Intermediate", "Distal"})
            n.push_back(std::string(side) + f + seg);
      }
      return n;
    }();
    std::vector<HumanoidJointSpec> v;
    size_t k = 0;
    for (int side = 0; side < 2; ++side) {
      const float sx = side == 0 ? 1.0f : -1.0f;
      const char* hand = side == 0 ? "leftHand" : "rightHand";
      const glm::vec3 thumb[3] = {{0.70f, 1.41f, 0.01f}, {0.73f, 1.40f, 0.04f}, {0.755f, 1.395f, 0.06f}};
      for (int j = 0; j < 3; ++j, ++k)
        v.push_back({names[k].c_str(),
                     j == 0 ? hand : names[k - 1].c_str(),
                     {sx * thumb[j].x, thumb[j].y, thumb[j].z}});
      const float across[4] = {0.005f, -0.015f, -0.034f, -0.05f};
      const float len[3] = {0.0f, 0.04f, 0.025f};
      for (int f = 0; f < 4; ++f) {
        float x = 0.77f;
        for (int j = 0; j < 3; ++j, ++k) {
          x += len[j];
          v.push_back({names[k].c_str(), j == 0 ? hand : names[k - 1].c_str(), {sx * x, 1.42f, across[f]}});
        }
      }
    }
    return v;
  }();
  return s;
}

struct HumanoidFile {
  nlohmann::json doc;
  std::vector<uint8_t> bin;
  std::map<std::string, int> nodeOfBone;  // VRM bone name -> glTF node index
  int bodyNode = -1, hairNode = -1, innerNode = -1;
  int bodyMesh = -1, hairMesh = -1, innerMesh = -1;

  // The twist joints `twists` adds: {twist, the bone it follows, the bone it precedes}.
  static const std::vector<std::array<const char*, 3>>& twistJoints() {
    static const std::vector<std::array<const char*, 3>> t = {
        {"leftUpperArmTwist", "leftUpperArm", "leftLowerArm"},    {"leftLowerArmTwist", "leftLowerArm", "leftHand"},
        {"leftUpperLegTwist", "leftUpperLeg", "leftLowerLeg"},    {"rightUpperArmTwist", "rightUpperArm", "rightLowerArm"},
        {"rightLowerArmTwist", "rightLowerArm", "rightHand"},     {"rightUpperLegTwist", "rightUpperLeg", "rightLowerLeg"}};
    return t;
  }
  static void insertTwists(std::vector<HumanoidJointSpec>& specs) {
    auto find = [&](const char* bone) -> HumanoidJointSpec& {
      return *std::find_if(specs.begin(), specs.end(), [&](const HumanoidJointSpec& j) { return std::string(j.bone) == bone; });
    };
    for (const auto& [twist, from, to] : twistJoints()) {
      HumanoidJointSpec& next = find(to);
      const glm::vec3 mid = 0.5f * (find(from).pos + next.pos);
      next.parent = twist;
      specs.push_back({twist, from, mid});
    }
  }

  // names: VRM bone name -> node name (bones not listed keep their VRM name).
  // facesMinusZ turns the whole rest pose 180 degrees about +Y (VRM 0.x convention).
  // fingers appends humanoidFingerSpecs(); twists puts a twist joint halfway along each upper
  // arm, forearm and thigh, inside the chain (Daz style: "leftUpperArmTwist", ...).
  explicit HumanoidFile(const std::map<std::string, std::string>& names = {}, bool facesMinusZ = false,
                        bool fingers = false, bool twists = false) {
    std::vector<HumanoidJointSpec> specs = humanoidJointSpecs();
    if (fingers) specs.insert(specs.end(), humanoidFingerSpecs().begin(), humanoidFingerSpecs().end());
    if (twists) insertTwists(specs);
    if (facesMinusZ)
      for (auto& j : specs) j.pos = glm::vec3(-j.pos.x, j.pos.y, -j.pos.z);
    doc = {{"asset", {{"version", "2.0"}}},        {"scene", 0},
           {"nodes", nlohmann::json::array()},     {"meshes", nlohmann::json::array()},
           {"accessors", nlohmann::json::array()}, {"bufferViews", nlohmann::json::array()}};
    // Rest rotations that are not identity: each joint turned by a different quaternion, the
    // child translations compensating so model-space positions stay as specified.
    std::vector<glm::quat> globalRot(specs.size());
    for (size_t i = 0; i < specs.size(); ++i) {
      globalRot[i] = glm::angleAxis(0.3f + 0.17f * static_cast<float>(i),
                                    glm::normalize(glm::vec3(1.0f, 0.5f * i, -0.7f)));
      nodeOfBone[specs[i].bone] = static_cast<int>(i);
    }
    for (size_t i = 0; i < specs.size(); ++i) doc["nodes"].push_back(nlohmann::json::object());
    for (size_t i = 0; i < specs.size(); ++i) {
      const auto it = names.find(specs[i].bone);
      nlohmann::json node = {{"name", it != names.end() ? it->second : std::string(specs[i].bone)}};
      glm::vec3 t = specs[i].pos;
      glm::quat r = globalRot[i];
      if (specs[i].parent) {
        const int p = nodeOfBone[specs[i].parent];
        t = glm::inverse(globalRot[p]) * (specs[i].pos - specs[p].pos);
        r = glm::inverse(globalRot[p]) * globalRot[i];
        doc["nodes"][static_cast<size_t>(p)]["children"].push_back(i);
      }
      node["translation"] = {t.x, t.y, t.z};
      node["rotation"] = {r.x, r.y, r.z, r.w};
      doc["nodes"][i].update(node);
    }
    // Skin over every joint; inverse bind = inverse(global rest).
    std::vector<float> ibm;
    for (size_t i = 0; i < specs.size(); ++i) {
      glm::mat4 g = glm::mat4_cast(globalRot[i]);
      g[3] = glm::vec4(specs[i].pos, 1.0f);
      const glm::mat4 inv = glm::inverse(g);
      ibm.insert(ibm.end(), glm::value_ptr(inv), glm::value_ptr(inv) + 16);
    }
    const int ibmAcc = addAccessor(ibm, 5126, "MAT4", specs.size(), false);
    nlohmann::json joints = nlohmann::json::array();
    for (size_t i = 0; i < specs.size(); ++i) joints.push_back(i);
    doc["skins"] = {{{"inverseBindMatrices", ibmAcc}, {"joints", joints}, {"skeleton", 0}}};

    // Body: a box per bone from the joint halfway to its first child; the neck box's upper
    // corners also weigh on the head.
    Boxes body;
    for (size_t i = 0; i < specs.size(); ++i) {
      if (std::string(specs[i].bone) == "head") continue;
      glm::vec3 end = specs[i].pos + glm::vec3(0, -0.05f, 0.05f);
      for (size_t c = 0; c < specs.size(); ++c)
        if (specs[c].parent && nodeOfBone[specs[c].parent] == static_cast<int>(i)) {
          end = specs[c].pos;
          break;
        }
      const bool neck = std::string(specs[i].bone) == "neck";
      body.add(specs[i].pos, end, 0.03f, static_cast<int>(i), neck ? nodeOfBone["head"] : -1);
    }
    Boxes hair, inner;
    const glm::vec3 head = specs[static_cast<size_t>(nodeOfBone["head"])].pos;
    hair.add(head, head + glm::vec3(0, 0.2f, 0), 0.1f, nodeOfBone["head"], -1);
    // A first-person-only mesh (weighted to the neck, so even it never shows the head).
    inner.add(head + glm::vec3(0, 0.05f, 0), head + glm::vec3(0, 0.1f, 0.05f), 0.02f, nodeOfBone["neck"], -1);
    bodyMesh = addMesh("body", body);
    hairMesh = addMesh("hair", hair);
    innerMesh = addMesh("inner", inner);
    bodyNode = addMeshNode("body", bodyMesh);
    hairNode = addMeshNode("hair", hairMesh);
    innerNode = addMeshNode("inner", innerMesh);
    doc["scenes"] = {{{"nodes", {0, bodyNode, hairNode, innerNode}}}};
  }

  std::vector<uint8_t> glb() {
    doc["buffers"] = {{{"byteLength", bin.size()}}};
    return makeGlb(doc, bin);
  }

 private:
  struct Boxes {
    std::vector<float> pos;
    std::vector<uint16_t> joints;
    std::vector<float> weights;
    std::vector<uint16_t> idx;
    void add(const glm::vec3& a, const glm::vec3& b, float half, int joint, int topJoint) {
      const uint16_t base = static_cast<uint16_t>(pos.size() / 3);
      const glm::vec3 lo = glm::min(a, b) - glm::vec3(half), hi = glm::max(a, b) + glm::vec3(half);
      for (int k = 0; k < 8; ++k) {
        const glm::vec3 p((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
        pos.insert(pos.end(), {p.x, p.y, p.z});
        const bool top = (k & 2) && topJoint >= 0;
        joints.insert(joints.end(),
                      {static_cast<uint16_t>(joint), static_cast<uint16_t>(top ? topJoint : 0), 0, 0});
        weights.insert(weights.end(), {top ? 0.5f : 1.0f, top ? 0.5f : 0.0f, 0.0f, 0.0f});
      }
      static const uint16_t faces[36] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                         2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
      for (uint16_t f : faces) idx.push_back(static_cast<uint16_t>(base + f));
    }
  };

  template <class T>
  int addAccessor(const std::vector<T>& data, int componentType, const char* type, size_t count,
                  bool vertexAttr) {
    while (bin.size() % 4) bin.push_back(0);
    const size_t at = bin.size();
    appendRaw(bin, data);
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", at}, {"byteLength", data.size() * sizeof(T)}};
    if (vertexAttr) view["target"] = 34962;
    doc["bufferViews"].push_back(view);
    doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1},
                                {"componentType", componentType},
                                {"count", count},
                                {"type", type}});
    return static_cast<int>(doc["accessors"].size() - 1);
  }

  int addMesh(const char* name, const Boxes& b) {
    const size_t vc = b.pos.size() / 3;
    nlohmann::json attrs = {{"POSITION", addAccessor(b.pos, 5126, "VEC3", vc, true)},
                            {"JOINTS_0", addAccessor(b.joints, 5123, "VEC4", vc, true)},
                            {"WEIGHTS_0", addAccessor(b.weights, 5126, "VEC4", vc, true)}};
    const int indices = addAccessor(b.idx, 5123, "SCALAR", b.idx.size(), false);
    doc["meshes"].push_back(
        {{"name", name}, {"primitives", {{{"attributes", attrs}, {"indices", indices}}}}});
    return static_cast<int>(doc["meshes"].size() - 1);
  }

  int addMeshNode(const char* name, int mesh) {
    doc["nodes"].push_back({{"name", name}, {"mesh", mesh}, {"skin", 0}});
    return static_cast<int>(doc["nodes"].size() - 1);
  }
};

// VRM 1.0 humanoid bone -> Mixamo node name ("mixamorig:" prefix included).
inline std::map<std::string, std::string> mixamoBoneNames() {
  std::map<std::string, std::string> m = {
      {"hips", "Hips"},           {"spine", "Spine"},           {"chest", "Spine1"},
      {"upperChest", "Spine2"},   {"neck", "Neck"},             {"head", "Head"},
      {"leftShoulder", "LeftShoulder"},   {"leftUpperArm", "LeftArm"},   {"leftLowerArm", "LeftForeArm"},
      {"leftHand", "LeftHand"},           {"rightShoulder", "RightShoulder"}, {"rightUpperArm", "RightArm"},
      {"rightLowerArm", "RightForeArm"},  {"rightHand", "RightHand"},   {"leftUpperLeg", "LeftUpLeg"},
      {"leftLowerLeg", "LeftLeg"},        {"leftFoot", "LeftFoot"},     {"leftToes", "LeftToeBase"},
      {"rightUpperLeg", "RightUpLeg"},    {"rightLowerLeg", "RightLeg"}, {"rightFoot", "RightFoot"},
      {"rightToes", "RightToeBase"}};
  // Fingers: LeftHandThumb1..3 (thumb1 is the metacarpal), LeftHandIndex1..3 ... LeftHandPinky1..3.
  for (const char* side : {"left", "right"}) {
    const std::string vrmSide = side, mixSide = vrmSide == "left" ? "Left" : "Right";
    const char* segs[3] = {"Metacarpal", "Proximal", "Distal"};
    for (int k = 0; k < 3; ++k)
      m[vrmSide + "Thumb" + segs[k]] = mixSide + "HandThumb" + std::to_string(k + 1);
    const char* fingerSegs[3] = {"Proximal", "Intermediate", "Distal"};
    const std::pair<const char*, const char*> fingers[] = {
        {"Index", "Index"}, {"Middle", "Middle"}, {"Ring", "Ring"}, {"Little", "Pinky"}};
    for (const auto& [vrm, mix] : fingers)
      for (int k = 0; k < 3; ++k)
        m[vrmSide + vrm + fingerSegs[k]] = mixSide + "Hand" + mix + std::to_string(k + 1);
  }
  for (auto& [bone, name] : m) name = "mixamorig:" + name;
  return m;
}

// The file loaded and prepared as an avatar (humanoid mapping and checks), with `boneMap` as
// --bone-map gives it (empty: none).
inline Result<avatar::AvatarAsset> loadPrepared(HumanoidFile& f, const std::string& boneMap = "") {
  auto a = avatar::loadGltfFromMemory(f.glb(), "");
  if (!a.ok()) return a;
  if (auto s = avatar::prepareAvatar(a.value(), boneMap); !s.ok()) return Error{s.error()};
  return a;
}

}  // namespace embody::test
