// Actions, action sets, suggested bindings, the emulated controllers and XR_EXT_hand_tracking.
//
// The emulated device is a pair of tracked controllers whose poses come from the pose provider.
// At xrAttachSessionActionSets the runtime picks the interaction profile it "is": EMBODY_XR_PROFILE
// (e.g. "oculus/touch_controller") when the application suggested bindings for it, else the first
// suggested of touch, index, vive, motion controller, simple controller.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "tools/xr_runtime/runtime.h"
#include "tools/xr_runtime/two_call.h"

namespace embody::xr_runtime {

namespace {

struct ProfileInfo {
  const char* path;
  const char* localized;
  // Components relative to /user/hand/<side>/; "L:"/"R:" prefix restricts to one hand.
  std::vector<const char*> components;
};

const std::vector<ProfileInfo>& profiles() {
  static const std::vector<ProfileInfo> list = {
      {"/interaction_profiles/oculus/touch_controller",
       "Oculus Touch Controller",
       {"L:input/x/click",        "L:input/x/touch",       "L:input/y/click",     "L:input/y/touch",
        "L:input/menu/click",     "R:input/a/click",       "R:input/a/touch",     "R:input/b/click",
        "R:input/b/touch",        "R:input/system/click",  "input/squeeze/value", "input/trigger/value",
        "input/trigger/touch",    "input/thumbstick/x",    "input/thumbstick/y",  "input/thumbstick/click",
        "input/thumbstick/touch", "input/thumbrest/touch", "input/grip/pose",     "input/aim/pose",
        "output/haptic"}},
      {"/interaction_profiles/valve/index_controller",
       "Index Controller",
       {"input/system/click",  "input/system/touch",     "input/a/click",          "input/a/touch",
        "input/b/click",       "input/b/touch",          "input/squeeze/value",    "input/squeeze/force",
        "input/trigger/click", "input/trigger/value",    "input/trigger/touch",    "input/thumbstick/x",
        "input/thumbstick/y",  "input/thumbstick/click", "input/thumbstick/touch", "input/trackpad/x",
        "input/trackpad/y",    "input/trackpad/force",   "input/trackpad/touch",   "input/grip/pose",
        "input/aim/pose",      "output/haptic"}},
      {"/interaction_profiles/htc/vive_controller",
       "Vive Controller",
       {"input/system/click", "input/squeeze/click", "input/menu/click", "input/trigger/click",
        "input/trigger/value", "input/trackpad/x", "input/trackpad/y", "input/trackpad/click",
        "input/trackpad/touch", "input/grip/pose", "input/aim/pose", "output/haptic"}},
      {"/interaction_profiles/microsoft/motion_controller",
       "Mixed Reality Motion Controller",
       {"input/menu/click", "input/squeeze/click", "input/trigger/value", "input/thumbstick/x",
        "input/thumbstick/y", "input/thumbstick/click", "input/trackpad/x", "input/trackpad/y",
        "input/trackpad/click", "input/trackpad/touch", "input/grip/pose", "input/aim/pose",
        "output/haptic"}},
      {"/interaction_profiles/khr/simple_controller",
       "Simple Controller",
       {"input/select/click", "input/menu/click", "input/grip/pose", "input/aim/pose", "output/haptic"}},
  };
  return list;
}

const ProfileInfo* findProfile(const std::string& path) {
  for (const auto& p : profiles())
    if (path == p.path) return &p;
  return nullptr;
}

// "/user/hand/left/input/trigger/value" -> hand 0, component "input/trigger/value".
bool splitBinding(const std::string& path, int& hand, std::string& component) {
  static const std::string left = "/user/hand/left/", right = "/user/hand/right/";
  if (path.rfind(left, 0) == 0) {
    hand = 0;
    component = path.substr(left.size());
    return true;
  }
  if (path.rfind(right, 0) == 0) {
    hand = 1;
    component = path.substr(right.size());
    return true;
  }
  return false;
}

// A binding is valid when it names a component of the profile or a parent of one (the spec lets
// ".../input/trigger" stand for value or click, picked by the action's type).
bool bindingSupported(const ProfileInfo& profile, int hand, const std::string& component) {
  for (const char* c : profile.components) {
    std::string comp = c;
    if (comp.rfind("L:", 0) == 0) {
      if (hand != 0) continue;
      comp = comp.substr(2);
    } else if (comp.rfind("R:", 0) == 0) {
      if (hand != 1) continue;
      comp = comp.substr(2);
    }
    if (comp == component || comp.rfind(component + "/", 0) == 0) return true;
  }
  return false;
}

bool validName(const char* s) {
  if (!s || !*s) return false;
  for (const char* c = s; *c; ++c)
    if (!((*c >= 'a' && *c <= 'z') || (*c >= '0' && *c <= '9') || *c == '-' || *c == '_' || *c == '.'))
      return false;
  return true;
}

bool isTopLevelUserPath(const std::string& p) {
  return p == "/user/hand/left" || p == "/user/hand/right" || p == "/user/head" || p == "/user/gamepad" ||
         p == "/user/treadmill";
}

bool sessionFocused(const Session& s) {
  return s.running && s.state == XR_SESSION_STATE_FOCUSED;
}

// Bindings of `action` in the current profile for one hand.
std::vector<std::string> boundComponents(Instance& inst, const Session& s, const Action* action, int hand) {
  std::vector<std::string> out;
  auto it = inst.suggested.find(s.currentProfile);
  if (it == inst.suggested.end()) return out;
  for (const auto& [a, path] : it->second) {
    int h = -1;
    std::string comp;
    if (a.get() == action && splitBinding(inst.pathString(path), h, comp) && h == hand) out.push_back(comp);
  }
  return out;
}

float sourceValue(const std::string& component, const BodySample& body, int hand) {
  const float trigger = hand == 0 ? body.leftTrigger : body.rightTrigger;
  if (component.rfind("input/trigger", 0) == 0 || component.rfind("input/select", 0) == 0)
    return std::clamp(std::isfinite(trigger) ? trigger : 0.0f, 0.0f, 1.0f);
  return 0.0f;  // squeeze, buttons, sticks: at rest
}

bool subactionAllowed(const Action& a, XrPath p) {
  return p == XR_NULL_PATH ||
         std::find(a.subactionPaths.begin(), a.subactionPaths.end(), p) != a.subactionPaths.end();
}

XrResult XRAPI_CALL CreateActionSet(XrInstance instance, const XrActionSetCreateInfo* ci, XrActionSet* out) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_ACTION_SET_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (!validName(ci->actionSetName)) return XR_ERROR_PATH_FORMAT_INVALID;
  if (ci->localizedActionSetName[0] == '\0') return XR_ERROR_LOCALIZED_NAME_INVALID;
  std::lock_guard lock(inst->mutex);
  for (const auto& [raw, s] : inst->actionSets) {
    if (s->name == ci->actionSetName) return XR_ERROR_NAME_DUPLICATED;
    if (s->localizedName == ci->localizedActionSetName) return XR_ERROR_LOCALIZED_NAME_DUPLICATED;
  }
  auto set = std::make_shared<ActionSet>();
  set->instance = inst;
  set->name = ci->actionSetName;
  set->localizedName = ci->localizedActionSetName;
  set->priority = ci->priority;
  *out = reinterpret_cast<XrActionSet>(set.get());
  {
    std::lock_guard rlock(registry().mutex);
    inst->actionSets.emplace(set.get(), std::move(set));
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(CreateActionSet)

XrResult XRAPI_CALL DestroyActionSet(XrActionSet actionSet) {
  Instance* inst = nullptr;
  ActionSet* set = findActionSet(actionSet, &inst);
  if (!set) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  // The handles of the set and its actions become invalid. The set itself is freed here only if
  // nothing else holds it: a session it is attached to still locates its actions' spaces, and the
  // session's teardown must not touch freed memory (spec: xrDestroyActionSet must not free
  // resources other valid handles use).
  std::lock_guard rlock(registry().mutex);
  for (const auto& a : set->actions) inst->actions.erase(a.get());
  inst->actionSets.erase(set);  // the instance's reference
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroyActionSet)

XrResult XRAPI_CALL CreateAction(XrActionSet actionSet, const XrActionCreateInfo* ci, XrAction* out) {
  Instance* inst = nullptr;
  ActionSet* set = findActionSet(actionSet, &inst);
  if (!set) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_ACTION_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (!validName(ci->actionName)) return XR_ERROR_PATH_FORMAT_INVALID;
  if (ci->localizedActionName[0] == '\0') return XR_ERROR_LOCALIZED_NAME_INVALID;
  switch (ci->actionType) {
    case XR_ACTION_TYPE_BOOLEAN_INPUT:
    case XR_ACTION_TYPE_FLOAT_INPUT:
    case XR_ACTION_TYPE_VECTOR2F_INPUT:
    case XR_ACTION_TYPE_POSE_INPUT:
    case XR_ACTION_TYPE_VIBRATION_OUTPUT:
      break;
    default:
      return XR_ERROR_VALIDATION_FAILURE;
  }
  std::lock_guard lock(inst->mutex);
  if (set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
  for (const auto& a : set->actions) {
    if (!inst->actions.count(a.get())) continue;  // a destroyed handle frees its names
    if (a->name == ci->actionName) return XR_ERROR_NAME_DUPLICATED;
    if (a->localizedName == ci->localizedActionName) return XR_ERROR_LOCALIZED_NAME_DUPLICATED;
  }
  std::vector<XrPath> subs;
  for (uint32_t i = 0; i < ci->countSubactionPaths; ++i) {
    const XrPath p = ci->subactionPaths[i];
    if (p == XR_NULL_PATH || p >= inst->paths.size()) return XR_ERROR_PATH_INVALID;
    if (!isTopLevelUserPath(inst->pathString(p))) return XR_ERROR_PATH_UNSUPPORTED;
    if (std::find(subs.begin(), subs.end(), p) != subs.end()) return XR_ERROR_PATH_UNSUPPORTED;
    subs.push_back(p);
  }
  auto owned = std::make_unique<Action>();
  Action* a = owned.get();
  a->set = set;
  a->name = ci->actionName;
  a->localizedName = ci->localizedActionName;
  a->type = ci->actionType;
  a->subactionPaths = std::move(subs);
  set->actions.push_back(std::move(owned));
  return publishHandle(inst->actions, a, out);
}
EMBODY_XR_ENTRY(CreateAction)

XrResult XRAPI_CALL DestroyAction(XrAction action) {
  Instance* inst = nullptr;
  Action* a = findAction(action, &inst);
  if (!a) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  // Only the handle goes (spec: the action's resources still make its action spaces locatable and
  // take part in xrSyncActions); its set frees it.
  unregisterHandle(inst->actions, a);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroyAction)

XrResult XRAPI_CALL SuggestInteractionProfileBindings(XrInstance instance,
                                                      const XrInteractionProfileSuggestedBinding* sb) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!sb || sb->type != XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING || sb->countSuggestedBindings == 0 ||
      !sb->suggestedBindings)
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (sb->interactionProfile == XR_NULL_PATH || sb->interactionProfile >= inst->paths.size())
    return XR_ERROR_PATH_INVALID;
  const ProfileInfo* profile = findProfile(inst->pathString(sb->interactionProfile));
  if (!profile) return XR_ERROR_PATH_UNSUPPORTED;
  std::vector<std::pair<ActionRef, XrPath>> bindings;
  for (uint32_t i = 0; i < sb->countSuggestedBindings; ++i) {
    const auto& b = sb->suggestedBindings[i];
    Action* a = reinterpret_cast<Action*>(b.action);
    if (!inst->actions.count(a)) return XR_ERROR_HANDLE_INVALID;
    if (a->set->attached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
    if (b.binding == XR_NULL_PATH || b.binding >= inst->paths.size()) return XR_ERROR_PATH_INVALID;
    int hand = -1;
    std::string comp;
    if (!splitBinding(inst->pathString(b.binding), hand, comp) || !bindingSupported(*profile, hand, comp))
      return XR_ERROR_PATH_UNSUPPORTED;
    bindings.emplace_back(actionRef(a), b.binding);
  }
  inst->suggested[sb->interactionProfile] = std::move(bindings);  // replaces earlier suggestions
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(SuggestInteractionProfileBindings)

XrResult XRAPI_CALL AttachSessionActionSets(XrSession session, const XrSessionActionSetsAttachInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO || info->countActionSets == 0 ||
      !info->actionSets)
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->actionSetsAttached) return XR_ERROR_ACTIONSETS_ALREADY_ATTACHED;
  for (uint32_t i = 0; i < info->countActionSets; ++i)
    if (!inst->actionSets.count(reinterpret_cast<ActionSet*>(info->actionSets[i])))
      return XR_ERROR_HANDLE_INVALID;
  for (uint32_t i = 0; i < info->countActionSets; ++i) {
    const std::shared_ptr<ActionSet>& set =
        inst->actionSets[reinterpret_cast<ActionSet*>(info->actionSets[i])];
    set->attached = true;
    s->attachedSets.push_back(set);
    for (const auto& a : set->actions) s->actionStates[a.get()] = {};
  }
  s->actionSetsAttached = true;
  // Pick the emulated controller.
  std::vector<std::string> order = {
      "/interaction_profiles/oculus/touch_controller", "/interaction_profiles/valve/index_controller",
      "/interaction_profiles/htc/vive_controller", "/interaction_profiles/microsoft/motion_controller",
      "/interaction_profiles/khr/simple_controller"};
  if (const char* want = std::getenv("EMBODY_XR_PROFILE"); want && *want)
    order.insert(order.begin(), std::string("/interaction_profiles/") + want);
  s->currentProfile = XR_NULL_PATH;
  for (const auto& p : order) {
    auto id = inst->pathIds.find(p);
    if (id != inst->pathIds.end() && inst->suggested.count(id->second)) {
      bool usesAttached = false;
      for (const auto& [a, path] : inst->suggested[id->second])
        usesAttached = usesAttached || a->set->attached;
      if (usesAttached) {
        s->currentProfile = id->second;
        break;
      }
    }
  }
  if (s->currentProfile != XR_NULL_PATH) {
    XrEventDataInteractionProfileChanged ev{XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED};
    ev.session = session;
    inst->pushEvent(&ev, sizeof(ev));
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(AttachSessionActionSets)

XrResult XRAPI_CALL GetCurrentInteractionProfile(XrSession session, XrPath topLevelUserPath,
                                                 XrInteractionProfileState* state) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!state || state->type != XR_TYPE_INTERACTION_PROFILE_STATE) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (!s->actionSetsAttached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  if (topLevelUserPath == XR_NULL_PATH || topLevelUserPath >= inst->paths.size())
    return XR_ERROR_PATH_INVALID;
  const std::string& p = inst->pathString(topLevelUserPath);
  if (!isTopLevelUserPath(p)) return XR_ERROR_PATH_UNSUPPORTED;
  state->interactionProfile =
      (p == "/user/hand/left" || p == "/user/hand/right") ? s->currentProfile : XR_NULL_PATH;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetCurrentInteractionProfile)

XrResult XRAPI_CALL SyncActions(XrSession session, const XrActionsSyncInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_ACTIONS_SYNC_INFO ||
      (info->countActiveActionSets > 0 && !info->activeActionSets))
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  // Which (set, hand) pairs are active this sync.
  std::map<ActionSet*, std::array<bool, 2>> active;
  for (uint32_t i = 0; i < info->countActiveActionSets; ++i) {
    auto* set = reinterpret_cast<ActionSet*>(info->activeActionSets[i].actionSet);
    if (!inst->actionSets.count(set)) return XR_ERROR_HANDLE_INVALID;
    if (std::none_of(s->attachedSets.begin(), s->attachedSets.end(),
                     [&](const auto& attached) { return attached.get() == set; }))
      return XR_ERROR_ACTIONSET_NOT_ATTACHED;
    const XrPath sub = info->activeActionSets[i].subactionPath;
    if (sub != XR_NULL_PATH && (sub >= inst->paths.size() || !isTopLevelUserPath(inst->pathString(sub))))
      return XR_ERROR_PATH_UNSUPPORTED;
    const std::string& subStr = inst->pathString(sub);
    auto& a = active[set];
    a[0] = a[0] || sub == XR_NULL_PATH || subStr == "/user/hand/left";
    a[1] = a[1] || sub == XR_NULL_PATH || subStr == "/user/hand/right";
  }
  const bool focused = sessionFocused(*s);
  const XrTime t = s->lastPredicted > 0 ? s->lastPredicted : nowNs();
  const BodySample body = inst->poses.sample(traceSeconds(*s, t));
  for (auto& [action, states] : s->actionStates) {
    for (int hand = 0; hand < 2; ++hand) {
      ActionStateData next;
      auto it = active.find(action->set);
      const auto comps = boundComponents(*inst, *s, action, hand);
      next.active = focused && it != active.end() && it->second[hand] && !comps.empty();
      if (next.active)
        for (const auto& c : comps) next.value = std::max(next.value, sourceValue(c, body, hand));
      if (action->type == XR_ACTION_TYPE_BOOLEAN_INPUT) next.value = next.value > 0.5f ? 1.0f : 0.0f;
      const ActionStateData& prev = states[hand];
      next.changed = next.active && prev.active && next.value != prev.value;
      next.lastChange = (next.changed || next.active != prev.active) ? t : prev.lastChange;
      states[hand] = next;
    }
  }
  return focused ? XR_SUCCESS : XR_SESSION_NOT_FOCUSED;
}
EMBODY_XR_ENTRY(SyncActions)

// Shared checks of the xrGetActionState* calls; combines the hands the subaction path selects.
XrResult actionState(XrSession session, const XrActionStateGetInfo* info, XrActionType type,
                     ActionStateData& out) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_ACTION_STATE_GET_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  Action* a = reinterpret_cast<Action*>(info->action);
  if (!inst->actions.count(a)) return XR_ERROR_HANDLE_INVALID;
  if (a->type != type) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  auto it = s->actionStates.find(a);
  if (it == s->actionStates.end()) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  if (!subactionAllowed(*a, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
  const int hand = handIndexForPath(*inst, info->subactionPath);
  out = {};
  for (int h = 0; h < 2; ++h) {
    if (info->subactionPath != XR_NULL_PATH && h != hand) continue;
    const auto& st = it->second[h];
    if (!st.active) continue;
    if (!out.active || std::fabs(st.value) > std::fabs(out.value)) out.value = st.value;
    out.active = true;
    out.changed = out.changed || st.changed;
    out.lastChange = std::max(out.lastChange, st.lastChange);
  }
  return XR_SUCCESS;
}

// The fields every action state has, from the merged per-source data.
template <class State>
void fillActionState(const ActionStateData& d, State* state) {
  state->changedSinceLastSync = d.changed ? XR_TRUE : XR_FALSE;
  state->lastChangeTime = d.lastChange;
  state->isActive = d.active ? XR_TRUE : XR_FALSE;
}

XrResult XRAPI_CALL GetActionStateBoolean(XrSession session, const XrActionStateGetInfo* info,
                                          XrActionStateBoolean* state) {
  if (!state || state->type != XR_TYPE_ACTION_STATE_BOOLEAN) return XR_ERROR_VALIDATION_FAILURE;
  ActionStateData d;
  if (XrResult r = actionState(session, info, XR_ACTION_TYPE_BOOLEAN_INPUT, d); XR_FAILED(r)) return r;
  state->currentState = d.value > 0.5f ? XR_TRUE : XR_FALSE;
  fillActionState(d, state);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetActionStateBoolean)

XrResult XRAPI_CALL GetActionStateFloat(XrSession session, const XrActionStateGetInfo* info,
                                        XrActionStateFloat* state) {
  if (!state || state->type != XR_TYPE_ACTION_STATE_FLOAT) return XR_ERROR_VALIDATION_FAILURE;
  ActionStateData d;
  if (XrResult r = actionState(session, info, XR_ACTION_TYPE_FLOAT_INPUT, d); XR_FAILED(r)) return r;
  state->currentState = d.value;
  fillActionState(d, state);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetActionStateFloat)

XrResult XRAPI_CALL GetActionStateVector2f(XrSession session, const XrActionStateGetInfo* info,
                                           XrActionStateVector2f* state) {
  if (!state || state->type != XR_TYPE_ACTION_STATE_VECTOR2F) return XR_ERROR_VALIDATION_FAILURE;
  ActionStateData d;
  if (XrResult r = actionState(session, info, XR_ACTION_TYPE_VECTOR2F_INPUT, d); XR_FAILED(r)) return r;
  fillActionState(d, state);
  state->currentState = {0.0f, 0.0f};  // the emulated sticks rest at the centre
  state->changedSinceLastSync = XR_FALSE;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetActionStateVector2f)

XrResult XRAPI_CALL GetActionStatePose(XrSession session, const XrActionStateGetInfo* info,
                                       XrActionStatePose* state) {
  if (!state || state->type != XR_TYPE_ACTION_STATE_POSE) return XR_ERROR_VALIDATION_FAILURE;
  ActionStateData d;
  if (XrResult r = actionState(session, info, XR_ACTION_TYPE_POSE_INPUT, d); XR_FAILED(r)) return r;
  state->isActive = d.active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetActionStatePose)

XrResult haptic(XrSession session, const XrHapticActionInfo* info) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_HAPTIC_ACTION_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  Action* a = reinterpret_cast<Action*>(info->action);
  if (!inst->actions.count(a)) return XR_ERROR_HANDLE_INVALID;
  if (a->type != XR_ACTION_TYPE_VIBRATION_OUTPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (!s->actionStates.count(a)) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  if (!subactionAllowed(*a, info->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
  return sessionFocused(*s) ? XR_SUCCESS : XR_SESSION_NOT_FOCUSED;  // no motors to drive
}

XrResult XRAPI_CALL ApplyHapticFeedback(XrSession session, const XrHapticActionInfo* info,
                                        const XrHapticBaseHeader* h) {
  if (!h) return XR_ERROR_VALIDATION_FAILURE;
  return haptic(session, info);
}
EMBODY_XR_ENTRY(ApplyHapticFeedback)

XrResult XRAPI_CALL StopHapticFeedback(XrSession session, const XrHapticActionInfo* info) {
  return haptic(session, info);
}
EMBODY_XR_ENTRY(StopHapticFeedback)

XrResult XRAPI_CALL CreateActionSpace(XrSession session, const XrActionSpaceCreateInfo* ci, XrSpace* out) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_ACTION_SPACE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  Action* a = reinterpret_cast<Action*>(ci->action);
  if (!inst->actions.count(a)) return XR_ERROR_HANDLE_INVALID;
  if (a->type != XR_ACTION_TYPE_POSE_INPUT) return XR_ERROR_ACTION_TYPE_MISMATCH;
  if (!subactionAllowed(*a, ci->subactionPath)) return XR_ERROR_PATH_UNSUPPORTED;
  const Pose offset = fromXr(ci->poseInActionSpace);
  const auto& q = ci->poseInActionSpace.orientation;
  if (std::fabs(std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w) - 1.0f) > 1e-3f)
    return XR_ERROR_POSE_INVALID;
  if (s->lost) return XR_ERROR_SESSION_LOST;
  auto* sp = new Space;
  sp->session = s;
  sp->kind = SpaceKind::Action;
  sp->action = actionRef(a);
  sp->subaction = ci->subactionPath;
  sp->offset = offset;
  return publishHandle(s->spaces, sp, out);
}
EMBODY_XR_ENTRY(CreateActionSpace)

XrResult XRAPI_CALL EnumerateBoundSourcesForAction(XrSession session,
                                                   const XrBoundSourcesForActionEnumerateInfo* info,
                                                   uint32_t capacity, uint32_t* count, XrPath* sources) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_BOUND_SOURCES_FOR_ACTION_ENUMERATE_INFO)
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  Action* a = reinterpret_cast<Action*>(info->action);
  if (!inst->actions.count(a)) return XR_ERROR_HANDLE_INVALID;
  if (!s->actionStates.count(a)) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  std::vector<XrPath> list;
  if (auto it = inst->suggested.find(s->currentProfile); it != inst->suggested.end())
    for (const auto& [act, path] : it->second)
      if (act.get() == a) list.push_back(path);
  return twoCall(capacity, count, sources, list.size(), [&](XrPath* p, size_t i) { *p = list[i]; });
}
EMBODY_XR_ENTRY(EnumerateBoundSourcesForAction)

std::string titleCase(const std::string& s) {
  std::string out;
  bool up = true;
  for (char c : s) {
    if (c == '_' || c == '/') {
      out += ' ';
      up = true;
    } else {
      out += up ? static_cast<char>(std::toupper(static_cast<unsigned char>(c))) : c;
      up = false;
    }
  }
  return out;
}

XrResult XRAPI_CALL GetInputSourceLocalizedName(XrSession session,
                                                const XrInputSourceLocalizedNameGetInfo* info,
                                                uint32_t capacity, uint32_t* count, char* buffer) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_INPUT_SOURCE_LOCALIZED_NAME_GET_INFO || info->whichComponents == 0)
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (!s->actionSetsAttached) return XR_ERROR_ACTIONSET_NOT_ATTACHED;
  if (info->sourcePath == XR_NULL_PATH || info->sourcePath >= inst->paths.size())
    return XR_ERROR_PATH_INVALID;
  int hand = -1;
  std::string comp;
  if (!splitBinding(inst->pathString(info->sourcePath), hand, comp)) return XR_ERROR_PATH_UNSUPPORTED;
  std::string name;
  auto add = [&](const std::string& part) { name += (name.empty() ? "" : " ") + part; };
  if (info->whichComponents & XR_INPUT_SOURCE_LOCALIZED_NAME_USER_PATH_BIT)
    add(hand == 0 ? "Left Hand" : "Right Hand");
  if (info->whichComponents & XR_INPUT_SOURCE_LOCALIZED_NAME_INTERACTION_PROFILE_BIT)
    if (const ProfileInfo* p = findProfile(inst->pathString(s->currentProfile))) add(p->localized);
  if (info->whichComponents & XR_INPUT_SOURCE_LOCALIZED_NAME_COMPONENT_BIT)
    add(titleCase(comp.rfind("input/", 0) == 0 ? comp.substr(6) : comp));
  return twoCall(capacity, count, buffer, name.size() + 1,
                 [&](char* c, size_t i) { *c = i < name.size() ? name[i] : '\0'; });
}
EMBODY_XR_ENTRY(GetInputSourceLocalizedName)

