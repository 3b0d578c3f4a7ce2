// glTF material completeness, end to end: a test file built here (tiles of quads, one material
// each), written with the project's GLB writer, checked by the Khronos glTF validator, loaded back
// and drawn. Tiles (4 columns x 3 rows, unlit unless said):
//   row 0: KHR_texture_transform offset+scale | rotation | texCoord 1 (TEXCOORD_1) | emissive strength (lit)
//   row 1: KHR_materials_unlit | alpha MASK | alpha BLEND, two overlapping quads | lit, no extension
//   row 2: double-sided back face | single-sided back face (culled) | mipmapped 1-px checker | empty
// The texture-transform tiles sample an atlas whose top-right quadrant is a green check mark and
// whose other quadrants are red crosses: a tile shows the check only when its transform is applied
// exactly (a rotation the wrong way lands on a cross).
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <glm/gtc/matrix_transform.hpp>
#include <nlohmann/json.hpp>

#include "avatar/gltf/glb_writer.h"
#include "avatar/gltf/gltf_loader.h"
#include "engine/avatar_renderer.h"
#include "engine_test_support.h"
#include "tests/support/gltf_validator_checks.h"

using namespace embody;

namespace {

const test::TileGrid kMaterialGrid{4, 3};
constexpr float kTile = test::TileGrid::kTile;
const glm::vec4 kGreen(0.0f, 0.63f, 0.0f, 1.0f), kRed(0.78f, 0.0f, 0.0f, 1.0f);

glm::vec2 tileCorner(int column, int row) { return kMaterialGrid.corner(column, row); }

// Paints a check mark (or a cross) in white over a coloured square of `size` pixels at (x0, y0).
void paintGlyph(avatar::Image& img, int x0, int y0, int size, glm::vec4 background, bool check) {
  auto segmentDistance = [](glm::vec2 p, glm::vec2 a, glm::vec2 b) {
    const glm::vec2 ab = b - a;
    const float t = glm::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0f, 1.0f);
    return glm::length(p - (a + t * ab));
  };
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const glm::vec2 p = glm::vec2(x + 0.5f, y + 0.5f) / float(size);
      const float d = check ? std::min(segmentDistance(p, {0.2f, 0.5f}, {0.42f, 0.75f}),
                                       segmentDistance(p, {0.42f, 0.75f}, {0.82f, 0.25f}))
                            : std::min(segmentDistance(p, {0.25f, 0.25f}, {0.75f, 0.75f}),
                                       segmentDistance(p, {0.75f, 0.25f}, {0.25f, 0.75f}));
      const glm::vec4 c = d < 0.07f ? glm::vec4(1.0f) : background;
      uint8_t* px = &img.rgba[(size_t(y0 + y) * img.width + size_t(x0 + x)) * 4];
      for (int k = 0; k < 4; ++k) px[k] = uint8_t(std::lround(c[k] * 255.0f));
    }
}

// 128 x 128: the top-right quadrant (u 0.5..1, v 0..0.5) a green check, the others red crosses.
avatar::Image transformAtlas() {
  avatar::Image img{128, 128, std::vector<uint8_t>(128 * 128 * 4)};
  for (int qy = 0; qy < 2; ++qy)
    for (int qx = 0; qx < 2; ++qx) {
      const bool check = qx == 1 && qy == 0;
      paintGlyph(img, qx * 64, qy * 64, 64, check ? kGreen : kRed, check);
    }
  return img;
}

// 64 x 64, black and white 1-pixel checker (alpha from `alphaChecker`: 8-pixel cells of 0.3/0.9).
avatar::Image checker(bool alphaChecker) {
  avatar::Image img{64, 64, std::vector<uint8_t>(64 * 64 * 4)};
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) {
      uint8_t* px = &img.rgba[(size_t(y) * 64 + size_t(x)) * 4];
      const uint8_t v = alphaChecker ? 255 : ((x + y) % 2 ? 255 : 0);
      px[0] = px[1] = px[2] = v;
      px[3] = alphaChecker ? (((x / 8) + (y / 8)) % 2 ? 230 : 77) : 255;
    }
  return img;
}

struct TileBuilder {
  avatar::AvatarAsset asset;

