// Instance, system, view configurations, paths, events and strings.
#include <cstdio>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <ctime>

#include "tools/xr_runtime/runtime.h"
#include "tools/xr_runtime/two_call.h"

namespace embody::xr_runtime {

namespace {

struct ExtensionInfo {
  const char* name;
  uint32_t version;
};
constexpr ExtensionInfo kExtensions[] = {
    {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME, 2},        {XR_KHR_VULKAN_ENABLE_EXTENSION_NAME, 8},
    {XR_EXT_HAND_TRACKING_EXTENSION_NAME, 4},         {XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME, 5},
    {XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME, 1},
};

bool validPathString(const std::string& s) {
  if (s.size() < 2 || s.front() != '/' || s.back() == '/' || s.size() >= XR_MAX_PATH_LENGTH) return false;
  size_t start = 1;
  while (start <= s.size()) {
    size_t end = s.find('/', start);
    if (end == std::string::npos) end = s.size();
    const std::string part = s.substr(start, end - start);
    if (part.empty() || part == "." || part == "..") return false;
    for (char c : part)
      if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.'))
        return false;
    start = end + 1;
  }
  return true;
}

void copyString(char* dst, size_t cap, const std::string& s) {
  std::snprintf(dst, cap, "%s", s.c_str());
}

// Per-eye render size: EMBODY_XR_VIEW_SIZE=WxH, default 512x560 (small on purpose: lavapipe).
void viewSize(uint32_t& w, uint32_t& h) {
  w = 512;
  h = 560;
  if (const char* e = std::getenv("EMBODY_XR_VIEW_SIZE")) {
    unsigned a = 0, b = 0;
    if (std::sscanf(e, "%ux%u", &a, &b) == 2 && a >= 16 && b >= 16 && a <= 4096 && b <= 4096) {
      w = a;
      h = b;
    }
  }
}

namespace {

// The runtime's test settings, checked once at xrCreateInstance: a malformed one is refused, not
// read as its default. EMBODY_XR_FRAMES=30x was read as "no limit" and left hello_xr running until
// its CI job's timeout; a bad view size or IPD quietly became the default (OpenXR robustness
// probe, session 20). Returns "" when every set variable is well formed.
std::string environmentProblem() {
  for (const char* name : {"EMBODY_XR_FRAMES", "EMBODY_XR_LOSS_FRAMES", "EMBODY_XR_SPACE_CHANGE_FRAMES",
                           "EMBODY_XR_HEAD_UNTRACKED"}) {
    const char* e = std::getenv(name);
    if (!e || !*e) continue;
    char* end = nullptr;
    errno = 0;
    (void)std::strtoull(e, &end, 10);
    if (!std::isdigit(static_cast<unsigned char>(e[0])) || *end != '\0' || errno == ERANGE)
      return std::string(name) + "='" + e + "' is not a whole number of frames";
  }
  if (const char* e = std::getenv("EMBODY_XR_VIEW_SIZE"); e && *e) {
    unsigned a = 0, b = 0;
    char tail = 0;
    if (std::sscanf(e, "%ux%u%c", &a, &b, &tail) != 2 || a < 16 || b < 16 || a > 4096 || b > 4096)
      return std::string("EMBODY_XR_VIEW_SIZE='") + e + "' is not WIDTHxHEIGHT with each 16 .. 4096";
  }
  if (const char* e = std::getenv("EMBODY_XR_IPD"); e && *e) {
    char* end = nullptr;
    const float v = std::strtof(e, &end);
    if (*end != '\0' || !std::isfinite(v) || v <= 0.04f || v >= 0.09f)
      return std::string("EMBODY_XR_IPD='") + e + "' is not an interpupillary distance in metres (0.04 .. 0.09)";
  }
  return "";
}

}  // namespace

XrResult XRAPI_CALL EnumerateInstanceExtensionProperties(const char* layerName, uint32_t capacity,
                                                         uint32_t* count, XrExtensionProperties* props) {
  if (layerName && *layerName) return XR_ERROR_API_LAYER_NOT_PRESENT;
  const size_t n = std::size(kExtensions);
  if (props)
    for (uint32_t i = 0; i < capacity && i < n; ++i)
      if (props[i].type != XR_TYPE_EXTENSION_PROPERTIES) return XR_ERROR_VALIDATION_FAILURE;
  return twoCall(capacity, count, props, n, [&](XrExtensionProperties* p, size_t i) {
    copyString(p->extensionName, XR_MAX_EXTENSION_NAME_SIZE, kExtensions[i].name);
    p->extensionVersion = kExtensions[i].version;
  });
}
EMBODY_XR_ENTRY(EnumerateInstanceExtensionProperties)

XrResult XRAPI_CALL CreateInstance(const XrInstanceCreateInfo* ci, XrInstance* out) {
  if (!ci || !out || ci->type != XR_TYPE_INSTANCE_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (ci->applicationInfo.applicationName[0] == '\0') return XR_ERROR_NAME_INVALID;
  if (XR_VERSION_MAJOR(ci->applicationInfo.apiVersion) != 1) return XR_ERROR_API_VERSION_UNSUPPORTED;
  if (const std::string problem = environmentProblem(); !problem.empty()) {
    std::fprintf(stderr, "embody headless runtime: %s; fix or unset it\n", problem.c_str());
    return XR_ERROR_INITIALIZATION_FAILED;
  }
  auto inst = std::make_unique<Instance>();
  for (uint32_t i = 0; i < ci->enabledExtensionCount; ++i) {
    const char* name = ci->enabledExtensionNames[i];
    bool known = false;
    for (const auto& e : kExtensions) known = known || (name && std::strcmp(name, e.name) == 0);
    if (!known) return XR_ERROR_EXTENSION_NOT_PRESENT;
    inst->enabledExtensions.insert(name);
  }
  inst->applicationName = ci->applicationInfo.applicationName;
  inst->poses.loadFromEnvironment();
  if (!inst->poses.error().empty())
    std::fprintf(stderr, "embody headless runtime: %s; using the synthetic motion\n",
                 inst->poses.error().c_str());
  Instance* raw = inst.release();
  {
    std::lock_guard lock(registry().mutex);
    registry().instances.insert(raw);
  }
  *out = reinterpret_cast<XrInstance>(raw);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(CreateInstance)

XrResult XRAPI_CALL DestroyInstance(XrInstance instance) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  // Child objects go with their parent (spec); sessions release what they own on the app device.
  std::vector<Session*> sessions(inst->sessions.begin(), inst->sessions.end());
  for (Session* s : sessions) {
    destroySessionChildren(*s);
    releaseSessionVulkan(*s);
    delete s;
  }
  // Action sets (and their actions) go with the instance's last references to them: its live
  // handles and suggested bindings, released with `inst` below.
  {
    std::lock_guard lock(registry().mutex);
    registry().instances.erase(inst);
  }
  delete inst;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroyInstance)

XrResult XRAPI_CALL GetInstanceProperties(XrInstance instance, XrInstanceProperties* props) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (!props || props->type != XR_TYPE_INSTANCE_PROPERTIES) return XR_ERROR_VALIDATION_FAILURE;
  props->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
  copyString(props->runtimeName, XR_MAX_RUNTIME_NAME_SIZE, "Embody headless runtime");
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetInstanceProperties)

XrResult XRAPI_CALL PollEvent(XrInstance instance, XrEventDataBuffer* buffer) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!buffer || buffer->type != XR_TYPE_EVENT_DATA_BUFFER) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (inst->events.empty()) return XR_EVENT_UNAVAILABLE;
  std::memcpy(buffer, &inst->events.front().data, sizeof(XrEventDataBuffer));
  inst->events.pop_front();
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(PollEvent)

XrResult XRAPI_CALL ResultToString(XrInstance instance, XrResult value,
                                   char buffer[XR_MAX_RESULT_STRING_SIZE]) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (!buffer) return XR_ERROR_VALIDATION_FAILURE;
  if (const char* n = resultName(value))
    copyString(buffer, XR_MAX_RESULT_STRING_SIZE, n);
  else
    std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "XR_%s_%d",
                  value < 0 ? "UNKNOWN_FAILURE" : "UNKNOWN_SUCCESS", static_cast<int>(value));
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(ResultToString)

