// VRM motion on the GPU: morph targets in the vertex shader (compared with the CPU skinner) and
// the goldens of the project's test bust (tests/support/vrm_test_avatar.h): spring-bone hair
// swinging after a head turn (two frames), an automatic blink at full closure, and the eyes
// looking left (expression look-at). Each golden is also checked by pixel values, so a
// regression fails with a reason, not only with a golden diff.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/vrm/secondary_motion.h"
#include "engine/avatar_renderer.h"
#include "engine_test_support.h"
#include "tests/support/gpu_skinning.h"
#include "tests/support/vrm_test_avatar.h"

using namespace embody;

namespace {

avatar::AvatarAsset loadBust() {
  const auto path = (std::filesystem::temp_directory_path() / ("embody_bust_" + std::to_string(::getpid()) + ".vrm")).string();
  REQUIRE(test::writeVrmTestAvatar(test::buildVrmTestAvatar(), path).ok());
  auto a = avatar::loadAvatarFile(path);
  std::filesystem::remove(path);
  REQUIRE(a.ok());
  return std::move(a.value());
}

engine::AvatarRendererOptions small() {
  engine::AvatarRendererOptions o;
  o.width = o.height = 256;
  return o;
}

// Front view of the face (close) or of the head and hair.
engine::Camera faceCamera(float distance, float targetHeight = 1.64f) {
  return engine::orbitCamera({0.0f, targetHeight, 0.0f}, distance, 0.0f, 0.05f, engine::FovAngles::symmetric(glm::radians(30.0f), 1.0f),
                             0.02f, 10.0f);
}

// The pixel a world point lands on.
glm::ivec2 pixelOf(const engine::Camera& cam, glm::vec3 p) {
  const glm::vec4 c = cam.viewProjection() * glm::vec4(p, 1.0f);
  const glm::vec2 ndc = glm::vec2(c) / c.w;
  return glm::ivec2(int((ndc.x * 0.5f + 0.5f) * 256.0f), int((ndc.y * 0.5f + 0.5f) * 256.0f));
}

glm::vec3 rgb(const avatar::Image& img, glm::ivec2 p) {
  const uint8_t* px = &img.rgba[(size_t(p.y) * size_t(img.width) + size_t(p.x)) * 4];
  return glm::vec3(px[0], px[1], px[2]) / 255.0f;
}

float brightness(glm::vec3 c) { return (c.r + c.g + c.b) / 3.0f; }

}  // namespace

TEST_CASE("morph targets: GPU morphing + skinning matches the CPU skinner", "[gpu]") {
  test::GpuContext ctx;
  const avatar::AvatarAsset a = loadBust();
  auto r = engine::AvatarRenderer::create(*ctx.device, a, small());
  REQUIRE(r);
  auto skinner = test::GpuSkinner::create(*ctx.device);
  REQUIRE(skinner);
  const auto pose = test::wobblePose(a.skeleton, 0.3f);
  REQUIRE((*r)->computePose(pose));
  const std::vector<float> weights = {0.6f, 0.3f, 0.0f, 1.0f, 0.2f, 0.9f};
  std::vector<glm::vec3> gp, gn, cp, cn;
  REQUIRE((*skinner)->run((*r)->gpuAvatar(), (*r)->palette(), gp, gn, weights));
  avatar::skinOnCpu(a.mesh, (*r)->palette(), cp, cn, weights);
  REQUIRE(gp.size() == cp.size());
  float maxError = 0.0f, maxMorph = 0.0f;
  std::vector<glm::vec3> rp, rn;
  avatar::skinOnCpu(a.mesh, (*r)->palette(), rp, rn);
  for (size_t i = 0; i < gp.size(); ++i) {
    maxError = std::max(maxError, glm::length(gp[i] - cp[i]));
    maxMorph = std::max(maxMorph, glm::length(cp[i] - rp[i]));
  }
  CHECK(maxMorph > 0.005f);  // the weights do move vertices
  CHECK(maxError < 1e-5f);
}

