// TrackedAvatarBody: the three-point body solved from tracking-space trackers and placed back in
// the tracking space (what `embody xr` renders): its solved wrists land on the tracked ones in
// tracking metres, and the avatar -> tracking map inverts the solver's.
#include <catch2/catch.hpp>
#include <glm/glm.hpp>

#include "runtime/tracked_avatar_body.h"
#include "runtime/runtime_test_support.h"

using namespace embody;

namespace {

using embody::test::defaultAvatar;

tracking::PoseSample threePoint(float headY, double t) {
  tracking::PoseSample s;
  s.time = t;
  // Forearms level and forward, palms facing each other (tracker.h's grip axes).
  const glm::quat left = tracking::gripOrientation(tracking::Side::Left, {0, 0, -1}, {1, 0, 0});
  const glm::quat right = tracking::gripOrientation(tracking::Side::Right, {0, 0, -1}, {-1, 0, 0});
  s[tracking::TrackerId::Head] = {{0.0f, headY, 0.0f}, glm::angleAxis(glm::radians(-20.0f), glm::vec3(1, 0, 0)), true};
  s[tracking::TrackerId::LeftHand] = {{-0.17f, headY - 0.32f, -0.33f}, left, true};
  s[tracking::TrackerId::RightHand] = {{0.17f, headY - 0.32f, -0.33f}, right, true};
  return s;
}

glm::vec3 solvedInTracking(const runtime::TrackedAvatarBody& body, tracking::TrackerId id) {
  return body.toTracking(body.solver().jointPosition(body.solver().trackerJoint(id)));
}

runtime::TrackedBodyOptions options() {
  runtime::TrackedBodyOptions o;
  o.body.trackers = tracking::TrackerMask::threePoint();
  o.stage.budgetSeconds = 0.2;  // generous: convergence, not timing, is under test
  o.stage.filter = false;
  return o;
}

}  // namespace

TEST_CASE("TrackedAvatarBody puts the avatar's wrists on the tracked wrists, in tracking metres", "[runtime]") {
  // (Seated mode has its own tests: seated_tests.cpp.)
  auto body = runtime::TrackedAvatarBody::create(defaultAvatar(), options());
  REQUIRE(body.ok());
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(defaultAvatar().skeleton);
  tracking::PoseSample s;
  for (int i = 0; i < 90; ++i) {
    s = threePoint(1.62f, i / 90.0);
    REQUIRE((*body)->solve(s, pose));
  }
  for (auto id : {tracking::TrackerId::LeftHand, tracking::TrackerId::RightHand}) {
    const glm::vec3 solved = solvedInTracking(**body, id);
    INFO("tracker " << int(id) << " solved " << solved.x << " " << solved.y << " " << solved.z);
    CHECK(glm::distance(solved, s[id].position) < 0.01f);
  }
  // The map back to tracking space inverts the solver's map into the avatar.
  const glm::vec3 p(0.3f, 1.1f, -0.4f);
  const Eigen::Vector3d a = (*body)->solver().toAvatar(p);
  const glm::vec3 back = glm::vec3((*body)->avatarToTracking() * glm::vec4(float(a.x()), float(a.y()), float(a.z()), 1.0f));
  CHECK(glm::distance(back, p) < 1e-4f);
  // The skeleton's roots carry that map: the posed avatar is scaled to the user (eye 1.62 m).
  for (size_t j = 0; j < pose.local.size(); ++j)
    if (defaultAvatar().skeleton.joints[j].parent < 0) {
      CHECK(std::isfinite(pose.local[j].translation.x));
      CHECK(pose.local[j].scale.x == Approx(1.0 / (*body)->solver().scale()).epsilon(1e-4));
    }
}

TEST_CASE("TrackedAvatarBody waits for a valid head and never produces NaN from a broken sample", "[runtime]") {
  auto body = runtime::TrackedAvatarBody::create(defaultAvatar(), options());
  REQUIRE(body.ok());
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(defaultAvatar().skeleton);
  tracking::PoseSample none;  // nothing valid: no calibration yet
  CHECK_FALSE((*body)->solve(none, pose));
  REQUIRE((*body)->solve(threePoint(1.62f, 0.0), pose));
  tracking::PoseSample broken = threePoint(1.62f, 0.02);
  broken[tracking::TrackerId::LeftHand].position.x = std::nanf("");
  REQUIRE((*body)->solve(broken, pose));
  for (const auto& t : pose.local) {
    CHECK(std::isfinite(t.translation.x + t.translation.y + t.translation.z));
    CHECK(std::isfinite(t.rotation.w + t.rotation.x + t.rotation.y + t.rotation.z));
  }
}
