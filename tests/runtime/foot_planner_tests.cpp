// The three-point foot planner on its own (runtime/foot_planner.h): where feet land.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "runtime/body_heading.h"
#include "runtime/foot_planner.h"

using namespace embody::runtime;

namespace {

// Up +Y, forward +Z: the body's left is +X. Ankles 10 cm either side of the centre, 8 cm up.
FootPlanner planner() {
  FootPlanner p;
  p.configure({}, FootShape{}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
              {Eigen::Vector3d(0.1, 0.08, 0.0), Eigen::Vector3d(-0.1, 0.08, 0.0)}, 1.0);
  return p;
}

// How far the left foot is on the left of the right one, across the heading `yaw`.
double leftOfRight(const std::array<FootTarget, 2>& feet, double yaw) {
  const Eigen::Vector3d side = yawRotation(yaw, Eigen::Vector3d::UnitY()) * Eigen::Vector3d::UnitX();
  return (feet[0].position - feet[1].position).dot(side);
}

// Drives the planner at 90 Hz along `centre(t)` facing `yaw(t)` for `seconds`; returns the
// smallest left-of-right separation at any landing, across the landing foot's heading.
template <class Centre, class Yaw>
double narrowestLanding(Centre centre, Yaw yaw, double seconds, int& steps) {
  FootPlanner p = planner();
  std::array<bool, 2> planted{true, true};
  double narrowest = 1e9;
  for (int i = 0; i <= int(seconds * 90.0); ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c = centre(t);
    const auto& feet = p.update(t, c, yaw(t), c);
    for (size_t f = 0; f < 2; ++f) {
      if (feet[f].planted && !planted[f]) narrowest = std::min(narrowest, leftOfRight(feet, feet[f].yaw));
      planted[f] = feet[f].planted;
    }
  }
  steps = p.steps();
  return narrowest;
}

}  // namespace

TEST_CASE("foot planner: a fast sidestep never lands a foot across the other one", "[runtime]") {
  // 1.2 m/s to the left for 1.5 s: the trailing foot's landing spot, led by the body's velocity,
  // would fall beyond the planted leading foot. Every landing keeps half the stance width (10 cm).
  int steps = 0;
  const double narrowest =
      narrowestLanding([](double t) { return Eigen::Vector3d(1.2 * std::min(t, 1.5), 0.9, 0.0); }, [](double) { return 0.0; }, 2.5, steps);
  INFO("narrowest landing " << narrowest << " m over " << steps << " steps");
  CHECK(steps >= 4);
  CHECK(narrowest >= 0.1 - 1e-9);
  // The same with the head dipping 2 cm every 0.5 s, its speed surging with each step (the steps'
  // rhythm may follow the dips): still no foot across the other.
  int dippingSteps = 0;
  const double dipping = narrowestLanding(
      [](double t) {
        const double x = t < 1.5 ? 1.2 * t - 0.05 * std::sin(4.0 * M_PI * t) : 1.8 - 0.05 * std::sin(6.0 * M_PI);
        return Eigen::Vector3d(x, 0.9 - 0.01 * std::cos(4.0 * M_PI * t), 0.0);
      },
      [](double) { return 0.0; }, 2.5, dippingSteps);
  INFO("with the head dipping: narrowest landing " << dipping << " m over " << dippingSteps << " steps");
  CHECK(dippingSteps >= 4);
  CHECK(dipping >= 0.1 - 1e-9);
}

TEST_CASE("foot planner: turning on the spot while drifting sideways keeps the feet uncrossed", "[runtime]") {
  // Half a turn in a second while the body drifts 0.6 m/s to its right.
  int steps = 0;
  const double narrowest = narrowestLanding([](double t) { return Eigen::Vector3d(-0.6 * std::min(t, 1.0), 0.9, 0.0); },
                                            [](double t) { return M_PI * std::min(t, 1.0); }, 2.0, steps);
  INFO("narrowest landing " << narrowest << " m over " << steps << " steps");
  CHECK(steps >= 2);
  CHECK(narrowest >= 0.1 - 1e-9);
}

