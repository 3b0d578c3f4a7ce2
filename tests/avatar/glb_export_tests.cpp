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
