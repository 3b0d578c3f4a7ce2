// What the renderer must get right, checked on pixels: readback with padded rows, the image the
// right way up, first person hiding the head, the three glTF alpha modes, bad input rejected,
// frames in flight giving the same image as a blocking frame, and stereo by multiview equal to
// stereo by two passes.
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <numbers>

#include "engine/avatar_renderer.h"
#include "engine/image_io.h"
#include "tests/support/test_avatar.h"
#include "engine_test_support.h"

using namespace embody;

namespace {

uint8_t srgbByte(float linear) {
  const float s = linear <= 0.0031308f ? linear * 12.92f : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
  return uint8_t(std::lround(std::clamp(s, 0.0f, 1.0f) * 255.0f));
}

bool isBackground(const avatar::Image& img, size_t p, const glm::u8vec4& bg) {
  return std::abs(img.rgba[p * 4] - bg.r) <= 2 && std::abs(img.rgba[p * 4 + 1] - bg.g) <= 2 &&
         std::abs(img.rgba[p * 4 + 2] - bg.b) <= 2;
}

// One camera-facing quad per material, side by side, unlit (ambient 1, no directional light).
avatar::AvatarAsset quadsAsset(const std::vector<avatar::Material>& materials) {
  avatar::AvatarAsset a;
  a.skeleton.joints.push_back({"root", -1, {}});
  a.mesh.inverseBind.push_back(glm::mat4(1.0f));
  a.materials = materials;
  for (size_t m = 0; m < materials.size(); ++m) {
    const float x0 = -1.0f + float(m) * 0.7f, x1 = x0 + 0.6f;
    const uint32_t base = uint32_t(a.mesh.vertices.size());
    for (glm::vec2 c : {glm::vec2(x0, 0.0f), glm::vec2(x1, 0.0f), glm::vec2(x1, 0.6f), glm::vec2(x0, 0.6f)}) {
      avatar::SkinnedVertex v;
      v.position = glm::vec3(c, 0.0f);
      v.normal = glm::vec3(0.0f, 0.0f, 1.0f);
      a.mesh.vertices.push_back(v);
    }
    const uint32_t first = uint32_t(a.mesh.indices.size());
    a.mesh.indices.insert(a.mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    a.mesh.primitives.push_back({first, 6, int(m)});
  }
  return a;
}

engine::FrameOptions flatLight() {
  engine::FrameOptions fo;
  fo.grid = false;
  fo.lighting.lightColor = glm::vec3(0.0f);
  fo.lighting.skyColor = fo.lighting.groundColor = glm::vec3(1.0f);
  fo.clearColor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  return fo;
}

}  // namespace

TEST_CASE("readback walks the padded row pitch (width not a multiple of 64)", "[gpu][render]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  engine::AvatarRendererOptions o;
  o.width = 100;  // 400-byte rows, read back with a 512-byte pitch
  o.height = 37;
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, o);
  REQUIRE(r);
  CHECK((*r)->target().rowPitchBytes() == 512);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.clearColor = glm::vec4(0.2f, 0.5f, 0.8f, 1.0f);
  // Camera looking away from the avatar: every pixel is the clear colour.
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  const engine::Camera away = engine::orbitCamera(glm::vec3(0.0f, 1.0f, -20.0f), 5.0f, std::numbers::pi_v<float>, 0.0f,
                                            engine::FovAngles::symmetric(0.8f, 100.0f / 37.0f));
  auto img = (*r)->render(pose, away, fo);
  REQUIRE(img);
  REQUIRE(img->width == 100);
  REQUIRE(img->height == 37);
  const glm::u8vec4 expected(srgbByte(0.2f), srgbByte(0.5f), srgbByte(0.8f), 255);
  size_t wrong = 0;
  for (size_t p = 0; p < 100 * 37; ++p)
    wrong += !isBackground(*img, p, expected) || img->rgba[p * 4 + 3] != 255;
  CHECK(wrong == 0);
}

