// Tracking loss: hold relative to the head, ease to neutral, blend back speed-limited; never NaN,
// never snapping, hands within reach.
#include <catch2/catch.hpp>
#include <cmath>

#include "tracking/synthetic_source.h"
#include "tracking/tracking_guard.h"

using namespace embody::tracking;

namespace {
constexpr double kFrameSeconds = 1.0 / 90.0;

bool finite(const TrackerPose& p) { return isUsable(p); }
}  // namespace

TEST_CASE("hands lost for 1 s mid-run: held, eased, recovered without exceeding 3 m/s or arm's reach") {
  for (const auto& motion : {"reach", "figure8", "look"}) {
    INFO(motion);
    auto src = SyntheticSource::create(motion).value();
    TrackingGuard guard;
    const auto& body = guard.body();
    PoseSample prevOut;
    bool sawHeld = false, sawEasing = false, sawRecovering = false;
    float maxSpeedAfterReturn = 0.0f, maxReachWhileLost = 0.0f;
    for (int i = 0; i < 90 * 6; ++i) {
      const double t = i * kFrameSeconds;
      PoseSample s = src->sample(t);
      const bool lost = t >= 2.0 && t < 3.0;
      if (lost) {
        s[TrackerId::LeftHand].valid = false;
        s[TrackerId::RightHand].position = glm::vec3(std::nanf(""), 0, 0);  // NaN, flagged valid
      }
      const GuardedSample& g = guard.update(s);
      for (auto id : kAllTrackers) REQUIRE(finite(g.pose[id]));
      for (auto [id, side] : {std::pair{TrackerId::LeftHand, Side::Left}, std::pair{TrackerId::RightHand, Side::Right}}) {
        const TrackerStatus st = g[id];
        sawHeld |= st == TrackerStatus::Held;
        sawEasing |= st == TrackerStatus::Easing;
        sawRecovering |= st == TrackerStatus::Recovering;
        if (lost) {
          CHECK(st != TrackerStatus::Tracked);
          const float r = glm::length(g.pose[id].position - body.shoulderFromHead(g.pose[TrackerId::Head], side));
          maxReachWhileLost = std::max(maxReachWhileLost, r / body.armReach);
        }
        if (t >= 3.0 && i > 0)
          maxSpeedAfterReturn = std::max(
              maxSpeedAfterReturn, glm::length(g.pose[id].position - prevOut[id].position) / static_cast<float>(kFrameSeconds));
        if (t > 4.5) CHECK(st == TrackerStatus::Tracked);  // caught up again
      }
      prevOut = g.pose;
    }
    CHECK(sawHeld);
    CHECK(sawEasing);
    CHECK(sawRecovering);
    CHECK(maxReachWhileLost <= 1.0f);
    CHECK(maxSpeedAfterReturn < 3.0f);
  }
}

TEST_CASE("a lost hand is held relative to the head's heading, then eases to hang at the side") {
  TrackingGuardConfig cfg;
  TrackingGuard guard(cfg);
  PoseSample s;
  s[TrackerId::Head] = {glm::vec3(0, 1.64f, 0), glm::quat(1, 0, 0, 0), true};
  s[TrackerId::LeftHand] = {glm::vec3(-0.2f, 1.3f, -0.45f), glm::quat(1, 0, 0, 0), true};
  s[TrackerId::RightHand] = {glm::vec3(0.2f, 1.3f, -0.45f), glm::quat(1, 0, 0, 0), true};
  guard.update(s);
  s[TrackerId::LeftHand].valid = false;
  // The user turns 90 degrees left and steps sideways while the hand is lost.
  s.time = 0.3;
  s[TrackerId::Head] = {glm::vec3(0.5f, 1.64f, 0), glm::angleAxis(glm::radians(90.0f), glm::vec3(0, 1, 0)), true};
  const GuardedSample& g = guard.update(s);
  CHECK(g[TrackerId::LeftHand] == TrackerStatus::Held);
  // Held in front of the head: after turning left, "in front" is -X.
  const glm::vec3 held = g.pose[TrackerId::LeftHand].position;
  CHECK(held.x == Approx(0.5f - 0.45f).margin(1e-4));
  CHECK(held.z == Approx(0.2f).margin(1e-4));
  CHECK(held.y == Approx(1.3f).margin(1e-4));
  // Long after: neutral, hanging at the left side of the turned body.
  s.time = 3.0;
  const GuardedSample& later = guard.update(s);
  CHECK(later[TrackerId::LeftHand] == TrackerStatus::Neutral);
  const TrackerPose neutral = guard.body().neutralHand(s[TrackerId::Head], Side::Left);
  CHECK(glm::length(later.pose[TrackerId::LeftHand].position - neutral.position) < 1e-4f);
  CHECK(later.pose[TrackerId::LeftHand].position.y < 1.0f);
}

