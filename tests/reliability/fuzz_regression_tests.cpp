// Inputs the fuzz targets once crashed on (fuzz/regressions/<target>/), each with the answer it
// must now get: one clear error, or a load whose data is finite. The replay driver also runs
// them through the targets' invariants (ctest -R '^fuzz:').
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "avatar/bvh/bvh.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/humanoid/humanoid_map.h"
#include "test_paths.h"
#include "tracking/trace.h"

using namespace embody;

namespace {
std::vector<uint8_t> regression(const std::string& name) {
  std::ifstream f(std::string(test::kSourceDir) + "/fuzz/regressions/" + name, std::ios::binary);
  REQUIRE(f);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}
}  // namespace

TEST_CASE("fuzz regression: a trace number beyond double range is a JSON error, not an exception",
          "[reliability][fuzz]") {
  const auto bytes = regression("trace/number_overflow.jsonl");
  std::istringstream in(std::string(bytes.begin(), bytes.end()));
  auto trace = tracking::parseTrace(in, "overflow.jsonl");
  REQUIRE_FALSE(trace.ok());
  CHECK(trace.error().find("number overflow") != std::string::npos);
}

TEST_CASE("fuzz regression: a glTF whose vertices overflow under their bind matrix is refused",
          "[reliability][fuzz]") {
  auto asset = avatar::loadGltfFromMemory(regression("gltf/nonfinite_normal.glb"), ".");
  if (!asset.ok()) {
    CHECK(asset.error().find("not finite") != std::string::npos);
    return;
  }
  for (const auto& v : asset->mesh.vertices) {
    CHECK(std::isfinite(v.position.x + v.position.y + v.position.z));
    CHECK(std::isfinite(v.normal.x + v.normal.y + v.normal.z));
  }
}

TEST_CASE("fuzz regression: a VRM humanoid that is not an object is ignored, not thrown on",
          "[reliability][fuzz]") {
  // {"extensions": {"VRMC_vrm": {"humanoid": 5}}}: json::value() on a number used to throw.
  const std::string doc = R"({"extensions": {"VRMC_vrm": {"humanoid": 5}, "VRM": {"humanoid": []}}})";
  avatar::Skeleton skeleton;
  skeleton.joints.resize(1);
  skeleton.joints[0].name = "hips";
  avatar::HumanoidInputs in;
  in.skeleton = &skeleton;
  in.gltfJson = doc;
  in.gltfNodeToJoint = {0};
  CHECK_NOTHROW(avatar::mapHumanoid(in));
}

TEST_CASE("fuzz regression: a BVH frame value beyond float range is an error, not an infinite channel",
          "[reliability][fuzz]") {
  const auto bytes = regression("bvh/value_beyond_float.bvh");
  auto clip = avatar::parseBvh(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), "big.bvh");
  REQUIRE_FALSE(clip.ok());
  CHECK(clip.error().find("within float range") != std::string::npos);
  CHECK(clip.error().find("big.bvh:19") != std::string::npos);  // names the line
}