  int material(avatar::Material m) {
    asset.materials.push_back(std::move(m));
    return int(asset.materials.size() - 1);
  }
  // A quad over part of a tile (fractions of the tile), at depth z, facing +Z (the camera) unless
  // `facingAway`; uv0 / uv1 over its corners as given (top-left origin, glTF convention).
  void quad(int column, int row, int material, glm::vec4 rect = {0, 0, 1, 1}, float z = 0.0f,
            glm::vec4 uv0 = {0, 0, 1, 1}, glm::vec4 uv1 = {0, 0, 1, 1}, bool facingAway = false) {
    const glm::vec2 c = tileCorner(column, row);
    const uint32_t base = uint32_t(asset.mesh.vertices.size());
    for (int k = 0; k < 4; ++k) {
      const float fx = (k == 1 || k == 2) ? 1.0f : 0.0f, fy = k >= 2 ? 1.0f : 0.0f;  // ccw from bottom-left
      avatar::SkinnedVertex v;
      v.position = glm::vec3(c.x + kTile * glm::mix(rect.x, rect.z, fx), c.y + kTile * glm::mix(rect.y, rect.w, fy), z);
      v.normal = glm::vec3(0, 0, facingAway ? -1.0f : 1.0f);
      v.uv = glm::vec2(glm::mix(uv0.x, uv0.z, fx), glm::mix(uv0.w, uv0.y, fy));  // v grows downwards
      v.uv1 = glm::vec2(glm::mix(uv1.x, uv1.z, fx), glm::mix(uv1.w, uv1.y, fy));
      asset.mesh.vertices.push_back(v);
    }
    const uint32_t first = uint32_t(asset.mesh.indices.size());
    const uint32_t front[6] = {0, 1, 2, 0, 2, 3}, back[6] = {0, 2, 1, 0, 3, 2};
    for (uint32_t i : facingAway ? back : front) asset.mesh.indices.push_back(base + i);
    asset.mesh.primitives.push_back({first, 6, material});
  }
};

avatar::Material unlitTextured(const char* name, int image, avatar::TextureTransform t) {
  avatar::Material m;
  m.name = name;
  m.baseColorImage = image;
  m.baseColorTransform = t;
  m.unlit = true;
  return m;
}

avatar::AvatarAsset materialTestAsset() {
  TileBuilder b;
  auto& a = b.asset;
  a.skeleton.joints.push_back({"root", -1, {}});
  a.mesh.inverseBind = {glm::mat4(1.0f)};
  a.images = {transformAtlas(), checker(false), checker(true)};

  // Row 0: texture transforms, each picking the check quadrant out of the atlas.
  b.quad(0, 0, b.material(unlitTextured("offset_scale", 0, {.offset = {0.5f, 0.0f}, .scale = {0.5f, 0.5f}})));
  b.quad(1, 0, b.material(unlitTextured("rotation", 0,
                                         {.offset = {0.5f, 0.5f}, .rotation = float(M_PI / 2), .scale = {0.5f, 0.5f}})));
  // TEXCOORD_0 covers a cross; the transform reads TEXCOORD_1 (the whole atlas) scaled onto the check.
  b.quad(2, 0, b.material(unlitTextured("texcoord1", 0, {.offset = {0.5f, 0.0f}, .scale = {0.5f, 0.5f}, .texCoord = 1})),
         {0, 0, 1, 1}, 0.0f, {0.0f, 0.5f, 0.5f, 1.0f});
  avatar::Material emissive;
  emissive.name = "emissive_strength";
  emissive.baseColorFactor = glm::vec4(0, 0, 0, 1);
  emissive.emissiveFactor = glm::vec3(0.0f, 0.2f, 0.25f);
  emissive.emissiveStrength = 4.0f;  // (0, 0.8, 1.0): without the extension it would be dark
  b.quad(3, 0, b.material(emissive));

  // Row 1: unlit, MASK, BLEND (the near red quad is listed first), lit.
  avatar::Material flat;
  flat.name = "unlit";
  flat.baseColorFactor = glm::vec4(0.8f, 0.5f, 0.1f, 1.0f);
  flat.unlit = true;
  b.quad(0, 1, b.material(flat));
  avatar::Material mask = unlitTextured("mask", 2, {});
  mask.alphaMode = avatar::AlphaMode::Mask;
  mask.alphaCutoff = 0.5f;
  b.quad(1, 1, b.material(mask));
  avatar::Material nearRed, farBlue;
  nearRed.name = "blend_near";
  nearRed.baseColorFactor = glm::vec4(1, 0, 0, 0.5f);
  nearRed.unlit = true;
  nearRed.alphaMode = avatar::AlphaMode::Blend;
  farBlue = nearRed;
  farBlue.name = "blend_far";
  farBlue.baseColorFactor = glm::vec4(0, 0, 1, 0.5f);
  b.quad(2, 1, b.material(nearRed), {0.0f, 0.0f, 0.7f, 1.0f}, 0.3f);
  b.quad(2, 1, b.material(farBlue), {0.3f, 0.0f, 1.0f, 1.0f}, 0.0f);
  avatar::Material lit;
  lit.name = "lit";
  lit.baseColorFactor = flat.baseColorFactor;
  b.quad(3, 1, b.material(lit));

  // Row 2: back faces (double-sided drawn, single-sided culled), a minified checker.
  avatar::Material twoSided = flat;
  twoSided.name = "double_sided";
  twoSided.doubleSided = true;
  b.quad(0, 2, b.material(twoSided), {0, 0, 1, 1}, 0.0f, {0, 0, 1, 1}, {0, 0, 1, 1}, true);
  avatar::Material oneSided = flat;
  oneSided.name = "single_sided";
  b.quad(1, 2, b.material(oneSided), {0, 0, 1, 1}, 0.0f, {0, 0, 1, 1}, {0, 0, 1, 1}, true);
  b.quad(2, 2, b.material(unlitTextured("mipmapped", 1, {})), {0.375f, 0.375f, 0.625f, 0.625f});
  a.mesh.firstPersonIndices.clear();
  return a;
}