// Drives a planner configured with `config` at 90 Hz along `centre(t)` facing +Z for `seconds`,
// the centre of mass `comShare` of the way from the start to the centre; returns its steps and
// the farthest a planted foot was left from where it would stand.
struct Drive {
  int steps = 0;
  double farthestPlanted = 0.0;
};
template <class Centre>
Drive drive(const FootPlannerConfig& config, Centre centre, double seconds, double comShare = 1.0) {
  FootPlanner p;
  const std::array<Eigen::Vector3d, 2> rest{Eigen::Vector3d(0.1, 0.08, 0.0), Eigen::Vector3d(-0.1, 0.08, 0.0)};
  p.configure(config, FootShape{}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), rest, 1.0);
  Drive d;
  for (int i = 0; i <= int(seconds * 90.0); ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c = centre(t);
    const auto& feet = p.update(t, c, 0.0, centre(0.0) + comShare * (c - centre(0.0)));
    for (size_t f = 0; f < 2; ++f) {
      const Eigen::Vector3d spot(c.x() + rest[f].x(), 0.0, c.z());
      if (feet[f].planted) d.farthestPlanted = std::max(d.farthestPlanted, Eigen::Vector3d(feet[f].position.x() - spot.x(), 0.0, feet[f].position.z() - spot.z()).norm());
    }
  }
  d.steps = p.steps();
  return d;
}

TEST_CASE("foot planner: a body swaying on the spot does not walk, one walking from the first frame does", "[runtime]") {
  // A boxer's or a dancer's head: standing for a second, then 15 cm forward and back at 1 Hz
  // (0.94 m/s at the middle) for 6 s, the hips keeping the centre of mass over the feet (a third
  // of the sway). Counted as walking while over 0.15 m/s (the planner before its travel test,
  // travelSpeed 0) it stepped at every swing; now it stands, whatever the landing spots' lead.
  // (Started at full speed from the first frame, the sway reads as walking at once, like a clip
  // starting mid-walk, and where that first step lands decides the rest: feet put down off the
  // sway's middle step at every swing, docs/runtime.md "Known limits".) Walking at 1.2 m/s from
  // the first frame (a clip starting mid-walk, tracking regained) steps at once and keeps stepping.
  auto sway = [](double t) { return Eigen::Vector3d(0.0, 0.9, t < 1.0 ? 0.0 : 0.15 * std::sin(2.0 * M_PI * (t - 1.0))); };
  FootPlannerConfig swayBlind, halfStep;
  swayBlind.travelSpeed = 0.0;
  halfStep.quickAheadShare = 0.5;
  const Drive swaying = drive(FootPlannerConfig{}, sway, 7.0, 1.0 / 3.0), blind = drive(swayBlind, sway, 7.0, 1.0 / 3.0);
  CHECK(drive(halfStep, sway, 7.0, 1.0 / 3.0).steps <= 2);
  INFO("swaying: " << swaying.steps << " steps, " << blind.steps << " taken for walking");
  CHECK(blind.steps >= 12);
  CHECK(swaying.steps <= 2);
  const Drive walking = drive(FootPlannerConfig{}, [](double t) { return Eigen::Vector3d(0.0, 0.9, 1.2 * t); }, 3.0);
  INFO("walking: " << walking.steps << " steps, a planted foot up to " << walking.farthestPlanted << " m from its spot");
  CHECK(walking.steps >= 7);
  CHECK(walking.farthestPlanted < 0.45);
}

