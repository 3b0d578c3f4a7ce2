#include <catch2/catch.hpp>
#include <functional>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/humanoid/first_person.h"
#include "test_paths.h"

using namespace embody::avatar;

namespace {
std::string boneNode(const AvatarAsset& a, HumanBone b) {
  const int j = a.humanoid.joint(b);
  return j < 0 ? std::string("-") : a.skeleton.joints[j].name;
}

// Every triangle of the first-person list avoids the head and its descendants.
void checkFirstPersonHeadless(const AvatarAsset& a) {
  const int head = a.humanoid.joint(HumanBone::head);
  REQUIRE(head >= 0);
  std::vector<bool> hidden(a.skeleton.joints.size());
  for (size_t j = 0; j < hidden.size(); ++j) hidden[j] = a.skeleton.isAncestor(head, static_cast<int>(j));
  size_t touching = 0;
  for (size_t t = 0; t < a.mesh.firstPersonIndices.size() / 3; ++t)
    touching += triangleTouches(a.mesh, a.mesh.firstPersonIndices, t, hidden) ? 1 : 0;
  CHECK(touching == 0);
  size_t primTotal = 0;
  for (const auto& p : a.mesh.firstPersonPrimitives) primTotal += p.indexCount;
  CHECK(primTotal == a.mesh.firstPersonIndices.size());
}
}  // namespace

TEST_CASE("CesiumMan maps by topology and hides its head in first person", "[humanoid]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  auto a = loadAvatarFile(path);
  REQUIRE(a.ok());
  const auto& h = a->humanoid;
  for (auto& n : h.notes) WARN(n);
  CHECK(h.method == MappingMethod::Topology);
  CHECK(h.missingRequired.empty());
  CHECK(boneNode(*a, HumanBone::hips) == "Skeleton_torso_joint_1");
  CHECK(boneNode(*a, HumanBone::spine) == "Skeleton_torso_joint_2");
  CHECK(boneNode(*a, HumanBone::chest) == "torso_joint_3");
  CHECK(boneNode(*a, HumanBone::neck) == "Skeleton_neck_joint_1");
  CHECK(boneNode(*a, HumanBone::head) == "Skeleton_neck_joint_2");
  CHECK(boneNode(*a, HumanBone::leftUpperLeg) == "leg_joint_L_1");
  CHECK(boneNode(*a, HumanBone::rightLowerLeg) == "leg_joint_R_2");
  CHECK(boneNode(*a, HumanBone::leftFoot) == "leg_joint_L_3");
  CHECK(boneNode(*a, HumanBone::leftToes) == "leg_joint_L_5");
  CHECK(boneNode(*a, HumanBone::leftUpperArm) == "Skeleton_arm_joint_L__4_");
  CHECK(boneNode(*a, HumanBone::leftLowerArm) == "Skeleton_arm_joint_L__3_");
  CHECK(boneNode(*a, HumanBone::leftHand) == "Skeleton_arm_joint_L__2_");
  CHECK(boneNode(*a, HumanBone::rightHand) == "Skeleton_arm_joint_R__3_");
  CHECK(h.forward.z > 0.99f);
  // Spine bones cover every vertebral level once, bottom to top.
  REQUIRE(h.spine.size() == 4);
  int next = 0;
  for (const auto& b : h.spine) {
    CHECK(b.firstLevel == next);
    next = b.endLevel;
  }
  CHECK(next == kVertebralJointCount);
  CHECK(h.spine[1].firstLevel == 5);   // chest from T12-L1
  CHECK(h.spine[2].firstLevel == 17);  // neck from C7-T1
  CHECK(a->firstPerson.mode == "auto");
  CHECK(a->firstPerson.removedTriangles > 100);
  CHECK(a->mesh.firstPersonIndices.size() < a->mesh.indices.size());
  checkFirstPersonHeadless(*a);
}

#include "avatar/avatar_loader.h"
#include "humanoid_test_files.h"

using embody::test::HumanoidFile;
using embody::test::humanoidJointSpecs;

