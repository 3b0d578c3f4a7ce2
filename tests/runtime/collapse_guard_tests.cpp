// The collapse guard's decisions (collapse_guard.h) on hand-made body measures, and the pieces
// a recovery uses: the standing seed under the head (body_seed.h), the knee/elbow pole targets
// (pole_tasks.h) and the pose fade (pose_blend.h).
#include <catch2/catch.hpp>
#include <cmath>
#include <utility>
#include <vector>

#include "runtime/body_seed.h"
#include "runtime/collapse_guard.h"
#include "runtime/pole_tasks.h"
#include "runtime/pose_blend.h"

using namespace embody::runtime;

namespace {
BodySignals standing(double t) {
  BodySignals s;
  s.time = t;
  s.pelvisHeight = s.standingPelvisHeight = 0.95;
  s.headTargetHeight = s.standingEyeHeight = 1.64;
  s.lowestTrunkOrKnee = 0.5;
  s.legSeparation = 0.2;
  s.inferredLegs = true;
  return s;
}
}  // namespace

TEST_CASE("collapse guard: a standing body and a crouch are left alone", "[runtime]") {
  CollapseGuard g;
  for (int i = 0; i < 200; ++i) CHECK(g.update(standing(i / 90.0)) == CollapseReason::None);
  // A deep crouch: the pelvis low, but so is the head.
  for (int i = 200; i < 400; ++i) {
    BodySignals s = standing(i / 90.0);
    s.pelvisHeight = 0.3;
    s.headTargetHeight = 0.9;
    CHECK(g.update(s) == CollapseReason::None);
  }
  CHECK(g.recoveries() == 0);
}

TEST_CASE("collapse guard: a heap under a standing head is confirmed after 0.1 s, then waits 1 s", "[runtime]") {
  CollapseGuard g;
  int first = -1, count = 0;
  for (int i = 0; i < 200; ++i) {
    BodySignals s = standing(i / 100.0);
    s.pelvisHeight = 0.2;  // sitting on the floor while the head target stands
    if (g.update(s) != CollapseReason::None) {
      if (first < 0) first = i;
      ++count;
    }
  }
  CHECK(first == 10);  // 0.1 s
  CHECK(count == 2);   // again after the 1 s cooldown
  CHECK(g.lastReason() == CollapseReason::PelvisLow);
  CHECK(g.collapsedFrames() == 200);
}

TEST_CASE("collapse guard: each condition, and NaN at once", "[runtime]") {
  auto firstReason = [](auto edit) {
    CollapseGuard g;
    for (int i = 0; i < 50; ++i) {
      BodySignals s = standing(i / 100.0);
      edit(s);
      const CollapseReason r = g.update(s);
      if (r != CollapseReason::None) return std::pair{r, i};
    }
    return std::pair{CollapseReason::None, -1};
  };
  CHECK(firstReason([](BodySignals& s) { s.finite = false; }) == std::pair{CollapseReason::NonFinite, 0});
  CHECK(firstReason([](BodySignals& s) { s.pelvisTilt = 1.5; }).first == CollapseReason::Folded);
  CHECK(firstReason([](BodySignals& s) { s.lowestTrunkOrKnee = -0.2; }).first == CollapseReason::ThroughFloor);
  CHECK(firstReason([](BodySignals& s) { s.legSeparation = -0.05; }).first == CollapseReason::CrossedLegs);
  // Tracked legs may cross: the user's own.
  CHECK(firstReason([](BodySignals& s) {
          s.legSeparation = -0.05;
          s.inferredLegs = false;
        }).first == CollapseReason::None);
}

TEST_CASE("collapse guard: an error that stays high is a stall, one that keeps falling is not", "[runtime]") {
  CollapseGuard stuck, falling;
  int stuckAt = -1;
  for (int i = 0; i < 120; ++i) {
    BodySignals s = standing(i / 100.0);
    s.residual = 0.15;
    s.iterations = 3;
    if (stuck.update(s) == CollapseReason::Stalled && stuckAt < 0) stuckAt = i;
    s.residual = 0.15 * std::exp(-i / 100.0);  // falls by ~40 % per half second
    CHECK(falling.update(s) == CollapseReason::None);
  }
  CHECK(stuckAt == 50);  // 0.5 s (and 150 iterations)
  // The same error at a few frames a second, one iteration each: the solver has had no chance.
  CollapseGuard slow;
  for (int i = 0; i < 20; ++i) {
    BodySignals s = standing(i / 8.0);
    s.residual = 0.15;
    s.iterations = 1;
    CHECK(slow.update(s) == CollapseReason::None);
  }
}