TEST_CASE("foot planner: a leap lifts a planted foot left beyond its leg's reach, even while the other swings", "[runtime]") {
  // Standing 1 s, then 1.2 m forward in 0.4 s (3 m/s) and standing again. One foot at a time a
  // planted foot was left up to 0.8 m behind (reachRadius 9: the planner before the reach test),
  // where the IK's top level dragged the head and hands after it.
  auto leap = [](double t) { return Eigen::Vector3d(0.0, 0.9, 1.2 * std::clamp((t - 1.0) / 0.4, 0.0, 1.0)); };
  FootPlannerConfig noReach;
  noReach.reachRadius = 9.0;
  const Drive guarded = drive(FootPlannerConfig{}, leap, 3.0), unguarded = drive(noReach, leap, 3.0);
  INFO("a planted foot up to " << guarded.farthestPlanted << " m from its spot (" << unguarded.farthestPlanted
                               << " m without the reach test)");
  CHECK(unguarded.farthestPlanted > 0.6);
  CHECK(guarded.farthestPlanted <= FootPlannerConfig{}.reachRadius + 0.05);
}

TEST_CASE("foot planner: a swinging foot leaves and meets the ground at walking speed, not with a jolt", "[runtime]") {
  // Walking at 1.2 m/s, 90 Hz: over every swing, the foot's vertical speed in its first and last
  // frame, and how high it rises. A sine bump (the planner before) lifted the foot from rest to
  // 0.73 m/s in one frame and stopped it as suddenly: 0.07 m high over a 0.3 s swing, pi h / T.
  // The heels stay down here: a rising heel lifts the ankle before lift-off (tested below).
  FootPlannerConfig config;
  config.maxHeelRise = 0.0;
  FootPlanner p;
  p.configure(config, FootShape{}, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(),
              {Eigen::Vector3d(0.1, 0.08, 0.0), Eigen::Vector3d(-0.1, 0.08, 0.0)}, 1.0);
  std::array<double, 2> lastHeight{0.0, 0.0};
  std::array<bool, 2> planted{true, true};
  double fastestEdge = 0.0, highest = 0.0;
  int swingFrames = 0;
  for (int i = 0; i <= 3 * 90; ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c(0.0, 0.9, 1.2 * t);
    const auto& feet = p.update(t, c, 0.0, c);
    for (size_t f = 0; f < 2; ++f) {
      const double height = feet[f].position.y() - 0.08;
      const double speed = std::abs(height - lastHeight[f]) * 90.0;
      // A frame that lifts a planted foot, or plants a swinging one.
      if (planted[f] != feet[f].planted) fastestEdge = std::max(fastestEdge, speed);
      if (!feet[f].planted) ++swingFrames;
      highest = std::max(highest, height);
      lastHeight[f] = height;
      planted[f] = feet[f].planted;
    }
  }
  INFO("vertical speed at lift-off or landing up to " << fastestEdge << " m/s, " << swingFrames
                                                      << " swinging frames, " << highest << " m high");
  REQUIRE(p.steps() >= 7);
  CHECK(fastestEdge < 0.1);
  CHECK(highest == Approx(config.liftHeight).margin(0.005));
}