TEST_CASE("golden: VRM spring-bone hair swinging after a head turn", "[gpu][golden]") {
  test::GpuContext ctx;
  const avatar::AvatarAsset a = loadBust();
  auto r = engine::AvatarRenderer::create(*ctx.device, a, small());
  REQUIRE(r);
  avatar::SecondaryMotion motion(a, {.blink = false, .lookAt = false});
  const int head = a.humanoid.joint(avatar::HumanBone::head);
  avatar::SkeletonPose pose;
  auto frame = [&](float yawDegrees) {
    pose = avatar::SkeletonPose::rest(a.skeleton);
    pose.local[static_cast<size_t>(head)].rotation = glm::angleAxis(glm::radians(yawDegrees), glm::vec3(0, 1, 0));
    motion.update(pose, 1.0 / 90.0, std::nullopt);
  };
  for (int i = 0; i < 90; ++i) frame(0.0f);                         // 1 s at rest: hair settled
  for (int i = 1; i <= 12; ++i) frame(70.0f * float(i) / 12.0f);     // turn 70 degrees left in 0.13 s
  for (int i = 0; i < 4; ++i) frame(70.0f);                         // frame A: 45 ms after the turn
  const engine::Camera cam = faceCamera(0.95f, 1.55f);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.morphWeights = motion.morphWeights();
  auto imgA = (*r)->render(pose, cam, fo);
  REQUIRE(imgA);
  const avatar::SkeletonPose poseA = pose;
  for (int i = 0; i < 18; ++i) frame(70.0f);  // frame B: 0.2 s later, swinging back
  auto imgB = (*r)->render(pose, cam, fo);
  REQUIRE(imgB);
  // By numbers: the strand tips trail the rigid head turn in A and move on between A and B.
  avatar::SkeletonPose rigid = avatar::SkeletonPose::rest(a.skeleton);
  rigid.local[static_cast<size_t>(head)].rotation = glm::angleAxis(glm::radians(70.0f), glm::vec3(0, 1, 0));
  std::vector<glm::mat4> gA, gB, gR;
  avatar::computeGlobals(a.skeleton, poseA, gA);
  avatar::computeGlobals(a.skeleton, pose, gB);
  avatar::computeGlobals(a.skeleton, rigid, gR);
  const test::VrmTestAvatar t = test::buildVrmTestAvatar();
  float lagA = 0.0f, moved = 0.0f;
  for (const auto& s : t.strands) {
    const size_t tip = static_cast<size_t>(s.back());
    lagA = std::max(lagA, glm::length(glm::vec3(gA[tip][3]) - glm::vec3(gR[tip][3])));
    moved = std::max(moved, glm::length(glm::vec3(gA[tip][3]) - glm::vec3(gB[tip][3])));
  }
  CHECK(lagA > 0.04f);
  CHECK(moved > 0.02f);
  // And the two frames differ where the hair is.
  size_t differing = 0;
  for (size_t i = 0; i < imgA->rgba.size(); i += 4)
    differing += std::abs(int(imgA->rgba[i]) - int(imgB->rgba[i])) > 20 ? 1 : 0;
  CHECK(differing > 200);
  test::checkGolden("vrm_spring_hair_turn_a", *imgA, ctx.device->driverString());
  test::checkGolden("vrm_spring_hair_turn_b", *imgB, ctx.device->driverString());
}

TEST_CASE("golden: VRM automatic blink at full closure", "[gpu][golden]") {
  test::GpuContext ctx;
  const avatar::AvatarAsset a = loadBust();
  auto r = engine::AvatarRenderer::create(*ctx.device, a, small());
  REQUIRE(r);
  avatar::SecondaryMotion motion(a, {.springBones = false, .lookAt = false, .blinkSeed = 3});
  const engine::Camera cam = faceCamera(0.42f);
  engine::FrameOptions fo;
  fo.grid = false;
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(a.skeleton);
  fo.morphWeights = motion.morphWeights();
  auto open = (*r)->render(pose, cam, fo);  // before the first blink
  REQUIRE(open);
  // Step at 90 Hz until the schedule's first blink is fully closed.
  for (int i = 0; i < 90 * 5 && motion.blinkWeight() < 1.0f; ++i) motion.update(pose, 1.0 / 90.0, std::nullopt);
  REQUIRE(motion.blinkWeight() == 1.0f);
  CHECK(motion.morphWeights()[0] == 1.0f);
  fo.morphWeights = motion.morphWeights();
  auto closed = (*r)->render(pose, cam, fo);
  REQUIRE(closed);
  // The left pupil's centre is dark while open and skin-coloured (bright) when closed.
  const glm::ivec2 pupil = pixelOf(cam, {0.033f, 1.663f, 0.0955f});
  CHECK(brightness(rgb(*open, pupil)) < 0.45f);
  CHECK(brightness(rgb(*closed, pupil)) > 0.5f);
  test::checkGolden("vrm_blink", *closed, ctx.device->driverString());
}

