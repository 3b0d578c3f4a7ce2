// Synthetic scripted motions: deterministic, finite, smooth, and plausible for the user's height.
#include <catch2/catch.hpp>
#include <cmath>

#include "tracking/synthetic_source.h"

using namespace embody::tracking;

namespace {
float speed(const TrackerPose& a, const TrackerPose& b, double dt) {
  return glm::length(b.position - a.position) / static_cast<float>(dt);
}
}  // namespace

TEST_CASE("synthetic motions are deterministic, complete and finite") {
  REQUIRE(syntheticMotions().size() == 7);
  for (const auto& m : syntheticMotions()) {
    INFO(m.name);
    auto a = SyntheticSource::create(m.name);
    auto b = SyntheticSource::create(m.name);
    REQUIRE(a.ok());
    REQUIRE(b.ok());
    CHECK((*a)->periodic());
    CHECK((*a)->duration() == Approx(m.period));
    for (double t = 0.0; t < m.period; t += 0.37) {
      const PoseSample s1 = (*a)->sample(t), s2 = (*b)->sample(t);
      CHECK(s1.validMask() == TrackerMask::all());
      for (auto id : kAllTrackers) {
        CHECK(isUsable(s1[id]));
        CHECK(s1[id].position == s2[id].position);
        CHECK(std::abs(glm::length(s1[id].orientation) - 1.0f) < 1e-4f);
      }
    }
  }
}

TEST_CASE("synthetic motions are smooth, periodic and within a 1.75 m body's reach") {
  const float height = 1.75f;
  const auto body = BodyDimensions::fromHeight(height);
  for (const auto& m : syntheticMotions()) {
    INFO(m.name);
    auto src = SyntheticSource::create(m.name, height).value();
    const double dt = 1.0 / 90.0;
    PoseSample prev = src->sample(0.0);
    float maxHand = 0.0f, maxHead = 0.0f, maxReach = 0.0f, maxEstimate = 0.0f, minHead = 10.0f;
    for (int i = 1; i <= static_cast<int>(m.period * 90.0) + 10; ++i) {  // across the loop point
      const PoseSample s = src->sample(i * dt);
      maxHand = std::max({maxHand, speed(prev[TrackerId::LeftHand], s[TrackerId::LeftHand], dt),
                          speed(prev[TrackerId::RightHand], s[TrackerId::RightHand], dt)});
      maxHead = std::max(maxHead, speed(prev[TrackerId::Head], s[TrackerId::Head], dt));
      minHead = std::min(minHead, s[TrackerId::Head].position.y);
      for (auto [id, side] : {std::pair{TrackerId::LeftHand, Side::Left}, std::pair{TrackerId::RightHand, Side::Right}}) {
        const float r = glm::length(s[id].position - src->shoulder(i * dt, side));
        maxReach = std::max(maxReach, r / body.armReach);
        // The head-only estimate the tracking-loss guard uses stays close (loose when bowing).
        const float e = glm::length(s[id].position - body.shoulderFromHead(s[TrackerId::Head], side));
        maxEstimate = std::max(maxEstimate, e / body.armReach);
      }
      // Feet planted on the floor, hips between feet and head.
      CHECK(s[TrackerId::LeftFoot].position.y == Approx(body.ankleHeight));
      CHECK(s[TrackerId::Hips].position.y < s[TrackerId::Head].position.y - 0.3f);
      CHECK(s[TrackerId::LeftHand].position.x < s[TrackerId::RightHand].position.x + 0.05f);
      prev = s;
    }
    CHECK(maxHand < 2.5f);   // m/s: brisk but human
    CHECK(maxHead < 1.5f);
    CHECK(minHead > 1.1f);   // even squatting and bowing
    CHECK(maxReach <= 0.961f);
    CHECK(maxEstimate < 1.2f);
    // Periodic: one period later, the same pose.
    const PoseSample a = src->sample(0.4), b = src->sample(0.4 + m.period);
    CHECK(glm::length(a[TrackerId::RightHand].position - b[TrackerId::RightHand].position) < 1e-4f);
  }
}

TEST_CASE("synthetic motions scale with the user's height") {
  auto tall = SyntheticSource::create("idle", 1.9f).value();
  auto small = SyntheticSource::create("idle", 1.5f).value();
  const float ht = tall->sample(0.0)[TrackerId::Head].position.y;
  const float hs = small->sample(0.0)[TrackerId::Head].position.y;
  CHECK(ht == Approx(kEyeHeightRatio * 1.9f).margin(0.02));
  CHECK(hs == Approx(kEyeHeightRatio * 1.5f).margin(0.02));
  CHECK_FALSE(SyntheticSource::create("idle", 0.1f).ok());
}

