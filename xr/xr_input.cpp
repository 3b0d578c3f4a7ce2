#include "xr/xr_input.h"

#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "xr/xr_session.h"
#include "xr/xr_system.h"

namespace embody::xr {

namespace {

struct ProfileBindings {
  const char* profile;
  const char* trigger;   // component under /user/hand/<side>/
  const char* recenter;  // "" when the profile has no spare button (bound on the left hand)
};

constexpr ProfileBindings kProfiles[] = {
    {"/interaction_profiles/khr/simple_controller", "input/select/click", "input/menu/click"},
    {"/interaction_profiles/oculus/touch_controller", "input/trigger/value", "input/menu/click"},
    {"/interaction_profiles/valve/index_controller", "input/trigger/value", "input/b/click"},
    {"/interaction_profiles/htc/vive_controller", "input/trigger/value", "input/menu/click"},
    {"/interaction_profiles/microsoft/motion_controller", "input/trigger/value", "input/menu/click"},
};

Status check(XrSystem& s, XrResult r, const char* what) {
  if (XR_FAILED(r)) return Error{std::string(what) + " failed: " + s.result(r)};
  return {};
}

}  // namespace

Pose gripToWrist(const std::string& profile, bool leftHand) {
  // Right-hand offsets (wrist in grip space); +Z points back towards the wrist, +X into the palm.
  Pose p;
  auto rot = [](float pitchDeg, float rollDeg) {
    return glm::angleAxis(glm::radians(pitchDeg), glm::vec3(1, 0, 0)) *
           glm::angleAxis(glm::radians(rollDeg), glm::vec3(0, 0, 1));
  };
  if (profile == "/interaction_profiles/oculus/touch_controller") {
    p = {{0.0f, -0.015f, 0.085f}, rot(-20.0f, 0.0f)};  // handle tilted ~20 degrees forward
  } else if (profile == "/interaction_profiles/valve/index_controller") {
    p = {{0.0f, -0.01f, 0.08f}, rot(-15.0f, 0.0f)};  // strap holds the palm close to the grip
  } else if (profile == "/interaction_profiles/htc/vive_controller") {
    p = {{0.0f, -0.02f, 0.1f}, rot(-10.0f, 0.0f)};  // long wand, grip further from the wrist
  } else if (profile == "/interaction_profiles/microsoft/motion_controller") {
    p = {{0.0f, -0.02f, 0.09f}, rot(-15.0f, 0.0f)};
  } else {
    p = {{0.0f, 0.0f, 0.08f}, rot(0.0f, 0.0f)};  // khr/simple: no geometry known
  }
  if (leftHand) {  // mirror across the grip's YZ plane
    p.position.x = -p.position.x;
    p.orientation = glm::quat(p.orientation.w, p.orientation.x, -p.orientation.y, -p.orientation.z);
  }
  return p;
}

glm::quat trackerHandOrientation(const glm::quat& xrWrist, bool leftHand) {
  // Columns: the tracker's X, Y, Z in the wrist joint's frame. Left: X = +Y (back of the hand =
  // away from the palm), Y = -Z (fingers), Z = X x Y = -X. Right: X = -Y (into the palm), Y = -Z, Z = +X.
  static const glm::quat kLeft = glm::quat_cast(glm::mat3(glm::vec3(0, 1, 0), glm::vec3(0, 0, -1), glm::vec3(-1, 0, 0)));
  static const glm::quat kRight = glm::quat_cast(glm::mat3(glm::vec3(0, -1, 0), glm::vec3(0, 0, -1), glm::vec3(1, 0, 0)));
  return glm::normalize(xrWrist * (leftHand ? kLeft : kRight));
}

Result<std::unique_ptr<XrInput>> XrInput::create(XrSystem& system, XrSessionRunner& session) {
  std::unique_ptr<XrInput> in(new XrInput(system, session));
  if (auto s = in->init(); !s) return Error{s.error()};
  return in;
}

Status XrInput::init() {
  if (auto s = createActions(); !s) return s;
  if (auto s = suggestBindings(); !s) return s;
  if (auto s = createHandSpaces(); !s) return s;
  createHandTrackers();
  return {};
}

Status XrInput::createActions() {
  handPaths_ = {system_.path("/user/hand/left"), system_.path("/user/hand/right")};
  XrActionSetCreateInfo si{XR_TYPE_ACTION_SET_CREATE_INFO};
  std::strcpy(si.actionSetName, "embody");
  std::strcpy(si.localizedActionSetName, "Embody");
  if (auto s = check(system_, xrCreateActionSet(system_.instance(), &si, &set_), "xrCreateActionSet"); !s) return s;
  auto action = [&](const char* name, const char* localized, XrActionType type, XrAction& out,
                    uint32_t hands) {
    XrActionCreateInfo ai{XR_TYPE_ACTION_CREATE_INFO};
    std::strcpy(ai.actionName, name);
    std::strcpy(ai.localizedActionName, localized);
    ai.actionType = type;
    ai.countSubactionPaths = hands;
    ai.subactionPaths = handPaths_.data();
    return check(system_, xrCreateAction(set_, &ai, &out), "xrCreateAction");
  };
  if (auto s = action("grip_pose", "Hand grip", XR_ACTION_TYPE_POSE_INPUT, grip_, 2); !s) return s;
  if (auto s = action("aim_pose", "Hand aim", XR_ACTION_TYPE_POSE_INPUT, aim_, 2); !s) return s;
  if (auto s = action("trigger", "Trigger", XR_ACTION_TYPE_FLOAT_INPUT, trigger_, 2); !s) return s;
  return action("recenter", "Recenter", XR_ACTION_TYPE_BOOLEAN_INPUT, recenter_, 0);
}

Status XrInput::suggestBindings() {
  for (const auto& p : kProfiles) {
    std::vector<XrActionSuggestedBinding> b;
    for (const char* side : {"left", "right"}) {
      const std::string base = std::string("/user/hand/") + side + "/";
      b.push_back({grip_, system_.path((base + "input/grip/pose").c_str())});
      b.push_back({aim_, system_.path((base + "input/aim/pose").c_str())});
      b.push_back({trigger_, system_.path((base + p.trigger).c_str())});
    }
    // Recenter on the left hand's spare button (index: the right B button).
    const bool indexProfile = std::strstr(p.profile, "index") != nullptr;
    b.push_back(
        {recenter_,
         system_.path(
             (std::string("/user/hand/") + (indexProfile ? "right/" : "left/") + p.recenter).c_str())});
    XrInteractionProfileSuggestedBinding sb{XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING};
    sb.interactionProfile = system_.path(p.profile);
    sb.countSuggestedBindings = static_cast<uint32_t>(b.size());
    sb.suggestedBindings = b.data();
    // A runtime may not know every profile: that is not an error for the application.
    if (XrResult r = xrSuggestInteractionProfileBindings(system_.instance(), &sb);
        XR_FAILED(r) && r != XR_ERROR_PATH_UNSUPPORTED)
      return Error{std::string("xrSuggestInteractionProfileBindings(") + p.profile +
                   ") failed: " + system_.result(r)};
  }
  return {};
}

Status XrInput::createHandSpaces() {
  for (int h = 0; h < 2; ++h) {
    XrActionSpaceCreateInfo ai{XR_TYPE_ACTION_SPACE_CREATE_INFO};
    ai.poseInActionSpace = toXr(Pose{});
    ai.subactionPath = handPaths_[h];
    for (auto [action, space] : {std::pair{grip_, &gripSpaces_[h]}, std::pair{aim_, &aimSpaces_[h]}}) {
      ai.action = action;
      if (auto s = check(system_, xrCreateActionSpace(session_.handle(), &ai, space), "xrCreateActionSpace"); !s)
        return s;
    }
  }
  XrSessionActionSetsAttachInfo at{XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO};
  at.countActionSets = 1;
  at.actionSets = &set_;
  return check(system_, xrAttachSessionActionSets(session_.handle(), &at), "xrAttachSessionActionSets");
}

void XrInput::createHandTrackers() {
  if (!system_.handTrackingEnabled()) return;
  auto create = reinterpret_cast<PFN_xrCreateHandTrackerEXT>(system_.proc("xrCreateHandTrackerEXT"));
  locateJoints_ = reinterpret_cast<PFN_xrLocateHandJointsEXT>(system_.proc("xrLocateHandJointsEXT"));
  destroyTracker_ = reinterpret_cast<PFN_xrDestroyHandTrackerEXT>(system_.proc("xrDestroyHandTrackerEXT"));
  if (!create || !locateJoints_ || !destroyTracker_) return;
  for (int h = 0; h < 2; ++h) {
    XrHandTrackerCreateInfoEXT hi{XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT};
    hi.hand = h == 0 ? XR_HAND_LEFT_EXT : XR_HAND_RIGHT_EXT;
    hi.handJointSet = XR_HAND_JOINT_SET_DEFAULT_EXT;
    if (XR_FAILED(create(session_.handle(), &hi, &trackers_[h]))) trackers_[h] = XR_NULL_HANDLE;
  }
}

XrInput::~XrInput() {
  for (auto& t : trackers_)
    if (t && destroyTracker_) destroyTracker_(t);
  for (auto* list : {&gripSpaces_, &aimSpaces_})
    for (XrSpace s : *list)
      if (s) xrDestroySpace(s);
  if (set_) xrDestroyActionSet(set_);  // destroys its actions too
}

void XrInput::refreshProfile() {
  XrInteractionProfileState st{XR_TYPE_INTERACTION_PROFILE_STATE};
  if (XR_SUCCEEDED(xrGetCurrentInteractionProfile(session_.handle(), handPaths_[1], &st)))
    profile_ = st.interactionProfile == XR_NULL_PATH ? "" : system_.pathString(st.interactionProfile);
}

void XrInput::locateHand(int h, XrTime time) {
  HandState& hs = hands_[h];
  hs.grip = hs.aim = hs.wrist = TrackedPose{};
  hs.wristFromHandTracking = hs.jointsValid = false;
  if (hs.active) {
    XrSpaceLocation loc{XR_TYPE_SPACE_LOCATION};
    if (XR_SUCCEEDED(xrLocateSpace(gripSpaces_[h], session_.worldSpace(), time, &loc)))
      hs.grip = fromSpaceLocation(loc);
    loc = {XR_TYPE_SPACE_LOCATION};
    if (XR_SUCCEEDED(xrLocateSpace(aimSpaces_[h], session_.worldSpace(), time, &loc)))
      hs.aim = fromSpaceLocation(loc);
    if (hs.grip.valid) {
      hs.wrist = hs.grip;
      hs.wrist.pose = hs.grip.pose * gripToWrist(profile_, h == 0);
    }
  }
  if (trackers_[h] && locateJoints_) {
    std::array<XrHandJointLocationEXT, kHandJointCount> joints{};
    XrHandJointLocationsEXT locs{XR_TYPE_HAND_JOINT_LOCATIONS_EXT};
    locs.jointCount = kHandJointCount;
    locs.jointLocations = joints.data();
    XrHandJointsLocateInfoEXT li{XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT};
    li.baseSpace = session_.worldSpace();
    li.time = time;
    if (XR_SUCCEEDED(locateJoints_(trackers_[h], &li, &locs)) && locs.isActive) {
      hs.jointsValid = true;
      for (int j = 0; j < kHandJointCount; ++j) {
        XrSpaceLocation l{XR_TYPE_SPACE_LOCATION};
        l.locationFlags = joints[j].locationFlags;
        l.pose = joints[j].pose;
        hs.joints[j] = fromSpaceLocation(l);
      }
      if (hs.joints[XR_HAND_JOINT_WRIST_EXT].valid) {
        hs.wrist = hs.joints[XR_HAND_JOINT_WRIST_EXT];
        hs.wristFromHandTracking = true;
      }
    }
  }
}

void XrInput::relocateWrists(XrTime time) {
  for (int h = 0; h < 2; ++h) locateHand(h, time);  // action states stay those of update()
}

Status XrInput::update(XrTime time) {
  if (session_.takeInteractionProfileChanged() || profile_.empty()) refreshProfile();
  XrActiveActionSet active{set_, XR_NULL_PATH};
  XrActionsSyncInfo sync{XR_TYPE_ACTIONS_SYNC_INFO};
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  const XrResult sr = xrSyncActions(session_.handle(), &sync);
  if (XR_FAILED(sr)) return Error{"xrSyncActions failed: " + system_.result(sr)};
  // XR_SESSION_NOT_FOCUSED: every action reads inactive below, which is what we want.

  XrActionStateGetInfo gi{XR_TYPE_ACTION_STATE_GET_INFO};
  gi.action = recenter_;
  XrActionStateBoolean rb{XR_TYPE_ACTION_STATE_BOOLEAN};
  recenterPressed_ = XR_SUCCEEDED(xrGetActionStateBoolean(session_.handle(), &gi, &rb)) && rb.isActive &&
                     rb.currentState && rb.changedSinceLastSync;

  for (int h = 0; h < 2; ++h) {
    HandState& hs = hands_[h];
    hs = HandState{};
    gi.subactionPath = handPaths_[h];
    gi.action = grip_;
    XrActionStatePose ps{XR_TYPE_ACTION_STATE_POSE};
    hs.active = XR_SUCCEEDED(xrGetActionStatePose(session_.handle(), &gi, &ps)) && ps.isActive;
    gi.action = trigger_;
    XrActionStateFloat fs{XR_TYPE_ACTION_STATE_FLOAT};
    if (XR_SUCCEEDED(xrGetActionStateFloat(session_.handle(), &gi, &fs)) && fs.isActive &&
        std::isfinite(fs.currentState))
      hs.trigger = fs.currentState;
    locateHand(h, time);
  }
  return {};
}

}  // namespace embody::xr