TEST_CASE("foot planner: a planted foot behind the body rises on its toes, the ball of the foot stays put", "[runtime]") {
  // Walking at 1.2 m/s, 90 Hz. A planted foot's ankle turns about the ball of the foot as the body
  // passes over it; a swinging foot lets the heel down by the landing, without a jump at
  // lift-off.
  FootPlanner p = planner();
  std::array<Eigen::Vector3d, 2> ball{}, lastAnkle{};
  std::array<bool, 2> planted{true, true};
  std::array<bool, 2> lifting{false, false};
  double worstSlide = 0.0, highestRoll = 0.0, rollAtLanding = 0.0, liftJump = 0.0;
  for (int i = 0; i <= 3 * 90; ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c(0.0, 0.9, 1.2 * t);
    const auto& feet = p.update(t, c, 0.0, c);
    for (size_t f = 0; f < 2; ++f) {
      if (feet[f].planted && !planted[f]) rollAtLanding = std::max(rollAtLanding, feet[f].roll);
      if (feet[f].planted && (i == 0 || !planted[f])) ball[f] = p.ballPoint(int(f));
      if (feet[f].planted) {
        // The ball of the foot, from the returned ankle and heel rise (the feet face +Z, their
        // left +X; the ankle 8 cm up), stays where the foot was put down.
        const Eigen::Vector3d flatBall(0.0, -0.08, FootShape{}.ball);
        const Eigen::Vector3d fromAnkle = Eigen::AngleAxisd(feet[f].roll, Eigen::Vector3d::UnitX()) * flatBall;
        worstSlide = std::max(worstSlide, (feet[f].position + fromAnkle - ball[f]).norm());
      }
      // The ankle's move over the frame a foot lifts and the one after: the heel's rise carried on.
      if (lifting[f] || (planted[f] && !feet[f].planted)) liftJump = std::max(liftJump, (feet[f].position - lastAnkle[f]).norm());
      lifting[f] = planted[f] && !feet[f].planted;
      highestRoll = std::max(highestRoll, feet[f].roll);
      lastAnkle[f] = feet[f].position;
      planted[f] = feet[f].planted;
    }
  }
  INFO("ball of the foot moved up to " << worstSlide << " m while planted; heel rise up to " << highestRoll << " rad, "
                                       << rollAtLanding << " at a landing; the ankle moved up to " << liftJump
                                       << " m in a lift-off frame");
  CHECK(worstSlide < 1e-9);
  CHECK(highestRoll > 0.2);
  CHECK(highestRoll <= FootPlannerConfig{}.maxHeelRise + 1e-12);
  CHECK(rollAtLanding == 0.0);
  CHECK(liftJump < 0.01);
}

namespace {

// A walk at `speed` m/s along +Z for 6 s, 90 Hz, steps every 0.6 s. The head dips 2 cm, lowest
// at t = 0.3 + 0.6 k (a foot landing; `dips` false: carried level), and sways sideways towards
// the landing foot: left at k even, right at k odd, or the other way round (swaySign -1).
// Returns whether the clock is locked at the end; `landings` gets (time, foot) of each landing.
constexpr double kWalkStep = 0.6, kFirstDip = 0.3;
bool walkWithDips(double speed, bool dips, double swaySign, std::vector<std::pair<double, int>>& landings) {
  auto centre = [&](double t) {
    const double phase = 2.0 * std::numbers::pi * (t - kFirstDip) / kWalkStep;
    const double bob = dips ? -0.01 * std::cos(phase) : 0.0;
    const double sway = 0.15 * kWalkStep / std::numbers::pi * std::sin(0.5 * phase);  // its velocity 0.15 cos(phase / 2)
    return Eigen::Vector3d(swaySign * sway, 0.9 + bob, speed * t);
  };
  FootPlanner p = planner();
  std::array<bool, 2> planted{true, true};
  for (int i = 0; i <= 6 * 90; ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c = centre(t);
    const auto& feet = p.update(t, c, 0.0, c);
    for (size_t f = 0; f < 2; ++f) {
      if (feet[f].planted && !planted[f]) landings.emplace_back(t, int(f));
      planted[f] = feet[f].planted;
    }
  }
  return p.gait().locked(6.0);
}

// Of the landings after `from`: how many, how far the worst is off its dip (seconds), and how
// many by the other foot than the dip's.
struct OnDips {
  int checked = 0, wrongFoot = 0;
  double worstOffset = 0.0;
};
OnDips landingsOnDips(const std::vector<std::pair<double, int>>& landings, double from, double swaySign) {
  OnDips r;
  for (const auto& [t, foot] : landings) {
    if (t < from) continue;
    const double k = std::round((t - kFirstDip) / kWalkStep);
    r.worstOffset = std::max(r.worstOffset, std::abs(t - (kFirstDip + k * kWalkStep)));
    if (foot != ((static_cast<long long>(k) % 2 == 0) == (swaySign > 0) ? 0 : 1)) ++r.wrongFoot;
    ++r.checked;
  }
  return r;
}

std::string describe(const std::vector<std::pair<double, int>>& landings) {
  std::ostringstream seq;
  for (const auto& [t, foot] : landings) seq << t << (foot == 0 ? "L " : "R ");
  return seq.str();
}

}  // namespace