TEST_CASE("figure8 traces a figure eight with both hands in front of the chest") {
  auto src = SyntheticSource::create("figure8").value();
  float minX = 1, maxX = -1;
  int crossings = 0;
  float prevX = 0.0f;
  for (int i = 0; i <= 600; ++i) {
    const PoseSample s = src->sample(i * 0.01);
    const glm::vec3 mid = 0.5f * (s[TrackerId::LeftHand].position + s[TrackerId::RightHand].position);
    CHECK(mid.z < -0.25f);  // in front of the body
    minX = std::min(minX, mid.x);
    maxX = std::max(maxX, mid.x);
    if (i > 0 && (prevX < 0.0f) != (mid.x < 0.0f)) ++crossings;
    prevX = mid.x;
  }
  CHECK(maxX == Approx(0.2f).margin(0.01));
  CHECK(minX == Approx(-0.2f).margin(0.01));
  CHECK(crossings >= 2);
  // The two lobes: at phase pi/4 the hands are up on the right, at 3pi/4 down on the right.
  const float yUp = src->sample(0.75)[TrackerId::RightHand].position.y;
  const float yDown = src->sample(2.25)[TrackerId::RightHand].position.y;
  CHECK(yUp - yDown > 0.25f);
}

TEST_CASE("unknown synthetic motions are errors that list the known ones") {
  auto s = openPoseSource("synthetic:dance");
  REQUIRE_FALSE(s.ok());
  CHECK(s.error().find("synthetic:figure8") != std::string::npos);
  CHECK_FALSE(openPoseSource("motion.xyz").ok());
  auto three = openPoseSource("synthetic:idle", {1.75f, 0.0, TrackerMask::threePoint()});
  REQUIRE(three.ok());
  CHECK((*three)->trackers() == TrackerMask::threePoint());
  CHECK_FALSE((*three)->sample(1.0)[TrackerId::Hips].valid);
}

TEST_CASE("grip orientation follows the OpenXR grip axes") {
  // Left hand hanging, palm towards the thigh: -Z (little finger to thumb) points forward.
  const glm::quat l = gripOrientation(Side::Left, {0, -1, 0}, {1, 0, 0});
  CHECK(glm::length(l * glm::vec3(0, 0, -1) - glm::vec3(0, 0, -1)) < 1e-5f);
  CHECK(glm::length(l * glm::vec3(1, 0, 0) - glm::vec3(-1, 0, 0)) < 1e-5f);  // away from the palm
  const glm::quat r = gripOrientation(Side::Right, {0, -1, 0}, {-1, 0, 0});
  CHECK(glm::length(r * glm::vec3(0, 0, -1) - glm::vec3(0, 0, -1)) < 1e-5f);
  CHECK(glm::length(r * glm::vec3(1, 0, 0) - glm::vec3(-1, 0, 0)) < 1e-5f);  // into the palm
  // T-pose, palms down: thumbs forward as well.
  const glm::quat lt = gripOrientation(Side::Left, {-1, 0, 0}, {0, -1, 0});
  CHECK(glm::length(lt * glm::vec3(0, 0, -1) - glm::vec3(0, 0, -1)) < 1e-5f);
  // headingOf keeps only the yaw, also when looking down.
  const glm::quat down = glm::angleAxis(0.5f, glm::vec3(0, 1, 0)) * glm::angleAxis(-1.5f, glm::vec3(1, 0, 0));
  const glm::quat h = headingOf(down);
  CHECK(std::abs(glm::angle(h) - 0.5f) < 1e-3f);
}

TEST_CASE("tracking loss can be injected into any source for a time window") {
  auto spec = parseTrackingLoss("left,right@2-3.5");
  REQUIRE(spec.ok());
  CHECK(spec->lost == TrackerMask({TrackerId::LeftHand, TrackerId::RightHand}));
  CHECK(spec->from == 2.0);
  CHECK(spec->to == 3.5);
  for (const char* bad : {"left", "elbow@1-2", "left@2", "left@3-2", "left@a-b", "@1-2", "left@1-2x"}) {
    INFO(bad);
    CHECK_FALSE(parseTrackingLoss(bad).ok());
  }
  auto src = withTrackingLoss(SyntheticSource::create("reach").value(), spec->lost, spec->from, spec->to);
  CHECK(src->name() == "synthetic:reach");
  CHECK(src->sample(1.99)[TrackerId::LeftHand].valid);
  const PoseSample lost = src->sample(2.5);
  CHECK_FALSE(lost[TrackerId::LeftHand].valid);
  CHECK_FALSE(lost[TrackerId::RightHand].valid);
  CHECK(std::isnan(lost[TrackerId::LeftHand].position.x));
  CHECK(lost[TrackerId::Head].valid);
  CHECK(src->sample(3.5)[TrackerId::RightHand].valid);
}