TEST_CASE("golden: VRM eyes looking left (expression look-at)", "[gpu][golden]") {
  test::GpuContext ctx;
  const avatar::AvatarAsset a = loadBust();
  auto r = engine::AvatarRenderer::create(*ctx.device, a, small());
  REQUIRE(r);
  avatar::SecondaryMotion motion(a, {.springBones = false, .blink = false});
  const engine::Camera cam = faceCamera(0.42f);
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(a.skeleton);
  // A target to the avatar's left (+X), 45 degrees off its nose.
  motion.update(pose, 1.0 / 90.0, glm::vec3(0.0f, 1.66f, 0.07f) + glm::vec3(0.6f, 0.0f, 0.6f));
  CHECK(motion.morphWeights()[1] == Approx(1.0f).margin(0.01));
  engine::FrameOptions fo;
  fo.grid = false;
  fo.morphWeights = motion.morphWeights();
  auto img = (*r)->render(pose, cam, fo);
  REQUIRE(img);
  // The pupils moved 8 mm towards +X: the old pupil centre's inner half shows the eye white, the
  // new centre is dark. (+X, the avatar's left, is the right of the image in a front view.)
  const glm::ivec2 oldInner = pixelOf(cam, {0.033f - 0.005f, 1.66f, 0.0955f});
  const glm::ivec2 moved = pixelOf(cam, {0.033f + 0.008f, 1.66f, 0.0955f});
  CHECK(brightness(rgb(*img, oldInner)) > 0.7f);
  CHECK(brightness(rgb(*img, moved)) < 0.45f);
  test::checkGolden("vrm_look_left", *img, ctx.device->driverString());
}

TEST_CASE("golden: VRM expression material binds (angry: red skin, striped shirt)", "[gpu][golden]") {
  test::GpuContext ctx;
  const avatar::AvatarAsset a = loadBust();
  auto r = engine::AvatarRenderer::create(*ctx.device, a, small());
  REQUIRE(r);
  avatar::SecondaryMotion motion(a, {.springBones = false, .blink = false, .lookAt = false});
  const size_t angry = static_cast<size_t>(a.expressions.find(avatar::ExpressionPreset::Angry));
  const engine::Camera cam = faceCamera(1.3f, 1.45f);
  const avatar::SkeletonPose pose = avatar::SkeletonPose::rest(a.skeleton);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.morphWeights = motion.morphWeights();
  auto shownAt = [&](float weight) {
    motion.expressionWeights()[angry] = weight;
    avatar::SkeletonPose p = pose;
    motion.update(p, 1.0 / 90.0, std::nullopt);
    fo.materialStates = motion.materialStates();
    auto img = (*r)->render(p, cam, fo);
    REQUIRE(img);
    return std::move(img).value();
  };
  fo.materialStates = {};
  auto loaded = (*r)->render(pose, cam, fo);  // no states: the materials as loaded
  REQUIRE(loaded);
  const avatar::Image off = shownAt(0.0f), on = shownAt(1.0f), half = shownAt(0.5f), offAgain = shownAt(0.0f);
  // Off is the loaded look, bit for bit, before and after the expression was on (both frame slots).
  CHECK(off.rgba == loaded->rgba);
  CHECK(offAgain.rgba == off.rgba);
  // The forehead: skin (green high) when off, red when on, in between at half weight.
  const glm::ivec2 forehead = pixelOf(cam, {0.0f, 1.71f, 0.075f});
  const glm::vec3 skinOff = rgb(off, forehead), skinOn = rgb(on, forehead), skinHalf = rgb(half, forehead);
  INFO("forehead off " << skinOff.r << " " << skinOff.g << " on " << skinOn.r << " " << skinOn.g << " half " << skinHalf.g);
  CHECK(skinOff.g > 0.7f * skinOff.r);
  CHECK(skinOn.g < 0.45f * skinOn.r);
  CHECK(skinHalf.g < skinOff.g - 0.05f);
  CHECK(skinHalf.g > skinOn.g + 0.05f);
  // The shirt: the texture transform (scale 2) shows the dark half of the texture on the
  // avatar's right front (u 0.75..1 -> 1.5..2), the white half on its left front (u 0..0.25).
  for (float side : {-1.0f, 1.0f}) {
    const float ph = glm::radians(30.0f * side);
    const glm::ivec2 p = pixelOf(cam, {0.17f * std::sin(ph), 1.25f, 0.1f * std::cos(ph)});
    const float b0 = brightness(rgb(off, p)), b1 = brightness(rgb(on, p));
    INFO("shirt side " << side << " off " << b0 << " on " << b1);
    CHECK(b0 > 0.2f);
    if (side < 0)
      CHECK(b1 < 0.35f * b0);
    else
      CHECK(std::abs(b1 - b0) < 0.02f);
  }
  test::checkGolden("vrm_expression_material_binds", on, ctx.device->driverString());
}