TEST_CASE("foot planner: walking with the head dipping once a step, the feet land on the dips, the foot the sway names",
          "[runtime]") {
  const double swaySign = GENERATE(1.0, -1.0);
  std::vector<std::pair<double, int>> onDips, level;
  REQUIRE(walkWithDips(0.8, true, swaySign, onDips));
  CHECK_FALSE(walkWithDips(0.8, false, swaySign, level));
  // The clock locks on the second dip (0.9 s, seen about 0.13 s later). Once the feet have come
  // into step (a foot named that has just stepped makes the other take a quick step first: with
  // the sway reversed, a right landing between the dips), every landing is on a dip, by the foot
  // that dip belongs to.
  INFO("landings " << describe(onDips));
  const OnDips r = landingsOnDips(onDips, 2.4, swaySign);
  INFO("sway sign " << swaySign << ": " << r.checked << " landings after 2.4 s, up to " << r.worstOffset << " s off a dip, "
                    << r.wrongFoot << " by the wrong foot; " << level.size() << " landings with the head level against "
                    << onDips.size());
  CHECK(r.checked >= 6);
  CHECK(r.worstOffset <= 1.5 / 90.0);
  CHECK(r.wrongFoot == 0);
  // A level head keeps the quick steps: more of them.
  CHECK(level.size() > onDips.size());
}

TEST_CASE("foot planner: a walk's stride a little past strideReach keeps to the dips, a run's past twice reachRadius does not",
          "[runtime]") {
  // 0.6 s steps at 1.3 m/s: 0.78 m a step, over the 0.72 m the legs let a planted foot travel
  // under the body (2 x strideReach x reachRadius) but within twice reachRadius (0.9 m). Such a
  // walk (cmu_12_01_walk's strides are 0.69-0.81 m) used to fall back to the quick steps whenever
  // its stride passed 0.72 m. At 1.6 m/s (0.96 m a step) the stride does not fit the legs.
  std::vector<std::pair<double, int>> walk, run;
  REQUIRE(walkWithDips(1.3, true, 1.0, walk));
  walkWithDips(1.6, true, 1.0, run);
  INFO("1.3 m/s: " << describe(walk));
  INFO("1.6 m/s: " << describe(run));
  // A planted foot that reaches its leg's limit lifts before its beat and swings a step long, so
  // such a stride may land a few frames early.
  const OnDips r = landingsOnDips(walk, 2.4, 1.0);
  CHECK(r.checked >= 6);
  CHECK(r.worstOffset <= 0.05);
  CHECK(r.wrongFoot == 0);
  const OnDips quick = landingsOnDips(run, 2.4, 1.0);
  CHECK(quick.worstOffset > 0.1);
  CHECK(run.size() > walk.size());
}

TEST_CASE("foot planner: re-planting the feet (a re-seed) keeps the count of steps taken", "[runtime]") {
  // stats.json body.steps counts the run's steps: a collapse guard's re-seed re-plants the feet
  // (reset) and once zeroed the count, so a run with a re-seed reported only the steps after it.
  FootPlanner p = planner();
  for (int i = 0; i <= 90; ++i) {
    const double t = i / 90.0;
    const Eigen::Vector3d c(0.0, 0.9, 1.0 * t);
    p.update(t, c, 0.0, c);
  }
  const int before = p.steps();
  REQUIRE(before >= 2);
  p.reset(Eigen::Vector3d(0.0, 0.9, 1.0), 0.0, 1.0);
  CHECK(p.steps() == before);
}

