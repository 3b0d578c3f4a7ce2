#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "test_paths.h"
#include "tests/support/gltf_validator_checks.h"

using namespace embody::avatar;

TEST_CASE("the exported default avatar reloads with the same skeleton, mesh and mapping", "[export]") {
  const bool fingers = GENERATE(false, true);  // also the mannequin with finger bones
  INFO("fingers " << fingers);
  const AvatarAsset a = buildDefaultAvatar(DefaultAvatarOptions{.fingers = fingers});
  auto bytes = encodeGlb(a);
  REQUIRE(bytes.ok());
  auto b = loadGltfFromMemory(bytes.value(), "");
  REQUIRE(b.ok());
  REQUIRE(prepareAvatar(b.value(), "").ok());
  // One extra node carries the mesh; every joint keeps its name and rest transform.
  REQUIRE(b->skeleton.joints.size() == a.skeleton.joints.size() + 1);
  for (size_t j = 0; j < a.skeleton.joints.size(); ++j) {
    const int k = b->skeleton.find(a.skeleton.joints[j].name);
    REQUIRE(k >= 0);
    CHECK(glm::length(b->skeleton.joints[k].rest.translation - a.skeleton.joints[j].rest.translation) <
          1e-6f);
  }
  CHECK(b->mesh.triangleCount() == a.mesh.triangleCount());
  CHECK(b->skinJointCount == static_cast<int>(a.skeleton.joints.size()));
  CHECK(b->humanoid.method == MappingMethod::Names);
  CHECK(b->humanoid.missingRequired.empty());
  CHECK(b->humanoid.spine.size() == 25);
  for (int bone = 0; bone < kHumanBoneCount; ++bone) {  // finger bones included
    const int ja = a.humanoid.bones[static_cast<size_t>(bone)],
              jb = b->humanoid.bones[static_cast<size_t>(bone)];
    INFO(humanBoneName(static_cast<HumanBone>(bone)));
    REQUIRE((ja < 0) == (jb < 0));
    if (ja >= 0)
      CHECK(a.skeleton.joints[static_cast<size_t>(ja)].name ==
            b->skeleton.joints[static_cast<size_t>(jb)].name);
  }
  CHECK(b->mesh.firstPersonIndices.size() == a.mesh.firstPersonIndices.size());
  // Skinned at rest, the reloaded mesh sits exactly where the original does.
  std::vector<glm::mat4> ga, gb, pa, pb;
  computeGlobals(a.skeleton, SkeletonPose::rest(a.skeleton), ga);
  computeGlobals(b->skeleton, SkeletonPose::rest(b->skeleton), gb);
  computeSkinningPalette(a, ga, pa);
  computeSkinningPalette(b.value(), gb, pb);
  std::vector<glm::vec3> xa, xb, na, nb;
  skinOnCpu(a.mesh, pa, xa, na);
  skinOnCpu(b->mesh, pb, xb, nb);
  REQUIRE(xa.size() == xb.size());
  float worst = 0.0f;
  for (size_t i = 0; i < xa.size(); ++i) worst = std::max(worst, glm::length(xa[i] - xb[i]));
  CHECK(worst < 1e-5f);
}

TEST_CASE("an exported avatar exports again: its mesh node is a second root, a plain node joins them", "[export]") {
  // The reloaded file's mesh node stands beside the armature at the scene root, so the skeleton
  // has two roots; `render --export FILE.glb` refused it ("exactly one root joint"), on the tool's
  // own `avatar export-default` output (robustness probe, session 20).
  auto once = loadGltfFromMemory(encodeGlb(buildDefaultAvatar()).value(), "");
  REQUIRE(once.ok());
  REQUIRE(prepareAvatar(once.value(), "").ok());
  int roots = 0;
  for (const Joint& j : once->skeleton.joints) roots += j.parent < 0 ? 1 : 0;
  REQUIRE(roots == 2);
  auto bytes = encodeGlb(once.value());
  REQUIRE(bytes.ok());
  auto twice = loadGltfFromMemory(bytes.value(), "");
  REQUIRE(twice.ok());
  REQUIRE(prepareAvatar(twice.value(), "").ok());
  CHECK(twice->skeleton.joints.size() == once->skeleton.joints.size() + 2);  // the joining node, the mesh node
  CHECK(twice->humanoid.missingRequired.empty());
  std::vector<glm::mat4> g1, g2, p1, p2;
  computeGlobals(once->skeleton, SkeletonPose::rest(once->skeleton), g1);
  computeGlobals(twice->skeleton, SkeletonPose::rest(twice->skeleton), g2);
  computeSkinningPalette(once.value(), g1, p1);
  computeSkinningPalette(twice.value(), g2, p2);
  std::vector<glm::vec3> x1, x2, n1, n2;
  skinOnCpu(once->mesh, p1, x1, n1);
  skinOnCpu(twice->mesh, p2, x2, n2);
  REQUIRE(x1.size() == x2.size());
  float worst = 0.0f;
  for (size_t i = 0; i < x1.size(); ++i) worst = std::max(worst, glm::length(x1[i] - x2[i]));
  CHECK(worst < 1e-5f);
  const auto file = std::filesystem::temp_directory_path() / ("embody_reexport_" + std::to_string(::getpid()) + ".glb");
  REQUIRE(writeGlbFile(once.value(), file.string()).ok());
  embody::test::requireNoGltfErrors(file.string());  // the joining node is the skin's common root
}

TEST_CASE("the exported default avatar passes the Khronos glTF validator with zero errors",
          "[export][validator]") {
  const bool fingers = GENERATE(false, true);  // also the mannequin with finger bones
  INFO("fingers " << fingers);
  const auto file = std::filesystem::temp_directory_path() /
                    ("embody_default_avatar_" + std::to_string(::getpid()) + ".glb");
  REQUIRE(writeGlbFile(buildDefaultAvatar(DefaultAvatarOptions{.fingers = fingers}), file.string()).ok());
  const auto report = embody::test::requireNoGltfErrors(file.string());
  if (report) CHECK((*report)["numWarnings"].get<int>() == 0);
}
