// The headless OpenXR runtime's EMBODY_XR_POSES input (tools/xr_runtime/poses.cpp: the project's
// trace and BVH readers, then the runtime's replay) on hostile input: what the runtime's own
// readers once did was an uncaught exception inside xrCreateInstance (which aborts the
// application under test), a multi-gigabyte allocation, or a read past the frame.
// Each case is also an input in fuzz/regressions/xr_poses/, replayed through the fuzz target.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>

#include "reliability/allocation_counter.h"
#include "test_paths.h"
#include "tools/xr_runtime/runtime.h"

using namespace embody;
using xr_runtime::BodySample;

namespace {
std::string xrPosesRegression(const std::string& name) {
  std::ifstream f(std::string(test::kSourceDir) + "/fuzz/regressions/xr_poses/" + name, std::ios::binary);
  REQUIRE(f);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

std::string parseTrace(const std::string& text, std::vector<BodySample>& out) {
  std::istringstream in(text);
  return xr_runtime::parseTraceSamples(in, "poses.jsonl", out);
}

std::string parseBvh(const std::string& text, std::vector<BodySample>& out) {
  std::istringstream in(text);
  return xr_runtime::parseBvhSamples(in, "poses.bvh", out);
}
}  // namespace

TEST_CASE("xr poses: a trigger of the wrong JSON type is read, a valid flag of the wrong type names its line",
          "[reliability][xr_poses]") {
  // The runtime reads its pose files with the project's trace reader (tracking::parseTrace): a
  // malformed "valid" is an error naming the line (the runtime then uses its synthetic motion).
  std::vector<BodySample> samples;
  const std::string text = xrPosesRegression("trigger_not_number.jsonl");
  REQUIRE(parseTrace(text.substr(0, text.find('\n') + 1), samples).empty());
  REQUIRE(samples.size() == 1);
  CHECK(samples[0].leftTrigger == 0.0f);   // "trigger": "pull"
  CHECK(samples[0].rightTrigger == 1.0f);  // "trigger": 7 clamps to 1
  const std::string e = parseTrace(text, samples);
  CHECK(e.find("poses.jsonl:2:") == 0);
  CHECK(e.find("\"valid\"") != std::string::npos);
}

TEST_CASE("xr poses: a trace whose times span more than a day is an error naming the file",
          "[reliability][xr_poses]") {
  std::vector<BodySample> samples;
  const std::string e = parseTrace(xrPosesRegression("time_span_overflow.jsonl"), samples);
  CHECK(e.find("poses.jsonl") == 0);
  CHECK(e.find("day") != std::string::npos);
  CHECK(samples.empty());
}

TEST_CASE("xr poses: a BVH claiming 2e9 frames is an error without the allocation",
          "[reliability][xr_poses]") {
  std::vector<BodySample> samples;
  const std::string text = xrPosesRegression("frames_claim.bvh");
  std::string e;
  test::AllocationCounts counts;
  {
    test::CountAllocations counter;
    e = parseBvh(text, samples);
    counts = counter.counts();
  }
  CHECK(e.find("more than this loader accepts") != std::string::npos);
  CHECK(counts.largestBytes < (size_t{1} << 20));
  // Under the limit but beyond the data: the frames present are used, nothing is reserved for
  // the claim.
  std::string shortFile = xrPosesRegression("frames_claim.bvh");
  shortFile.replace(shortFile.find("2000000000"), 10, "2000000");
  {
    test::CountAllocations counter;
    e = parseBvh(shortFile, samples);
    counts = counter.counts();
  }
  CHECK(counts.largestBytes < (size_t{1} << 20));
}

TEST_CASE("xr poses: a BVH joint with two CHANNELS lines is refused (it read past the frame)",
          "[reliability][xr_poses]") {
  std::vector<BodySample> samples;
  CHECK(parseBvh(xrPosesRegression("channels_twice.bvh"), samples).find("second CHANNELS") != std::string::npos);
}

TEST_CASE("xr poses: an overflowing BVH chain is an error or lost tracking, never a NaN pose",
          "[reliability][xr_poses]") {
  std::vector<BodySample> samples;
  const std::string e = parseBvh(xrPosesRegression("offset_overflow.bvh"), samples);
  INFO(e);
  CHECK(e.empty() != samples.empty());
  for (const auto& s : samples)
    for (const auto* p : {&s.head, &s.left, &s.right}) {
      CHECK(std::isfinite(p->position.x + p->position.y + p->position.z));
      CHECK(std::isfinite(p->orientation.x + p->orientation.y + p->orientation.z + p->orientation.w));
    }
}