TEST_CASE("faceHeadingOf: a head looking down, past the vertical or bent over and turned to a leg keeps its heading",
          "[runtime]") {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY(), forward = Eigen::Vector3d::UnitZ(), left = up.cross(forward);
  const double deg = std::numbers::pi / 180.0;
  const auto turn = [&](double yaw, double pitchDown, double lookAside) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(yaw * deg, up) * Eigen::AngleAxisd(pitchDown * deg, left) *
                              Eigen::AngleAxisd(lookAside * deg, up));
  };
  for (double yaw : {-150.0, -40.0, 0.0, 40.0, 170.0}) {
    INFO("yaw " << yaw);
    // Level, looking down, straight down and past the vertical (a head bent far over): the same.
    for (double pitch : {0.0, 55.0, 89.9, 90.0, 120.0, -60.0})
      CHECK(std::remainder(faceHeadingOf(turn(yaw, pitch, 0.0), up, forward) - yaw * deg, 2 * std::numbers::pi) ==
            Approx(0.0).margin(1e-9));
  }
  // Bent over 55 degrees and turned 35 degrees about its own up to look at a leg: the forward's
  // ground projection alone reads 51 degrees; with the up vector blended in, 29.
  CHECK(faceHeadingOf(turn(0.0, 55.0, 35.0), up, forward) / deg == Approx(29.4).margin(0.2));
  CHECK(headingOf(turn(0.0, 55.0, 35.0), up, forward) / deg == Approx(50.7).margin(0.2));
  CHECK(std::abs(std::remainder(headingOf(turn(40.0, 120.0, 0.0), up, forward) / deg - 40.0, 360.0)) == Approx(180.0));
}

TEST_CASE("BodyHeading: the head's heading upright, a neck's turn of slack when bent over", "[runtime]") {
  const double deg = std::numbers::pi / 180.0;
  BodyHeading h({.smoothed = false});
  double t = 0.0;
  auto update = [&](double yaw, double slack) { return h.update(yaw, slack, t += 1.0 / 90.0); };
  CHECK(update(10 * deg, 45 * deg) == Approx(10 * deg));  // the first call takes the head's
  CHECK(update(40 * deg, 45 * deg) == Approx(10 * deg));  // within the neck's turn: the body stays
  CHECK(update(70 * deg, 45 * deg) == Approx(25 * deg));  // beyond it: dragged along
  CHECK(update(-20 * deg, 45 * deg) == Approx(25 * deg));
  CHECK(update(0.0, 0.0) == Approx(0.0).margin(1e-12));   // upright: the head's own
  // Across +-180 degrees the shorter way round.
  CHECK(update(170 * deg, 0.0) == Approx(170 * deg));
  CHECK(std::remainder(update(-160 * deg, 45 * deg) - 170 * deg, 2 * std::numbers::pi) == Approx(0.0).margin(1e-12));
  CHECK(std::remainder(update(-100 * deg, 45 * deg) - (-145 * deg), 2 * std::numbers::pi) == Approx(0.0).margin(1e-12));
  h.reset();
  CHECK(update(-100 * deg, 45 * deg) == Approx(-100 * deg));
}