namespace {
using embody::test::loadPrepared;

std::map<std::string, std::string> meaninglessNames() {
  std::map<std::string, std::string> m;
  int i = 0;
  for (const auto& s : humanoidJointSpecs()) m[s.bone] = "J" + std::to_string(100 + i++);
  return m;
}

void checkAllBonesMapped(const AvatarAsset& a, HumanoidFile& f) {
  for (const auto& s : humanoidJointSpecs()) {
    HumanBone b;
    REQUIRE(parseHumanBone(s.bone, b));
    INFO(s.bone);
    CHECK(a.humanoid.joint(b) == a.gltfNodeToJoint[static_cast<size_t>(f.nodeOfBone[s.bone])]);
  }
  CHECK(a.humanoid.missingRequired.empty());
}
}  // namespace

TEST_CASE("a VRM 1.0 file written from the specification maps by VRMC_vrm and honours firstPerson",
          "[humanoid][vrm]") {
  HumanoidFile f(meaninglessNames());
  nlohmann::json bones = nlohmann::json::object();
  for (const auto& [bone, node] : f.nodeOfBone) bones[bone] = {{"node", node}};
  f.doc["extensionsUsed"] = {"VRMC_vrm"};
  f.doc["extensions"]["VRMC_vrm"] = {
      {"specVersion", "1.0"},
      {"meta", {{"name", "test"}, {"authors", {"embody"}}, {"licenseUrl", "https://vrm.dev/licenses/1.0/"}}},
      {"humanoid", {{"humanBones", bones}}},
      {"firstPerson",
       {{"meshAnnotations",
         {{{"node", f.bodyNode}, {"type", "auto"}},
          {{"node", f.hairNode}, {"type", "thirdPersonOnly"}},
          {{"node", f.innerNode}, {"type", "firstPersonOnly"}}}}}}};
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  CHECK(a->format == AvatarFormat::Vrm1);
  CHECK(a->humanoid.method == MappingMethod::Vrm);
  checkAllBonesMapped(*a, f);
  CHECK(a->humanoid.forward.z > 0.99f);
  // spine.md §5: spine L5-S1..L1-L2, chest T12-L1..T7-T8, upperChest T6-T7..T1-T2, neck C7-T1..C1-C2.
  REQUIRE(a->humanoid.spine.size() == 5);
  CHECK(a->humanoid.spine[0].firstLevel == 0);
  CHECK(a->humanoid.spine[0].endLevel == 5);
  CHECK(a->humanoid.spine[1].endLevel == 11);
  CHECK(a->humanoid.spine[2].endLevel == 17);
  CHECK(a->humanoid.spine[3].endLevel == 24);
  CHECK(a->humanoid.spine[4].levelCount() == 1);
  CHECK(a->firstPerson.mode == "vrm");
  // Hair (thirdPersonOnly) is not in first person; the inner mesh (firstPersonOnly) only there.
  auto hasMesh = [](const std::vector<Primitive>& prims, int mesh) {
    for (const auto& p : prims)
      if (p.sourceMesh == mesh) return true;
    return false;
  };
  CHECK(hasMesh(a->mesh.primitives, f.hairMesh));
  CHECK_FALSE(hasMesh(a->mesh.firstPersonPrimitives, f.hairMesh));
  CHECK(hasMesh(a->mesh.firstPersonPrimitives, f.innerMesh));
  CHECK_FALSE(hasMesh(a->mesh.primitives, f.innerMesh));
  CHECK(hasMesh(a->mesh.firstPersonPrimitives, f.bodyMesh));
  // The neck box blends into the head: its upper triangles are gone, the rest of the body stays.
  CHECK(a->firstPerson.removedTriangles > 12);
  checkFirstPersonHeadless(*a);
}