// ---- XR_EXT_hand_tracking ----------------------------------------------------------------------

XrResult XRAPI_CALL CreateHandTrackerEXT(XrSession session, const XrHandTrackerCreateInfoEXT* ci,
                                         XrHandTrackerEXT* out) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_HAND_TRACKER_CREATE_INFO_EXT) return XR_ERROR_VALIDATION_FAILURE;
  if (ci->hand != XR_HAND_LEFT_EXT && ci->hand != XR_HAND_RIGHT_EXT) return XR_ERROR_VALIDATION_FAILURE;
  if (ci->handJointSet != XR_HAND_JOINT_SET_DEFAULT_EXT) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  auto* h = new HandTracker;
  h->session = s;
  h->hand = ci->hand;
  return publishHandle(s->handTrackers, h, out);
}
EMBODY_XR_ENTRY(CreateHandTrackerEXT)

XrResult XRAPI_CALL DestroyHandTrackerEXT(XrHandTrackerEXT tracker) {
  Instance* inst = nullptr;
  HandTracker* h = findHandTracker(tracker, &inst);
  if (!h) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  unregisterHandle(h->session->handTrackers, h);
  delete h;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroyHandTrackerEXT)

// Joints of one hand relative to `base` at time t; false when the hand or the base is not located.
bool handJointsRelative(Session& s, const Space& base, XrTime t, bool left,
                        std::array<HandJoint, 26>& joints) {
  const BodySample body = s.instance->poses.sample(traceSeconds(s, t));
  const TrackerPose& hand = left ? body.left : body.right;
  const Located b = locateInStage(s, base, t);
  if (!hand.valid || !b.valid) return false;
  handJointsFromGrip(hand, left, left ? body.leftTrigger : body.rightTrigger, joints);
  const Pose inv = b.pose.inverse();
  for (auto& j : joints) j.pose = inv * j.pose;
  return true;
}

