#include <catch2/catch.hpp>

#include "avatar/gltf/gltf_loader.h"
#include "test_paths.h"

using namespace embody::avatar;

TEST_CASE("CesiumMan loads with its skin, texture and 19 skin joints", "[gltf]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  GltfLoadReport report;
  auto a = loadGltfFile(path, &report);
  REQUIRE(a.ok());
  for (auto& w : report.warnings) WARN(w);
  CHECK(a->skeleton.validate().empty());
  CHECK(a->skinJointCount == 19);
  CHECK(a->mesh.triangleCount() > 1000);
  REQUIRE(a->images.size() == 1);
  CHECK(a->images[0].width > 0);
  CHECK(a->materials.size() == 1);
  CHECK(a->materials[0].baseColorImage == 0);
  for (auto& j : a->skeleton.joints) INFO(j.name << " parent " << j.parent);
}

#include <glm/gtc/epsilon.hpp>

#include "gltf_test_files.h"
#include "tests/support/cpu_skinning.h"

using embody::test::TriangleFile;

namespace {
std::string loadError(const std::vector<uint8_t>& bytes) {
  auto r = loadGltfFromMemory(bytes, "");
  return r.ok() ? std::string("(loaded)") : r.error();
}
}  // namespace

TEST_CASE("a rigid triangle becomes weight 1 on its node with computed normals", "[gltf]") {
  TriangleFile f;
  auto a = loadGltfFromMemory(f.glb(), "");
  REQUIRE(a.ok());
  REQUIRE(a->skeleton.joints.size() == 1);
  CHECK(a->skinJointCount == 0);
  REQUIRE(a->mesh.vertices.size() == 3);
  REQUIRE(a->mesh.indices.size() == 3);
  REQUIRE(a->mesh.primitives.size() == 1);
  CHECK(a->mesh.firstPersonIndices == a->mesh.indices);
  for (const auto& v : a->mesh.vertices) {
    CHECK(v.joints0.x == 0u);
    CHECK(v.weights0.x == 1.0f);
    CHECK(glm::all(glm::epsilonEqual(v.normal, glm::vec3(0, 0, 1), 1e-6f)));
  }
  // Skinned at rest, the vertex lands where the node puts it.
  const std::vector<glm::vec3> p = test::skinnedPositions(a.value(), SkeletonPose::rest(a->skeleton));
  CHECK(glm::all(glm::epsilonEqual(p[1], glm::vec3(1, 1, 0), 1e-6f)));
}

TEST_CASE("a mesh on a child of a non-uniformly scaled node turns rigidly with its parent", "[gltf]") {
  // The arm has scale (1, 1.6, 1) and its child's offset is divided by it: valid glTF with the
  // same rest as the unscaled arm whose child (the triangle's node, scaled (3, 1, 1) itself) has
  // scale (3, 1.6, 1). With the arm and the forearm turned, the triangle moves rigidly, as the
  // unscaled file's, instead of shearing through the arm's scale.
  auto file = [](bool scaled) {
    TriangleFile f;
    f.doc["nodes"] = {{{"name", "arm"},
                       {"rotation", {0, 0, 0.38268343, 0.92387953}},  // 45 degrees about z
                       {"children", {1}}},
                      {{"name", "forearm"}, {"translation", {0, 0.5, 0}}, {"scale", {3, 1.6, 1}}, {"mesh", 0}}};
    if (scaled) {
      f.doc["nodes"][1]["scale"] = {3, 1, 1};
      f.doc["nodes"][0]["scale"] = {1, 1.6, 1};
      f.doc["nodes"][1]["translation"] = {0, 0.5 / 1.6, 0};
    }
    auto a = loadGltfFromMemory(f.glb(), "");
    REQUIRE(a.ok());
    return std::move(a.value());
  };
  auto skinned = [](const AvatarAsset& a, bool turned) {
    SkeletonPose pose = SkeletonPose::rest(a.skeleton);
    if (turned)
      for (int j : {0, 1})  // the arm 90 degrees about z, the forearm 60 degrees about x
        pose.local[j].rotation = pose.local[j].rotation * glm::angleAxis(glm::radians(j == 0 ? 90.0f : 60.0f),
                                                                         glm::vec3(j == 0 ? 0 : 1, 0, j == 0 ? 1 : 0));
    return test::skinnedPositions(a, pose);
  };
  const AvatarAsset plain = file(false), scaled = file(true);
  for (bool turned : {false, true}) {
    INFO((turned ? "turned" : "at rest"));
    const auto want = skinned(plain, turned), got = skinned(scaled, turned);
    REQUIRE(got.size() == 3);
    for (size_t i = 0; i < 3; ++i) CHECK(glm::length(got[i] - want[i]) < 1e-5f);
  }
}

