#pragma once
// The project's own small VRM 1.0 avatar for the spring-bone, expression and look-at tests and
// goldens (no third-party file): a bust (root, hips, spine, chest, neck, head, two eyes) with a
// sphere head, eye whites, pupils and a mouth, and eight hair strands of five joints each hanging
// around the back and sides of the head; arms and legs are joints without skin (a complete
// humanoid for the body model). Built as an AvatarAsset and written with the project's
// GLB writer plus the VRMC_vrm / VRMC_springBone extension JSON.
//
// Morph targets (channels on the mesh node, in this order): blink (eyes squashed shut),
// lookLeft / lookRight / lookUp / lookDown (pupils moved), aa (mouth opened). Expressions:
// blink, lookLeft, lookRight, lookUp, lookDown, aa, happy (half blink + a little aa, blocks
// blinking), custom "wink" (binary), and angry: material binds only (a colour bind turning the
// skin red, a texture-transform bind that puts dark stripes on the shirt). The shirt carries an
// 8x1 texture, four white texels then four dark ones; its own KHR_texture_transform (scale 0.25,
// offset 0.125) reads only the white half, so the shirt looks untextured until `angry` moves the
// transform to scale 2, offset 0 (two white/dark periods around the torso).
// lookAt: expression type (or bone, on request).
// Springs: one per strand (four swinging joints, the fifth is the tail), colliders: a head
// sphere and a chest capsule in one group.
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/gltf/glb_writer.h"

