// MToon (VRMC_materials_mtoon 1.0, VRM 0.x "VRM/MToon"), end to end:
//   - the project's MToon test avatars (tests/support/mtoon_test_avatar.h) pass the Khronos glTF
//     validator and load back with the values written (1.0) or converted (0.x);
//   - hostile MToon values load with warnings and the specification's defaults;
//   - shading: flat quads facing the camera, each with one normal, drawn and compared with the
//     specification's formulas evaluated here on the CPU (lit, shade, toony ramp, GI
//     equalization, parametric rim, matcap, shade texture, emission, shading shift texture,
//     KHR_texture_transform on an MToon texture);
//   - render order: renderQueueOffsetNumber and transparentWithZWrite over distance;
//   - outline width on a sphere: world metres, screen share of the height at two distances;
//   - goldens of the mannequin in VRM 1.0 and VRM 0.x MToon, with outline and rim checked by value.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <numbers>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "avatar/avatar_loader.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/gltf/mtoon_json.h"
#include "avatar/vrm/secondary_motion.h"
#include "engine/avatar_renderer.h"
#include "engine_test_support.h"
#include "tests/support/gltf_validator_checks.h"
#include "tests/support/mtoon_test_avatar.h"
#include "tests/support/vrm_test_avatar.h"

using namespace embody;
using nlohmann::json;

namespace {

avatar::AvatarAsset loadBytes(const Result<std::vector<uint8_t>>& bytes, std::vector<std::string>* warnings = nullptr) {
  REQUIRE(bytes.ok());
  avatar::GltfLoadReport report;
  auto asset = avatar::loadGltfFromMemory(bytes.value(), "", &report);
  REQUIRE(asset.ok());
  REQUIRE(avatar::prepareAvatar(*asset, "").ok());
  if (warnings) *warnings = report.warnings;
  return std::move(asset).value();
}

// Runs the Khronos validator: no errors; warnings only about the VRM extensions it does not know
// (VRM 0.x's "VRM" also breaks the PREFIX_name convention: INVALID_EXTENSION_NAME_FORMAT).
void requireValid(const std::vector<uint8_t>& bytes, const char* name) {
  const auto file = std::filesystem::temp_directory_path() / (std::string(name) + std::to_string(::getpid()) + ".vrm");
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  const auto found = test::requireNoGltfErrors(file.string());
  if (!found) return;
  const json& report = *found;
  std::string codes;
  for (const auto& w : report.value("warnings", json::array())) codes += " " + w.value("code", "");
  WARN(name << ": Khronos validator " << report["numErrors"] << " errors, " << report["numWarnings"] << " warnings"
            << codes << ", " << report["numInfos"] << " infos");
  if (report.contains("warnings"))
    for (const auto& w : report["warnings"]) {
      const std::string code = w.value("code", "");
      CHECK((code == "UNSUPPORTED_EXTENSION" || code == "INVALID_EXTENSION_NAME_FORMAT"));
    }
}

}  // namespace

TEST_CASE("MToon VRM 1.0 test avatar: Khronos validator, values round-trip through the writer", "[materials][validator]") {
  const auto bytes = test::mtoonVrm1File();
  REQUIRE(bytes.ok());
  requireValid(bytes.value(), "embody_mtoon1_");
  const auto expected = test::mtoonMannequin();
  std::vector<std::string> warnings;
  const auto a = loadBytes(bytes, &warnings);
  CHECK(warnings.empty());
  CHECK(a.format == avatar::AvatarFormat::Vrm1);
  CHECK(a.humanoid.usable());
  REQUIRE(a.materials.size() == 2);
  for (size_t i = 0; i < 2; ++i) {
    const auto &x = expected.materials[i].mtoon, &y = a.materials[i].mtoon;
    INFO(expected.materials[i].name);
    CHECK(a.materials[i].isMToon);
    CHECK(glm::length(x.shadeColor - y.shadeColor) < 1e-6f);
    CHECK(x.shadingShift == Approx(y.shadingShift));
    CHECK(x.shadingToony == Approx(y.shadingToony));
    CHECK(x.giEqualization == Approx(y.giEqualization));
    CHECK(glm::length(x.rimColor - y.rimColor) < 1e-6f);
    CHECK(x.rimFresnelPower == Approx(y.rimFresnelPower));
    CHECK(x.rimLift == Approx(y.rimLift));
    CHECK(x.rimLightingMix == Approx(y.rimLightingMix));
    CHECK(x.matcapImage == y.matcapImage);
    CHECK(x.outlineMode == y.outlineMode);
    CHECK(x.outlineWidth == Approx(y.outlineWidth));
    CHECK(glm::length(x.outlineColor - y.outlineColor) < 1e-6f);
    CHECK(x.outlineLightingMix == Approx(y.outlineLightingMix));
  }
}

TEST_CASE("the orbit camera's yaw is measured from the avatar's front (VRM 0.x faces -Z, some files +X)",
          "[gpu][render]") {
  // orbitCamera's yaw 0 is from +Z, the glTF front: a VRM 0.x avatar (humanoid.forward -Z, found
  // by the loader) was shown from behind at --yaw 0 and one facing +X in profile (the robustness
  // probe, session 20). The loader's forward detection has its own tests (avatar suite).
  test::GpuContext ctx;
  for (const glm::vec3 forward : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0)}) {
    avatar::AvatarAsset asset = test::mtoonMannequin();
    asset.humanoid.forward = forward;
    auto r = engine::AvatarRenderer::create(*ctx.device, asset);
    REQUIRE(r);
    const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
    const glm::vec3 side = glm::cross(glm::vec3(0, 1, 0), forward);  // the avatar's left
    const glm::vec3 front = (*r)->orbitAround(pose, 0.0f, 0.0f).position();
    const glm::vec3 left = (*r)->orbitAround(pose, float(std::numbers::pi / 2), 0.0f).position();
    INFO("forward " << forward.x << " " << forward.z << "; yaw 0 camera at " << front.x << " " << front.z
                    << ", yaw 90 degrees at " << left.x << " " << left.z);
    CHECK(glm::dot(glm::normalize(glm::vec3(front.x, 0, front.z)), forward) > 0.99f);
    CHECK(glm::dot(glm::normalize(glm::vec3(left.x, 0, left.z)), side) > 0.99f);
  }
}

