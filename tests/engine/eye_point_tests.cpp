// One eye point: the first-person camera (AvatarRenderer::eyePose at the rest pose) and the body
// solver's head target (AvatarBodySolver::restEyePosition) are both avatar::restEyePoint, for the
// default avatar, a glTF file and a BVH clip (the head's mesh gives it) and a skeleton without a
// mesh (the proportion rule).
#include <catch2/catch.hpp>
#include <string>

#include "avatar/avatar_loader.h"
#include "avatar/body/anthropometry.h"
#include "avatar/body/eye_point.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "engine/avatar_renderer.h"
#include "engine_test_support.h"
#include "runtime/avatar_body_solver.h"
#include "test_paths.h"
#include "tests/support/vrm_test_avatar.h"
#include "tracking/bvh_avatar.h"

using namespace embody;

namespace {

avatar::AvatarAsset vrmTestBust() {
  const test::VrmTestAvatar t = test::buildVrmTestAvatar();
  auto bytes = avatar::encodeGlb(t.asset, nullptr, t.extensionsJson);
  REQUIRE(bytes.ok());
  auto asset = avatar::loadGltfFromMemory(bytes.value(), "");
  REQUIRE(asset.ok());
  REQUIRE(avatar::prepareAvatar(asset.value(), "").ok());
  return std::move(asset).value();
}

// A BVH clip's avatar: its skeleton with a capsule per bone; `skin` false drops the capsules.
avatar::AvatarAsset mixamoFixture(bool skin) {
  tracking::BvhTrackerOptions o;
  auto bvh = tracking::loadBvhAvatar(std::string(test::kSourceDir) + "/tests/tracking/fixtures/mixamo.bvh", o);
  REQUIRE(bvh.ok());
  avatar::AvatarAsset a = bvh->asset;
  if (!skin) a.mesh = avatar::SkinnedMesh{};
  return a;
}

double distance(const glm::dvec3& a, const glm::dvec3& b) { return glm::length(a - b); }

}  // namespace

TEST_CASE("one eye point: the first-person camera and the body solver's head target agree", "[gpu][eye]") {
  test::GpuContext ctx;
  struct Case {
    const char* name;
    avatar::AvatarAsset asset;
    bool fromMesh;
  };
  const Case cases[] = {{"default avatar", avatar::buildDefaultAvatar(), true},
                        {"glTF (the VRM test bust)", vrmTestBust(), true},
                        {"BVH clip (a capsule per bone)", mixamoFixture(true), true},
                        {"BVH skeleton without a mesh", mixamoFixture(false), false}};
  for (const Case& c : cases) {
    INFO(c.name);
    const avatar::AvatarAsset& asset = c.asset;
    const int head = asset.humanoid.joint(avatar::HumanBone::head);
    REQUIRE(head >= 0);
    const avatar::EyePoint eye = avatar::restEyePoint(asset, head, glm::normalize(asset.humanoid.forward));
    CHECK(eye.fromMesh == c.fromMesh);
    // Between the eyes: below the top of the head, within plausible eye heights.
    CHECK(eye.aboveFloor > 0.8 * avatar::kEyeHeightRatio * avatar::restStature(asset, {0, 1, 0}).height);
    CHECK(eye.aboveFloor < avatar::restStature(asset, {0, 1, 0}).height);

    auto solver = runtime::AvatarBodySolver::create(asset);
    REQUIRE(solver.ok());
    const Eigen::Vector3d solverEye = (*solver)->restEyePosition();
    CHECK(distance(glm::dvec3(solverEye.x(), solverEye.y(), solverEye.z()), eye.position) < 1e-5);

    engine::AvatarRendererOptions ro;
    ro.width = ro.height = 64;
    auto renderer = engine::AvatarRenderer::create(*ctx.device, asset, ro);
    if (!renderer.ok()) {
      // A skeleton without a mesh has nothing to upload; the camera rule is then the same call.
      CHECK_FALSE(c.fromMesh);
      continue;
    }
    const glm::vec3 cameraEye((*renderer)->eyePose(avatar::SkeletonPose::rest(asset.skeleton))[3]);
    CHECK(distance(glm::dvec3(cameraEye), eye.position) < 1e-5);
  }
}
