#include <catch2/catch.hpp>

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
