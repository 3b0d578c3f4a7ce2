// The recenter of the tracking space (tracking/space_transform.h): the head ends over the origin
// facing -Z with its height kept, the whole sample moves rigidly, and a lost head moves nothing.
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/quaternion.hpp>
#include <limits>

#include "tracking/space_transform.h"
#include "tracking/synthetic_source.h"

using namespace embody;
using namespace embody::tracking;

namespace {

float yawDegrees(const glm::quat& q) {
  const glm::quat h = headingOf(q);
  return glm::degrees(2.0f * std::atan2(h.y, h.w));
}

}  // namespace

TEST_CASE("recenterOn: the head over the origin facing -Z, its height and the body's shape kept") {
  auto src = SyntheticSource::create("reach").value();
  PoseSample sample = src->sample(1.3);
  // Move the play space: turned 120 degrees and 3 m away, as another room setup would give.
  const SpaceTransform elsewhere{glm::angleAxis(glm::radians(120.0f), glm::vec3(0, 1, 0)), glm::vec3(3.0f, 0.0f, -2.0f)};
  elsewhere.apply(sample);
  const TrackerPose head = sample[TrackerId::Head];
  const float headingBefore = yawDegrees(head.orientation);
  const glm::vec3 leftBefore = sample[TrackerId::LeftHand].position;

  const SpaceTransform recenter = recenterOn(head);
  PoseSample moved = sample;
  recenter.apply(moved);
  const TrackerPose& h = moved[TrackerId::Head];
  CHECK(std::hypot(h.position.x, h.position.z) < 1e-5f);
  CHECK(h.position.y == Approx(head.position.y).margin(1e-6));
  CHECK(yawDegrees(h.orientation) == Approx(0.0f).margin(1e-3));
  CHECK(std::abs(headingBefore) > 10.0f);  // it did have to turn
  // Rigid: distances and the head's view of the hand are unchanged; nothing tilts.
  CHECK(glm::distance(h.position, moved[TrackerId::LeftHand].position) ==
        Approx(glm::distance(head.position, leftBefore)).margin(1e-5));
  const glm::vec3 inHeadBefore = glm::inverse(head.orientation) * (leftBefore - head.position);
  const glm::vec3 inHeadAfter = glm::inverse(h.orientation) * (moved[TrackerId::LeftHand].position - h.position);
  CHECK(glm::distance(inHeadBefore, inHeadAfter) < 1e-5f);
  CHECK(moved[TrackerId::LeftHand].position.y == Approx(leftBefore.y).margin(1e-5));
  CHECK(moved[TrackerId::LeftHand].valid == sample[TrackerId::LeftHand].valid);
}

TEST_CASE("recenterOn: an invalid or broken head leaves the space where it is") {
  TrackerPose head{{1.0f, 1.7f, 2.0f}, glm::angleAxis(1.0f, glm::vec3(0, 1, 0)), false};
  SpaceTransform t = recenterOn(head);
  CHECK(t.rotation == glm::quat(1, 0, 0, 0));
  CHECK(t.translation == glm::vec3(0.0f));
  head.valid = true;
  head.position.x = std::numeric_limits<float>::quiet_NaN();
  t = recenterOn(head);
  CHECK(t.translation == glm::vec3(0.0f));
  CHECK(t.rotation == glm::quat(1, 0, 0, 0));
}

TEST_CASE("SpaceTransform: after() composes in order and inverse() undoes") {
  const SpaceTransform a{glm::angleAxis(0.7f, glm::vec3(0, 1, 0)), glm::vec3(1.0f, 0.0f, 0.5f)};
  const SpaceTransform b{glm::angleAxis(-1.9f, glm::vec3(0, 1, 0)), glm::vec3(-2.0f, 0.1f, 3.0f)};
  const glm::vec3 p(0.3f, 1.2f, -0.8f);
  CHECK(glm::distance(b.after(a).apply(p), b.apply(a.apply(p))) < 1e-5f);
  CHECK(glm::distance(a.inverse().apply(a.apply(p)), p) < 1e-5f);
  const SpaceTransform id = a.inverse().after(a);
  CHECK(glm::distance(id.translation, glm::vec3(0.0f)) < 1e-5f);
  CHECK(std::abs(std::abs(id.rotation.w) - 1.0f) < 1e-6f);
}