TEST_CASE("hostile glTF files give a clear error, never a crash or a huge allocation", "[gltf]") {
  SECTION("empty and truncated GLB") {
    CHECK(loadError({}) == "empty file");
    auto glb = TriangleFile().glb();
    for (size_t cut : {size_t{3}, size_t{12}, size_t{19}, size_t{40}, glb.size() - 1}) {
      auto e = loadError(std::vector<uint8_t>(glb.begin(), glb.begin() + static_cast<std::ptrdiff_t>(cut)));
      INFO("cut at " << cut << ": " << e);
      CHECK(e != "(loaded)");
    }
    CHECK_THAT(loadError(std::vector<uint8_t>(glb.begin(), glb.end() - 4)), Catch::Contains("truncated GLB"));
  }
  SECTION("not glTF at all") {
    std::string junk = "this is not json";
    CHECK_THAT(loadError(std::vector<uint8_t>(junk.begin(), junk.end())), Catch::Contains("not a glTF file"));
    // Random bytes: one readable line, no raw parser message quoting a byte.
    std::vector<uint8_t> noise(512);
    uint32_t state = 12345u;
    for (auto& b : noise) b = uint8_t((state = state * 1664525u + 1013904223u) >> 24);
    noise[0] = 0x8f;
    const std::string e = loadError(noise);
    CHECK(e == "not a glTF file: neither a GLB container (no 'glTF' magic) nor glTF JSON text");
    std::string broken = "{ \"asset\": ";  // JSON that starts right and breaks: the parser's message
    CHECK_THAT(loadError(std::vector<uint8_t>(broken.begin(), broken.end())), Catch::Contains("parse error"));
  }
  SECTION("accessor reads past its bufferView") {
    TriangleFile f;
    f.doc["accessors"][0]["byteOffset"] = 8;
    CHECK_THAT(loadError(f.glb()), Catch::Contains("POSITION (accessor 0)") && Catch::Contains("bufferView"));
  }
  SECTION("bufferView past its buffer") {
    TriangleFile f;
    f.doc["bufferViews"][0]["byteLength"] = 4000;
    f.doc["accessors"][0]["count"] = 300;
    CHECK(loadError(f.glb()) != "(loaded)");
  }
  SECTION("wrong accessor type") {
    TriangleFile f;
    f.doc["accessors"][0]["type"] = "VEC2";
    CHECK_THAT(loadError(f.glb()), Catch::Contains("expected 3 components"));
  }
  SECTION("accessor index out of range") {
    TriangleFile f;
    f.doc["meshes"][0]["primitives"][0]["indices"] = 7;
    CHECK_THAT(loadError(f.glb()), Catch::Contains("out of"));
  }
  SECTION("vertex index out of range") {
    TriangleFile f;
    uint16_t bad = 3;
    std::memcpy(&f.bin[36 + 4], &bad, 2);
    CHECK_THAT(loadError(f.glb()), Catch::Contains("index 3 out of range"));
  }
  SECTION("cycle in the hierarchy") {
    TriangleFile f;
    f.doc["nodes"].push_back({{"name", "a"}, {"children", {2}}});
    f.doc["nodes"].push_back({{"name", "b"}, {"children", {1}}});
    CHECK_THAT(loadError(f.glb()), Catch::Contains("cycle"));
    f.doc["nodes"][1]["children"] = {1};
    CHECK_THAT(loadError(f.glb()), Catch::Contains("cycle"));
  }
  SECTION("a node with two parents") {
    TriangleFile f;
    f.doc["nodes"][0]["children"] = {1};
    f.doc["nodes"].push_back({{"name", "a"}});
    f.doc["nodes"].push_back({{"name", "b"}, {"children", {1}}});
    CHECK_THAT(loadError(f.glb()), Catch::Contains("two parents"));
  }
  SECTION("child index out of range") {
    TriangleFile f;
    f.doc["nodes"][0]["children"] = {42};
    CHECK_THAT(loadError(f.glb()), Catch::Contains("child 42"));
  }
  SECTION("absurd counts are refused before allocating") {
    TriangleFile f;
    f.doc["accessors"][0].erase("bufferView");  // a zero-filled accessor of 2^40 elements
    f.doc["accessors"][0]["count"] = uint64_t{1} << 40;
    CHECK_THAT(loadError(f.glb()), Catch::Contains("exceeds the limit"));
    TriangleFile g;
    g.doc["accessors"][1]["count"] = 4000000000u;
    CHECK(loadError(g.glb()) != "(loaded)");
  }
  SECTION("skin joint index out of range") {
    TriangleFile f;
    std::vector<uint8_t> joints = {5, 0, 0, 0, 5, 0, 0, 0, 5, 0, 0, 0};
    std::vector<float> weights = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    const size_t jAt = f.bin.size();
    embody::test::appendRaw(f.bin, joints);
    const size_t wAt = f.bin.size();
    embody::test::appendRaw(f.bin, weights);
    f.doc["buffers"][0]["byteLength"] = f.bin.size();
    f.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", jAt}, {"byteLength", 12}});
    f.doc["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", wAt}, {"byteLength", 48}});
    f.doc["accessors"].push_back(
        {{"bufferView", 2}, {"componentType", 5121}, {"count", 3}, {"type", "VEC4"}});
    f.doc["accessors"].push_back(
        {{"bufferView", 3}, {"componentType", 5126}, {"count", 3}, {"type", "VEC4"}});
    f.doc["meshes"][0]["primitives"][0]["attributes"]["JOINTS_0"] = 2;
    f.doc["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"] = 3;
    f.doc["skins"] = {{{"joints", {0}}}};
    f.doc["nodes"][0]["skin"] = 0;
    CHECK_THAT(loadError(f.glb()), Catch::Contains("JOINTS_0 index 5 out of range"));
  }
  SECTION("non-finite transform") {
    TriangleFile f;
    f.doc["nodes"][0]["rotation"] = {0, 0, 0, 0};
    CHECK_THAT(loadError(f.glb()), Catch::Contains("zero rotation"));
  }
  SECTION("missing file") {
    auto r = loadGltfFile("/nonexistent/file.glb");
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error(), Catch::Contains("cannot open"));
  }
}