TEST_CASE("MToon VRM 0.x test avatar: Khronos validator, materialProperties converted to the 1.0 model",
          "[materials][validator]") {
  const auto bytes = test::mtoonVrm0File();
  REQUIRE(bytes.ok());
  requireValid(bytes.value(), "embody_mtoon0_");
  std::vector<std::string> warnings;
  const auto a = loadBytes(bytes, &warnings);
  CHECK(warnings.empty());
  CHECK(a.format == avatar::AvatarFormat::Vrm0);
  REQUIRE(a.materials.size() == 2);
  const auto &cloth = a.materials[0], &skin = a.materials[1];
  CHECK(cloth.isMToon);
  CHECK_FALSE(cloth.unlit);  // the KHR_materials_unlit fallback is replaced
  // _Color was written gamma-encoded: decoded back to linear.
  CHECK(glm::length(glm::vec3(cloth.baseColorFactor) - glm::vec3(0.50f, 0.08f, 0.06f)) < 1e-4f);
  // _ShadeShift -0.2, _ShadeToony 0.8: 0.x ramp [-0.2, lerp(1, -0.2, 0.8) = 0.04] -> toony 0.88, shift 0.08.
  CHECK(cloth.mtoon.shadingToony == Approx(0.88f));
  CHECK(cloth.mtoon.shadingShift == Approx(0.08f));
  CHECK(cloth.mtoon.giEqualization == Approx(0.9f));  // 1 - _IndirectLightIntensity
  CHECK(cloth.mtoon.rimFresnelPower == Approx(3.0f));
  CHECK(cloth.mtoon.rimLightingMix == Approx(0.3f));
  CHECK(cloth.mtoon.outlineMode == avatar::OutlineWidthMode::WorldCoordinates);
  CHECK(cloth.mtoon.outlineWidth == Approx(0.012f));  // 1.2 cm
  CHECK(cloth.mtoon.outlineLightingMix == Approx(0.5f));  // _OutlineColorMode 1 (mixed)
  CHECK(skin.mtoon.outlineMode == avatar::OutlineWidthMode::ScreenCoordinates);
  CHECK(skin.mtoon.outlineWidth == Approx(0.006f));  // 0.01 x 1.2 NDC = 0.6 % of the height
  CHECK(skin.mtoon.outlineLightingMix == 0.0f);       // _OutlineColorMode 0 (fixed)
  CHECK(skin.mtoon.matcapImage == 0);                 // _SphereAdd
  CHECK(skin.mtoon.matcapFactor == glm::vec3(1.0f));
}

TEST_CASE("MToon: hostile values load with one warning each and the specification's defaults", "[materials]") {
  auto bytes = test::mtoonVrm1File();
  REQUIRE(bytes.ok());
  auto hostile = test::editGlbJson(*bytes, [](json& doc) {
    json& t = doc["materials"][0]["extensions"]["VRMC_materials_mtoon"];
    t.erase("specVersion");
    t["shadingToonyFactor"] = "high";
    t["giEqualizationFactor"] = 7.0;
    t["shadeColorFactor"] = {0.5, "x", 0.1};
    t["parametricRimFresnelPowerFactor"] = -3.0;
    t["outlineWidthMode"] = "thick";
    t["outlineWidthFactor"] = -1.0;
    t["shadeMultiplyTexture"] = {{"index", 99}};
    t["matcapTexture"] = {{"index", "zero"}};
    t["rimMultiplyTexture"] = 5;
    t["renderQueueOffsetNumber"] = 42;
    t["transparentWithZWrite"] = "yes";
    t["outlineColorFactor"] = {2.0, -1.0, 0.5};
    doc["materials"][1]["extensions"]["VRMC_materials_mtoon"] = json::array();
  });
  std::vector<std::string> warnings;
  const auto a = loadBytes(hostile, &warnings);
  for (const auto& w : warnings) INFO(w);
  CHECK(warnings.size() == 14);
  const auto& t = a.materials[0].mtoon;
  CHECK(t.shadingToony == 0.9f);
  CHECK(t.giEqualization == 1.0f);
  CHECK(t.shadeColor == glm::vec3(0.0f));
  CHECK(t.rimFresnelPower == 0.0f);
  CHECK(t.outlineMode == avatar::OutlineWidthMode::None);
  CHECK(t.outlineWidth == 0.0f);
  CHECK(t.shadeImage == -1);
  CHECK(t.matcapImage == -1);
  CHECK(t.rimImage == -1);
  CHECK(t.renderQueueOffset == 0);
  CHECK_FALSE(t.transparentWithZWrite);
  CHECK(t.outlineColor == glm::vec3(1.0f, 0.0f, 0.5f));
  CHECK_FALSE(a.materials[1].isMToon);  // not an object: drawn as its glTF material

  // VRM 0.x: a property list that is not an array, then broken entries.
  auto vrm0 = test::mtoonVrm0File();
  REQUIRE(vrm0.ok());
  auto notArray = test::editGlbJson(*vrm0, [](json& doc) { doc["extensions"]["VRM"]["materialProperties"] = 3; });
  loadBytes(notArray, &warnings);
  CHECK(warnings.size() == 1);
  auto broken = test::editGlbJson(*vrm0, [](json& doc) {
    json& list = doc["extensions"]["VRM"]["materialProperties"];
    list[0]["floatProperties"] = json::array({1, 2});  // ignored: defaults
    list[0]["vectorProperties"]["_Color"] = "red";
    list[1]["floatProperties"]["_OutlineWidth"] = "wide";
    list[1]["textureProperties"]["_SphereAdd"] = -4;
    list[1]["vectorProperties"]["_MainTex"] = {0, 0};
    list.push_back({{"shader", "VRM/MToon"}});  // no glTF material 2
  });
  const auto b = loadBytes(broken, &warnings);
  for (const auto& w : warnings) INFO(w);
  CHECK(warnings.size() == 6);
  CHECK(b.materials[0].isMToon);
  CHECK(b.materials[0].mtoon.shadingToony == Approx(0.95f));  // 0.x defaults: toony 0.9, shift 0
  CHECK(b.materials[1].mtoon.outlineWidth == 0.0f);
  CHECK(b.materials[1].mtoon.matcapImage == -1);

  // What the loader accepted also draws (no validation message).
  test::GpuContext ctx;
  auto r = engine::AvatarRenderer::create(*ctx.device, a);
  REQUIRE(r);
  auto img = (*r)->render(avatar::SkeletonPose::rest(a.skeleton), (*r)->orbitAround(avatar::SkeletonPose::rest(a.skeleton)), {});
  CHECK(img);
}

