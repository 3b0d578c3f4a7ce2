// Avatar placement (calibration from the HMD height, recentering, seated mode) and the
// per-profile grip-to-wrist offsets: pure math, no runtime.
#include <catch2/catch.hpp>
#include <cmath>

#include "xr/avatar_placement.h"
#include "xr/xr_input.h"

using namespace embody::xr;

namespace {
Pose headAt(glm::vec3 p, float headingDeg, float pitchDeg = 0.0f) {
  return {p, glm::angleAxis(glm::radians(headingDeg), glm::vec3(0, 1, 0)) *
                 glm::angleAxis(glm::radians(pitchDeg), glm::vec3(1, 0, 0))};
}
glm::vec3 transformPoint(const glm::mat4& m, glm::vec3 p) {
  return glm::vec3(m * glm::vec4(p, 1.0f));
}
}  // namespace

TEST_CASE("calibration scales the avatar so its eyes are at the HMD, feet on the floor", "[xr]") {
  const glm::vec3 avatarEye{0.0f, 1.84f, 0.1f};  // glTF avatar facing +Z
  AvatarPlacement p(avatarEye, {0, 0, 1}, {});
  CHECK_FALSE(p.calibrated());
  CHECK_FALSE(p.calibrate(headAt({0, 0.5f, 0}, 0)));  // too low to be standing
  CHECK_FALSE(p.calibrate(headAt({0, NAN, 0}, 0)));   // broken tracking never calibrates
  const Pose head = headAt({0.3f, 1.6f, -0.2f}, 40.0f, -20.0f);
  REQUIRE(p.calibrate(head));
  CHECK(p.scale() == Approx(1.6f / 1.84f));
  const glm::mat4 root = p.root(head);
  CHECK(glm::distance(transformPoint(root, avatarEye), head.position) < 1e-4f);
  CHECK(transformPoint(root, glm::vec3(0.0f)).y == Approx(0.0f).margin(1e-6));  // feet on the floor
  // The avatar's front (+Z) now points where the head looks (heading only, pitch ignored).
  const glm::vec3 front = glm::normalize(glm::mat3(root) * glm::vec3(0, 0, 1));
  CHECK(headingOf({{}, glm::quatLookAtRH(front, glm::vec3(0, 1, 0))}) ==
        Approx(glm::radians(40.0f)).margin(1e-4));
}

TEST_CASE("a fixed eye height skips calibration, and the seated rest-pose fallback keeps the eyes at the HMD",
          "[xr]") {
  const glm::vec3 avatarEye{0.0f, 1.5f, 0.0f};
  AvatarPlacement fixed(avatarEye, {0, 0, 1}, {false, 1.65f});
  CHECK(fixed.calibrated());
  CHECK(fixed.scale() == Approx(1.1f));
  CHECK_FALSE(fixed.calibrate(headAt({0, 1.8f, 0}, 0)));
  CHECK(fixed.scale() == Approx(1.1f));

  AvatarPlacement seated(avatarEye, {0, 0, 1}, {true, 0.0f});
  const Pose head = headAt({0.0f, 1.15f, 0.0f}, -30.0f);
  CHECK_FALSE(seated.calibrate(head));  // a seated head says nothing about standing height
  const glm::mat4 root = seated.root(head);
  // Only the rest pose is placed here (embody xr --body rest, or before the first solve): it cannot
  // sit, so its eyes go to the HMD and its feet sink below the floor. The solved seated body keeps
  // its feet on the floor (tests/runtime/seated_tests.cpp, embody xr --seated in embody_xr_tests).
  CHECK(glm::distance(transformPoint(root, avatarEye), head.position) < 1e-4f);
  CHECK(transformPoint(root, glm::vec3(0.0f)).y == Approx(1.15f - 1.5f).margin(1e-4));
}

TEST_CASE("recentering puts the head over the origin facing -Z", "[xr]") {
  AvatarPlacement p({0, 1.7f, 0}, {0, 0, 1}, {});
  const Pose head = headAt({1.0f, 1.7f, 2.0f}, 90.0f, 10.0f);
  p.recenter(head);
  const Pose w = p.toWorld(head);
  CHECK(glm::length(glm::vec2(w.position.x, w.position.z)) < 1e-5f);
  CHECK(w.position.y == Approx(1.7f));
  CHECK(headingOf(w) == Approx(0.0f).margin(1e-5));
  // A hand half a metre in front of the head stays half a metre in front after recentering.
  const Pose hand = head * Pose{{0.0f, 0.0f, -0.5f}, {1, 0, 0, 0}};
  CHECK(glm::distance(p.toWorld(hand).position, (w * Pose{{0.0f, 0.0f, -0.5f}, {1, 0, 0, 0}}).position) <
        1e-5f);
}

TEST_CASE("grip-to-wrist offsets: the wrist sits behind the grip, mirrored between hands", "[xr]") {
  for (const char* profile :
       {"/interaction_profiles/khr/simple_controller", "/interaction_profiles/oculus/touch_controller",
        "/interaction_profiles/valve/index_controller", "/interaction_profiles/htc/vive_controller",
        "/interaction_profiles/microsoft/motion_controller", ""}) {
    INFO(profile);
    const Pose r = gripToWrist(profile, false), l = gripToWrist(profile, true);
    CHECK(r.position.z > 0.05f);  // +Z: back towards the user's wrist
    CHECK(r.position.z < 0.12f);
    CHECK(l.position.x == Approx(-r.position.x));
    CHECK(l.position.y == Approx(r.position.y));
    const glm::vec3 rf = r.orientation * glm::vec3(0, 0, -1), lf = l.orientation * glm::vec3(0, 0, -1);
    CHECK(lf.x == Approx(-rf.x).margin(1e-6));
    CHECK(lf.y == Approx(rf.y).margin(1e-6));
  }
  CHECK(gripToWrist("/interaction_profiles/htc/vive_controller", false).position.z >
        gripToWrist("/interaction_profiles/valve/index_controller", false).position.z);
}