XrResult XRAPI_CALL StructureTypeToString(XrInstance instance, XrStructureType value,
                                          char buffer[XR_MAX_STRUCTURE_NAME_SIZE]) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (!buffer) return XR_ERROR_VALIDATION_FAILURE;
  if (const char* n = structureTypeName(value))
    copyString(buffer, XR_MAX_STRUCTURE_NAME_SIZE, n);
  else
    std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "XR_UNKNOWN_STRUCTURE_TYPE_%d",
                  static_cast<int>(value));
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(StructureTypeToString)

XrResult XRAPI_CALL GetSystem(XrInstance instance, const XrSystemGetInfo* info, XrSystemId* systemId) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!info || !systemId || info->type != XR_TYPE_SYSTEM_GET_INFO) return XR_ERROR_VALIDATION_FAILURE;
  if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY) {
    if (info->formFactor == XR_FORM_FACTOR_HANDHELD_DISPLAY) return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
    return XR_ERROR_VALIDATION_FAILURE;
  }
  std::lock_guard lock(inst->mutex);
  inst->systemQueried = true;
  *systemId = kSystemId;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetSystem)

XrResult XRAPI_CALL GetSystemProperties(XrInstance instance, XrSystemId systemId, XrSystemProperties* props) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (!props || props->type != XR_TYPE_SYSTEM_PROPERTIES) return XR_ERROR_VALIDATION_FAILURE;
  props->systemId = kSystemId;
  props->vendorId = 0x454d;  // "EM"
  copyString(props->systemName, XR_MAX_SYSTEM_NAME_SIZE, "Embody headless HMD");
  props->graphicsProperties.maxSwapchainImageWidth = 4096;
  props->graphicsProperties.maxSwapchainImageHeight = 4096;
  props->graphicsProperties.maxLayerCount = XR_MIN_COMPOSITION_LAYERS_SUPPORTED;
  props->trackingProperties.orientationTracking = XR_TRUE;
  props->trackingProperties.positionTracking = XR_TRUE;
  for (auto* n = static_cast<XrBaseOutStructure*>(props->next); n; n = n->next)
    if (n->type == XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT)
      reinterpret_cast<XrSystemHandTrackingPropertiesEXT*>(n)->supportsHandTracking =
          inst->extension(XR_EXT_HAND_TRACKING_EXTENSION_NAME) ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetSystemProperties)