namespace {

const test::TileGrid kMtoonGrid{4, 4};

// The specification's MToon formulas (Lighting, Global Illumination, Rim Lighting) for one
// material, normal and view direction, with the renderer's lights; textures given as their
// (linear) values.
glm::vec3 mtoonReference(const avatar::Material& m, glm::vec3 n, glm::vec3 v, const engine::Lighting& light,
                         glm::vec3 shadeTexel = glm::vec3(1.0f), glm::vec3 matcapTexel = glm::vec3(0.0f)) {
  const avatar::MToon& t = m.mtoon;
  const glm::vec3 base(m.baseColorFactor);
  const glm::vec3 l = glm::normalize(light.directionToLight);
  const float a = -1.0f + t.shadingToony, b = 1.0f - t.shadingToony;
  const float shading = glm::clamp((glm::dot(n, l) + t.shadingShift - a) / std::max(b - a, 1e-5f), 0.0f, 1.0f);
  glm::vec3 color = glm::mix(t.shadeColor * shadeTexel, base, shading) * light.lightColor;
  const glm::vec3 rawGi = glm::mix(light.groundColor, light.skyColor, n.y * 0.5f + 0.5f);
  const glm::vec3 gi = glm::mix(rawGi, 0.5f * (light.skyColor + light.groundColor), t.giEqualization);
  color += gi * base;
  glm::vec3 rim = t.matcapFactor * matcapTexel;
  rim += std::pow(glm::clamp(1.0f - glm::dot(n, v) + t.rimLift, 0.0f, 1.0f), std::max(t.rimFresnelPower, 1e-5f)) * t.rimColor;
  rim *= glm::mix(glm::vec3(1.0f), light.lightColor + gi, t.rimLightingMix);
  return color + rim + m.emissiveFactor * m.emissiveStrength;
}

int srgbByte(float linear) {
  const float c = glm::clamp(linear, 0.0f, 1.0f);
  return int(std::lround(255.0f * (c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f)));
}

avatar::Image solidImage(uint8_t r, uint8_t g, uint8_t b, uint8_t a = 255) {
  avatar::Image img{4, 4, {}};
  for (int i = 0; i < 16; ++i) img.rgba.insert(img.rgba.end(), {r, g, b, a});
  return img;
}

struct MToonTiles {
  avatar::AvatarAsset asset;
  MToonTiles() {
    asset.skeleton.joints.push_back({"root", -1, {}});
    asset.mesh.inverseBind = {glm::mat4(1.0f)};
  }
  int material(avatar::Material m) {
    asset.materials.push_back(std::move(m));
    return int(asset.materials.size() - 1);
  }
  // A quad over part of a tile (fractions), at depth z, facing the camera; every vertex has `normal`.
  void quad(int column, int row, int material, glm::vec3 normal, glm::vec4 rect = {0, 0, 1, 1}, float z = 0.0f) {
    const glm::vec2 c = kMtoonGrid.corner(column, row);
    const uint32_t first = uint32_t(asset.mesh.indices.size()), base = uint32_t(asset.mesh.vertices.size());
    for (int k = 0; k < 4; ++k) {
      avatar::SkinnedVertex v;
      const float fx = (k == 1 || k == 2) ? 1.0f : 0.0f, fy = k >= 2 ? 1.0f : 0.0f;
      v.position = glm::vec3(c.x + glm::mix(rect.x, rect.z, fx), c.y + glm::mix(rect.y, rect.w, fy), z);
      v.normal = normal;
      v.uv = glm::vec2(fx, 1.0f - fy);
      asset.mesh.vertices.push_back(v);
    }
    for (uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) asset.mesh.indices.push_back(base + i);
    asset.mesh.primitives.push_back({first, 6, material});
  }
};

avatar::Material toon(glm::vec3 base, glm::vec3 shade, float toony = 0.9f) {
  avatar::Material m;
  m.isMToon = true;
  m.baseColorFactor = glm::vec4(base, 1.0f);
  m.mtoon.shadeColor = shade;
  m.mtoon.shadingToony = toony;
  return m;
}

avatar::Material blended(glm::vec3 color, int queueOffset, bool zwrite) {
  avatar::Material m = toon(glm::vec3(0.0f), glm::vec3(0.0f));
  m.baseColorFactor = glm::vec4(0.0f, 0.0f, 0.0f, 0.5f);
  m.emissiveFactor = color;  // black lit colour: the emission alone shows
  m.alphaMode = avatar::AlphaMode::Blend;
  m.mtoon.giEqualization = 1.0f;
  m.mtoon.renderQueueOffset = queueOffset;
  m.mtoon.transparentWithZWrite = zwrite;
  return m;
}

}  // namespace