TEST_CASE("BodyHeading: the body trails a fast turn of the head by a few degrees and ends where the head does", "[runtime]") {
  // Half a turn in 0.6 s (smoothstep, up to 7.9 rad/s) from 170 degrees, across +-180, at 90 Hz,
  // then still: the head's yaw as a clean source gives it, which the tracker filter no longer
  // smooths. The body follows it through the tuned orientation cutoffs, as it did when the head
  // itself was filtered with them: taken as it came, the body turned with the head to the frame,
  // and one foot at a time could not step round behind it (the legs crossed; "three-point turning
  // on the spot", tests/runtime/avatar_body_tests.cpp).
  const double deg = std::numbers::pi / 180.0;
  auto headYaw = [&](double t) {
    const double x = std::clamp(t / 0.6, 0.0, 1.0);
    return std::remainder(170 * deg + std::numbers::pi * x * x * (3.0 - 2.0 * x), 2.0 * std::numbers::pi);
  };
  BodyHeading eased, plain({.smoothed = false});
  double easedTrail = 0.0, plainTrail = 0.0, settled = 0.0;
  for (int i = -10; i <= 135; ++i) {
    const double t = i / 90.0;
    const double ye = eased.update(headYaw(t), 0.0, t), yp = plain.update(headYaw(t), 0.0, t);
    REQUIRE(std::isfinite(ye));
    easedTrail = std::max(easedTrail, std::abs(std::remainder(headYaw(t) - ye, 2 * std::numbers::pi)));
    plainTrail = std::max(plainTrail, std::abs(std::remainder(headYaw(t) - yp, 2 * std::numbers::pi)));
    if (t >= 1.4) settled = std::max(settled, std::abs(std::remainder(headYaw(t) - ye, 2 * std::numbers::pi)));
  }
  INFO("trailing the head by up to " << easedTrail / deg << " degrees (" << plainTrail / deg << " taken as it came), "
                                     << settled / deg << " once it has stopped");
  CHECK(plainTrail < 1e-9);
  CHECK(easedTrail > 4 * deg);
  CHECK(easedTrail < 15 * deg);
  CHECK(settled < 0.5 * deg);
}

TEST_CASE("BodyHeading: a walking body faces where it goes, the head looking about, not stepping sideways or back",
          "[runtime]") {
  const double deg = std::numbers::pi / 180.0;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY(), forward = Eigen::Vector3d::UnitZ();
  const BodyHeading heading;
  // Travel along +Z (yaw 0) at 1.2 m/s; the head's heading 15 degrees to the right of it, as the
  // CMU walk's performer looked.
  const Eigen::Vector3d ahead(0.0, 0.0, 1.2);
  CHECK(heading.facingTravel(-15.0 * deg, ahead, 1.0, up, forward, 1.0) == Approx(0.0).margin(1e-12));
  // Half walking (the planner easing in): half way.
  CHECK(heading.facingTravel(-15.0 * deg, ahead, 0.5, up, forward, 1.0) == Approx(-7.5 * deg));
  // Standing, or drifting slower than 0.3 m/s: the head's heading.
  CHECK(heading.facingTravel(-15.0 * deg, ahead, 0.0, up, forward, 1.0) == Approx(-15.0 * deg));
  CHECK(heading.facingTravel(-15.0 * deg, Eigen::Vector3d(0.0, 0.0, 0.25), 1.0, up, forward, 1.0) == Approx(-15.0 * deg));
  // A child-sized avatar (scale 0.6) walking 0.5 m/s walks as fast as an adult at 0.83 m/s.
  CHECK(heading.facingTravel(-15.0 * deg, Eigen::Vector3d(0.0, 0.0, 0.5), 1.0, up, forward, 0.6) == Approx(0.0).margin(1e-12));
  // Stepping sideways (travel 90 degrees off) or backwards: the head's heading.
  CHECK(heading.facingTravel(0.0, Eigen::Vector3d(1.2, 0.0, 0.0), 1.0, up, forward, 1.0) == 0.0);
  CHECK(heading.facingTravel(0.0, Eigen::Vector3d(0.0, 0.0, -1.2), 1.0, up, forward, 1.0) == 0.0);
  // Between 25 and 45 degrees off, a share of the way; across the wrap at +-180 the shorter way.
  const double partial = heading.facingTravel(35.0 * deg, ahead, 1.0, up, forward, 1.0);
  CHECK(partial > 0.0);
  CHECK(partial < 35.0 * deg);
  const Eigen::Vector3d back(0.0, 0.0, -1.2);  // yaw 180
  CHECK(std::abs(std::remainder(heading.facingTravel(170.0 * deg, back, 1.0, up, forward, 1.0) - M_PI, 2.0 * M_PI)) < 1e-12);
}
