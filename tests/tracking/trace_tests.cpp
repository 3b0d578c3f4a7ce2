// JSON Lines traces: round trip, invalid data, malformed lines with line numbers, replay.
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "test_paths.h"
#include "tracking/synthetic_source.h"
#include "tracking/trace.h"

using namespace embody::tracking;

namespace {
embody::Result<Trace> parse(const std::string& text) {
  std::istringstream in(text);
  return parseTrace(in, "t.jsonl");
}
const char* kPose = R"({"p": [0, 1.6, 0], "q": [0, 0, 0, 1]})";
}  // namespace

TEST_CASE("a trace line round-trips every tracker") {
  auto src = SyntheticSource::create("reach").value();
  std::string text;
  for (int i = 0; i < 20; ++i) text += formatTraceLine(src->sample(i * 0.1), TrackerMask::all()) + "\n";
  auto t = parse(text);
  REQUIRE(t.ok());
  REQUIRE(t->samples.size() == 20);
  CHECK(t->trackers == TrackerMask::all());
  for (int i = 0; i < 20; ++i) {
    const PoseSample want = src->sample(i * 0.1);
    CHECK(t->samples[static_cast<size_t>(i)].time == Approx(i * 0.1).margin(1e-6));
    for (auto id : kAllTrackers) {
      const auto& got = t->samples[static_cast<size_t>(i)][id];
      CHECK(got.valid);
      CHECK(glm::length(got.position - want[id].position) < 2e-6f);
      CHECK(std::abs(std::abs(glm::dot(got.orientation, want[id].orientation)) - 1.0f) < 1e-6f);
    }
  }
}

TEST_CASE("non-finite and flagged trackers become invalid, absent ones stay absent") {
  auto t = parse(std::string("{\"t\": 0, \"head\": ") + kPose + ", \"left\": {\"p\": [NaN, 1, 0], \"q\": [0,0,0,1]}, " +
                 "\"right\": {\"p\": [0, 1, 0], \"q\": [0, 0, 0, 1], \"valid\": false}}\n" +
                 "{\"t\": 0.01, \"head\": {\"p\": [0, Infinity, 0], \"q\": [0,0,0,1]}, \"left\": {\"p\": null, " +
                 "\"q\": null, \"valid\": false}, \"right\": {\"p\": [0, 1, 0], \"q\": [0, 0, 0, 0]}}\n");
  REQUIRE(t.ok());
  const auto& a = t->samples[0];
  CHECK(a[TrackerId::Head].valid);
  CHECK_FALSE(a[TrackerId::LeftHand].valid);
  CHECK_FALSE(a[TrackerId::RightHand].valid);
  CHECK_FALSE(a[TrackerId::Hips].valid);
  CHECK(t->trackers == TrackerMask::threePoint());
  const auto& b = t->samples[1];
  CHECK_FALSE(b[TrackerId::Head].valid);
  CHECK_FALSE(b[TrackerId::LeftHand].valid);
  CHECK_FALSE(b[TrackerId::RightHand].valid);  // zero quaternion
}