TEST_CASE("MToon shading follows the specification's formulas, render queue and transparentWithZWrite order",
          "[gpu][materials]") {
  const engine::Lighting light;
  const glm::vec3 l = glm::normalize(light.directionToLight);
  const glm::vec3 perp = glm::normalize(glm::cross(l, glm::vec3(1, 0, 0)));
  const glm::vec3 towardCamera(0.0f, 0.0f, 1.0f);
  struct Tile {
    avatar::Material material;
    glm::vec3 normal;
    glm::vec3 shadeTexel{1.0f}, matcapTexel{0.0f};
  };
  std::vector<Tile> tiles;
  const glm::vec3 base(0.6f, 0.3f, 0.2f), shade(0.1f, 0.1f, 0.3f);
  tiles.push_back({toon(base, shade), l});   // lit
  tiles.push_back({toon(base, shade), -l});  // shade
  tiles.push_back({toon(base, shade, 0.5f), glm::normalize(0.1f * l + std::sqrt(0.99f) * perp)});  // on the ramp: 0.6
  auto gi0 = toon(glm::vec3(0.5f), glm::vec3(0.5f));
  gi0.mtoon.giEqualization = 0.0f;
  tiles.push_back({gi0, glm::vec3(0, -1, 0)});  // GI from below only
  auto gi1 = gi0;
  gi1.mtoon.giEqualization = 1.0f;
  tiles.push_back({gi1, glm::vec3(0, -1, 0)});  // GI equalized
  auto rim = toon(glm::vec3(0.1f), glm::vec3(0.1f));
  rim.mtoon.rimColor = glm::vec3(0.8f, 0.2f, 0.0f);
  rim.mtoon.rimLift = 0.6f;
  rim.mtoon.rimFresnelPower = 2.0f;
  rim.mtoon.rimLightingMix = 0.0f;
  tiles.push_back({rim, glm::normalize(glm::vec3(0.6f, 0.0f, 0.8f))});
  auto rimLit = rim;
  rimLit.mtoon.rimLightingMix = 1.0f;
  tiles.push_back({rimLit, glm::normalize(glm::vec3(0.6f, 0.0f, 0.8f))});
  auto matcap = toon(glm::vec3(0.1f), glm::vec3(0.1f));
  matcap.mtoon.matcapImage = 0;  // a solid sRGB (128, 200, 60) image
  matcap.mtoon.matcapFactor = glm::vec3(0.5f);
  tiles.push_back({matcap, towardCamera, glm::vec3(1.0f),
                   glm::vec3(avatar::srgbToLinear(128 / 255.0f), avatar::srgbToLinear(200 / 255.0f), avatar::srgbToLinear(60 / 255.0f))});
  auto shadeTex = toon(base, glm::vec3(0.8f));
  shadeTex.mtoon.shadeImage = 1;  // solid sRGB (200, 100, 50)
  tiles.push_back({shadeTex, -l,
                   glm::vec3(avatar::srgbToLinear(200 / 255.0f), avatar::srgbToLinear(100 / 255.0f), avatar::srgbToLinear(50 / 255.0f))});
  auto emissive = toon(glm::vec3(0.2f), glm::vec3(0.05f));
  emissive.emissiveFactor = glm::vec3(0.3f, 0.2f, 0.0f);
  tiles.push_back({emissive, towardCamera});
  // Shading shift texture: linear data (R 128 = +0.502 through the UNORM copy; an sRGB read would
  // give +0.216), toony 0 so that the ramp shows the shift: linearstep(-1, 1, 0 + 0.502) = 0.751.
  auto shift = toon(base, shade, 0.0f);
  shift.mtoon.shadingShiftImage = 2;
  tiles.push_back({shift, perp});
  const float shiftR = 128 / 255.0f;  // the reference adds the texture through shadingShift
  tiles.back().material.mtoon.shadingShift = shiftR;
  // KHR_texture_transform on an MToon texture: the shade texture's right half (green) picked out
  // of a red | green image by offset (0.5, 0) and scale (0.5, 1).
  auto halves = toon(base, glm::vec3(1.0f));
  halves.mtoon.shadeImage = 3;
  halves.mtoon.shadeTransform.offset = {0.5f, 0.0f};
  halves.mtoon.shadeTransform.scale = {0.5f, 1.0f};
  tiles.push_back({halves, -l, glm::vec3(0.0f, 1.0f, 0.0f)});

  MToonTiles scene;
  avatar::Image redGreen{2, 2, {255, 0, 0, 255, 0, 255, 0, 255, 255, 0, 0, 255, 0, 255, 0, 255}};
  scene.asset.images = {solidImage(128, 200, 60), solidImage(200, 100, 50), solidImage(128, 0, 0), redGreen};
  for (size_t i = 0; i < tiles.size(); ++i) {
    avatar::Material drawn = tiles[i].material;
    if (drawn.mtoon.shadingShiftImage >= 0) drawn.mtoon.shadingShift = 0.0f;  // the texture shifts instead
    scene.quad(int(i % 4), int(i / 4), scene.material(drawn), tiles[i].normal);
  }
  // Tile (0, 3): the near red quad (offset -5) is drawn before the far blue one (offset 0):
  // blue over red where they overlap, although back to front alone would put red on top.
  scene.quad(0, 3, scene.material(blended({1, 0, 0}, -5, false)), towardCamera, {0.0f, 0.0f, 0.7f, 1.0f}, 0.3f);
  scene.quad(0, 3, scene.material(blended({0, 0, 1}, 0, false)), towardCamera, {0.3f, 0.0f, 1.0f, 1.0f}, 0.0f);
  // Tile (1, 3): the near green quad writes depth (transparentWithZWrite, drawn first), so the
  // far blue quad is hidden behind it.
  scene.quad(1, 3, scene.material(blended({0, 1, 0}, 0, true)), towardCamera, {0.0f, 0.0f, 0.7f, 1.0f}, 0.3f);
  scene.quad(1, 3, scene.material(blended({0, 0, 1}, 0, false)), towardCamera, {0.3f, 0.0f, 1.0f, 1.0f}, 0.0f);
  scene.asset.mesh.firstPersonIndices.clear();

  test::GpuContext ctx;
  engine::AvatarRendererOptions o;
  o.width = 256;
  o.height = 256;
  auto r = engine::AvatarRenderer::create(*ctx.device, scene.asset, o);
  REQUIRE(r);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.clearColor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  const engine::Camera cam = kMtoonGrid.camera();
  auto img = (*r)->render(avatar::SkeletonPose::rest(scene.asset.skeleton), cam, fo);
  REQUIRE(img);
  auto at = [&](int column, int row, glm::vec2 f) { return test::rgbaAt(*img, kMtoonGrid.pixel(cam, column, row, f, 256, 256)); };

  for (size_t i = 0; i < tiles.size(); ++i) {
    const int column = int(i % 4), row = int(i / 4);
    const glm::vec2 centre = kMtoonGrid.corner(column, row) + glm::vec2(0.5f);
    const glm::vec3 v = glm::normalize(glm::vec3(0, 0, 10) - glm::vec3(centre, 0.0f));
    const glm::vec3 expected = mtoonReference(tiles[i].material, tiles[i].normal, v, light, tiles[i].shadeTexel, tiles[i].matcapTexel);
    const glm::ivec4 got = at(column, row, {0.5f, 0.5f});
    INFO("tile " << i << ": expected linear " << expected.r << " " << expected.g << " " << expected.b << ", got sRGB "
                 << got.r << " " << got.g << " " << got.b);
    for (int c = 0; c < 3; ++c) CHECK(std::abs(got[c] - srgbByte(expected[c])) <= 3);
  }
  const glm::ivec4 overlapQueue = at(0, 3, {0.5f, 0.5f}), overlapZWrite = at(1, 3, {0.5f, 0.5f});
  INFO("queue overlap " << overlapQueue.r << " " << overlapQueue.b << "; z-write overlap " << overlapZWrite.g << " "
                        << overlapZWrite.b);
  CHECK(overlapQueue.b > overlapQueue.r + 40);  // blue (later queue) over red
  CHECK(overlapZWrite.g > 150);
  CHECK(overlapZWrite.b < 8);  // the far quad is behind the z-writing one
  CHECK(at(1, 3, {0.9f, 0.5f}).b > 150);  // and drawn where nothing hides it
}