XrResult XRAPI_CALL LocateHandJointsEXT(XrHandTrackerEXT tracker, const XrHandJointsLocateInfoEXT* info,
                                        XrHandJointLocationsEXT* locations) {
  Instance* inst = nullptr;
  HandTracker* h = findHandTracker(tracker, &inst);
  if (!h) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_HAND_JOINTS_LOCATE_INFO_EXT || !locations ||
      locations->type != XR_TYPE_HAND_JOINT_LOCATIONS_EXT ||
      locations->jointCount != XR_HAND_JOINT_COUNT_EXT || !locations->jointLocations)
    return XR_ERROR_VALIDATION_FAILURE;
  if (info->time <= 0) return XR_ERROR_TIME_INVALID;
  Space* base = findSpace(info->baseSpace);
  if (!base || base->session != h->session) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  Session& s = *h->session;
  if (s.lost) return XR_ERROR_SESSION_LOST;
  const bool left = h->hand == XR_HAND_LEFT_EXT;
  std::array<HandJoint, 26> joints;
  const bool ok = handJointsRelative(s, *base, info->time, left, joints);
  locations->isActive = ok ? XR_TRUE : XR_FALSE;
  for (uint32_t i = 0; i < XR_HAND_JOINT_COUNT_EXT; ++i) {
    auto& loc = locations->jointLocations[i];
    loc.locationFlags =
        ok ? (XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT |
              XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT | XR_SPACE_LOCATION_POSITION_TRACKED_BIT)
           : 0;
    loc.pose = toXr(ok ? joints[i].pose : Pose{});
    loc.radius = ok ? joints[i].radius : 0.0f;
  }
  for (auto* n = static_cast<XrBaseOutStructure*>(locations->next); n; n = n->next) {
    if (n->type != XR_TYPE_HAND_JOINT_VELOCITIES_EXT) continue;
    auto* v = reinterpret_cast<XrHandJointVelocitiesEXT*>(n);
    if (v->jointCount != XR_HAND_JOINT_COUNT_EXT || !v->jointVelocities) return XR_ERROR_VALIDATION_FAILURE;
    constexpr XrTime kDt = 5000000;
    std::array<HandJoint, 26> a, b;
    const bool okv = ok && handJointsRelative(s, *base, info->time - kDt, left, a) &&
                     handJointsRelative(s, *base, info->time + kDt, left, b);
    for (uint32_t i = 0; i < XR_HAND_JOINT_COUNT_EXT; ++i) {
      auto& jv = v->jointVelocities[i];
      jv.velocityFlags = okv ? XR_SPACE_VELOCITY_LINEAR_VALID_BIT : 0;  // angular: not estimated
      const glm::vec3 lin = okv ? (b[i].pose.position - a[i].pose.position) / (2.0f * kDt * 1e-9f) : glm::vec3(0.0f);
      jv.linearVelocity = {lin.x, lin.y, lin.z};
      jv.angularVelocity = {0, 0, 0};
    }
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(LocateHandJointsEXT)

}  // namespace