TEST_CASE("collapse guard: a body dragged off its targets is caught in 0.1 s, also soon after another recovery",
          "[runtime]") {
  // Legs crossed at 0.1 s (a recovery), then from 0.5 s the head pulled away 1 cm a frame.
  // Over 0.2 m from frame 70; confirmed 0.1 s later, 0.7 s after the first recovery (a stall
  // would have waited 0.5 s, the other conditions the full 1 s cooldown). Not again while it
  // stays off after that recovery: the re-seeded body never got back, so it is a stall's to take.
  CollapseGuard g;
  std::vector<std::pair<CollapseReason, int>> recoveries;
  for (int i = 0; i < 120; ++i) {
    BodySignals s = standing(i / 100.0);
    s.iterations = 3;
    if (i < 20) s.legSeparation = -0.05;
    if (i >= 50) s.residual = 0.01 * (i - 49);
    const CollapseReason r = g.update(s);
    if (r != CollapseReason::None) recoveries.emplace_back(r, i);
  }
  REQUIRE(recoveries.size() == 2);
  CHECK(recoveries[0] == std::pair{CollapseReason::CrossedLegs, 10});
  CHECK(recoveries[1] == std::pair{CollapseReason::Diverged, 80});
  // An error under the bound is no divergence: only a stall, after 0.5 s.
  CollapseGuard h;
  int first = -1;
  for (int i = 0; i < 80 && first < 0; ++i) {
    BodySignals s = standing(i / 100.0);
    s.iterations = 3;
    s.residual = 0.19;
    if (h.update(s) != CollapseReason::None) first = i;
  }
  CHECK(first == 50);
  CHECK(h.lastReason() == CollapseReason::Stalled);
  // At a body a fifth smaller the bound is a fifth smaller.
  CollapseGuard small;
  first = -1;
  for (int i = 0; i < 40 && first < 0; ++i) {
    BodySignals s = standing(i / 100.0);
    s.scale = 0.8;
    s.residual = i < 10 ? 0.0 : 0.17;
    if (small.update(s) != CollapseReason::None) first = i;
  }
  CHECK(first == 20);
  CHECK(small.lastReason() == CollapseReason::Diverged);
}

TEST_CASE("collapse guard: a target the body never reached is a stall, not a divergence", "[runtime]") {
  // A head on the floor, a hand target far away: 0.5 m off from the first frame for 3 s. Taken
  // for a divergence it re-seeded every 0.4 s; as a stall, after 0.5 s and then once a cooldown.
  CollapseGuard g;
  std::vector<std::pair<CollapseReason, int>> recoveries;
  for (int i = 0; i < 300; ++i) {
    BodySignals s = standing(i / 100.0);
    s.iterations = 3;
    s.residual = 0.5;
    const CollapseReason r = g.update(s);
    if (r != CollapseReason::None) recoveries.emplace_back(r, i);
  }
  REQUIRE(!recoveries.empty());
  CHECK(recoveries.front() == std::pair{CollapseReason::Stalled, 50});
  for (const auto& r : recoveries) CHECK(r.first == CollapseReason::Stalled);
  CHECK(recoveries.size() <= 3);
}

TEST_CASE("collapse guard: a head target above standing height only explains that much of its error", "[runtime]") {
  CHECK(fixableHeadError(0.3, 1.6, 1.64) == Approx(0.3));          // below standing: all of it
  CHECK(fixableHeadError(0.3, 1.64 * 1.02, 1.64) == Approx(0.3));  // within 2 %
  CHECK(fixableHeadError(0.3, 1.64 * 1.02 + 0.1, 1.64) == Approx(0.2));
  CHECK(fixableHeadError(0.05, 1.64 * 1.02 + 0.1, 1.64) == 0.0);  // a taller user: none of it
}