namespace {

const glm::vec4 kBackground(0.45f, 0.50f, 0.55f, 1.0f);

// The avatar at rest from a fixed three-quarter view (the camera framed on `framing`, so that
// variants of one avatar are seen from exactly the same place), 256 x 256, no grid.
avatar::Image shoot(test::GpuContext& ctx, const avatar::AvatarAsset& asset, const avatar::AvatarAsset& framing) {
  auto framer = engine::AvatarRenderer::create(*ctx.device, framing);
  REQUIRE(framer);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  const engine::Camera cam = (*framer)->orbitAround(pose, 0.6f, 0.1f);
  auto r = engine::AvatarRenderer::create(*ctx.device, asset);
  REQUIRE(r);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.clearColor = kBackground;
  auto img = (*r)->render(pose, cam, fo);
  REQUIRE(img);
  return std::move(img).value();
}

bool isBackground(const avatar::Image& img, int x, int y, glm::ivec4 bg) {
  return test::rgbaAt(img, {x, y}) == bg;
}

// Pixels the outline adds around the silhouette (background without it, covered with it), and the
// mean of their brightest channel.
std::pair<int, float> outlineRing(const avatar::Image& with, const avatar::Image& without) {
  const glm::ivec4 bg = test::rgbaAt(without, {0, 0});
  int count = 0;
  float brightness = 0.0f;
  for (int y = 0; y < with.height; ++y)
    for (int x = 0; x < with.width; ++x)
      if (isBackground(without, x, y, bg) && !isBackground(with, x, y, bg)) {
        const glm::ivec4 c = test::rgbaAt(with, {x, y});
        ++count;
        brightness += float(std::max({c.r, c.g, c.b}));
      }
  return {count, count ? brightness / float(count) : 0.0f};
}

std::vector<avatar::Material> withoutOutlines(std::vector<avatar::Material> ms) {
  for (auto& m : ms) m.mtoon.outlineMode = avatar::OutlineWidthMode::None;
  return ms;
}

}  // namespace

TEST_CASE("golden: MToon VRM 1.0 avatar with outline and rim", "[gpu][golden][materials]") {
  const auto asset = loadBytes(test::mtoonVrm1File());
  auto noOutline = asset, noRim = asset;
  noOutline.materials = withoutOutlines(asset.materials);
  noRim.materials = noOutline.materials;
  for (auto& m : noRim.materials) m.mtoon.rimColor = glm::vec3(0.0f);
  test::GpuContext ctx;
  const auto full = shoot(ctx, asset, asset), bare = shoot(ctx, noOutline, asset), flat = shoot(ctx, noRim, asset);

  // Outline: a ring of dark pixels around the silhouette (world 1.2 cm on the cloth, 0.6 % of the
  // height on the skin: about 1.5 px here).
  const auto [ring, ringBrightness] = outlineRing(full, bare);
  INFO("outline ring: " << ring << " px, mean brightest channel " << ringBrightness);
  CHECK(ring > 400);
  CHECK(ringBrightness < 110.0f);
  // Rim: the fresnel rim adds red mostly near the silhouette (pixels within 2 px of the background).
  const glm::ivec4 bg = test::rgbaAt(flat, {0, 0});
  double edgeGain = 0, innerGain = 0;
  int edges = 0, inners = 0;
  for (int y = 2; y < 254; ++y)
    for (int x = 2; x < 254; ++x) {
      if (isBackground(flat, x, y, bg)) continue;
      bool edge = false;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) edge |= isBackground(flat, x + dx, y + dy, bg);
      const int gain = test::rgbaAt(bare, {x, y}).r - test::rgbaAt(flat, {x, y}).r;
      (edge ? edgeGain : innerGain) += gain;
      ++(edge ? edges : inners);
    }
  edgeGain /= std::max(edges, 1);
  innerGain /= std::max(inners, 1);
  INFO("rim red gain: edge " << edgeGain << " (" << edges << " px), inside " << innerGain << " (" << inners << " px)");
  CHECK(edgeGain > 20.0);
  CHECK(edgeGain > 2.0 * innerGain);
  test::checkGolden("mtoon_vrm1", full, ctx.device->driverString());
}

