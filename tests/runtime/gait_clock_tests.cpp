// The walk's rhythm from the head's height and sway (runtime/gait_clock.h).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "runtime/gait_clock.h"

using namespace embody::runtime;

namespace {

// 90 Hz for `seconds`: the head at `height(t)`, its sideways velocity `sway(t)`.
template <class Height, class Sway>
GaitClock drive(Height height, Sway sway, double seconds) {
  GaitClock clock;
  clock.configure({}, 1.0);
  for (int i = 0; i <= int(seconds * 90.0); ++i) {
    const double t = i / 90.0;
    clock.update(t, height(t), sway(t));
  }
  return clock;
}

constexpr double kFrame = 1.0 / 90.0;

}  // namespace

TEST_CASE("GaitClock: a head dipping 2 cm every 0.6 s, swaying to the landing foot: period, next dip and its foot", "[runtime]") {
  // Lowest at 0.3 + 0.6 k; the sway towards the left foot (positive) at k even.
  auto height = [](double t) { return 1.6 - 0.01 * std::cos(2.0 * M_PI * (t - 0.3) / 0.6); };
  auto sway = [](double t) { return 0.15 * std::cos(M_PI * (t - 0.3) / 0.6); };
  const GaitClock clock = drive(height, sway, 4.0);
  REQUIRE(clock.locked(4.0));
  CHECK(clock.period() == Approx(0.6).margin(kFrame));
  // Dips at 3.9 (k = 6, left) and 4.5 (k = 7, right).
  CHECK(clock.nextDip(4.0) == Approx(4.5).margin(1.5 * kFrame));
  CHECK(clock.nextFoot(4.0) == 1);
  CHECK(clock.nextDip(4.6) == Approx(5.1).margin(2.0 * kFrame));
  CHECK(clock.nextFoot(4.6) == 0);
  // Stale: nothing seen for more than 1.5 steps.
  CHECK_FALSE(clock.locked(5.0));
}

TEST_CASE("GaitClock: no lock on a level head, irregular dips or a ripple below the dip size, no foot without a sway",
          "[runtime]") {
  auto noSway = [](double) { return 0.0; };
  auto sway = [](double t) { return 0.15 * std::cos(M_PI * (t - 0.3) / 0.6); };
  CHECK_FALSE(drive([](double) { return 1.6; }, sway, 4.0).locked(4.0));
  // A 5 mm ripple (breathing, a shuffle): under the 8 mm dip.
  const GaitClock ripple = drive([](double t) { return 1.6 - 0.0025 * std::cos(2.0 * M_PI * t / 0.6); }, sway, 4.0);
  CHECK(ripple.dips() == 0);
  CHECK_FALSE(ripple.locked(4.0));
  // Dips 0.4 s and 0.8 s apart by turns (a boxer's bounce, a dance): never two periods alike.
  // Lowest at the segments' ends: 0, 0.4, 1.2, 1.6, ...
  auto irregular = [](double t) {
    const double cycle = std::fmod(t, 1.2);
    return cycle < 0.4 ? 1.59 + 0.01 * std::sin(M_PI * cycle / 0.4) : 1.59 + 0.01 * std::sin(M_PI * (cycle - 0.4) / 0.8);
  };
  const GaitClock bounce = drive(irregular, sway, 6.0);
  CHECK(bounce.dips() >= 6);
  CHECK_FALSE(bounce.locked(6.0));
  // Regular dips without a sway: the rhythm, but no foot named.
  const GaitClock straight = drive([](double t) { return 1.6 - 0.01 * std::cos(2.0 * M_PI * (t - 0.3) / 0.6); }, noSway, 4.0);
  CHECK(straight.locked(4.0));
  CHECK(straight.nextFoot(4.0) == -1);
}

TEST_CASE("GaitClock: non-finite samples are skipped", "[runtime]") {
  GaitClock clock;
  clock.configure({}, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i <= 4 * 90; ++i) {
    const double t = i / 90.0;
    const bool bad = i % 7 == 3;
    clock.update(t, bad ? nan : 1.6 - 0.01 * std::cos(2.0 * M_PI * (t - 0.3) / 0.6),
                 bad ? nan : 0.15 * std::cos(M_PI * (t - 0.3) / 0.6));
  }
  REQUIRE(clock.locked(4.0));
  CHECK(std::isfinite(clock.nextDip(4.0)));
  CHECK(clock.period() == Approx(0.6).margin(2.0 * kFrame));
}

TEST_CASE("GaitClock: a dip whose lowest point is the first frame below the fall names its foot", "[runtime]") {
  // The head drops 2 cm in one frame every 0.6 s and climbs back over the next 0.3 s; the sway
  // points left at the dips at odd multiples of 0.6 s, right at even ones, and is zero elsewhere.
  // The lowest point is the very frame the fall is seen, so the sway must be read there too.
  auto height = [](double t) {
    const double since = std::fmod(t, 0.6);
    return t < 0.6 ? 1.6 : 1.58 + 0.02 * std::min(since / 0.3, 1.0);
  };
  auto sway = [](double t) {
    const double since = std::fmod(t, 0.6);
    if (t < 0.6 || since > 0.05) return 0.0;
    return static_cast<long long>(std::floor(t / 0.6)) % 2 != 0 ? 0.15 : -0.15;
  };
  const GaitClock clock = drive(height, sway, 4.0);
  REQUIRE(clock.locked(4.0));
  // The last dip at 3.6 (6 x 0.6: right), the next at 4.2 (7 x 0.6: left). Read where the sway
  // was before the fall (zero), no dip named a foot (-1).
  CHECK(clock.nextDip(4.0) == Approx(4.2).margin(1.5 * kFrame));
  CHECK(clock.nextFoot(4.0) == 0);
}

TEST_CASE("GaitClock: locks on the first two dips a step apart, unlocks on a step that disagrees until the next agrees",
          "[runtime]") {
  // Dips at 0.3 and 0.9 (each seen as the head has risen 8 mm, 0.1 s later), then one 0.9 s
  // late (1.8: a step that does not agree with 0.6), then 0.6 s apart again (2.4, 3.0).
  const std::vector<double> lows{0.3, 0.9, 1.8, 2.4, 3.0};
  auto height = [&](double t) {
    double nearest = 1e9;
    for (double low : lows) nearest = std::min(nearest, std::abs(t - low));
    return 1.6 - 0.02 * std::max(0.0, 1.0 - nearest / 0.25);  // a 2 cm dip 0.5 s wide at each
  };
  auto sway = [](double) { return 0.0; };
  CHECK_FALSE(drive(height, sway, 0.8).locked(0.8));       // one dip: no period yet
  const GaitClock second = drive(height, sway, 1.2);       // two: the first period, locked
  REQUIRE(second.locked(1.2));
  CHECK(second.period() == Approx(0.6).margin(kFrame));
  CHECK(second.nextDip(1.2) == Approx(1.5).margin(1.5 * kFrame));
  CHECK_FALSE(drive(height, sway, 2.1).locked(2.1));       // 0.9 s against 0.6: unlocked
  CHECK_FALSE(drive(height, sway, 2.7).locked(2.7));       // 0.6 s against 0.9: still unlocked
  const GaitClock agreed = drive(height, sway, 3.3);       // 0.6 s against 0.6: locked again
  REQUIRE(agreed.locked(3.3));
  CHECK(agreed.nextDip(3.3) == Approx(3.6).margin(1.5 * kFrame));
}