TEST_CASE("standing seed: under the head, facing between the head and the hands, never below half height",
          "[runtime]") {
  SeedInputs in;
  in.headPivot = {1.0, 1.55, 2.0};
  in.headYaw = 0.4;
  in.restHeadToHips = {0.0, -0.6, -0.02};
  in.restHipsHeight = 0.95;
  CHECK(seedYaw(in) == Approx(0.4));
  // Hands held in front, turned 0.4 rad further than the head: halfway.
  const Eigen::Vector3d side = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitX();
  in.leftHand = in.headPivot + 0.25 * side;
  in.rightHand = in.headPivot - 0.25 * side;
  CHECK(seedYaw(in) == Approx(0.6).margin(1e-9));
  // Hands behind the back (their heading opposite): the head's.
  in.leftHand = in.headPivot - 0.25 * side;
  in.rightHand = in.headPivot + 0.25 * side;
  CHECK(seedYaw(in) == Approx(0.4));
  const Eigen::Vector3d p = seedPelvis(in, 0.4);
  CHECK(p.y() == Approx(0.95));  // standing height (the head is at 1.55 + 0.6 above it: higher)
  in.headPivot.y() = 1.2;        // a crouch: the pelvis goes down with the head
  CHECK(seedPelvis(in, 0.4).y() == Approx(0.6).margin(1e-9));
  in.headPivot.y() = 0.2;  // lying: never below half height
  CHECK(seedPelvis(in, 0.4).y() == Approx(0.475));
}

TEST_CASE("pole targets: on the limb's circle, in the pole's direction, never straight", "[runtime]") {
  const LimbGeometry leg{0.45, 0.45};
  const Eigen::Vector3d hip(0, 1, 0), fwd(0, 0, 1);
  // A bent leg: the knee at the segment lengths from both ends, ahead.
  const Eigen::Vector3d ankle(0, 0.3, 0);
  const Eigen::Vector3d knee = poleTarget(hip, ankle, leg, fwd, fwd);
  CHECK((knee - hip).norm() == Approx(0.45));
  CHECK((knee - ankle).norm() == Approx(0.45));
  CHECK(knee.z() > 0.2);
  // A straight leg: still slightly ahead of the line, in the anatomical direction.
  const Eigen::Vector3d straight = poleTarget(hip, Eigen::Vector3d(0, 0.1, 0), leg, fwd, fwd);
  CHECK(straight.z() > 0.01);
  CHECK(std::isfinite(poleTarget(hip, hip, leg, fwd, fwd).norm()));
  // The elbow: a palm facing down sends the elbow further out than a palm facing in.
  const Eigen::Vector3d up(0, 1, 0), out(1, 0, 0);
  const Eigen::Vector3d down = elbowPole(up, fwd, out, -up, Eigen::Vector3d(0, -0.3, 0.3));
  const Eigen::Vector3d in = elbowPole(up, fwd, out, -out, Eigen::Vector3d(0, -0.3, 0.3));
  CHECK(down.dot(out) > in.dot(out));
}

TEST_CASE("pose fade: from the shown pose to the new one over its time", "[runtime]") {
  embody::avatar::SkeletonPose a, b;
  a.local.resize(2);
  b.local.resize(2);
  b.local[1].translation = glm::vec3(1, 0, 0);
  b.local[1].rotation = glm::angleAxis(1.0f, glm::vec3(0, 1, 0));
  PoseFade f;
  f.start(a, 10.0, 0.2);
  embody::avatar::SkeletonPose p = b;
  f.apply(10.0, p);
  CHECK(p.local[1].translation.x == Approx(0.0));
  p = b;
  f.apply(10.1, p);
  CHECK(p.local[1].translation.x == Approx(0.5));
  CHECK(glm::angle(p.local[1].rotation) == Approx(0.5).margin(1e-5));
  p = b;
  f.apply(10.3, p);
  CHECK(p.local[1].translation.x == Approx(1.0));
  CHECK_FALSE(f.active());
}
