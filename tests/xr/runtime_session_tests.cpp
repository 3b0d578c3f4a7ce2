// The headless runtime's session-level behaviour, in-process: state machine and call-order
// errors, frame timing, views, actions and action spaces, hand tracking, tracking loss.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "headless_session.h"
#include "test_paths.h"

using namespace embody::test;

namespace {

// Head at 1.7 m, right controller at (0.2, 1.1, -0.3), left one lost from t = 1 s on.
std::string staticTrace(const std::string& name) {
  return writeTraceFile(
      name,
      {R"({"t":0,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.1,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":0.75}})",
       R"({"t":0.999,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.1,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":0.75}})",
       R"({"t":1,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[0,0,0],"q":[0,0,0,1],"valid":false},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":0.75}})",
       R"({"t":100,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[0,0,0],"q":[0,0,0,1],"valid":false},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":0.75}})"});
}

glm::vec3 vec(const XrVector3f& v) {
  return {v.x, v.y, v.z};
}

using HandJoints = std::array<XrHandJointLocationEXT, XR_HAND_JOINT_COUNT_EXT>;

}  // namespace

TEST_CASE("the session walks IDLE, READY, SYNCHRONIZED, VISIBLE, FOCUSED and rejects calls out of order",
          "[xr]") {
  HeadlessSession h;
  CHECK(xrEndSession(h.session) == XR_ERROR_SESSION_NOT_RUNNING);
  XrFrameState fs{XR_TYPE_FRAME_STATE};
  CHECK(xrWaitFrame(h.session, nullptr, &fs) == XR_ERROR_SESSION_NOT_RUNNING);
  const auto first = h.poll();
  REQUIRE(first == std::vector<XrSessionState>{XR_SESSION_STATE_IDLE, XR_SESSION_STATE_READY});
  XrSessionBeginInfo bi{XR_TYPE_SESSION_BEGIN_INFO};
  bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_MONO;
  CHECK(xrBeginSession(h.session, &bi) == XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED);
  bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  REQUIRE(xrBeginSession(h.session, &bi) == XR_SUCCESS);
  CHECK(xrBeginSession(h.session, &bi) == XR_ERROR_SESSION_RUNNING);
  CHECK(xrBeginFrame(h.session, nullptr) == XR_ERROR_CALL_ORDER_INVALID);  // no xrWaitFrame yet
  XrFrameEndInfo ei{XR_TYPE_FRAME_END_INFO};
  ei.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;

  // Frame timing: 90 Hz, strictly increasing predicted display times on the period grid.
  XrTime previous = 0;
  for (int i = 0; i < 4; ++i) {
    REQUIRE(xrWaitFrame(h.session, nullptr, &fs) == XR_SUCCESS);
    CHECK(fs.predictedDisplayPeriod == 11111111);
    CHECK(fs.predictedDisplayTime > previous);
    if (previous) CHECK((fs.predictedDisplayTime - previous) % 11111111 == 0);
    previous = fs.predictedDisplayTime;
    CHECK(fs.shouldRender == (i > 0 ? XR_TRUE : XR_FALSE));  // visible after the first frame
    REQUIRE(xrBeginFrame(h.session, nullptr) == XR_SUCCESS);
    ei.displayTime = fs.predictedDisplayTime;
    REQUIRE(xrEndFrame(h.session, &ei) == XR_SUCCESS);
    if (i == 0)
      CHECK(h.poll() == std::vector<XrSessionState>{XR_SESSION_STATE_SYNCHRONIZED, XR_SESSION_STATE_VISIBLE,
                                                    XR_SESSION_STATE_FOCUSED});
  }
  CHECK(xrEndFrame(h.session, &ei) == XR_ERROR_CALL_ORDER_INVALID);  // no xrBeginFrame
  CHECK(xrEndSession(h.session) == XR_ERROR_SESSION_NOT_STOPPING);
  REQUIRE(xrRequestExitSession(h.session) == XR_SUCCESS);
  CHECK(h.poll() == std::vector<XrSessionState>{XR_SESSION_STATE_VISIBLE, XR_SESSION_STATE_SYNCHRONIZED,
                                                XR_SESSION_STATE_STOPPING});
  REQUIRE(xrEndSession(h.session) == XR_SUCCESS);
  CHECK(h.poll() == std::vector<XrSessionState>{XR_SESSION_STATE_IDLE, XR_SESSION_STATE_EXITING});
}

