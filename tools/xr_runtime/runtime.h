#pragma once
// Internal header of the Embody headless OpenXR runtime (libembody_xr_runtime.so).
//
// A complete-enough OpenXR 1.0 runtime for CI: no display, no compositor. The real OpenXR loader
// loads it through its manifest (XR_RUNTIME_JSON); the application renders into swapchain images
// that this runtime creates on the application's own VkDevice (XR_KHR_vulkan_enable2), and
// xrEndFrame can read the left eye back to PNG (EMBODY_XR_CAPTURE). Poses come from a pose file
// (EMBODY_XR_POSES: a JSON Lines trace or a BVH clip, read by the project's own readers in
// embody_tracking, linked in position-independent) or a gentle synthetic motion. Only the loader
// entry point is exported, so the linked-in libraries never clash with the host's copies.
//
// Threading: one mutex per instance guards all runtime state; xrWaitFrame sleeps without it.
#include <vulkan/vulkan.h>
#define XR_NO_PROTOTYPES
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include <array>
#include <condition_variable>
#include <ctime>
#include <deque>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <iosfwd>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "tracking/tracker.h"
#include "xr/xr_pose.h"

namespace embody::xr_runtime {

// ---- poses ---------------------------------------------------------------------------------

// The project's one pose type (tracking/tracker.h) and the conversions from and to OpenXR's.
using tracking::Pose;
using tracking::TrackerPose;
using xr::fromXr;  // xr/xr_pose.h: a non-finite pose becomes identity
using xr::toXr;

// One sample of the tracked body, in STAGE space (floor origin), OpenXR conventions.
struct BodySample {
  double t = 0.0;  // seconds from the start of the trace
  TrackerPose head, left, right;
  float leftTrigger = 0.0f, rightTrigger = 0.0f;
};

// Where poses come from: a pose file (looped) or the synthetic default motion.
class PoseProvider {
 public:
  // Reads EMBODY_XR_POSES (a .bvh, else a JSON Lines trace); on a broken file, error() says why
  // and the synthetic motion is used.
  void loadFromEnvironment();
  void use(std::vector<BodySample> samples, std::string source);  // samples from a parse* below
  BodySample sample(double seconds) const;  // seconds since the session began
  const std::string& error() const { return error_; }
  const std::string& source() const { return source_; }

 private:
  std::vector<BodySample> samples_;
  std::string error_, source_ = "synthetic";
};

// The EMBODY_XR_POSES readers: text in, samples out, "" or why it failed (naming `name`). They
// are the project's own readers (tracking::parseTrace; avatar::parseBvh + tracking::bvhToTrace,
// the performer scaled to 1.75 m), whose hostile-input limits and errors apply; accepted samples
// have non-decreasing finite times within a day of the first, and a valid pose is finite with a
// unit quaternion. Fuzzed by fuzz/fuzz_xr_poses.cpp.
//   JSON Lines: tracking/trace.h's format; the hands' optional "trigger" (0..1) curls the fingers.
std::string parseTraceSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out);
// BVH motion capture (head, hands) as samples in OpenXR conventions.
std::string parseBvhSamples(std::istream& in, const std::string& name, std::vector<BodySample>& out);

// The 26 XR_EXT_hand_tracking joints of a hand holding a controller at `grip`; poses in the same
// space as the grip, radius in metres. `curl` (0..1, the trace's per-hand "trigger") bends each
// finger joint of index..little by 12 + 60 * curl degrees towards the palm: 0 a relaxed hand, 1 a
// fist. The thumb does not curl. Each joint's +Y is the back of its finger (carried joint to
// joint, so it stays there past 90 degrees).
struct HandJoint {
  Pose pose;
  float radius = 0.01f;
};
void handJointsFromGrip(const Pose& grip, bool leftHand, float curl, std::array<HandJoint, 26>& out);
// The aim pose of a controller held at `grip` (a ray from the index finger, pitched down a bit).
Pose aimFromGrip(const Pose& grip);

// ---- objects -------------------------------------------------------------------------------

constexpr XrTime kFramePeriodNs = 11111111;  // 90 Hz
constexpr XrSystemId kSystemId = 1;

struct Instance;
struct Session;

// Action sets and actions outlive their handles. xrDestroyActionSet and xrDestroyAction only take
// the application's access away: the spec forbids freeing what other valid handles still use
// (the sessions the set is attached to, action spaces, suggested bindings), and applications do
// destroy action sets before their session. So a set is shared: the instance holds it while its
// handle lives, and every session it is attached to, every action space of one of its actions
// and every suggested binding naming one holds it too. A set owns its actions; an ActionRef keeps
// an action alive by sharing its set.
struct Action;
struct ActionSet : std::enable_shared_from_this<ActionSet> {
  Instance* instance = nullptr;
  std::string name, localizedName;
  uint32_t priority = 0;
  bool attached = false;  // included in an xrAttachSessionActionSets call: immutable for good
  std::vector<std::unique_ptr<Action>> actions;  // every action created in it, handle live or not
};