engine::Camera tileCamera() { return kMaterialGrid.camera(); }

glm::ivec2 pixelOf(const engine::Camera& cam, int column, int row, glm::vec2 f, uint32_t width, uint32_t height) {
  return kMaterialGrid.pixel(cam, column, row, f, width, height);
}

using test::rgbaAt;

// Share of a tile's inner pixels (10 % margin) that are green-dominant among the coloured ones.
float greenShare(const avatar::Image& img, const engine::Camera& cam, int column, int row) {
  const glm::ivec2 lo = pixelOf(cam, column, row, {0.1f, 0.9f}, img.width, img.height);
  const glm::ivec2 hi = pixelOf(cam, column, row, {0.9f, 0.1f}, img.width, img.height);
  int green = 0, red = 0;
  for (int y = lo.y; y < hi.y; ++y)
    for (int x = lo.x; x < hi.x; ++x) {
      const glm::ivec4 c = rgbaAt(img, {x, y});
      if (c.g > c.r + 60 && c.b < 80) ++green;
      if (c.r > c.g + 60 && c.b < 80) ++red;
    }
  return green + red > 0 ? float(green) / float(green + red) : 0.0f;
}

}  // namespace

TEST_CASE("the material test file round-trips through the GLB writer and passes the glTF validator",
          "[gpu][materials][validator]") {
  const auto asset = materialTestAsset();
  auto bytes = avatar::encodeGlb(asset);
  REQUIRE(bytes.ok());
  auto loaded = avatar::loadGltfFromMemory(*bytes, "");
  REQUIRE(loaded.ok());
  REQUIRE(loaded->materials.size() == asset.materials.size());
  for (size_t i = 0; i < asset.materials.size(); ++i) {
    const auto &a = asset.materials[i], &b = loaded->materials[i];
    INFO(a.name);
    CHECK(b.unlit == a.unlit);
    CHECK(b.alphaMode == a.alphaMode);
    CHECK(b.doubleSided == a.doubleSided);
    CHECK(b.emissiveStrength == Approx(a.emissiveStrength));
    CHECK(glm::length(b.emissiveFactor - a.emissiveFactor) < 1e-6f);
    CHECK(glm::length(b.baseColorTransform.offset - a.baseColorTransform.offset) < 1e-6f);
    CHECK(glm::length(b.baseColorTransform.scale - a.baseColorTransform.scale) < 1e-6f);
    CHECK(b.baseColorTransform.rotation == Approx(a.baseColorTransform.rotation));
    CHECK(b.baseColorTransform.texCoord == a.baseColorTransform.texCoord);
  }
  // The transform maps the tile's corners onto the check quadrant (u 0.5..1, v 0..0.5).
  const auto& rotation = loaded->materials[1].baseColorTransform;
  CHECK(glm::length(rotation.apply({0, 0}) - glm::vec2(0.5f, 0.5f)) < 1e-6f);
  CHECK(glm::length(rotation.apply({1, 1}) - glm::vec2(1.0f, 0.0f)) < 1e-6f);

  const auto file = std::filesystem::temp_directory_path() / ("embody_materials_" + std::to_string(::getpid()) + ".glb");
  REQUIRE(avatar::writeGlbFile(asset, file.string()).ok());
  const auto report = test::requireNoGltfErrors(file.string());
  if (report) CHECK((*report)["numWarnings"].get<int>() == 0);
}