XrResult XRAPI_CALL EnumerateEnvironmentBlendModes(XrInstance instance, XrSystemId systemId,
                                                   XrViewConfigurationType viewConfig, uint32_t capacity,
                                                   uint32_t* count, XrEnvironmentBlendMode* modes) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (viewConfig != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  return twoCall(capacity, count, modes, 1,
                 [](XrEnvironmentBlendMode* m, size_t) { *m = XR_ENVIRONMENT_BLEND_MODE_OPAQUE; });
}
EMBODY_XR_ENTRY(EnumerateEnvironmentBlendModes)

XrResult XRAPI_CALL EnumerateViewConfigurations(XrInstance instance, XrSystemId systemId, uint32_t capacity,
                                                uint32_t* count, XrViewConfigurationType* types) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  return twoCall(capacity, count, types, 1,
                 [](XrViewConfigurationType* t, size_t) { *t = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO; });
}
EMBODY_XR_ENTRY(EnumerateViewConfigurations)

XrResult XRAPI_CALL GetViewConfigurationProperties(XrInstance instance, XrSystemId systemId,
                                                   XrViewConfigurationType type,
                                                   XrViewConfigurationProperties* props) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (!props || props->type != XR_TYPE_VIEW_CONFIGURATION_PROPERTIES) return XR_ERROR_VALIDATION_FAILURE;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  props->viewConfigurationType = type;
  props->fovMutable = XR_FALSE;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(GetViewConfigurationProperties)