struct Action {
  ActionSet* set = nullptr;  // the set that owns this action
  std::string name, localizedName;
  XrActionType type = XR_ACTION_TYPE_BOOLEAN_INPUT;
  std::vector<XrPath> subactionPaths;
};

using ActionRef = std::shared_ptr<const Action>;
inline ActionRef actionRef(const Action* a) {
  return ActionRef(a->set->shared_from_this(), a);  // aliasing: shares the owning set's lifetime
}

// Per-action state kept for each hand (0 left, 1 right) after xrSyncActions.
struct ActionStateData {
  bool active = false;
  float value = 0.0f;
  bool changed = false;
  XrTime lastChange = 0;
};

enum class SpaceKind { Reference, Action };

struct Space {
  Session* session = nullptr;
  SpaceKind kind = SpaceKind::Reference;
  XrReferenceSpaceType refType = XR_REFERENCE_SPACE_TYPE_STAGE;
  ActionRef action;  // action spaces: kept alive past xrDestroyAction(Set)
  XrPath subaction = XR_NULL_PATH;
  Pose offset;
};

struct Swapchain {
  Session* session = nullptr;
  XrSwapchainCreateInfo info{};
  VkFormat format = VK_FORMAT_UNDEFINED;
  bool depth = false;
  std::vector<VkImage> images;
  std::vector<VkDeviceMemory> memory;
  std::deque<uint32_t> acquired;  // acquired, in order
  uint32_t nextIndex = 0;
  bool waited = false;            // the oldest acquired image was waited on
  int64_t lastReleased = -1;      // index of the most recently released image
  std::vector<bool> initialized;  // moved out of VK_IMAGE_LAYOUT_UNDEFINED yet
};

struct HandTracker {
  Session* session = nullptr;
  XrHandEXT hand = XR_HAND_LEFT_EXT;
};

struct Session {
  Instance* instance = nullptr;
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false;        // between xrBeginSession and xrEndSession
  bool exitRequested = false;  // xrRequestExitSession or EMBODY_XR_FRAMES reached
  bool lost = false;
  XrTime startTime = 0;   // session creation: the 90 Hz display grid's anchor
  // Trace time 0 (EMBODY_XR_POSES): the session's first xrWaitFrame, not its creation, so an
  // application that takes long to start (pipelines compiled on a loaded machine) still sees a
  // trace from its beginning; 0 until then (trace time counts from startTime).
  XrTime traceStart = 0;
  // Vulkan binding (application objects; the runtime only borrows them).
  VkInstance vkInstance = VK_NULL_HANDLE;
  VkPhysicalDevice vkPhysicalDevice = VK_NULL_HANDLE;
  VkDevice vkDevice = VK_NULL_HANDLE;
  uint32_t queueFamily = 0, queueIndex = 0;
  VkQueue queue = VK_NULL_HANDLE;
  VkCommandPool cmdPool = VK_NULL_HANDLE;
  // Frame loop.
  uint64_t framesWaited = 0, framesBegun = 0, framesEnded = 0;
  bool frameBegun = false;
  uint64_t waitedNotBegun = 0;  // xrWaitFrame calls not yet matched by xrBeginFrame
  // A second xrWaitFrame blocks on this until the previous frame is begun (or the session stops).
  std::condition_variable_any frameBegun_cv;
  XrTime lastPredicted = 0;
  // Actions.
  bool actionSetsAttached = false;
  std::vector<std::shared_ptr<ActionSet>> attachedSets;  // alive while attached, handles or not
  std::map<const Action*, std::array<ActionStateData, 2>> actionStates;  // actions of attachedSets
  XrPath currentProfile = XR_NULL_PATH;
  std::set<Space*> spaces;
  std::set<Swapchain*> swapchains;
  std::set<HandTracker*> handTrackers;
  std::string captureDir;
  uint64_t frameLimit = 0;  // EMBODY_XR_FRAMES, 0 = none
  uint64_t lossAt = 0;      // EMBODY_XR_LOSS_FRAMES: LOSS_PENDING after this many frames
  uint64_t spaceChangeAt = 0;  // EMBODY_XR_SPACE_CHANGE_FRAMES: REFERENCE_SPACE_CHANGE_PENDING (LOCAL, STAGE)
  // EMBODY_XR_HEAD_UNTRACKED=1: the head is located valid but never tracked (position and
  // orientation), as Monado's simulated HMD and 3-dof headsets report it.
  bool headUntracked = false;
  uint32_t capturedFrames = 0;
  Pose localOrigin;      // LOCAL space in STAGE: the head at session start, yaw only
  TrackerPose lastHead;  // last valid head pose, reported (untracked) while tracking is lost
};

struct Event {
  XrEventDataBuffer data;
};