TEST_CASE("frames are upright and first person hides the head", "[gpu][render]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, {});
  REQUIRE(r);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  const engine::Camera cam = (*r)->orbitAround(pose, 0.0f, 0.0f);
  engine::FrameOptions fo;
  fo.grid = false;
  auto third = (*r)->render(pose, cam, fo);
  fo.view = engine::ViewKind::FirstPerson;
  auto first = (*r)->render(pose, cam, fo);
  REQUIRE(third);
  REQUIRE(first);
  const auto bg = glm::u8vec4((*third).rgba[0], (*third).rgba[1], (*third).rgba[2], 255);
  double avatarRows = 0, headRows = 0;
  size_t avatarPixels = 0, headPixels = 0;
  for (size_t p = 0; p < size_t(third->width) * third->height; ++p) {
    const double row = double(p / size_t(third->width));
    if (!isBackground(*third, p, bg)) avatarRows += row, ++avatarPixels;
    bool differs = false;
    for (int c = 0; c < 3; ++c) differs |= third->rgba[p * 4 + c] != first->rgba[p * 4 + c];
    if (differs) headRows += row, ++headPixels;
  }
  REQUIRE(avatarPixels > 1000);
  REQUIRE(headPixels > 200);  // the head (and only what the head covered) disappeared
  // Row 0 is the top of the image: the head is above the body's centre.
  CHECK(headRows / double(headPixels) < avatarRows / double(avatarPixels) - 20.0);
}

TEST_CASE("alpha modes: OPAQUE ignores alpha, MASK cuts, BLEND mixes", "[gpu][render]") {
  test::GpuContext ctx;
  const glm::vec4 red(1.0f, 0.0f, 0.0f, 0.4f);
  auto material = [&](const char* name, avatar::AlphaMode mode, float cutoff) {
    return avatar::Material{
        .name = name, .baseColorFactor = red, .alphaMode = mode, .alphaCutoff = cutoff, .doubleSided = true};
  };
  const auto asset = quadsAsset({material("opaque", avatar::AlphaMode::Opaque, 0.5f),
                                 material("mask", avatar::AlphaMode::Mask, 0.5f),
                                 material("mask-kept", avatar::AlphaMode::Mask, 0.3f),
                                 material("blend", avatar::AlphaMode::Blend, 0.5f)});
  engine::AvatarRendererOptions o;
  o.width = 320;
  o.height = 160;
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, o);
  REQUIRE(r);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  const engine::Camera cam = engine::orbitCamera(glm::vec3(0.05f, 0.3f, 0.0f), 2.6f, 0.0f, 0.0f,
                                           engine::FovAngles::symmetric(glm::radians(40.0f), 2.0f));
  auto img = (*r)->render(pose, cam, flatLight());
  REQUIRE(img);
  auto at = [&](float x) {  // pixel at the centre of the quad starting at world x
    const glm::vec4 clip = cam.viewProjection() * glm::vec4(x + 0.3f, 0.3f, 0.0f, 1.0f);
    const int px = int((clip.x / clip.w * 0.5f + 0.5f) * float(o.width));
    const int py = int((clip.y / clip.w * 0.5f + 0.5f) * float(o.height));
    const uint8_t* p = &img->rgba[(size_t(py) * o.width + size_t(px)) * 4];
    return glm::ivec3(p[0], p[1], p[2]);
  };
  CHECK(at(-1.0f) == glm::ivec3(255, 0, 0));                  // opaque: alpha ignored
  CHECK(at(-0.3f) == glm::ivec3(0, 0, 0));                    // mask, 0.4 < 0.5: discarded
  CHECK(at(0.4f) == glm::ivec3(255, 0, 0));                   // mask, 0.4 >= 0.3: kept, opaque
  CHECK(std::abs(at(1.1f).x - int(srgbByte(0.4f))) <= 2);     // blend: 40 % red over black
  CHECK(at(1.1f).y == 0);
}

