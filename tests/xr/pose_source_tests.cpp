// The OpenXR side as a tracking::PoseSource, and the loop's body-pose hook (where the IK stage
// plugs in) fed by the headless runtime in-process.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>

#include "tests/support/test_avatar.h"
#include "headless_session.h"
#include "xr/xr_input.h"
#include "xr/xr_loop.h"
#include "xr/xr_pose_source.h"
#include "xr_test_support.h"

using namespace embody;
using embody::tracking::TrackerId;

TEST_CASE("XrPoseSource publishes head and wrists with OpenXR's validity, never NaN", "[xr]") {
  xr::XrPoseSource src;
  CHECK(src.name() == "openxr");
  CHECK(src.trackers() == tracking::TrackerMask::threePoint());
  CHECK_FALSE(src.sample(0.0)[TrackerId::Head].valid);  // nothing published yet
  const xr::TrackedPose head{{{0, 1.7f, 0}, {1, 0, 0, 0}}, true, true};
  const xr::TrackedPose lost{{{0, 0, 0}, {1, 0, 0, 0}}, false, false};
  const xr::TrackedPose broken{{{NAN, 1, 0}, {1, 0, 0, 0}}, true, true};
  src.publish(0.5, head, lost, broken);
  const auto s = src.sample(123.0);
  CHECK(s.time == 0.5);
  CHECK(s[TrackerId::Head].valid);
  CHECK(s[TrackerId::Head].position.y == Approx(1.7f));
  CHECK_FALSE(s[TrackerId::LeftHand].valid);
  CHECK_FALSE(s[TrackerId::RightHand].valid);  // sanitized: NaN is never a valid tracker
  CHECK_FALSE(s[TrackerId::Hips].valid);
  CHECK(src.published() == 1);
}

TEST_CASE("the headset loop hands each frame's trackers to the body hook on the IK thread", "[xr]") {
  const std::string trace = test::writeTraceFile(
      "body_hook",
      {R"({"t":0,"head":{"p":[0,1.6,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.2,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.2,-0.3],"q":[0,0,0,1]}})",
       R"({"t":100,"head":{"p":[0,1.6,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.2,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.2,-0.3],"q":[0,0,0,1]}})"});
  setenv("XR_RUNTIME_JSON", test::runtimeManifest().c_str(), 1);
  setenv("EMBODY_XR_POSES", trace.c_str(), 1);
  setenv("EMBODY_XR_VIEW_SIZE", "64x64", 1);
  unsetenv("EMBODY_XR_FRAMES");
  const auto avatar = test::makeTestAvatar();
  xr::XrLoopOptions o;
  o.avatar = &avatar;
  o.frames = 10;
  o.vulkanValidation = true;
  std::vector<tracking::PoseSample> seen;  // written on the IK thread, read after the loop joined it
  uint64_t sequence = 0;
  o.solveBody = [&](const tracking::PoseSample& s, runtime::SolvedFrame& out) {
    seen.push_back(s);
    out.stats.sequence = ++sequence;
    out.stats.sampleTime = s.time;
  };
  o.ikBudgetSeconds = 1.0;  // the join waits for every solve: the hook is checked, not the timing
  const auto r = xr::runXrLoop(o);
  unsetenv("EMBODY_XR_POSES");
  unsetenv("EMBODY_XR_VIEW_SIZE");
  INFO(r.error);
  REQUIRE(r.error.empty());
  CHECK(r.vulkanValidationMessages == 0);
  CHECK(r.bodyPoseFrames == 10);
  REQUIRE(seen.size() == 10);
  const auto& s = seen.back();
  CHECK(s[TrackerId::Head].valid);
  CHECK(s[TrackerId::Head].position.y == Approx(1.6f).margin(1e-4));
  // The wrist: hand tracking's wrist joint (it wins over the controller estimate), which lies
  // within a few centimetres of the grip times the Touch grip-to-wrist offset.
  const xr::Pose grip{{0.2f, 1.2f, -0.3f}, {1, 0, 0, 0}};
  const glm::vec3 wrist =
      (grip * xr::gripToWrist("/interaction_profiles/oculus/touch_controller", false)).position;
  REQUIRE(s[TrackerId::RightHand].valid);
  CHECK(glm::distance(s[TrackerId::RightHand].position, wrist) < 0.05f);
  CHECK(glm::distance(s[TrackerId::RightHand].position, grip.position) > 0.04f);  // not the grip itself
  CHECK(s.time > seen.front().time);
}