TEST_CASE("golden: glTF material tiles (texture transform check marks, unlit, emissive, alpha, mipmaps)",
          "[gpu][golden][materials]") {
  auto bytes = avatar::encodeGlb(materialTestAsset());
  REQUIRE(bytes.ok());
  auto asset = avatar::loadGltfFromMemory(*bytes, "");
  REQUIRE(asset.ok());
  test::GpuContext ctx;
  engine::AvatarRendererOptions o;
  o.width = 256;
  o.height = 192;
  auto r = engine::AvatarRenderer::create(*ctx.device, *asset, o);
  REQUIRE(r);
  engine::FrameOptions fo;
  fo.grid = false;
  fo.clearColor = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
  const engine::Camera cam = tileCamera();
  auto img = (*r)->render(avatar::SkeletonPose::rest(asset->skeleton), cam, fo);
  REQUIRE(img);
  auto at = [&](int column, int row, glm::vec2 f) { return rgbaAt(*img, pixelOf(cam, column, row, f, 256, 192)); };

  // Texture transforms: the tiles show the check (green), not a cross (red).
  for (int column = 0; column < 3; ++column) {
    INFO("texture-transform tile " << column);
    CHECK(greenShare(*img, cam, column, 0) > 0.95f);
  }
  // Emissive x strength 4 = (0, 0.8, 1.0) linear on a black base: bright, not (0, 0.2, 0.25).
  const glm::ivec4 e = at(3, 0, {0.5f, 0.5f});
  CHECK(e.r < 8);
  CHECK(e.g > 225);
  CHECK(e.b > 250);
  // Unlit: exactly the base colour (sRGB of 0.8, 0.5, 0.1 = 231, 188, 89); lit differs.
  const glm::ivec4 u = at(0, 1, {0.5f, 0.5f}), l = at(3, 1, {0.5f, 0.5f});
  CHECK(std::abs(u.r - 231) <= 2);
  CHECK(std::abs(u.g - 188) <= 2);
  CHECK(std::abs(u.b - 89) <= 2);
  CHECK(std::abs(l.r - u.r) + std::abs(l.g - u.g) + std::abs(l.b - u.b) > 30);
  // MASK: cells with alpha 0.3 are cut (background), cells with alpha 0.9 drawn white.
  CHECK(at(1, 1, {0.5f / 8, 1.0f - 0.5f / 8}).r < 8);    // top-left cell: alpha 0.3
  CHECK(at(1, 1, {1.5f / 8, 1.0f - 0.5f / 8}).r > 250);  // its neighbour: alpha 0.9
  // BLEND, back to front: the far blue first, the near red over it. In the overlap
  // 0.5 red + 0.25 blue (+ 0.25 black): red (linear 0.5, sRGB 188) above blue (0.25, 137).
  const glm::ivec4 overlap = at(2, 1, {0.5f, 0.5f});
  CHECK(std::abs(overlap.r - 188) <= 3);
  CHECK(std::abs(overlap.b - 137) <= 3);
  // Double-sided back face drawn; single-sided back face culled.
  CHECK(at(0, 2, {0.5f, 0.5f}).r > 200);
  CHECK(at(1, 2, {0.5f, 0.5f}).r < 8);
  // A 1-pixel black/white checker minified ~4x: the mip chain averages it to mid grey (linear
  // 0.5 = sRGB 188) instead of aliasing to black, white or a moire.
  for (glm::vec2 f : {glm::vec2(0.45f, 0.45f), glm::vec2(0.55f, 0.5f), glm::vec2(0.5f, 0.55f)}) {
    const glm::ivec4 g = at(2, 2, f);
    CHECK(std::abs(g.r - 188) <= 20);
  }
  test::checkGolden("materials_tiles", *img, ctx.device->driverString());
}