TEST_CASE("xrLocateViews gives two eyes an IPD apart with mirrored asymmetric fields of view", "[xr]") {
  HeadlessSession h({{"EMBODY_XR_POSES", staticTrace("views")}, {"EMBODY_XR_IPD", "0.064"}});
  h.runUntilFocused();
  XrViewLocateInfo li{XR_TYPE_VIEW_LOCATE_INFO};
  li.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  li.displayTime = h.lastDisplayTime;
  li.space = h.stage;
  XrViewState vs{XR_TYPE_VIEW_STATE};
  XrView views[2] = {{XR_TYPE_VIEW}, {XR_TYPE_VIEW}};
  uint32_t n = 0;
  REQUIRE(xrLocateViews(h.session, &li, &vs, 2, &n, views) == XR_SUCCESS);
  REQUIRE(n == 2);
  CHECK((vs.viewStateFlags & XR_VIEW_STATE_POSITION_TRACKED_BIT) != 0);
  CHECK(glm::distance(vec(views[0].pose.position), vec(views[1].pose.position)) ==
        Approx(0.064f).margin(1e-5));
  CHECK(views[0].pose.position.x < views[1].pose.position.x);
  CHECK(views[0].pose.position.y == Approx(1.7f).margin(1e-5));
  CHECK(views[0].fov.angleLeft == Approx(-views[1].fov.angleRight));
  CHECK(views[0].fov.angleRight == Approx(-views[1].fov.angleLeft));
  CHECK(-views[0].fov.angleLeft > views[0].fov.angleRight);  // asymmetric: more on the outer side
}

