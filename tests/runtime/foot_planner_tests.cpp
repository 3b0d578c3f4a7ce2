// The three-point foot planner on its own (runtime/foot_planner.h): where feet land.
#include <catch2/catch.hpp>
#include <cmath>

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