TEST_CASE("golden: VRM 0.x MToon materialProperties avatar", "[gpu][golden][materials]") {
  const auto asset = loadBytes(test::mtoonVrm0File());
  auto noOutline = asset;
  noOutline.materials = withoutOutlines(asset.materials);
  // The same file without materialProperties: what a reader without 0.x MToon shows (unlit).
  const auto vrm0 = test::mtoonVrm0File();
  REQUIRE(vrm0.ok());
  auto fallbackBytes = test::editGlbJson(vrm0.value(), [](json& doc) {
    doc["extensions"]["VRM"].erase("materialProperties");
  });
  const auto fallback = loadBytes(fallbackBytes);
  test::GpuContext ctx;
  const auto full = shoot(ctx, asset, asset), bare = shoot(ctx, noOutline, asset), unlit = shoot(ctx, fallback, asset);
  const auto [ring, ringBrightness] = outlineRing(full, bare);
  INFO("outline ring: " << ring << " px, mean brightest channel " << ringBrightness);
  CHECK(ring > 400);
  CHECK(ringBrightness < 110.0f);
  // Toon shading, not the flat fallback: most covered pixels differ.
  const glm::ivec4 bg = test::rgbaAt(bare, {0, 0});
  int covered = 0, differ = 0;
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      if (isBackground(bare, x, y, bg)) continue;
      ++covered;
      const glm::ivec4 a = test::rgbaAt(bare, {x, y}), b = test::rgbaAt(unlit, {x, y});
      differ += std::abs(a.r - b.r) + std::abs(a.g - b.g) + std::abs(a.b - b.b) > 24;
    }
  INFO(differ << " of " << covered << " covered pixels differ from the unlit fallback");
  CHECK(differ > covered / 2);
  test::checkGolden("mtoon_vrm0", full, ctx.device->driverString());
}

namespace {

// A UV sphere (smooth normals) of `radius` at the origin with one material.
avatar::AvatarAsset sphereAsset(float radius, const avatar::Material& material) {
  avatar::AvatarAsset a;
  a.skeleton.joints.push_back({"root", -1, {}});
  a.mesh.inverseBind = {glm::mat4(1.0f)};
  constexpr int kRings = 48, kSegments = 96;
  for (int i = 0; i <= kRings; ++i)
    for (int j = 0; j <= kSegments; ++j) {
      const float theta = float(M_PI) * float(i) / kRings, phi = 2.0f * float(M_PI) * float(j) / kSegments;
      avatar::SkinnedVertex v;
      v.normal = glm::vec3(std::sin(theta) * std::cos(phi), std::cos(theta), -std::sin(theta) * std::sin(phi));
      v.position = radius * v.normal;
      a.mesh.vertices.push_back(v);
    }
  for (uint32_t i = 0; i < kRings; ++i)
    for (uint32_t j = 0; j < kSegments; ++j) {
      const uint32_t p = i * (kSegments + 1) + j, q = p + kSegments + 1;
      for (uint32_t k : {p, q, p + 1, p + 1, q, q + 1}) a.mesh.indices.push_back(k);
    }
  a.mesh.primitives.push_back({0, uint32_t(a.mesh.indices.size()), 0});
  a.materials = {material};
  return a;
}

// Radii (pixels) of the sphere's disc and of the disc with its outline ring (pure green), from
// their areas in a 256 x 256 frame.
std::pair<double, double> discRadii(const avatar::Image& img) {
  int surface = 0, ring = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const glm::ivec4 c = test::rgbaAt(img, {x, y});
      if (c.g > 200 && c.r < 60 && c.b < 60) ++ring;
      else if (c.r + c.g + c.b > 0) ++surface;
    }
  return {std::sqrt(surface / M_PI), std::sqrt((surface + ring) / M_PI)};
}

}  // namespace

TEST_CASE("MToon outline width: metres in world mode, a share of the height at any distance in screen mode",
          "[gpu][materials]") {
  avatar::Material m = toon(glm::vec3(0.8f, 0.1f, 0.1f), glm::vec3(0.4f, 0.0f, 0.0f));
  m.mtoon.outlineColor = glm::vec3(0.0f, 1.0f, 0.0f);
  m.mtoon.outlineLightingMix = 0.0f;
  const float radius = 0.5f, fovY = 0.6f;
  test::GpuContext ctx;
  auto radii = [&](avatar::OutlineWidthMode mode, float width, float distance) {
    m.mtoon.outlineMode = mode;
    m.mtoon.outlineWidth = width;
    const auto asset = sphereAsset(radius, m);
    auto r = engine::AvatarRenderer::create(*ctx.device, asset);
    REQUIRE(r);
    engine::FrameOptions fo;
    fo.grid = false;
    fo.clearColor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    const auto cam = engine::cameraFromPose(glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, distance)),
                                            engine::FovAngles::symmetric(fovY, 1.0f), 0.1f, 50.0f);
    auto img = (*r)->render(avatar::SkeletonPose::rest(asset.skeleton), cam, fo);
    REQUIRE(img);
    return discRadii(*img);
  };
  // The silhouette of a sphere of radius s at distance d: tan(asin(s / d)) / tan(fov / 2) x 128 px.
  auto silhouette = [&](float s, float d) { return std::tan(std::asin(s / d)) / std::tan(fovY / 2) * 128.0; };
  const auto world = radii(avatar::OutlineWidthMode::WorldCoordinates, 0.08f, 4.0f);
  INFO("world: sphere " << world.first << " px (expected " << silhouette(radius, 4.0f) << "), with outline "
                        << world.second << " px (expected " << silhouette(radius + 0.08f, 4.0f) << ")");
  CHECK(std::abs(world.first - silhouette(radius, 4.0f)) < 0.5);
  CHECK(std::abs(world.second - silhouette(radius + 0.08f, 4.0f)) < 0.5);
  // Screen: 0.02 of 256 px = 5.12 px, near and twice as far.
  for (float distance : {4.0f, 8.0f}) {
    const auto screen = radii(avatar::OutlineWidthMode::ScreenCoordinates, 0.02f, distance);
    INFO("screen at " << distance << " m: ring " << screen.second - screen.first << " px");
    CHECK(std::abs(screen.second - screen.first - 5.12) < 0.3);
  }
  const auto none = radii(avatar::OutlineWidthMode::None, 0.08f, 4.0f);
  CHECK(none.second == none.first);
}