TEST_CASE("grip and aim action spaces follow the trace, and a lost hand clears its location flags", "[xr]") {
  HeadlessSession h({{"EMBODY_XR_POSES", staticTrace("actions")}});
  XrActionSetCreateInfo si{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(si.actionSetName, "test");
  std::strcpy(si.localizedActionSetName, "Test");
  XrActionSet set = XR_NULL_HANDLE;
  REQUIRE(xrCreateActionSet(h.instance, &si, &set) == XR_SUCCESS);
  CHECK(xrCreateActionSet(h.instance, &si, &set) == XR_ERROR_NAME_DUPLICATED);
  const XrPath hands[2] = {h.path("/user/hand/left"), h.path("/user/hand/right")};
  auto action = [&](const char* name, XrActionType type) {
    XrActionCreateInfo ai{XR_TYPE_ACTION_CREATE_INFO};
    std::strcpy(ai.actionName, name);
    std::strcpy(ai.localizedActionName, name);
    ai.actionType = type;
    ai.countSubactionPaths = 2;
    ai.subactionPaths = hands;
    XrAction a = XR_NULL_HANDLE;
    REQUIRE(xrCreateAction(set, &ai, &a) == XR_SUCCESS);
    return a;
  };
  const XrAction grip = action("grip", XR_ACTION_TYPE_POSE_INPUT),
                 aim = action("aim", XR_ACTION_TYPE_POSE_INPUT),
                 trigger = action("trigger", XR_ACTION_TYPE_FLOAT_INPUT);
  std::vector<XrActionSuggestedBinding> b = {{grip, h.path("/user/hand/left/input/grip/pose")},
                                             {grip, h.path("/user/hand/right/input/grip/pose")},
                                             {aim, h.path("/user/hand/right/input/aim/pose")},
                                             {trigger, h.path("/user/hand/right/input/trigger/value")}};
  XrInteractionProfileSuggestedBinding sb{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
  sb.interactionProfile = h.path("/interaction_profiles/oculus/touch_controller");
  sb.countSuggestedBindings = uint32_t(b.size());
  sb.suggestedBindings = b.data();
  REQUIRE(xrSuggestInteractionProfileBindings(h.instance, &sb) == XR_SUCCESS);
  // A component the profile does not have is refused.
  XrActionSuggestedBinding bad{trigger, h.path("/user/hand/right/input/trackpad/x")};
  XrInteractionProfileSuggestedBinding sbBad = sb;
  sbBad.countSuggestedBindings = 1;
  sbBad.suggestedBindings = &bad;
  CHECK(xrSuggestInteractionProfileBindings(h.instance, &sbBad) == XR_ERROR_PATH_UNSUPPORTED);

  XrActionSpaceCreateInfo ai{XR_TYPE_ACTION_SPACE_CREATE_INFO};
  ai.poseInActionSpace.orientation.w = 1.0f;
  XrSpace gripSpace[2], aimRight;
  for (int i = 0; i < 2; ++i) {
    ai.action = grip;
    ai.subactionPath = hands[i];
    REQUIRE(xrCreateActionSpace(h.session, &ai, &gripSpace[i]) == XR_SUCCESS);
  }
  ai.action = aim;
  ai.subactionPath = hands[1];
  REQUIRE(xrCreateActionSpace(h.session, &ai, &aimRight) == XR_SUCCESS);
  XrSessionActionSetsAttachInfo at{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  at.countActionSets = 1;
  at.actionSets = &set;
  REQUIRE(xrAttachSessionActionSets(h.session, &at) == XR_SUCCESS);
  CHECK(xrAttachSessionActionSets(h.session, &at) == XR_ERROR_ACTIONSETS_ALREADY_ATTACHED);

  XrActiveActionSet active{set, XR_NULL_PATH};
  XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  CHECK(xrSyncActions(h.session, &sync) == XR_SESSION_NOT_FOCUSED);  // not focused yet: all inactive
  h.runUntilFocused();
  REQUIRE(xrSyncActions(h.session, &sync) == XR_SUCCESS);

  XrInteractionProfileState ps{XR_TYPE_INTERACTION_PROFILE_STATE};
  REQUIRE(xrGetCurrentInteractionProfile(h.session, hands[1], &ps) == XR_SUCCESS);
  CHECK(ps.interactionProfile == sb.interactionProfile);

  XrActionStateGetInfo gi{XR_TYPE_ACTION_STATE_GET_INFO};
  gi.action = trigger;
  gi.subactionPath = hands[1];
  XrActionStateFloat fs{XR_TYPE_ACTION_STATE_FLOAT};
  REQUIRE(xrGetActionStateFloat(h.session, &gi, &fs) == XR_SUCCESS);
  CHECK(fs.isActive == XR_TRUE);
  CHECK(fs.currentState == Approx(0.75f));
  XrActionStateBoolean bs{XR_TYPE_ACTION_STATE_BOOLEAN};
  CHECK(xrGetActionStateBoolean(h.session, &gi, &bs) == XR_ERROR_ACTION_TYPE_MISMATCH);

  XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
  REQUIRE(xrLocateSpace(gripSpace[1], h.stage, h.lastDisplayTime, &loc) == XR_SUCCESS);
  CHECK((loc.locationFlags & XR_SPACE_LOCATION_POSITION_TRACKED_BIT) != 0);
  CHECK(glm::distance(vec(loc.pose.position), glm::vec3(0.2f, 1.1f, -0.3f)) < 1e-4f);
  XrSpaceLocation aimLoc{XR_TYPE_SPACE_LOCATION};
  REQUIRE(xrLocateSpace(aimRight, h.stage, h.lastDisplayTime, &aimLoc) == XR_SUCCESS);
  CHECK(aimLoc.pose.position.z < loc.pose.position.z);  // the aim ray starts ahead of the grip

  // The left hand: tracked at 0.5 s, lost (flags cleared) at 2 s.
  XrSpaceLocation left{XR_TYPE_SPACE_LOCATION};
  XrTime start = h.lastDisplayTime - 4 * 11111111;  // about the session start
  REQUIRE(xrLocateSpace(gripSpace[0], h.stage, start + 500000000, &left) == XR_SUCCESS);
  CHECK((left.locationFlags & XR_SPACE_LOCATION_POSITION_VALID_BIT) != 0);
  REQUIRE(xrLocateSpace(gripSpace[0], h.stage, start + 2000000000, &left) == XR_SUCCESS);
  CHECK(left.locationFlags == 0);
}

TEST_CASE("XR_EXT_hand_tracking gives 26 joints of a plausible hand at the controller, none when lost",
          "[xr]") {
  HeadlessSession h({{"EMBODY_XR_POSES", staticTrace("hands")}});
  h.runUntilFocused();
  HandJoints joints;
  // The left hand (trigger released: a relaxed open hand).
  REQUIRE(h.locateHand(XR_HAND_LEFT_EXT, h.lastDisplayTime, joints));
  const glm::vec3 palm = vec(joints[XR_HAND_JOINT_PALM_EXT].pose.position);
  CHECK(glm::distance(palm, glm::vec3(-0.2f, 1.1f, -0.3f)) < 1e-3f);  // palm at the grip
  for (const auto& j : joints) {
    CHECK(j.locationFlags ==
          (XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
           XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT));
    CHECK(glm::distance(vec(j.pose.position), palm) < 0.2f);  // within a hand's reach of the palm
    CHECK(j.radius > 0.004f);
  }
  // Fingertips ahead (-Z of the identity grip) of the wrist, the wrist behind the palm.
  const float openReach =
      joints[XR_HAND_JOINT_WRIST_EXT].pose.position.z - joints[XR_HAND_JOINT_MIDDLE_TIP_EXT].pose.position.z;
  CHECK(openReach > 0.15f);
  CHECK(joints[XR_HAND_JOINT_WRIST_EXT].pose.position.z > palm.z);
  // Holding a controller with the index finger forward: the thumb is on top (+Y).
  CHECK(joints[XR_HAND_JOINT_THUMB_TIP_EXT].pose.position.y >
        joints[XR_HAND_JOINT_LITTLE_TIP_EXT].pose.position.y);
  // The right hand pulls its trigger (0.75): the fingers curl, so they reach less far forward.
  REQUIRE(h.locateHand(XR_HAND_RIGHT_EXT, h.lastDisplayTime, joints));
  CHECK(joints[XR_HAND_JOINT_THUMB_TIP_EXT].pose.position.y >
        joints[XR_HAND_JOINT_LITTLE_TIP_EXT].pose.position.y);
  const float curledReach =
      joints[XR_HAND_JOINT_WRIST_EXT].pose.position.z - joints[XR_HAND_JOINT_MIDDLE_TIP_EXT].pose.position.z;
  CHECK(curledReach < openReach - 0.03f);
  // The left hand is lost after 1 s of trace time.
  CHECK_FALSE(h.locateHand(XR_HAND_LEFT_EXT, h.lastDisplayTime + 2000000000, joints));
  for (const auto& j : joints) CHECK(j.locationFlags == 0);
}

namespace {
// Head (VIEW space) and the two palms (hand tracking) in STAGE at `time`.
struct BodyProbe {
  glm::vec3 head{0.0f}, left{0.0f}, right{0.0f};
  glm::quat headQ{1, 0, 0, 0};
  bool handsActive = false;
};
BodyProbe probeBody(HeadlessSession& h, XrTime time) {
  BodyProbe b;
  XrReferenceSpaceCreateInfo rci{XR_TYPE_REFERENCE_SPACE_CREATE_INFO};
  rci.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  rci.poseInReferenceSpace.orientation.w = 1.0f;
  XrSpace view = XR_NULL_HANDLE;
  REQUIRE(xrCreateReferenceSpace(h.session, &rci, &view) == XR_SUCCESS);
  XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
  REQUIRE(xrLocateSpace(view, h.stage, time, &loc) == XR_SUCCESS);
  b.head = vec(loc.pose.position);
  b.headQ = glm::quat(loc.pose.orientation.w, loc.pose.orientation.x, loc.pose.orientation.y,
                      loc.pose.orientation.z);
  xrDestroySpace(view);
  HandJoints joints;
  b.handsActive = h.locateHand(XR_HAND_LEFT_EXT, time, joints);
  b.left = vec(joints[XR_HAND_JOINT_PALM_EXT].pose.position);
  b.handsActive = h.locateHand(XR_HAND_RIGHT_EXT, time, joints) && b.handsActive;
  b.right = vec(joints[XR_HAND_JOINT_PALM_EXT].pose.position);
  return b;
}
}  // namespace

TEST_CASE("a BVH file drives the head and hands: metres, +Y up, the performer facing -Z", "[xr]") {
  const std::string bvh = embody::test::sharedAsset("cmu_12_01_walk.bvh");
  if (bvh.empty()) {
    WARN("SKIPPED: shared asset cmu_12_01_walk.bvh not found");
    return;
  }
  HeadlessSession h({{"EMBODY_XR_POSES", bvh}});
  h.runUntilFocused();
  const XrTime start = h.lastDisplayTime - 4 * 11111111;
  // (The capture's first frame is a T-pose; the walk starts right after.)
  const BodyProbe a = probeBody(h, start + 1000000000), b = probeBody(h, start + 2500000000);
  REQUIRE(a.handsActive);
  CHECK(a.head.y == Approx(1.6f).margin(0.15f));  // scaled so the rest head stands 1.6 m high
  for (const auto& p : {a, b}) {
    INFO("head " << p.head.x << "," << p.head.y << "," << p.head.z << " left " << p.left.x << "," << p.left.y
                 << "," << p.left.z << " right " << p.right.x << "," << p.right.y << "," << p.right.z);
    // Hands hang well below the head, at either side of it (left on the user's left).
    const glm::vec3 l = glm::conjugate(p.headQ) * (p.left - p.head),
                    r = glm::conjugate(p.headQ) * (p.right - p.head);
    CHECK(l.y < -0.3f);
    CHECK(r.y < -0.3f);
    CHECK(l.x < r.x);
    CHECK(glm::distance(p.left, p.right) > 0.2f);
    CHECK(glm::distance(p.left, p.right) < 1.2f);
  }
  // The performer walks: the head moves forward (-Z in the head's own frame).
  const glm::vec3 moved = glm::conjugate(a.headQ) * (b.head - a.head);
  CHECK(moved.z < -0.5f);
}

TEST_CASE("a broken pose file falls back to the synthetic motion without failing", "[xr]") {
  const std::string broken = writeTraceFile("broken_trace", {R"({"t":0,"head":)", "not json"});
  for (const std::string& file : {broken, std::string("/nonexistent/poses.bvh")}) {
    INFO(file);
    HeadlessSession h(std::map<std::string, std::string>{{"EMBODY_XR_POSES", file}});
    h.runUntilFocused();
    const BodyProbe p = probeBody(h, h.lastDisplayTime);
    CHECK(p.handsActive);
    CHECK(p.head.y == Approx(1.62f).margin(0.05f));
  }
}