XrResult XRAPI_CALL EnumerateViewConfigurationViews(XrInstance instance, XrSystemId systemId,
                                                    XrViewConfigurationType type, uint32_t capacity,
                                                    uint32_t* count, XrViewConfigurationView* views) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  if (views)
    for (uint32_t i = 0; i < capacity && i < 2; ++i)
      if (views[i].type != XR_TYPE_VIEW_CONFIGURATION_VIEW) return XR_ERROR_VALIDATION_FAILURE;
  uint32_t w, h;
  viewSize(w, h);
  return twoCall(capacity, count, views, 2, [&](XrViewConfigurationView* v, size_t) {
    v->recommendedImageRectWidth = w;
    v->recommendedImageRectHeight = h;
    v->maxImageRectWidth = 4096;
    v->maxImageRectHeight = 4096;
    v->recommendedSwapchainSampleCount = 1;
    v->maxSwapchainSampleCount = 1;
  });
}
EMBODY_XR_ENTRY(EnumerateViewConfigurationViews)

XrResult XRAPI_CALL StringToPath(XrInstance instance, const char* pathString, XrPath* path) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!pathString || !path) return XR_ERROR_VALIDATION_FAILURE;
  if (!validPathString(pathString)) return XR_ERROR_PATH_FORMAT_INVALID;
  std::lock_guard lock(inst->mutex);
  *path = inst->path(pathString);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(StringToPath)

XrResult XRAPI_CALL PathToString(XrInstance instance, XrPath path, uint32_t capacity, uint32_t* count,
                                 char* buffer) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  if (path == XR_NULL_PATH || path >= inst->paths.size()) return XR_ERROR_PATH_INVALID;
  const std::string& s = inst->paths[path];
  return twoCall(capacity, count, buffer, s.size() + 1,
                 [&](char* c, size_t i) { *c = i < s.size() ? s[i] : '\0'; });
}
EMBODY_XR_ENTRY(PathToString)

XrResult XRAPI_CALL ConvertTimespecTimeToTimeKHR(XrInstance instance, const struct timespec* ts,
                                                 XrTime* time) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (!ts || !time) return XR_ERROR_VALIDATION_FAILURE;
  *time = static_cast<XrTime>(ts->tv_sec) * 1000000000 + ts->tv_nsec;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(ConvertTimespecTimeToTimeKHR)

XrResult XRAPI_CALL ConvertTimeToTimespecTimeKHR(XrInstance instance, XrTime time, struct timespec* ts) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (!ts) return XR_ERROR_VALIDATION_FAILURE;
  if (time <= 0) return XR_ERROR_TIME_INVALID;
  ts->tv_sec = static_cast<time_t>(time / 1000000000);
  ts->tv_nsec = static_cast<long>(time % 1000000000);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(ConvertTimeToTimespecTimeKHR)

}  // namespace

XrPath Instance::path(const std::string& s) {
  auto it = pathIds.find(s);
  if (it != pathIds.end()) return it->second;
  paths.push_back(s);
  const XrPath id = paths.size() - 1;
  pathIds[s] = id;
  return id;
}

const std::string& Instance::pathString(XrPath p) const {
  static const std::string empty;
  return p < paths.size() ? paths[p] : empty;
}

void Instance::pushEvent(const void* eventStruct, size_t size) {
  Event e{};
  std::memcpy(&e.data, eventStruct, std::min(size, sizeof(XrEventDataBuffer)));
  events.push_back(e);
}

void Instance::setState(Session& s, XrSessionState state, XrTime time) {
  if (s.state == state) return;
  s.state = state;
  XrEventDataSessionStateChanged ev{XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED};
  ev.session = reinterpret_cast<XrSession>(&s);
  ev.state = state;
  ev.time = time;
  pushEvent(&ev, sizeof(ev));
}

XrTime nowNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<XrTime>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

}  // namespace embody::xr_runtime