TEST_CASE("malformed trace lines are errors naming the line") {
  const std::string ok = std::string("{\"t\": 0, \"head\": ") + kPose + "}\n";
  struct Case {
    std::string text, expect;
  };
  const Case cases[] = {
      {ok + "\n{\"t\": 0.1, \"head\": \n", "t.jsonl:3: not valid JSON"},
      {ok + "[1, 2]\n", "t.jsonl:2: expected a JSON object"},
      {ok + "{\"head\": {}}\n", "t.jsonl:2: missing number \"t\""},
      {ok + "{\"t\": -1}\n", "t.jsonl:2: time goes backwards"},
      {ok + "{\"t\": 1, \"head\": {\"p\": [1, 2], \"q\": [0,0,0,1]}}\n", "t.jsonl:2: \"head\": \"p\" must be an array of 3"},
      {ok + "{\"t\": 1, \"left\": {\"p\": [1, 2, 3]}}\n", "t.jsonl:2: \"left\": a valid tracker needs both"},
      {ok + "{\"t\": 1, \"left\": {\"p\": [1, 2, \"x\"], \"q\": [0,0,0,1]}}\n", "t.jsonl:2: \"left\": \"p\" must be"},
      {ok + "{\"t\": 1, \"left\": {\"valid\": 1}}\n", "\"valid\" must be true or false"},
      {"", "no samples"},
      {ok + ok.substr(0, 0) + "{\"embody_trace\": 1}\n", "header line after the first sample"},
  };
  for (const auto& c : cases) {
    INFO(c.text);
    auto t = parse(c.text);
    REQUIRE_FALSE(t.ok());
    CHECK_THAT(t.error(), Catch::Contains(c.expect));
  }
  // Over-long lines are refused without reading them whole.
  auto big = parse(std::string(kMaxTraceLineBytes + 10, ' '));
  REQUIRE_FALSE(big.ok());
  CHECK_THAT(big.error(), Catch::Contains("t.jsonl:1: line longer than"));
  // Unknown keys are notes, not errors.
  auto notes = parse(std::string("{\"t\": 0, \"lefthand\": 3, \"head\": ") + kPose + "}\n");
  REQUIRE(notes.ok());
  REQUIRE(notes->notes.size() == 1);
  CHECK_THAT(notes->notes[0], Catch::Contains("t.jsonl:1: unknown key \"lefthand\""));
}

TEST_CASE("trace replay interpolates valid neighbours and holds across invalid ones") {
  auto t = parse(
      "{\"t\": 1.0, \"head\": {\"p\": [0, 1, 0], \"q\": [0, 0, 0, 1]}, \"left\": {\"p\": [0, 1, 0], \"q\": [0,0,0,1]}}\n"
      "{\"t\": 1.5, \"head\": {\"p\": [1, 1, 0], \"q\": [0, 0.7071068, 0, 0.7071068]}, \"left\": {\"valid\": false}}\n");
  REQUIRE(t.ok());
  TraceSource src(std::move(*t), "t.jsonl");
  CHECK(src.duration() == Approx(0.5));
  CHECK(src.nativeRate() == Approx(2.0));
  const PoseSample mid = src.sample(0.25);  // trace time 1.25
  CHECK(mid.time == 0.25);
  CHECK(mid[TrackerId::Head].position.x == Approx(0.5f));
  CHECK(glm::angle(mid[TrackerId::Head].orientation) == Approx(glm::radians(45.0f)).margin(1e-4));
  CHECK(mid[TrackerId::LeftHand].valid);  // held from the earlier sample
  CHECK(mid[TrackerId::LeftHand].position.x == 0.0f);
  CHECK(src.sample(-3.0)[TrackerId::Head].position.x == 0.0f);
  CHECK(src.sample(99.0)[TrackerId::Head].position.x == 1.0f);
  CHECK_FALSE(src.sample(99.0)[TrackerId::LeftHand].valid);
}

TEST_CASE("the trace writer writes a header and samples the reader reads back") {
  const auto path = std::filesystem::temp_directory_path() / "embody_trace_writer_test.jsonl";
  auto src = SyntheticSource::create("look").value();
  {
    TraceWriter w;
    REQUIRE(w.open(path.string(), TrackerMask::threePoint(), "synthetic:look", 1.75f).ok());
    for (int i = 0; i < 10; ++i) {
      PoseSample s = src->sample(i / 90.0);
      if (i == 4) s[TrackerId::LeftHand].position.x = std::nanf("");
      if (i == 4) s[TrackerId::LeftHand].valid = false;
      REQUIRE(w.write(s).ok());
    }
    REQUIRE(w.close().ok());
  }
  auto t = readTrace(path.string());
  std::filesystem::remove(path);
  REQUIRE(t.ok());
  CHECK(t->source == "synthetic:look");
  CHECK(t->userHeight == Approx(1.75f));
  CHECK(t->samples.size() == 10);
  CHECK(t->trackers == TrackerMask::threePoint());
  CHECK_FALSE(t->samples[4][TrackerId::LeftHand].valid);
  CHECK(t->samples[5][TrackerId::LeftHand].valid);
  CHECK_FALSE(readTrace("/nonexistent/x.jsonl").ok());
}