TEST_CASE("JSON nested deeper than 512 levels is refused before tinygltf recurses into it", "[gltf]") {
  // "extras": [[[ ... ]]] on the node, written as text (nlohmann's dump would recurse too).
  auto nested = [](size_t depth) {
    TriangleFile f;
    f.doc["nodes"][0]["extras"] = "EXTRAS";
    std::string json = f.doc.dump();
    const size_t at = json.find("\"EXTRAS\"");
    json.replace(at, 8, std::string(depth, '[') + std::string(depth, ']'));
    return std::pair{json, f.bin};
  };
  for (size_t depth : {size_t{20000}, size_t{513}}) {
    INFO("depth " << depth);
    auto [json, bin] = nested(depth);
    CHECK_THAT(loadError(embody::test::makeGlb(json, bin)), Catch::Contains("JSON nested deeper than 512 levels"));
    // The same as a .gltf text file (its buffer is never reached).
    CHECK_THAT(loadError(std::vector<uint8_t>(json.begin(), json.end())), Catch::Contains("nested deeper than 512"));
  }
  // 500 levels load, and brackets inside strings (escaped quotes included) do not count.
  auto [json, bin] = nested(500);
  CHECK(loadError(embody::test::makeGlb(json, bin)) == "(loaded)");
  TriangleFile f;
  f.doc["nodes"][0]["name"] = "\"" + std::string(20000, '[');
  CHECK(loadError(f.glb()) == "(loaded)");
}

TEST_CASE("extensionsRequired: an extension the loader does not read is refused by name", "[gltf]") {
  SECTION("compressed or quantized geometry") {
    TriangleFile f;
    f.doc["extensionsUsed"] = {"KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization"};
    f.doc["extensionsRequired"] = f.doc["extensionsUsed"];
    const std::string e = loadError(f.glb());
    CHECK_THAT(e, Catch::Contains("requires KHR_draco_mesh_compression, EXT_meshopt_compression, KHR_mesh_quantization") &&
                      Catch::Contains("does not support"));
    f.doc["extensionsRequired"] = {"KHR_texture_transform", "VENDOR_unknown"};
    CHECK_THAT(loadError(f.glb()), Catch::Contains("requires VENDOR_unknown (extensionsRequired)"));
  }
  SECTION("a Draco primitive whose accessors have no bufferView names Draco, not an accessor") {
    TriangleFile f;
    f.doc["accessors"][0]["bufferView"] = 7;
    f.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    f.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    CHECK_THAT(loadError(f.glb()), Catch::StartsWith("the file requires KHR_draco_mesh_compression"));
  }
  SECTION("extensions the loader reads, and ones only used, still load") {
    TriangleFile f;
    f.doc["extensionsUsed"] = {"KHR_texture_transform", "KHR_materials_unlit", "VENDOR_unknown"};
    f.doc["extensionsRequired"] = {"KHR_texture_transform", "KHR_materials_unlit"};
    CHECK(loadError(f.glb()) == "(loaded)");
  }
}