TEST_CASE("bad avatars and poses give clear errors, not GPU faults", "[gpu][render]") {
  test::GpuContext ctx;
  auto renderer = engine::Renderer::create(*ctx.device);
  REQUIRE(renderer);
  auto asset = test::makeTestAvatar();
  SECTION("joint index outside the skeleton") {
    asset.mesh.vertices[10].joints1.y = 99;
    auto g = (*renderer)->upload(asset);
    REQUIRE_FALSE(g);
    CHECK_THAT(g.error(), Catch::Contains("joint"));
  }
  SECTION("vertex index out of range") {
    asset.mesh.indices[5] = uint32_t(asset.mesh.vertices.size());
    auto g = (*renderer)->upload(asset);
    REQUIRE_FALSE(g);
    CHECK_THAT(g.error(), Catch::Contains("out of range"));
  }
  SECTION("material index out of range") {
    asset.mesh.primitives[0].material = 42;
    REQUIRE_FALSE((*renderer)->upload(asset));
  }
  SECTION("NaN in the pose") {
    auto r = engine::AvatarRenderer::create(*ctx.device, asset, {});
    REQUIRE(r);
    auto pose = avatar::SkeletonPose::rest(asset.skeleton);
    pose.local[3].translation.x = std::nanf("");
    auto img = (*r)->render(pose, (*r)->orbitAround(avatar::SkeletonPose::rest(asset.skeleton)), {});
    REQUIRE_FALSE(img);
    CHECK_THAT(img.error(), Catch::Contains("non-finite"));
    // The renderer is still usable afterwards.
    CHECK((*r)->render(avatar::SkeletonPose::rest(asset.skeleton),
                       (*r)->orbitAround(avatar::SkeletonPose::rest(asset.skeleton)), {}));
  }
  SECTION("pose for another skeleton") {
    auto r = engine::AvatarRenderer::create(*ctx.device, asset, {});
    REQUIRE(r);
    avatar::SkeletonPose pose;
    pose.local.resize(2);
    REQUIRE_FALSE((*r)->render(pose, engine::Camera{}, {}));
  }
}

TEST_CASE("frames in flight give the same image as a blocking frame", "[gpu][render]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  auto r = engine::AvatarRenderer::create(*ctx.device, asset, {});
  REQUIRE(r);
  const auto pose = test::bentTestPose(asset.skeleton, 0.25f);
  const engine::Camera cam = (*r)->orbitAround(pose);
  auto reference = (*r)->render(pose, cam, {});
  REQUIRE(reference);
  engine::FrameOptions fo;
  for (int i = 0; i < 6; ++i) {
    // Growing line lists reallocate the per-frame buffers; old ones retire with their frame.
    fo.gizmos.push_back(engine::Gizmo{glm::translate(glm::mat4(1.0f), glm::vec3(float(i), 0.0f, -30.0f))});
    const engine::Camera c[1] = {cam};
    REQUIRE((*r)->submitFrame(test::bentTestPose(asset.skeleton, 0.05f * float(i)), c, fo, false, false));
  }
  auto again = (*r)->render(pose, cam, {});
  REQUIRE(again);
  CHECK(again->rgba == reference->rgba);
  CHECK((*r)->renderer().stats().frames == 8);
}

TEST_CASE("stereo by multiview equals stereo by two passes", "[gpu][render]") {
  test::GpuContext ctx;
  const auto asset = test::makeTestAvatar();
  const auto pose = test::bentTestPose(asset.skeleton, 0.2f);
  const glm::mat4 head = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.3f, 2.2f), glm::vec3(0.0f, 1.0f, 0.0f),
                                                  glm::vec3(0.0f, 1.0f, 0.0f)));
  const engine::FovAngles left{-0.9f, 0.7f, 0.8f, -0.85f}, right{-0.7f, 0.9f, 0.8f, -0.85f};
  const auto eyes = engine::stereoCameras(head, 0.064f, left, right);
  // Grid off: lavapipe (Mesa 22.3) mis-clips lines crossing the near plane in the second view of a
  // multiview pass (docs/renderer.md); triangles are unaffected.
  engine::FrameOptions fo;
  fo.grid = false;
  std::array<avatar::Image, 2> images[2];
  for (int mode = 0; mode < 2; ++mode) {
    engine::AvatarRendererOptions o;
    o.width = 160;
    o.height = 176;
    o.stereo = true;
    o.stereoMode = mode == 0 ? engine::StereoMode::Multiview : engine::StereoMode::TwoPass;
    auto r = engine::AvatarRenderer::create(*ctx.device, asset, o);
    REQUIRE(r);
    auto pair = (*r)->renderStereo(pose, eyes, fo);
    REQUIRE(pair);
    images[mode] = std::move(pair).value();
    // One camera on a stereo renderer draws (and reads back) only the first layer.
    auto mono = (*r)->render(pose, eyes[0], fo);
    REQUIRE(mono);
    CHECK(engine::compareImages(*mono, images[mode][0], 5).failingFraction() <= 0.001);
  }
  for (int eye = 0; eye < 2; ++eye) {
    const auto d = engine::compareImages(images[0][eye], images[1][eye], 5);
    CHECK(d.failingFraction() <= 0.001);
  }
  // The eyes see different images (asymmetric frusta, 64 mm apart).
  CHECK(engine::compareImages(images[1][0], images[1][1], 5).failingPixels > 100);
}