TEST_CASE("a VRM 0.x file maps by its humanBones array and faces -Z", "[humanoid][vrm]") {
  HumanoidFile f(meaninglessNames(), /*facesMinusZ=*/true);
  nlohmann::json bones = nlohmann::json::array();
  for (const auto& [bone, node] : f.nodeOfBone) bones.push_back({{"bone", bone}, {"node", node}});
  f.doc["extensionsUsed"] = {"VRM"};
  f.doc["extensions"]["VRM"] = {
      {"humanoid", {{"humanBones", bones}}},
      {"firstPerson",
       {{"firstPersonBone", f.nodeOfBone["head"]},
        {"meshAnnotations", {{{"mesh", f.hairMesh}, {"firstPersonFlag", "ThirdPersonOnly"}}}}}}};
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  CHECK(a->format == AvatarFormat::Vrm0);
  CHECK(a->humanoid.method == MappingMethod::Vrm);
  checkAllBonesMapped(*a, f);
  CHECK(a->humanoid.forward.z < -0.99f);
  checkFirstPersonHeadless(*a);
}

TEST_CASE("a Mixamo-named skeleton maps by names", "[humanoid]") {
  HumanoidFile f(embody::test::mixamoBoneNames());
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  CHECK(a->format == AvatarFormat::Gltf);
  CHECK(a->humanoid.method == MappingMethod::Names);
  checkAllBonesMapped(*a, f);
  CHECK(a->firstPerson.mode == "auto");
  checkFirstPersonHeadless(*a);
}

TEST_CASE("meaningless names without VRM data map by topology", "[humanoid]") {
  HumanoidFile f(meaninglessNames());
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  CHECK(a->humanoid.method == MappingMethod::Topology);
  CHECK(a->humanoid.missingRequired.empty());
  for (const char* bone : {"hips", "head", "leftUpperArm", "leftHand", "rightLowerArm", "leftUpperLeg",
                           "rightFoot", "leftToes"}) {
    HumanBone b;
    REQUIRE(parseHumanBone(bone, b));
    INFO(bone);
    CHECK(a->humanoid.joint(b) == a->gltfNodeToJoint[static_cast<size_t>(f.nodeOfBone[bone])]);
  }
}

TEST_CASE("twist joints inside the limbs (Daz style) under meaningless names map by topology to the limbs' joints",
          "[humanoid]") {
  // A twist halfway along each upper arm, forearm and thigh, in the chain: arms and legs were one
  // joint off (the left hand on the right upper arm's twist, the clavicle as the upper arm) and
  // the body faced away, at exit 0 (robustness probe, session 20).
  std::map<std::string, std::string> names = meaninglessNames();
  int i = 0;
  for (const auto& t : HumanoidFile::twistJoints()) names[t[0]] = "J" + std::to_string(200 + i++);
  HumanoidFile f(names, false, false, true);
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  CHECK(a->humanoid.method == MappingMethod::Topology);
  checkAllBonesMapped(*a, f);
}

TEST_CASE("a user bone map wins, and a bad one is a clear error", "[humanoid]") {
  HumanoidFile f(meaninglessNames());
  // Swap the hands on purpose: the user's word is final.
  auto a = loadPrepared(f, R"({"leftHand": "J113", "rightHand": "J109"})");
  REQUIRE(a.ok());
  CHECK(a->humanoid.method == MappingMethod::BoneMap);
  CHECK(a->skeleton.joints[a->humanoid.joint(HumanBone::leftHand)].name == "J113");
  CHECK(a->skeleton.joints[a->humanoid.joint(HumanBone::rightHand)].name == "J109");
  HumanoidFile g(meaninglessNames());
  auto bad = loadPrepared(g, R"({"leftHnd": "J113"})");
  REQUIRE_FALSE(bad.ok());
  CHECK_THAT(bad.error(), Catch::Contains("leftHnd"));
  HumanoidFile h(meaninglessNames());
  auto missing = loadPrepared(h, R"({"leftHand": "nope"})");
  REQUIRE_FALSE(missing.ok());
  CHECK_THAT(missing.error(), Catch::Contains("nope"));
}

TEST_CASE("a skeleton that is not a humanoid lists the missing required bones", "[humanoid]") {
  embody::test::TriangleFile t;
  auto a = loadGltfFromMemory(t.glb(), "");
  REQUIRE(a.ok());
  REQUIRE(prepareAvatar(a.value(), "").ok());
  CHECK(a->humanoid.method == MappingMethod::None);
  CHECK(a->humanoid.missingRequired.size() == requiredHumanBones().size());
  CHECK(a->firstPerson.mode == "none");
  CHECK(a->mesh.firstPersonIndices == a->mesh.indices);
}