TEST_CASE("implausible jumps are rejected, a lasting jump is accepted and blended in") {
  TrackingGuard guard;
  PoseSample s;
  s[TrackerId::Head] = {glm::vec3(0, 1.64f, 0), glm::quat(1, 0, 0, 0), true};
  s[TrackerId::RightHand] = {glm::vec3(0.2f, 1.0f, -0.2f), glm::quat(1, 0, 0, 0), true};
  guard.update(s);
  s.time = kFrameSeconds;
  s[TrackerId::RightHand].position = glm::vec3(2.2f, 1.0f, -0.2f);  // 2 m in 11 ms: a glitch
  const GuardedSample& g = guard.update(s);
  CHECK(g[TrackerId::RightHand] == TrackerStatus::Held);
  CHECK(g.pose[TrackerId::RightHand].position.x == Approx(0.2f));
  s.time = 2 * kFrameSeconds;
  s[TrackerId::RightHand].position = glm::vec3(0.21f, 1.0f, -0.2f);  // back to plausible
  CHECK(guard.update(s)[TrackerId::RightHand] != TrackerStatus::Held);
  // A jump that lasts (the play space was recentred) is taken after 0.25 s, speed-limited.
  float maxStep = 0.0f;
  glm::vec3 prev = guard.update(s).pose[TrackerId::RightHand].position;
  for (int i = 3; i < 200; ++i) {
    s.time = i * kFrameSeconds;
    s[TrackerId::Head].position = glm::vec3(1.0f, 1.64f, 0);
    s[TrackerId::RightHand].position = glm::vec3(1.2f, 1.0f, -0.2f);
    const GuardedSample& h = guard.update(s);
    maxStep = std::max(maxStep, glm::length(h.pose[TrackerId::RightHand].position - prev));
    prev = h.pose[TrackerId::RightHand].position;
  }
  CHECK(guard.update(s)[TrackerId::RightHand] == TrackerStatus::Tracked);
  CHECK(prev.x == Approx(1.2f));
  CHECK(maxStep / kFrameSeconds < 3.0);
}

TEST_CASE("never-seen trackers: hands neutral, hips and feet absent, head at eye height, all finite") {
  TrackingGuard guard;
  PoseSample s;  // nothing valid at all
  s[TrackerId::Head].position = glm::vec3(std::nanf(""));
  const GuardedSample& g = guard.update(s);
  CHECK(g[TrackerId::Head] == TrackerStatus::Neutral);
  CHECK(g.pose[TrackerId::Head].position.y == Approx(kEyeHeightRatio * 1.75f));
  CHECK(g[TrackerId::LeftHand] == TrackerStatus::Neutral);
  CHECK(g.pose[TrackerId::LeftHand].valid);
  CHECK(g.pose[TrackerId::LeftHand].position.y > 0.5f);  // not at the origin
  CHECK(g[TrackerId::Hips] == TrackerStatus::Absent);
  CHECK_FALSE(g.pose[TrackerId::Hips].valid);
  for (auto id : kAllTrackers) CHECK(finite(g.pose[id]));
  // The head arriving later blends in from the default instead of snapping.
  s.time = 0.5;
  s[TrackerId::Head] = {glm::vec3(1.0f, 1.64f, 1.0f), glm::quat(1, 0, 0, 0), true};
  const GuardedSample& h = guard.update(s);
  CHECK(h[TrackerId::Head] == TrackerStatus::Recovering);
  CHECK(glm::length(h.pose[TrackerId::Head].position - glm::vec3(0, 1.638f, 0)) < 2.0f * 0.1f + 1e-3f);  // dt clamped to 0.1 s
}

TEST_CASE("lost feet hold in the world, then drop, a lost head holds") {
  TrackingGuard guard;
  auto src = SyntheticSource::create("idle").value();
  PoseSample s = src->sample(0.0);
  guard.update(s);
  const glm::vec3 foot = s[TrackerId::LeftFoot].position;
  s.time = 0.2;
  s[TrackerId::LeftFoot].valid = false;
  s[TrackerId::Head].valid = false;
  s[TrackerId::Hips].valid = false;
  const GuardedSample& g = guard.update(s);
  CHECK(g[TrackerId::LeftFoot] == TrackerStatus::Held);
  CHECK(g.pose[TrackerId::LeftFoot].position == foot);
  CHECK(g[TrackerId::Head] == TrackerStatus::Held);
  CHECK(g[TrackerId::Hips] == TrackerStatus::Held);
  s.time = 1.0;
  const GuardedSample& later = guard.update(s);
  CHECK(later[TrackerId::LeftFoot] == TrackerStatus::Absent);
  CHECK_FALSE(later.pose[TrackerId::LeftFoot].valid);
  CHECK(later[TrackerId::Hips] == TrackerStatus::Absent);
  CHECK(later[TrackerId::Head] == TrackerStatus::Held);
  CHECK(statusName(TrackerStatus::Easing) == "easing");
}

TEST_CASE("a hand recovering towards a target beyond the estimated reach still arrives") {
  // Bowing: the head-only shoulder estimate is off, the live hands are farther than it allows.
  auto src = SyntheticSource::create("bow").value();
  TrackingGuard guard;
  for (int i = 0; i < 90 * 4; ++i) {
    const double t = 1.5 + i * kFrameSeconds;  // deep in the bow
    PoseSample s = src->sample(t);
    if (i < 90) s[TrackerId::LeftHand].valid = false;
    const GuardedSample& g = guard.update(s);
    if (i > 200) {
      CHECK(g[TrackerId::LeftHand] == TrackerStatus::Tracked);
      CHECK(g.pose[TrackerId::LeftHand].position == s[TrackerId::LeftHand].position);
    }
  }
}