struct Instance {
  std::recursive_mutex mutex;
  std::set<std::string> enabledExtensions;
  std::string applicationName;
  bool systemQueried = false;
  bool graphicsRequirementsQueried = false;
  std::vector<std::string> paths{""};  // XrPath n -> paths[n]; 0 is XR_NULL_PATH
  std::map<std::string, XrPath> pathIds;
  // Live handles (what the handle lookups accept). The instance's reference to a set goes with its
  // handle; the set itself lives on while anything else uses it (ActionSet above).
  std::map<ActionSet*, std::shared_ptr<ActionSet>> actionSets;
  std::set<Action*> actions;
  // Suggested bindings per interaction profile: (action, binding path) pairs.
  std::map<XrPath, std::vector<std::pair<ActionRef, XrPath>>> suggested;
  std::set<Session*> sessions;
  std::deque<Event> events;
  PoseProvider poses;
  VkInstance createdVkInstance = VK_NULL_HANDLE;
  bool extension(const char* name) const { return enabledExtensions.count(name) != 0; }
  XrPath path(const std::string& s);  // interns
  const std::string& pathString(XrPath p) const;
  void pushEvent(const void* eventStruct, size_t size);
  void setState(Session& s, XrSessionState state, XrTime time);
};

// ---- handle validation (the runtime never dereferences an unknown handle) --------------------

struct Registry {
  std::mutex mutex;
  std::set<Instance*> instances;
};
Registry& registry();
// Handle sets are read by the find* functions under the registry's lock: objects enter and leave
// them under it. publishHandle also hands the new object to the application as its handle.
template <class T>
void registerHandle(std::set<T*>& handles, T* object) {
  std::lock_guard rlock(registry().mutex);
  handles.insert(object);
}
template <class T>
void unregisterHandle(std::set<T*>& handles, T* object) {
  std::lock_guard rlock(registry().mutex);
  handles.erase(object);
}
template <class Handle, class T>
XrResult publishHandle(std::set<T*>& handles, T* object, Handle* out) {
  registerHandle(handles, object);
  *out = reinterpret_cast<Handle>(object);
  return XR_SUCCESS;
}
Instance* findInstance(XrInstance h);  // nullptr when not live
Session* findSession(XrSession h, Instance** inst = nullptr);
Space* findSpace(XrSpace h, Instance** inst = nullptr);
Swapchain* findSwapchain(XrSwapchain h, Instance** inst = nullptr);
ActionSet* findActionSet(XrActionSet h, Instance** inst = nullptr);
Action* findAction(XrAction h, Instance** inst = nullptr);
HandTracker* findHandTracker(XrHandTrackerEXT h, Instance** inst = nullptr);

XrTime nowNs();
double traceSeconds(const Session& s, XrTime t);
// Pose of a space in STAGE at time t; valid/tracked flags.
struct Located {
  Pose pose;
  bool valid = false, tracked = false;
};
Located locateInStage(Session& s, const Space& space, XrTime t);
int handIndexForPath(Instance& inst, XrPath subaction);  // 0 left, 1 right, -1 other

// Lookup of every implemented entry point by name (nullptr when not implemented).
PFN_xrVoidFunction lookupFunction(const std::string& name);

// Strings for enums (xrResultToString, xrStructureTypeToString).
const char* resultName(XrResult r);
const char* structureTypeName(XrStructureType t);

// Vulkan helpers used by the session (vulkan.cpp).
void destroySwapchainImages(Swapchain& sc);
void captureLeftEye(Session& s, Swapchain& sc, uint32_t imageIndex, const XrRect2Di& rect,
                    uint32_t arrayIndex);
void releaseSessionVulkan(Session& s);
// Deletes a session's swapchains (and their images), spaces and hand trackers (session.cpp).
void destroySessionChildren(Session& s);
bool initSessionVulkan(Session& s);  // queue + command pool on the application's device

// Action poses (actions.cpp): the pose of an action space's action in STAGE from a body sample.
Located actionPoseInStage(Session& s, const Space& space, const BodySample& body);
// Resets per-session action state (session destruction).
void forgetSessionActions(Session& s);

}  // namespace embody::xr_runtime

// Every implemented entry point registers itself by name; EMBODY_XR_ENTRY(CreateInstance) checks
// the signature against PFN_xrCreateInstance at compile time.
namespace embody::xr_runtime {
struct EntryRegistrar {
  EntryRegistrar(const char* name, PFN_xrVoidFunction fn);
};
}  // namespace embody::xr_runtime
#define EMBODY_XR_ENTRY(fn)                                                        \
  static_assert(std::is_same_v<decltype(&fn), PFN_xr##fn>, "signature of xr" #fn); \
  static const ::embody::xr_runtime::EntryRegistrar registrar_##fn("xr" #fn,             \
                                                             reinterpret_cast<PFN_xrVoidFunction>(&fn));