namespace embody::test {

struct VrmTestAvatarOptions {
  bool boneLookAt = false;     // lookAt type "bone" (eyes turn) instead of "expression"
  float stiffness = 1.5f;
  float dragForce = 0.4f;
  float gravityPower = 0.2f;
  bool vrm0 = false;  // write VRM 0.x extensions (secondaryAnimation, blendShapeMaster, firstPerson) instead
};

// The skin colour (linear) the `angry` expression's colour bind moves to.
constexpr glm::vec3 kAngrySkin{0.9f, 0.12f, 0.1f};

struct VrmTestAvatar {
  avatar::AvatarAsset asset;   // skeleton, mesh (with morph channels), materials; not prepared
  std::string extensionsJson;  // {"VRMC_vrm": ..., "VRMC_springBone": ...} (or {"VRM": ...})
  int head = 5, leftEye = 6, rightEye = 7;
  std::vector<std::vector<int>> strands;  // joints of each hair strand, root first
  std::vector<std::pair<std::string, int>> limbBones;  // VRM bone name -> joint (arms, legs; no skin)
  int meshNode() const { return static_cast<int>(asset.skeleton.joints.size()); }
};

namespace vrm_test_detail {

inline int addJoint(avatar::Skeleton& s, const std::string& name, int parent, glm::vec3 translation) {
  avatar::Joint j;
  j.name = name;
  j.parent = parent;
  j.rest.translation = translation;
  s.joints.push_back(j);
  return static_cast<int>(s.joints.size() - 1);
}

struct MeshBuilder {
  avatar::SkinnedMesh& mesh;
  uint32_t vertex(glm::vec3 p, glm::vec3 n, int joint, glm::vec2 uv = glm::vec2(0.0f)) {
    avatar::SkinnedVertex v;
    v.position = p;
    v.uv = uv;
    v.normal = glm::normalize(n);
    v.joints0 = glm::uvec4(static_cast<uint32_t>(joint), 0, 0, 0);
    v.weights0 = glm::vec4(1, 0, 0, 0);
    mesh.vertices.push_back(v);
    return static_cast<uint32_t>(mesh.vertices.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c) { mesh.indices.insert(mesh.indices.end(), {a, b, c}); }
  void primitive(uint32_t first, int material) {
    avatar::Primitive p;
    p.firstIndex = first;
    p.indexCount = static_cast<uint32_t>(mesh.indices.size()) - first;
    p.material = material;
    mesh.primitives.push_back(p);
  }
  // A UV sphere (bind space = model space: every joint's rest rotation is identity).
  void sphere(glm::vec3 c, glm::vec3 r, int joint, int rings = 16, int segments = 24) {
    const uint32_t base = static_cast<uint32_t>(mesh.vertices.size());
    for (int i = 0; i <= rings; ++i)
      for (int k = 0; k <= segments; ++k) {
        const float th = glm::pi<float>() * float(i) / float(rings), ph = 2.0f * glm::pi<float>() * float(k) / float(segments);
        const glm::vec3 d(std::sin(th) * std::sin(ph), std::cos(th), std::sin(th) * std::cos(ph));
        vertex(c + d * r, d / r, joint, {float(k) / float(segments), float(i) / float(rings)});  // u: around from +Z
      }
    for (int i = 0; i < rings; ++i)
      for (int k = 0; k < segments; ++k) {
        const uint32_t a = base + uint32_t(i * (segments + 1) + k), b = a + uint32_t(segments + 1);
        tri(a, b, a + 1);
        tri(a + 1, b, b + 1);
      }
  }
  // A disc facing +Z; returns its vertex range [first, end).
  std::pair<uint32_t, uint32_t> disc(glm::vec3 c, float rx, float ry, int joint, int segments = 16) {
    const uint32_t centre = vertex(c, {0, 0, 1}, joint);
    for (int k = 0; k < segments; ++k) {
      const float a = 2.0f * glm::pi<float>() * float(k) / float(segments);
      vertex(c + glm::vec3(rx * std::cos(a), ry * std::sin(a), 0.0f), {0, 0, 1}, joint);
    }
    for (int k = 0; k < segments; ++k) tri(centre, centre + 1 + uint32_t(k), centre + 1 + uint32_t((k + 1) % segments));
    return {centre, static_cast<uint32_t>(mesh.vertices.size())};
  }
};

inline avatar::Material material(const char* name, glm::vec4 color, bool doubleSided = false) {
  avatar::Material m;
  m.name = name;
  m.baseColorFactor = color;
  m.doubleSided = doubleSided;
  return m;
}

// The bust (root .. eyes) and the eight hair strands hanging from the head.
inline void addBustAndHair(VrmTestAvatar& t) {
  auto& s = t.asset.skeleton;
  addJoint(s, "Root", -1, {0, 0, 0});
  addJoint(s, "J_Hips", 0, {0, 0.9f, 0});
  addJoint(s, "J_Spine", 1, {0, 0.1f, 0});
  addJoint(s, "J_Chest", 2, {0, 0.2f, 0});
  addJoint(s, "J_Neck", 3, {0, 0.25f, 0});
  addJoint(s, "J_Head", 4, {0, 0.1f, 0});                       // head pivot at y = 1.55
  addJoint(s, "J_Eye_L", 5, {0.033f, 0.11f, 0.07f});            // eyes at y = 1.66
  addJoint(s, "J_Eye_R", 5, {-0.033f, 0.11f, 0.07f});
  const glm::vec3 headCentre(0, 1.65f, 0);
  constexpr int kStrands = 8, kJointsPerStrand = 5;
  constexpr float kSegment = 0.055f;
  for (int k = 0; k < kStrands; ++k) {
    // Around the back and sides (70..290 degrees from the face), on the skull.
    const float ang = glm::radians(70.0f + 220.0f * float(k) / float(kStrands - 1));
    const glm::vec3 out(std::sin(ang), 0.0f, std::cos(ang));
    const glm::vec3 rootPos = headCentre + glm::vec3(0, 0.04f, 0) + out * 0.095f;
    std::vector<int> strand;
    int parent = t.head;
    glm::vec3 parentPos(0, 1.55f, 0);
    glm::vec3 p = rootPos;
    for (int j = 0; j < kJointsPerStrand; ++j) {
      strand.push_back(addJoint(s, "J_Hair" + std::to_string(k) + "_" + std::to_string(j), parent, p - parentPos));
      parent = strand.back();
      parentPos = p;
      p += glm::vec3(0, -kSegment, 0) + out * 0.012f;
    }
    t.strands.push_back(strand);
  }
}

// Limbs without skin (after the hair, so every index above stays): the humanoid is complete, so
// the IK body model and `embody render` accept the file.
inline void addSkinlessLimbs(VrmTestAvatar& t) {
  auto& s = t.asset.skeleton;
  const struct { const char* name; const char* bone; int parentLimb; glm::vec3 global; } limbs[] = {
      {"J_UpperArm_L", "leftUpperArm", -1, {0.17f, 1.42f, 0}}, {"J_LowerArm_L", "leftLowerArm", 0, {0.43f, 1.42f, 0}},
      {"J_Hand_L", "leftHand", 1, {0.68f, 1.42f, 0}},           {"J_UpperArm_R", "rightUpperArm", -1, {-0.17f, 1.42f, 0}},
      {"J_LowerArm_R", "rightLowerArm", 3, {-0.43f, 1.42f, 0}}, {"J_Hand_R", "rightHand", 4, {-0.68f, 1.42f, 0}},
      {"J_UpperLeg_L", "leftUpperLeg", -2, {0.09f, 0.88f, 0}},  {"J_LowerLeg_L", "leftLowerLeg", 6, {0.09f, 0.48f, 0}},
      {"J_Foot_L", "leftFoot", 7, {0.09f, 0.08f, 0}},           {"J_UpperLeg_R", "rightUpperLeg", -2, {-0.09f, 0.88f, 0}},
      {"J_LowerLeg_R", "rightLowerLeg", 9, {-0.09f, 0.48f, 0}}, {"J_Foot_R", "rightFoot", 10, {-0.09f, 0.08f, 0}}};
  std::vector<int> limbJoint;
  std::vector<glm::vec3> limbGlobal;
  for (const auto& l : limbs) {
    const int parent = l.parentLimb == -1 ? 3 : l.parentLimb == -2 ? 1 : limbJoint[static_cast<size_t>(l.parentLimb)];
    const glm::vec3 parentPos = l.parentLimb == -1 ? glm::vec3(0, 1.2f, 0) : l.parentLimb == -2 ? glm::vec3(0, 0.9f, 0)
                                                                                               : limbGlobal[static_cast<size_t>(l.parentLimb)];
    limbJoint.push_back(addJoint(s, l.name, parent, l.global - parentPos));
    limbGlobal.push_back(l.global);
    t.limbBones.emplace_back(l.bone, limbJoint.back());
  }
  t.asset.mesh.inverseBind.assign(s.joints.size(), glm::mat4(1.0f));
  {
    std::vector<glm::mat4> g;
    avatar::computeGlobals(s, avatar::SkeletonPose::rest(s), g);
    for (size_t j = 0; j < g.size(); ++j) t.asset.mesh.inverseBind[j] = glm::inverse(g[j]);
  }
}

// The vertex ranges the morph targets move.
struct FaceVertices {
  std::vector<std::pair<uint32_t, uint32_t>> whites, pupils;
  std::pair<uint32_t, uint32_t> mouth;
};

// Materials and the skinned mesh: head and neck, torso, eye whites, pupils, mouth, hair ribbons.
inline FaceVertices addMaterialsAndMesh(VrmTestAvatar& t) {
  avatar::AvatarAsset& a = t.asset;
  const auto& s = a.skeleton;
  const glm::vec3 headCentre(0, 1.65f, 0);
  a.materials = {material("skin", {0.93f, 0.78f, 0.68f, 1}), material("eyeWhite", {0.97f, 0.97f, 0.97f, 1}),
                 material("pupil", {0.08f, 0.1f, 0.25f, 1}), material("hair", {0.45f, 0.22f, 0.1f, 1}, true),
                 material("shirt", {0.2f, 0.45f, 0.7f, 1}), material("mouth", {0.55f, 0.12f, 0.15f, 1})};
  // The shirt's stripes (see the header comment).
  avatar::Image stripes;
  stripes.width = 8;
  stripes.height = 1;
  for (int x = 0; x < 8; ++x) stripes.rgba.insert(stripes.rgba.end(), {uint8_t(x < 4 ? 255 : 40), uint8_t(x < 4 ? 255 : 40), uint8_t(x < 4 ? 255 : 40), 255});
  a.images.push_back(stripes);
  a.materials[4].baseColorImage = 0;
  a.materials[4].baseColorTransform.scale = {0.25f, 1.0f};
  a.materials[4].baseColorTransform.offset = {0.125f, 0.0f};
  MeshBuilder mb{a.mesh};
  FaceVertices face;
  auto& whites = face.whites;
  auto& pupils = face.pupils;
  uint32_t first = 0;
  mb.sphere(headCentre, {0.09f, 0.105f, 0.095f}, t.head);
  mb.sphere({0, 1.5f, 0}, {0.035f, 0.07f, 0.035f}, 4, 8, 12);  // neck
  mb.primitive(first, 0);
  first = static_cast<uint32_t>(a.mesh.indices.size());
  mb.sphere({0, 1.25f, 0}, {0.17f, 0.22f, 0.1f}, 3);  // torso
  mb.primitive(first, 4);
  first = static_cast<uint32_t>(a.mesh.indices.size());
  for (int e = 0; e < 2; ++e) whites.push_back(mb.disc({e ? -0.033f : 0.033f, 1.66f, 0.093f}, 0.017f, 0.013f, e ? t.rightEye : t.leftEye));
  mb.primitive(first, 1);
  first = static_cast<uint32_t>(a.mesh.indices.size());
  for (int e = 0; e < 2; ++e) pupils.push_back(mb.disc({e ? -0.033f : 0.033f, 1.66f, 0.0955f}, 0.008f, 0.009f, e ? t.rightEye : t.leftEye));
  mb.primitive(first, 2);
  first = static_cast<uint32_t>(a.mesh.indices.size());
  face.mouth = mb.disc({0, 1.595f, 0.09f}, 0.022f, 0.004f, t.head);
  mb.primitive(first, 5);
  first = static_cast<uint32_t>(a.mesh.indices.size());
  for (const auto& strand : t.strands) {  // a ribbon 3 cm wide, facing outwards, one level per joint
    std::vector<glm::mat4> g;
    avatar::computeGlobals(s, avatar::SkeletonPose::rest(s), g);
    const glm::vec3 root(g[static_cast<size_t>(strand[0])][3]);
    const glm::vec3 out = glm::normalize(glm::vec3(root.x, 0, root.z));
    const glm::vec3 side = glm::cross(glm::vec3(0, 1, 0), out) * 0.015f;
    const uint32_t base = static_cast<uint32_t>(a.mesh.vertices.size());
    for (size_t j = 0; j < strand.size(); ++j) {
      const glm::vec3 p(g[static_cast<size_t>(strand[j])][3]);
      const int joint = j == 0 ? strand[0] : strand[j - 1];  // a level moves with the bone ending there
      mb.vertex(p - side, out, joint);
      mb.vertex(p + side, out, joint);
    }
    for (uint32_t j = 0; j + 1 < strand.size(); ++j) {
      mb.tri(base + 2 * j, base + 2 * j + 1, base + 2 * j + 2);
      mb.tri(base + 2 * j + 1, base + 2 * j + 3, base + 2 * j + 2);
    }
  }
  mb.primitive(first, 3);
  a.mesh.firstPersonIndices = a.mesh.indices;
  a.mesh.firstPersonPrimitives = a.mesh.primitives;
  return face;
}

// Morph channels on the mesh node.
inline void addMorphTargets(VrmTestAvatar& t, const FaceVertices& face) {
  avatar::AvatarAsset& a = t.asset;
  const auto& whites = face.whites;
  const auto& pupils = face.pupils;
  const auto& mouth = face.mouth;
  const char* names[6] = {"blink", "lookLeft", "lookRight", "lookUp", "lookDown", "aa"};
  for (int c = 0; c < 6; ++c) {
    avatar::MorphChannel ch;
    ch.sourceNode = t.meshNode();
    ch.sourceMesh = 0;
    ch.targetIndex = c;
    ch.name = names[c];
    a.mesh.morphChannels.push_back(ch);
  }
  auto& d = a.mesh.morphDeltas;
  auto add = [&](uint32_t v, uint32_t c, glm::vec3 dp) { d.push_back({v, c, dp, glm::vec3(0.0f)}); };
  for (int e = 0; e < 2; ++e) {
    for (uint32_t v = whites[e].first; v < whites[e].second; ++v)
      add(v, 0, {0, (1.66f - a.mesh.vertices[v].position.y) * 0.92f, 0});
    for (uint32_t v = pupils[e].first; v < pupils[e].second; ++v) {
      add(v, 0, {0, (1.66f - a.mesh.vertices[v].position.y) * 0.92f, -0.004f});
      add(v, 1, {0.008f, 0, 0});
      add(v, 2, {-0.008f, 0, 0});
      add(v, 3, {0, 0.0045f, 0});
      add(v, 4, {0, -0.0045f, 0});
    }
  }
  for (uint32_t v = mouth.first; v < mouth.second; ++v) {
    const float y = a.mesh.vertices[v].position.y - 1.595f;
    add(v, 5, {0, y * 3.0f, 0});
  }
  std::stable_sort(d.begin(), d.end(), [](const avatar::MorphDelta& x, const avatar::MorphDelta& y) { return x.vertex < y.vertex; });
}

inline nlohmann::json humanBonesJson(const VrmTestAvatar& t) {
  nlohmann::json humanBones = {{"hips", {{"node", 1}}}, {"spine", {{"node", 2}}}, {"chest", {{"node", 3}}},
                               {"neck", {{"node", 4}}}, {"head", {{"node", 5}}}, {"leftEye", {{"node", 6}}},
                               {"rightEye", {{"node", 7}}}};
  for (const auto& [bone, joint] : t.limbBones) humanBones[bone] = {{"node", joint}};
  return humanBones;
}

// VRMC_vrm: meta, humanoid, first person, look-at and the expressions.
inline nlohmann::json vrm1Extension(const VrmTestAvatar& t, const VrmTestAvatarOptions& o) {
  using nlohmann::json;
  const int mesh = t.meshNode();
  auto bind = [&](int channel, double w) { return json::array({{{"node", mesh}, {"index", channel}, {"weight", w}}}); };
  const json range = {{"inputMaxValue", 45.0}, {"outputScale", o.boneLookAt ? 12.0 : 1.0}};
  json vrm = {
      {"specVersion", "1.0"},
      {"meta", {{"name", "Embody VRM test bust"}, {"version", "1"}, {"authors", {"Embody tests"}},
                {"licenseUrl", "https://vrm.dev/licenses/1.0/"}, {"avatarPermission", "onlyAuthor"},
                {"commercialUsage", "personalNonProfit"}, {"creditNotation", "required"},
                {"allowRedistribution", false}, {"modification", "prohibited"}}},
      {"humanoid", {{"humanBones", humanBonesJson(t)}}},
      {"firstPerson", {{"meshAnnotations", {{{"node", mesh}, {"type", "auto"}}}}}},
      {"lookAt", {{"offsetFromHeadBone", {0, 0.11, 0.07}}, {"type", o.boneLookAt ? "bone" : "expression"},
                  {"rangeMapHorizontalInner", range}, {"rangeMapHorizontalOuter", range},
                  {"rangeMapVerticalDown", range}, {"rangeMapVerticalUp", range}}},
      {"expressions",
       {{"preset",
         {{"blink", {{"morphTargetBinds", bind(0, 1.0)}}},
          {"lookLeft", {{"morphTargetBinds", bind(1, 1.0)}}},
          {"lookRight", {{"morphTargetBinds", bind(2, 1.0)}}},
          {"lookUp", {{"morphTargetBinds", bind(3, 1.0)}}},
          {"lookDown", {{"morphTargetBinds", bind(4, 1.0)}}},
          {"aa", {{"morphTargetBinds", bind(5, 1.0)}}},
          {"happy", {{"morphTargetBinds", {{{"node", mesh}, {"index", 0}, {"weight", 0.5}}, {{"node", mesh}, {"index", 5}, {"weight", 0.3}}}},
                     {"overrideBlink", "block"}}}}},
        {"custom", {{"wink", {{"morphTargetBinds", bind(0, 0.8)}, {"isBinary", true}}}}}}}};
  vrm["expressions"]["preset"]["angry"] = {
      {"materialColorBinds", {{{"material", 0}, {"type", "color"}, {"targetValue", {kAngrySkin.r, kAngrySkin.g, kAngrySkin.b, 1.0}}}}},
      {"textureTransformBinds", {{{"material", 4}, {"scale", {2.0, 1.0}}, {"offset", {0.0, 0.0}}}}}};
  return vrm;
}

// VRMC_springBone: one spring per strand, a head sphere and a chest capsule in one group.
inline nlohmann::json springBoneExtension(const VrmTestAvatar& t, const VrmTestAvatarOptions& o) {
  using nlohmann::json;
  json springs = json::array();
  for (size_t k = 0; k < t.strands.size(); ++k) {
    json joints = json::array();
    for (int j : t.strands[k])
      joints.push_back({{"node", j}, {"stiffness", o.stiffness}, {"dragForce", o.dragForce}, {"gravityPower", o.gravityPower},
                        {"gravityDir", {0, -1, 0}}, {"hitRadius", 0.01}});
    springs.push_back({{"name", "hair" + std::to_string(k)}, {"joints", joints}, {"colliderGroups", {0}}});
  }
  json headSphere = {{"node", t.head}, {"shape", {{"sphere", {{"offset", {0, 0.1, 0}}, {"radius", 0.095}}}}}};
  json chestCapsule = {{"node", 3}, {"shape", {{"capsule", {{"offset", {0, 0, 0}}, {"tail", {0, 0.2, 0}}, {"radius", 0.14}}}}}};
  json colliderGroup = {{"name", "body"}, {"colliders", {0, 1}}};
  json spring = {{"specVersion", "1.0"},
                 {"colliders", json::array({headSphere, chestCapsule})},
                 {"colliderGroups", json::array({colliderGroup})},
                 {"springs", springs}};
  return spring;
}

// VRM 0.x: the same data in the 0.x schema (its z axis is Unity's: collider offsets, the look-at
// offset and gravity are written with z negated; this avatar faces +Z, as a 0.x file would not,
// which the parsers do not care about).
inline nlohmann::json vrm0Extension(const VrmTestAvatar& t, const VrmTestAvatarOptions& o) {
  using nlohmann::json;
  const json humanBones = humanBonesJson(t);
  json bones = json::array();
  for (const auto& [bone, node] : humanBones.items()) bones.push_back({{"bone", bone}, {"node", node["node"]}});
  json roots = json::array();
  for (const auto& strand : t.strands) roots.push_back(strand[0]);
  auto group = [&](const char* preset, int channel, double w) {
    return json{{"name", preset}, {"presetName", preset}, {"binds", {{{"mesh", 0}, {"index", channel}, {"weight", w * 100}}}}};
  };
  // angry: _Color is sRGB-encoded in 0.x (Unity's colour), _MainTex_ST is Unity's
  // [scale.x, scale.y, offset.x, offset.y] with v from the bottom (offset.y = 1 - 0 - 1 = 0).
  auto encode = [](float c) { return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f; };
  const json angry0 = {{"name", "angry"}, {"presetName", "angry"}, {"binds", json::array()},
                       {"materialValues", {{{"materialName", "skin"}, {"propertyName", "_Color"},
                                            {"targetValue", {encode(kAngrySkin.r), encode(kAngrySkin.g), encode(kAngrySkin.b), 1.0}}},
                                           {{"materialName", "shirt"}, {"propertyName", "_MainTex_ST"}, {"targetValue", {2.0, 1.0, 0.0, 0.0}}}}}};
  auto group0 = [](int node, float y, float radius) {
    const json collider = {{"offset", {{"x", 0}, {"y", y}, {"z", 0}}}, {"radius", radius}};
    return json{{"node", node}, {"colliders", json::array({collider})}};
  };
  const json curve = {{"curve", {0, 0, 0, 1, 1, 1, 1, 0}}, {"xRange", 45.0}, {"yRange", o.boneLookAt ? 12.0 : 1.0}};
  json v0 = {
      {"specVersion", "0.0"},
      {"humanoid", {{"humanBones", bones}}},
      {"firstPerson", {{"firstPersonBone", t.head}, {"firstPersonBoneOffset", {{"x", 0}, {"y", 0.11}, {"z", -0.07}}},
                       {"lookAtTypeName", o.boneLookAt ? "Bone" : "BlendShape"}, {"lookAtHorizontalInner", curve},
                       {"lookAtHorizontalOuter", curve}, {"lookAtVerticalDown", curve}, {"lookAtVerticalUp", curve}}},
      {"blendShapeMaster", {{"blendShapeGroups", {group("blink", 0, 1), group("lookleft", 1, 1), group("lookright", 2, 1),
                                                  group("lookup", 3, 1), group("lookdown", 4, 1), group("a", 5, 1), angry0}}}},
      {"secondaryAnimation",
       {{"boneGroups", {{{"comment", "hair"}, {"stiffiness", o.stiffness}, {"gravityPower", o.gravityPower},
                         {"gravityDir", {{"x", 0}, {"y", -1}, {"z", 0}}}, {"dragForce", o.dragForce}, {"center", -1},
                         {"hitRadius", 0.01}, {"bones", roots}, {"colliderGroups", {0, 1}}}}},
        {"colliderGroups", json::array({group0(t.head, 0.1f, 0.095f), group0(3, 0.1f, 0.14f)})}}}};
  return v0;
}

}  // namespace vrm_test_detail

inline VrmTestAvatar buildVrmTestAvatar(const VrmTestAvatarOptions& o = {}) {
  using namespace vrm_test_detail;
  using nlohmann::json;
  VrmTestAvatar t;
  t.asset.format = avatar::AvatarFormat::Vrm1;
  addBustAndHair(t);
  addSkinlessLimbs(t);
  const FaceVertices face = addMaterialsAndMesh(t);
  addMorphTargets(t, face);
  if (!o.vrm0) {
    t.extensionsJson = json({{"VRMC_vrm", vrm1Extension(t, o)}, {"VRMC_springBone", springBoneExtension(t, o)}}).dump();
    return t;
  }
  t.asset.format = avatar::AvatarFormat::Vrm0;
  t.extensionsJson = json({{"VRM", vrm0Extension(t, o)}}).dump();
  return t;
}

// Writes the avatar as a .vrm (GLB) file.
inline Status writeVrmTestAvatar(const VrmTestAvatar& t, const std::string& path) {
  return avatar::writeGlbFile(t.asset, path, nullptr, t.extensionsJson);
}

}  // namespace embody::test