namespace {

// The avatar at rest from shoot()'s view, with per-frame material bind states (empty: as loaded).
avatar::Image shootWithStates(test::GpuContext& ctx, const avatar::AvatarAsset& asset,
                              std::span<const avatar::MaterialBindState> states, double seconds = 0.0) {
  auto r = engine::AvatarRenderer::create(*ctx.device, asset);
  REQUIRE(r);
  const auto pose = avatar::SkeletonPose::rest(asset.skeleton);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.clearColor = kBackground;
  fo.materialStates = states;
  fo.seconds = seconds;
  auto img = (*r)->render(pose, (*r)->orbitAround(pose, 0.6f, 0.1f), fo);
  REQUIRE(img);
  return std::move(img).value();
}

int maxChannelDifference(const avatar::Image& a, const avatar::Image& b) {
  int d = 0;
  for (size_t i = 0; i < a.rgba.size(); ++i) d = std::max(d, std::abs(int(a.rgba[i]) - int(b.rgba[i])));
  return d;
}

}  // namespace

TEST_CASE("MToon expression binds on the GPU: every colour type and the texture transform, as if authored",
          "[gpu][materials]") {
  // An expression moving every MToon colour and the texture transforms of both MToon materials
  // (cloth, skin with a matcap), drawn at weight 1 through the per-frame blocks, must look like
  // the same avatar whose materials were authored with the targets (drawn from the static blocks).
  auto asset = loadBytes(test::mtoonVrm1File());
  REQUIRE(asset.materials.size() >= 2);
  using T = avatar::MaterialColorType;
  const std::pair<T, glm::vec4> targets[] = {{T::Color, {0.2f, 0.7f, 0.3f, 1.0f}},      {T::EmissionColor, {0.1f, 0.0f, 0.2f, 1.0f}},
                                             {T::ShadeColor, {0.0f, 0.0f, 0.6f, 1.0f}}, {T::MatcapColor, {0.3f, 0.3f, 0.0f, 1.0f}},
                                             {T::RimColor, {0.0f, 0.8f, 0.8f, 1.0f}},   {T::OutlineColor, {0.9f, 0.1f, 0.1f, 1.0f}}};
  avatar::Expression e;
  e.name = "everything";
  for (int m : {0, 1}) {
    for (const auto& [type, value] : targets) e.colorBinds.push_back({m, type, value});
    e.textureTransformBinds.push_back({m, {1.5f, 0.75f}, {0.1f, 0.2f}});
  }
  asset.expressions.expressions.push_back(e);
  asset.expressions.boundMaterials = {0, 1};
  auto authored = asset;
  for (int m : {0, 1}) {
    avatar::Material& x = authored.materials[static_cast<size_t>(m)];
    x.baseColorFactor = targets[0].second;
    x.emissiveFactor = glm::vec3(targets[1].second);
    x.mtoon.shadeColor = glm::vec3(targets[2].second);
    x.mtoon.matcapFactor = glm::vec3(targets[3].second);
    x.mtoon.rimColor = glm::vec3(targets[4].second);
    x.mtoon.outlineColor = glm::vec3(targets[5].second);
    for (avatar::TextureTransform* t : {&x.baseColorTransform, &x.emissiveTransform, &x.mtoon.shadeTransform,
                                        &x.mtoon.shadingShiftTransform, &x.mtoon.rimTransform, &x.mtoon.outlineWidthTransform}) {
      t->scale = {1.5f, 0.75f};
      t->offset = {0.1f, 0.2f};
    }
  }
  avatar::SecondaryMotion motion(asset, {.springBones = false, .blink = false, .lookAt = false});
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(asset.skeleton);
  motion.expressionWeights().back() = 1.0f;
  motion.update(pose, 0.01, std::nullopt);
  test::GpuContext ctx;
  const avatar::Image bound = shootWithStates(ctx, asset, motion.materialStates());
  const avatar::Image asAuthored = shootWithStates(ctx, authored, {});
  const avatar::Image loaded = shootWithStates(ctx, asset, {});
  // Equal up to a rounding step (base + (target - base) is the target to within an ulp).
  CHECK(maxChannelDifference(bound, asAuthored) <= 1);
  size_t changed = 0;
  for (size_t i = 0; i < bound.rgba.size(); i += 4)
    changed += std::abs(int(bound.rgba[i]) - int(loaded.rgba[i])) + std::abs(int(bound.rgba[i + 1]) - int(loaded.rgba[i + 1])) > 30;
  INFO("pixels the expression changes: " << changed);
  CHECK(changed > 2000);
}

