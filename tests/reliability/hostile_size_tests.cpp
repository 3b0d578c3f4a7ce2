// Declared counts that the file cannot back (a BVH claiming 10^9 frames, a glTF accessor of 10^9
// or 1.6e7 elements over a 36-byte buffer) are refused, or trimmed, before any allocation of
// their size: the largest single allocation stays small and the answer comes in milliseconds.
#include <catch2/catch.hpp>

#include <chrono>
#include <string>

#include "allocation_counter.h"
#include "avatar/bvh/bvh.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/gltf_test_files.h"

using namespace embody;

namespace {

constexpr size_t kSmallAllocation = 1 << 20;  // 1 MiB: far below any hostile claim here

const char* kBvhHeader =
    "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Xposition Yposition Zposition\n"
    "  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\n";

template <class F>
double secondsOf(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TEST_CASE("a BVH claiming 10^9 frames is a clear error without allocating them", "[reliability][bvh]") {
  const std::string text = std::string(kBvhHeader) + "Frames: 1000000000\nFrame Time: 0.01\n0 1 2\n";
  test::AllocationCounts counts;
  Result<avatar::BvhClip> clip = Error{""};
  const double s = secondsOf([&] {
    test::CountAllocations counter;
    clip = avatar::parseBvh(text, "huge.bvh");
    counts = counter.counts();
  });
  REQUIRE_FALSE(clip.ok());
  CHECK(clip.error().find("Frames: 1000000000") != std::string::npos);
  CHECK(counts.largestBytes < kSmallAllocation);
  CHECK(s < 0.05);
}

TEST_CASE("a BVH claim within the value limit reserves only what the file can hold", "[reliability][bvh]") {
  // 2 * 10^7 frames x 3 channels is under the 64 Mi value limit: the claim alone used to reserve
  // 240 MB for a file of a few hundred bytes. Now it is trimmed to the frames present.
  const std::string text = std::string(kBvhHeader) + "Frames: 20000000\nFrame Time: 0.01\n0 1 2\n3 4 5\n";
  test::AllocationCounts counts;
  Result<avatar::BvhClip> clip = Error{""};
  {
    test::CountAllocations counter;
    clip = avatar::parseBvh(text, "claims.bvh");
    counts = counter.counts();
  }
  REQUIRE(clip.ok());
  CHECK(clip->frameCount == 2);
  REQUIRE_FALSE(clip->warnings.empty());
  CHECK(clip->warnings.back().find("declares 20000000 frames but has 2") != std::string::npos);
  CHECK(counts.largestBytes < kSmallAllocation);
}

TEST_CASE("a BVH without channels cannot claim more frames than it has lines", "[reliability][bvh]") {
  const std::string text =
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 0\n}\nMOTION\nFrames: 1000000000000\nFrame Time: 0.01\n";
  auto clip = avatar::parseBvh(text, "still.bvh");
  // Beyond the loader's value limit the claim is refused naming the limit (a frame of no channels
  // counts as one value), before anything is sized by it.
  REQUIRE_FALSE(clip.ok());
  CHECK(clip.error().find("is more than this loader accepts") != std::string::npos);
  auto small = avatar::parseBvh(
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 0\n}\nMOTION\nFrames: 1000000\nFrame Time: 0.01\n", "still.bvh");
  REQUIRE(small.ok());  // within the limit: the frames the text has
  CHECK(small->frameCount <= text.size());
}

namespace {

// The one-triangle GLB with its position accessor (36 bytes of data) declaring `count` elements.
Result<avatar::AvatarAsset> triangleClaiming(uint64_t count, bool withBufferView, test::AllocationCounts& counts) {
  test::TriangleFile f;
  f.doc["accessors"][0]["count"] = count;
  if (!withBufferView) f.doc["accessors"][0].erase("bufferView");
  const std::vector<uint8_t> glb = f.glb();
  test::CountAllocations counter;
  auto r = avatar::loadGltfFromMemory(glb, ".");
  counts = counter.counts();
  return r;
}

}  // namespace

TEST_CASE("a glTF accessor of 10^9 elements is a clear error without allocating them", "[reliability][gltf]") {
  test::AllocationCounts counts;
  Result<avatar::AvatarAsset> r = Error{""};
  const double s = secondsOf([&] { r = triangleClaiming(1000000000, true, counts); });
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().find("count 1000000000 exceeds the limit") != std::string::npos);
  CHECK(counts.largestBytes < kSmallAllocation);
  CHECK(s < 0.05);
}

TEST_CASE("a glTF accessor under the count limit is checked against its bytes before allocating",
          "[reliability][gltf]") {
  // 1.6e7 VEC3 elements: under the 2^24 element limit, 384 MB as doubles, over 36 bytes of data.
  test::AllocationCounts counts;
  Result<avatar::AvatarAsset> r = Error{""};
  const double s = secondsOf([&] { r = triangleClaiming(16000000, true, counts); });
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().find("-byte bufferView") != std::string::npos);
  CHECK(counts.largestBytes < kSmallAllocation);
  CHECK(s < 0.05);
}

TEST_CASE("a glTF accessor without a bufferView cannot outgrow the file's buffers", "[reliability][gltf]") {
  test::AllocationCounts counts;
  auto r = triangleClaiming(16000000, false, counts);
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().find("without a bufferView exceed") != std::string::npos);
  CHECK(counts.largestBytes < kSmallAllocation);
}

TEST_CASE("glTF byte offsets and strides near 2^64 cannot wrap the range check", "[reliability][gltf]") {
  test::TriangleFile f;
  f.doc["accessors"][0]["byteOffset"] = 18446744073709551000ull;
  auto r = avatar::loadGltfFromMemory(f.glb(), ".");
  CHECK_FALSE(r.ok());
  test::TriangleFile g;
  g.doc["bufferViews"][0]["byteOffset"] = 18446744073709551000ull;
  auto r2 = avatar::loadGltfFromMemory(g.glb(), ".");
  CHECK_FALSE(r2.ok());
}

TEST_CASE("a .gltf whose buffer URI names a device or FIFO is refused, not read", "[reliability][gltf]") {
  test::TriangleFile f;
  f.doc["buffers"][0]["uri"] = "dev/zero";  // resolved against the base folder "/"
  const std::string json = f.doc.dump();
  auto r = avatar::loadGltfFromMemory(std::vector<uint8_t>(json.begin(), json.end()), "/");
  REQUIRE_FALSE(r.ok());
  CHECK(r.error().find("not a regular file") != std::string::npos);
}
