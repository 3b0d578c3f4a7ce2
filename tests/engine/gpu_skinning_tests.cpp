// GPU skinning (the compute shader sharing skinning.glsl with the vertex shader) against the CPU
// reference skinner: same positions and normals within 1e-4.
#include <catch2/catch.hpp>

#include "avatar/gltf/gltf_loader.h"
#include "tests/support/gpu_skinning.h"
#include "engine/renderer.h"
#include "tests/support/test_avatar.h"
#include "engine_test_support.h"
#include "test_paths.h"

using namespace embody;

namespace {

struct Compared {
  float maxPositionError = 0.0f, maxNormalError = 0.0f, maxDisplacement = 0.0f;
};

Compared compareSkinning(test::GpuContext& ctx, const avatar::AvatarAsset& asset, const avatar::SkeletonPose& pose) {
  auto renderer = engine::Renderer::create(*ctx.device);
  REQUIRE(renderer);
  auto gpuAvatar = (*renderer)->upload(asset);
  REQUIRE(gpuAvatar);
  auto skinner = test::GpuSkinner::create(*ctx.device);
  REQUIRE(skinner);

  std::vector<glm::mat4> globals, palette;
  avatar::computeGlobals(asset.skeleton, pose, globals);
  avatar::computeSkinningPalette(asset, globals, palette);
  std::vector<glm::vec3> cpuPos, cpuNrm, gpuPos, gpuNrm;
  avatar::skinOnCpu(asset.mesh, palette, cpuPos, cpuNrm);
  REQUIRE((*skinner)->run(**gpuAvatar, palette, gpuPos, gpuNrm));
  REQUIRE(gpuPos.size() == cpuPos.size());
  Compared c;
  for (size_t i = 0; i < cpuPos.size(); ++i) {
    c.maxPositionError = std::max(c.maxPositionError, glm::length(gpuPos[i] - cpuPos[i]));
    c.maxNormalError = std::max(c.maxNormalError, glm::length(gpuNrm[i] - cpuNrm[i]));
  }
  // How far the pose moved the vertices from the rest pose: proves the pose is not trivial.
  std::vector<glm::mat4> restGlobals, restPalette;
  avatar::computeGlobals(asset.skeleton, avatar::SkeletonPose::rest(asset.skeleton), restGlobals);
  avatar::computeSkinningPalette(asset, restGlobals, restPalette);
  std::vector<glm::vec3> restPos, restNrm;
  avatar::skinOnCpu(asset.mesh, restPalette, restPos, restNrm);
  for (size_t i = 0; i < cpuPos.size(); ++i)
    c.maxDisplacement = std::max(c.maxDisplacement, glm::length(cpuPos[i] - restPos[i]));
  return c;
}

}  // namespace

TEST_CASE("GPU skinning equals CPU skinning on the bent procedural mesh", "[gpu][skinning]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  // The mesh exercises the second influence set (JOINTS_1/WEIGHTS_1).
  size_t withFive = 0;
  for (const auto& v : asset.mesh.vertices) withFive += v.weights1.x > 1e-3f;
  CHECK(withFive > asset.mesh.vertices.size() / 4);
  const auto c = compareSkinning(ctx, asset, test::bentTestPose(asset.skeleton, 0.35f));
  CHECK(c.maxDisplacement > 0.3f);
  CHECK(c.maxPositionError < 1e-4f);
  CHECK(c.maxNormalError < 1e-4f);
}

TEST_CASE("GPU skinning equals CPU skinning on CesiumMan in a non-rest pose", "[gpu][skinning]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  auto asset = avatar::loadAvatarFile(path);
  REQUIRE(asset);
  test::GpuContext ctx;
  const auto c = compareSkinning(ctx, *asset, test::wobblePose(asset->skeleton));
  CHECK(c.maxDisplacement > 0.1f);
  CHECK(c.maxPositionError < 1e-4f);
  CHECK(c.maxNormalError < 1e-4f);
}