#include <random>

TEST_CASE("randomly corrupted humanoid files load or fail cleanly, never crash", "[humanoid][fuzz]") {
  HumanoidFile f(meaninglessNames());
  nlohmann::json bones = nlohmann::json::object();
  for (const auto& [bone, node] : f.nodeOfBone) bones[bone] = {{"node", node}};
  f.doc["extensionsUsed"] = {"VRMC_vrm"};
  f.doc["extensions"]["VRMC_vrm"] = {
      {"humanoid", {{"humanBones", bones}}},
      {"firstPerson", {{"meshAnnotations", {{{"node", f.bodyNode}, {"type", "auto"}}}}}}};
  const std::vector<uint8_t> good = f.glb();
  std::mt19937 rng(1234);
  int loaded = 0, failed = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<uint8_t> bytes = good;
    const int flips = 1 + static_cast<int>(rng() % 8);
    for (int k = 0; k < flips; ++k) {
      const size_t at = rng() % bytes.size();
      switch (rng() % 3) {
        case 0:
          bytes[at] = static_cast<uint8_t>(rng());
          break;  // random byte
        case 1:
          bytes[at] = static_cast<uint8_t>('0' + rng() % 10);
          break;  // a digit (JSON numbers)
        default:
          bytes[at] ^= 0x80;
          break;
      }
    }
    auto a = loadGltfFromMemory(bytes, "");
    if (a.ok()) {
      REQUIRE(prepareAvatar(a.value(), "").ok());
      REQUIRE(a->skeleton.validate().empty());
      for (uint32_t i : a->mesh.indices) REQUIRE(i < a->mesh.vertices.size());
      for (uint32_t i : a->mesh.firstPersonIndices) REQUIRE(i < a->mesh.vertices.size());
      ++loaded;
    } else {
      REQUIRE_FALSE(a.error().empty());
      ++failed;
    }
  }
  INFO(loaded << " loaded, " << failed << " refused");
  CHECK(loaded + failed == 300);
}

TEST_CASE("a humanoid skeleton without any mesh still maps (names and topology)", "[humanoid]") {
  for (bool meaningless : {false, true}) {
    HumanoidFile f(meaningless ? meaninglessNames() : std::map<std::string, std::string>{});
    for (auto& node : f.doc["nodes"]) {
      node.erase("mesh");
      node.erase("skin");
    }
    f.doc.erase("meshes");
    f.doc.erase("skins");
    auto a = loadPrepared(f);
    REQUIRE(a.ok());
    CHECK(a->skinJointCount == 0);
    CHECK(a->mesh.triangleCount() == 0);
    CHECK(a->humanoid.method == (meaningless ? MappingMethod::Topology : MappingMethod::Names));
    CHECK(a->humanoid.missingRequired.empty());
  }
}