int handIndexForPath(Instance& inst, XrPath subaction) {
  const std::string& p = inst.pathString(subaction);
  if (p == "/user/hand/left") return 0;
  if (p == "/user/hand/right") return 1;
  return -1;
}

Located actionPoseInStage(Session& s, const Space& space, const BodySample& body) {
  Instance& inst = *s.instance;
  auto it = s.actionStates.find(space.action.get());
  if (it == s.actionStates.end()) return {};
  int hand = handIndexForPath(inst, space.subaction);
  if (space.subaction == XR_NULL_PATH)  // no subaction path: the first hand the action is bound to
    hand = it->second[0].active ? 0 : (it->second[1].active ? 1 : -1);
  if (hand < 0 || !it->second[hand].active) return {};
  const TrackerPose& tp = hand == 0 ? body.left : body.right;
  if (!tp.valid) return {};  // tracking lost: no location flags
  const auto comps = boundComponents(inst, s, space.action.get(), hand);
  const bool aim = !comps.empty() && comps.front().rfind("input/aim", 0) == 0;
  return {aim ? aimFromGrip(tp) : Pose(tp), true, true};
}

void forgetSessionActions(Session& s) {
  // Drops the session's references: a set whose handle is already destroyed may go with it. The
  // sets stay `attached` (the spec keeps a set immutable once it was attached, session or not).
  s.actionStates.clear();
  s.attachedSets.clear();
}

}  // namespace embody::xr_runtime