TEST_CASE("MToon UV animation: read from VRM 1.0 and 0.x into the 1.0 model", "[materials]") {
  auto bytes = test::mtoonVrm1File();
  REQUIRE(bytes.ok());
  auto edited = test::editGlbJson(*bytes, [](json& doc) {
    json& t = doc["materials"][0]["extensions"]["VRMC_materials_mtoon"];
    t["uvAnimationScrollXSpeedFactor"] = 0.25;
    t["uvAnimationScrollYSpeedFactor"] = -0.5;
    t["uvAnimationRotationSpeedFactor"] = 1.5;
    t["uvAnimationMaskTexture"] = doc["materials"][1]["extensions"]["VRMC_materials_mtoon"]["matcapTexture"];
    json& u = doc["materials"][1]["extensions"]["VRMC_materials_mtoon"];
    u["uvAnimationScrollXSpeedFactor"] = 1e9;  // hostile: clamped to 1000 UV/s
    u["uvAnimationRotationSpeedFactor"] = "fast";
  });
  std::vector<std::string> warnings;
  const auto a = loadBytes(edited, &warnings);
  for (const auto& w : warnings) INFO(w);
  CHECK(warnings.size() == 2);
  const auto& t = a.materials[0].mtoon;
  CHECK(t.uvAnimationScroll == glm::vec2(0.25f, -0.5f));
  CHECK(t.uvAnimationRotation == 1.5f);
  CHECK(t.uvAnimationMaskImage >= 0);
  CHECK_FALSE(t.uvAnimationVrm0);
  CHECK(t.hasUvAnimation());
  CHECK(a.materials[1].mtoon.uvAnimationScroll.x == 1000.0f);
  CHECK(a.materials[1].mtoon.uvAnimationRotation == 0.0f);
  // 0.x: Unity's bottom-up v negates the scroll's y; rotation is in turns per second.
  auto vrm0 = test::mtoonVrm0File();
  REQUIRE(vrm0.ok());
  auto edited0 = test::editGlbJson(*vrm0, [](json& doc) {
    json& f = doc["extensions"]["VRM"]["materialProperties"][0]["floatProperties"];
    f["_UvAnimScrollX"] = 0.25;
    f["_UvAnimScrollY"] = 0.5;
    f["_UvAnimRotation"] = 0.25;
  });
  warnings.clear();
  const auto b = loadBytes(edited0, &warnings);
  CHECK(warnings.empty());
  const auto& t0 = b.materials[0].mtoon;
  CHECK(t0.uvAnimationScroll == glm::vec2(0.25f, -0.5f));
  CHECK(t0.uvAnimationRotation == Approx(glm::half_pi<float>()));
  CHECK(t0.uvAnimationVrm0);
}

namespace {

// The VRM test bust with its shirt drawn as MToon (lit colour = shade colour, so only the texture
// matters) reading the whole 8x1 stripe texture (four white texels, four dark) untransformed.
avatar::AvatarAsset stripedMToonBust() {
  avatar::AvatarAsset a = test::buildVrmTestAvatar().asset;
  avatar::Material& shirt = a.materials[4];
  shirt.isMToon = true;
  shirt.mtoon.shadeColor = glm::vec3(shirt.baseColorFactor);
  shirt.baseColorTransform = {};
  return a;
}

// KHR_texture_transform with the rotation and offset that `rotate about (0.5, 0.5) by angle, then
// add scroll` amounts to (scrollFirst: add scroll first, as VRM 0.x does): offset + R(uv).
avatar::TextureTransform equivalentTransform(float angle, glm::vec2 scroll, bool scrollFirst) {
  const float c = std::cos(angle), s = std::sin(angle);
  const auto rotate = [&](glm::vec2 p) { return glm::vec2(c * p.x + s * p.y, -s * p.x + c * p.y); };
  avatar::TextureTransform t;
  t.rotation = angle;
  t.offset = glm::vec2(0.5f) - rotate(glm::vec2(0.5f)) + (scrollFirst ? rotate(scroll) : scroll);
  return t;
}

}  // namespace

TEST_CASE("MToon UV animation on the GPU: equals the texture transform it amounts to, the mask stops it",
          "[gpu][materials]") {
  const avatar::AvatarAsset still = stripedMToonBust();
  const glm::vec2 scrollSpeed(0.3f, -0.2f);
  const float rotationSpeed = 0.7f, seconds = 1.5f;
  auto animated = still;
  animated.materials[4].mtoon.uvAnimationScroll = scrollSpeed;
  animated.materials[4].mtoon.uvAnimationRotation = rotationSpeed;
  test::GpuContext ctx;
  const avatar::Image atRest = shootWithStates(ctx, still, {});
  const avatar::Image atZero = shootWithStates(ctx, animated, {}, 0.0);
  const avatar::Image moving = shootWithStates(ctx, animated, {}, seconds);
  for (bool vrm0 : {false, true}) {
    INFO((vrm0 ? "VRM 0.x order (scroll, then rotate)" : "VRM 1.0 order (rotate, then scroll)"));
    auto a = animated, authored = still;
    a.materials[4].mtoon.uvAnimationVrm0 = vrm0;
    authored.materials[4].baseColorTransform = equivalentTransform(rotationSpeed * seconds, scrollSpeed * seconds, vrm0);
    const avatar::Image img = shootWithStates(ctx, a, {}, seconds), expected = shootWithStates(ctx, authored, {});
    CHECK(maxChannelDifference(img, expected) <= 2);
  }
  CHECK(atZero.rgba == atRest.rgba);  // time 0: no motion
  size_t changed = 0;
  for (size_t i = 0; i < moving.rgba.size(); i += 4) changed += std::abs(int(moving.rgba[i]) - int(atRest.rgba[i])) > 40;
  INFO("pixels the animation changes at 1.5 s: " << changed);
  CHECK(changed > 500);
  // A mask with B = 0 (and R = 1) stops the 1.0 animation; VRM 0.x reads R and still moves.
  auto masked = animated;
  avatar::Image mask;
  mask.width = mask.height = 1;
  mask.rgba = {255, 255, 0, 255};
  masked.images.push_back(mask);
  masked.materials[4].mtoon.uvAnimationMaskImage = static_cast<int>(masked.images.size() - 1);
  CHECK(shootWithStates(ctx, masked, {}, seconds).rgba == atRest.rgba);
  masked.materials[4].mtoon.uvAnimationVrm0 = true;
  CHECK(shootWithStates(ctx, masked, {}, seconds).rgba != atRest.rgba);
}