namespace {

// A CMU-shaped skeleton (CMU units, Y up, facing +Z): one torso bone (Hips -> Spine1 -> Neck), the
// neck and both clavicles at Spine1's own pivot, clavicles 3.8 units long against a 4.9 upper
// arm. `rename` changes names before the skeleton is built.
Skeleton cmuShapedSkeleton(const std::function<std::string(const std::string&)>& rename) {
  Skeleton s;
  auto add = [&](const std::string& name, int parent, glm::vec3 t) {
    Joint j;
    j.name = rename(name);
    j.parent = parent;
    j.rest.translation = t;
    s.joints.push_back(j);
    return static_cast<int>(s.joints.size() - 1);
  };
  const int hips = add("Hips", -1, {0, 17, 0});
  for (float side : {1.0f, -1.0f}) {
    const std::string n = side > 0 ? "Left" : "Right";
    const int up = add(n + "UpLeg", hips, {1.4f * side, -0.8f, 0});
    const int leg = add(n + "Leg", up, {0, -7.5f, 0});
    const int foot = add(n + "Foot", leg, {0, -7.4f, 0});
    add(n + "ToeBase", foot, {0, -0.7f, 2.2f});
  }
  const int spine = add("Spine1", hips, {0, 4.5f, 0});
  const int neck = add("Neck", spine, {0, 0, 0});
  const int head = add("Neck1", neck, {0, 2.2f, 0});
  add("Head", head, {0, 1.6f, 0.2f});
  for (float side : {1.0f, -1.0f}) {
    const std::string n = side > 0 ? "Left" : "Right";
    const int clav = add(n + "Shoulder", spine, {0, 0, 0});
    const int arm = add(n + "Arm", clav, {3.65f * side, 0.8f, -0.4f});
    const int fore = add(n + "ForeArm", arm, {4.9f * side, 0, 0});
    const int hand = add(n + "Hand", fore, {2.7f * side, 0, 0});
    add(n + "HandEnd", hand, {0.8f * side, 0, 0});
  }
  return s;
}

// mapHumanoid on a skeleton without glTF data; the map must drive the body, found by names (kept
// or filled by topology).
HumanoidMap usableByNames(const Skeleton& s) {
  HumanoidInputs in;
  in.skeleton = &s;
  auto map = mapHumanoid(in);
  REQUIRE(map.ok());
  CHECK(map->usable());
  CHECK(map->method == MappingMethod::Names);
  return std::move(map).value();
}

std::string jointName(const Skeleton& s, const HumanoidMap& m, HumanBone b) {
  return m.has(b) ? s.joints[static_cast<size_t>(m.joint(b))].name : std::string("(none)");
}

}  // namespace

TEST_CASE("one torso bone, clavicles at the spine's pivot: names, topology and both together map the arms right",
          "[humanoid]") {
  // The robustness probe (session 20): with one required bone left unmapped by names, the whole
  // map was replaced by the topology's, which took the clavicle for the upper arm and the forearm
  // for the hand (the hand trackers 19 cm off, at the elbows).
  // 1. Names: Spine1 is the only torso bone, so it is the spine (required), not a chest.
  const Skeleton named = cmuShapedSkeleton([](const std::string& n) { return n; });
  const HumanoidMap byNames = usableByNames(named);
  CHECK(jointName(named, byNames, HumanBone::spine) == "Spine1");
  CHECK(jointName(named, byNames, HumanBone::leftUpperArm) == "LeftArm");
  CHECK(jointName(named, byNames, HumanBone::leftHand) == "LeftHand");
  // 2. Topology alone: a first arm joint at the junction's pivot is a clavicle, whatever its length.
  int counter = 0;
  const Skeleton unnamed = cmuShapedSkeleton([&counter](const std::string&) { return "j" + std::to_string(counter++); });
  const HumanoidMap byTopology = mapByTopology(unnamed, {});
  CHECK(byTopology.missingRequired.empty());
  for (auto [bone, expected] : {std::pair{HumanBone::leftShoulder, "LeftShoulder"}, std::pair{HumanBone::leftUpperArm, "LeftArm"},
                                std::pair{HumanBone::leftLowerArm, "LeftForeArm"}, std::pair{HumanBone::rightHand, "RightHand"}}) {
    INFO(humanBoneName(bone));
    CHECK(byTopology.joint(bone) == byNames.joint(bone));  // the same joint order in both skeletons
    CHECK(jointName(named, byNames, bone) == expected);
  }
  // 3. Names with a leg no table knows: the named bones stay, topology fills only the gap.
  const Skeleton partly = cmuShapedSkeleton([](const std::string& n) { return n == "LeftUpLeg" ? std::string("Bone.007") : n; });
  const HumanoidMap filled = usableByNames(partly);
  CHECK(jointName(partly, filled, HumanBone::leftUpperLeg) == "Bone.007");
  CHECK(jointName(partly, filled, HumanBone::leftHand) == "LeftHand");
  CHECK(jointName(partly, filled, HumanBone::leftUpperArm) == "LeftArm");
  REQUIRE_FALSE(filled.notes.empty());
  CHECK(filled.notes.back().find("filled by topology: leftUpperLeg") != std::string::npos);
}