#include "avatar/avatar_loader.h"

TEST_CASE("a 60000-node chain loads and maps without deep recursion", "[gltf]") {
  TriangleFile f;
  const int n = 60000;
  for (int i = 1; i < n; ++i)
    f.doc["nodes"].push_back({{"name", "n" + std::to_string(i)}, {"translation", {0, 0.001, 0}}});
  for (int i = 0; i + 1 < n; ++i) f.doc["nodes"][static_cast<size_t>(i)]["children"] = {i + 1};
  auto a = loadGltfFromMemory(f.glb(), "");
  REQUIRE(a.ok());
  REQUIRE(prepareAvatar(a.value(), "").ok());
  CHECK(a->skeleton.joints.size() == static_cast<size_t>(n));
  CHECK(a->skeleton.joints.back().parent == n - 2);
  CHECK(a->humanoid.method == MappingMethod::None);
}

TEST_CASE("material extensions: texture transform (texCoord override), unlit, emissive strength", "[gltf]") {
  TriangleFile f;
  f.doc["textures"] = {{{"source", 0}}};
  f.doc["images"] = {{{"uri", "data:image/png;base64,AAAA"}}};  // undecodable: untextured
  auto transform = [](nlohmann::json t) {
    return nlohmann::json{{"index", 0}, {"texCoord", 0}, {"extensions", {{"KHR_texture_transform", t}}}};
  };
  f.doc["materials"] = {
      {{"pbrMetallicRoughness",
        {{"baseColorTexture", transform({{"offset", {0.25, 0.5}}, {"rotation", 0.5}, {"scale", {2, 3}}, {"texCoord", 1}})}}},
       {"emissiveFactor", {0.1, 0.2, 0.3}},
       {"emissiveTexture", transform({{"texCoord", 2}})},
       {"extensions", {{"KHR_materials_unlit", nlohmann::json::object()},
                       {"KHR_materials_emissive_strength", {{"emissiveStrength", 5.0}}}}}},
      // Malformed values fall back to the defaults.
      {{"pbrMetallicRoughness", {{"baseColorTexture", transform({{"offset", "left"}, {"scale", {1}}, {"rotation", "x"}})}}},
       {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", -2.0}}}}}}};
  f.doc["meshes"][0]["primitives"][0]["material"] = 0;
  embody::avatar::GltfLoadReport report;
  auto a = loadGltfFromMemory(f.glb(), "", &report);
  REQUIRE(a.ok());
  REQUIRE(a->materials.size() == 2);
  const auto& m = a->materials[0];
  CHECK(m.baseColorImage == -1);
  CHECK(m.baseColorTransform.offset == glm::vec2(0.25f, 0.5f));
  CHECK(m.baseColorTransform.rotation == Approx(0.5f));
  CHECK(m.baseColorTransform.scale == glm::vec2(2.0f, 3.0f));
  CHECK(m.baseColorTransform.texCoord == 1);  // the extension's texCoord wins over the textureInfo's
  CHECK(m.emissiveTransform.texCoord == 0);   // TEXCOORD_2 is not read: falls back, with a warning
  CHECK(m.unlit);
  CHECK(m.emissiveStrength == Approx(5.0f));
  CHECK(m.emissiveFactor == glm::vec3(0.1f, 0.2f, 0.3f));
  bool warned = false;
  for (const auto& w : report.warnings) warned |= w.find("TEXCOORD_2") != std::string::npos;
  CHECK(warned);
  // u' = cos*sx*u + sin*sy*v + ox, v' = -sin*sx*u + cos*sy*v + oy
  const glm::vec2 p = m.baseColorTransform.apply({1.0f, 0.0f});
  CHECK(p.x == Approx(0.25f + 2.0f * std::cos(0.5f)));
  CHECK(p.y == Approx(0.5f - 2.0f * std::sin(0.5f)));
  const auto& bad = a->materials[1];
  CHECK(bad.baseColorTransform.isIdentity());
  CHECK_FALSE(bad.unlit);
  CHECK(bad.emissiveStrength == 0.0f);
}
