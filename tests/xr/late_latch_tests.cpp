// The late latch's math (xr/hand_late_latch.h): a posed chain in the world, its hand moved rigidly
// onto a newer wrist pose.
#include <catch2/catch.hpp>
#include <glm/gtc/quaternion.hpp>

#include "xr/hand_late_latch.h"

using namespace embody;
using namespace embody::xr;

namespace {

// root (placed in the world: turned, scaled 0.9) -> shoulder -> elbow -> hand -> finger.
avatar::Skeleton arm() {
  avatar::Skeleton s;
  s.joints = {{"root", -1, {}}, {"shoulder", 0, {}}, {"elbow", 1, {}}, {"hand", 2, {}}, {"finger", 3, {}}};
  s.joints[1].rest.translation = {0.2f, 1.4f, 0.0f};
  s.joints[2].rest.translation = {0.3f, 0.0f, 0.0f};
  s.joints[3].rest.translation = {0.25f, 0.0f, 0.0f};
  s.joints[4].rest.translation = {0.08f, 0.0f, 0.0f};
  return s;
}

glm::vec3 worldOf(const std::vector<glm::mat4>& g, int j) { return glm::vec3(g[size_t(j)][3]); }

}  // namespace

TEST_CASE("the late latch moves the hand joint and its fingers rigidly onto the newest wrist", "[xr]") {
  const avatar::Skeleton s = arm();
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(s);
  pose.local[0].rotation = glm::angleAxis(0.7f, glm::vec3(0, 1, 0));
  pose.local[0].translation = {0.5f, 0.0f, -0.3f};
  pose.local[0].scale = glm::vec3(0.9f);
  pose.local[2].rotation = glm::angleAxis(-0.4f, glm::vec3(0, 0, 1));
  std::vector<glm::mat4> g;
  avatar::computeGlobals(s, pose, g);
  const glm::vec3 handBefore = worldOf(g, 3), elbowBefore = worldOf(g, 2);
  const glm::vec3 fingerBefore = worldOf(g, 4);
  const float fingerLength = glm::distance(fingerBefore, handBefore);

  std::array<HandLatch, 2> latch;
  latch[1].joint = 3;
  latch[1].solvedFor = {handBefore, glm::angleAxis(0.2f, glm::vec3(1, 0, 0))};
  const glm::quat turn = glm::angleAxis(0.3f, glm::normalize(glm::vec3(0, 1, 1)));
  latch[1].newest = {handBefore + glm::vec3(0.012f, -0.02f, 0.03f), turn * latch[1].solvedFor.orientation};
  latch[1].apply = true;
  LatchResult out;
  latchHands(s, latch, pose, g, out);
  avatar::computeGlobals(s, pose, g);
  REQUIRE(out.applied[1]);
  CHECK_FALSE(out.applied[0]);  // not asked to
  CHECK(glm::distance(worldOf(g, 3), latch[1].newest.position) < 1e-5f);
  CHECK(out.error[1] < 1e-5f);
  CHECK(out.correction[1] == Approx(glm::length(glm::vec3(0.012f, -0.02f, 0.03f))).margin(1e-5));
  CHECK(glm::distance(worldOf(g, 2), elbowBefore) < 1e-6f);  // the arm keeps its solved pose
  CHECK(glm::distance(worldOf(g, 4), worldOf(g, 3)) == Approx(fingerLength).margin(1e-5));  // rigid
  // The hand's world rotation turned by newest * solvedFor^-1: its +X axis (towards the finger).
  const glm::vec3 fingerDir = glm::normalize(worldOf(g, 4) - worldOf(g, 3));
  const glm::vec3 fingerDirBefore = glm::normalize(turn * glm::normalize(fingerBefore - handBefore));
  CHECK(glm::distance(fingerDir, fingerDirBefore) < 1e-4f);
}

TEST_CASE("the late latch leaves a hand alone when the correction is a tracking jump", "[xr]") {
  const avatar::Skeleton s = arm();
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(s);
  std::vector<glm::mat4> g;
  avatar::computeGlobals(s, pose, g);
  std::array<HandLatch, 2> latch;
  latch[0].joint = 3;
  latch[0].solvedFor = {worldOf(g, 3), glm::quat(1, 0, 0, 0)};
  latch[0].newest = {worldOf(g, 3) + glm::vec3(0.0f, kMaxLatchMetres + 0.01f, 0.0f), glm::quat(1, 0, 0, 0)};
  latch[0].apply = true;
  const auto localBefore = pose.local[3].translation;
  LatchResult out;
  latchHands(s, latch, pose, g, out);
  CHECK_FALSE(out.applied[0]);
  CHECK(pose.local[3].translation == localBefore);
}
