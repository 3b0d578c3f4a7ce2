// Golden images (256x256, tests/golden/, driver string beside each): the procedural skinned mesh
// in two poses, CesiumMan in a fixed pose, a stereo pair with asymmetric per-eye frusta, the
// first-person view, 4x MSAA, and the built-in default avatar in its rest pose. Regenerate on purpose only: scripts/update-goldens.sh.
#include <catch2/catch.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/procedural/default_avatar.h"
#include "engine/avatar_renderer.h"
#include "tests/support/test_avatar.h"
#include "engine_test_support.h"
#include "test_paths.h"

using namespace embody;

namespace {

engine::AvatarRendererOptions small(bool stereo = false) {
  engine::AvatarRendererOptions o;
  o.width = o.height = 256;
  o.stereo = stereo;
  return o;
}

}  // namespace

TEST_CASE("golden: procedural mesh, rest pose, gizmos", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, small());
  REQUIRE(r);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  engine::FrameOptions fo;
  fo.gizmos = (*r)->trackingGizmos(pose);
  CHECK(fo.gizmos.size() == 3);
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, 0.5f, 0.15f), fo);
  REQUIRE(img);
  test::checkGolden("procedural_rest", *img, ctx.device->driverString());
}

TEST_CASE("golden: procedural mesh, bent pose, skeleton overlay", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, small());
  REQUIRE(r);
  const auto pose = test::bentTestPose(asset.skeleton, 0.3f);
  engine::FrameOptions fo;
  fo.skeleton = true;
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, -0.4f, 0.2f), fo);
  REQUIRE(img);
  test::checkGolden("procedural_bent", *img, ctx.device->driverString());
}

TEST_CASE("golden: procedural mesh, first-person view", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, small());
  REQUIRE(r);
  const auto pose = test::bentTestPose(asset.skeleton, 0.04f);
  engine::FrameOptions fo;
  fo.view = engine::ViewKind::FirstPerson;
  const glm::mat4 eye = (*r)->eyePose(pose) * glm::rotate(glm::mat4(1.0f), glm::radians(-70.0f), glm::vec3(1, 0, 0));
  auto img = (*r)->render(pose, engine::cameraFromPose(eye, engine::FovAngles::symmetric(glm::radians(100.0f), 1.0f), 0.02f), fo);
  REQUIRE(img);
  test::checkGolden("procedural_first_person", *img, ctx.device->driverString());
}

TEST_CASE("golden: procedural mesh with 4x MSAA", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto o = small();
  o.samples = VK_SAMPLE_COUNT_4_BIT;
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, o);
  REQUIRE(r);
  const auto pose = test::bentTestPose(asset.skeleton, 0.3f);
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, 0.9f, 0.3f), {});
  REQUIRE(img);
  test::checkGolden("procedural_msaa4", *img, ctx.device->driverString());
}

TEST_CASE("golden: CesiumMan in a fixed pose", "[gpu][golden]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  auto asset = avatar::loadAvatarFile(path);
  REQUIRE(asset);
  test::GpuContext ctx;
  auto r = engine::AvatarRenderer::create(*ctx.device, *asset, small());
  REQUIRE(r);
  const auto pose = test::wobblePose(asset->skeleton);
  engine::FrameOptions fo;
  fo.gizmos = (*r)->trackingGizmos(pose);
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, 0.4f, 0.1f), fo);
  REQUIRE(img);
  test::checkGolden("cesiumman_pose", *img, ctx.device->driverString());
}

TEST_CASE("golden: stereo pair with asymmetric per-eye frusta", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, small(true));
  REQUIRE(r);
  const auto pose = test::bentTestPose(asset.skeleton, 0.2f);
  // A head 1.6 m in front of the avatar at eye height looking at it; OpenXR-like fovs (the outer
  // half-angle wider than the inner one, as on most headsets).
  const glm::mat4 head = glm::inverse(glm::lookAt(glm::vec3(0.3f, 1.5f, 1.6f), glm::vec3(0.0f, 1.0f, 0.0f),
                                                  glm::vec3(0.0f, 1.0f, 0.0f)));
  const engine::FovAngles left{-0.90f, 0.70f, 0.80f, -0.85f}, right{-0.70f, 0.90f, 0.80f, -0.85f};
  auto pair = (*r)->renderStereo(pose, engine::stereoCameras(head, 0.064f, left, right), {});
  REQUIRE(pair);
  test::checkGolden("stereo_left", (*pair)[0], ctx.device->driverString());
  test::checkGolden("stereo_right", (*pair)[1], ctx.device->driverString());
}

TEST_CASE("golden: the default avatar in its rest pose", "[gpu][golden]") {
  test::GpuContext ctx;
  const auto asset = avatar::buildDefaultAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, small());
  REQUIRE(r);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  engine::FrameOptions fo;
  fo.gizmos = (*r)->trackingGizmos(pose);
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, 0.5f, 0.15f), fo);
  REQUIRE(img);
  test::checkGolden("default_avatar_rest", *img, ctx.device->driverString());
}
