// Loader negotiation, xrGetInstanceProcAddr, handle registry and enum strings.
#include <openxr/openxr_reflection.h>

#include <cstring>
#include <unordered_map>

#include "tools/xr_runtime/runtime.h"

// The loader <-> runtime interface (OpenXR loader design doc, "Runtime Interface Negotiation").
// Debian's 1.0.20 headers do not install loader_interfaces.h, so the structs are declared here
// with the exact layout the loader uses.
extern "C" {
enum XrLoaderInterfaceStructs {
  XR_LOADER_INTERFACE_STRUCT_UNINTIALIZED = 0,
  XR_LOADER_INTERFACE_STRUCT_LOADER_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_CREATE_INFO,
  XR_LOADER_INTERFACE_STRUCT_API_LAYER_NEXT_INFO,
};
constexpr uint32_t kLoaderInfoStructVersion = 1;
constexpr uint32_t kRuntimeInfoStructVersion = 1;
constexpr uint32_t kLoaderRuntimeInterfaceVersion = 1;

struct XrNegotiateLoaderInfo {
  XrLoaderInterfaceStructs structType;  // XR_LOADER_INTERFACE_STRUCT_LOADER_INFO
  uint32_t structVersion;               // kLoaderInfoStructVersion
  size_t structSize;                    // sizeof(XrNegotiateLoaderInfo)
  uint32_t minInterfaceVersion;
  uint32_t maxInterfaceVersion;
  XrVersion minApiVersion;
  XrVersion maxApiVersion;
};

struct XrNegotiateRuntimeRequest {
  XrLoaderInterfaceStructs structType;  // XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST
  uint32_t structVersion;               // kRuntimeInfoStructVersion
  size_t structSize;                    // sizeof(XrNegotiateRuntimeRequest)
  uint32_t runtimeInterfaceVersion;
  XrVersion runtimeApiVersion;
  PFN_xrGetInstanceProcAddr getInstanceProcAddr;
};

__attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* runtimeRequest);
}

namespace embody::xr_runtime {

namespace {

std::unordered_map<std::string, PFN_xrVoidFunction>& entryTable() {
  static std::unordered_map<std::string, PFN_xrVoidFunction> table;
  return table;
}

// Functions that need no instance (the spec lists exactly these for XR_NULL_HANDLE).
bool allowedWithoutInstance(const std::string& name) {
  return name == "xrEnumerateInstanceExtensionProperties" || name == "xrEnumerateApiLayerProperties" ||
         name == "xrCreateInstance";
}

// Extension entry points and the extension that must be enabled to get them.
const char* extensionOf(const std::string& name) {
  static const std::unordered_map<std::string, const char*> map = {
      {"xrCreateVulkanInstanceKHR", XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME},
      {"xrCreateVulkanDeviceKHR", XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME},
      {"xrGetVulkanGraphicsDevice2KHR", XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME},
      {"xrGetVulkanGraphicsRequirements2KHR", XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME},
      {"xrGetVulkanInstanceExtensionsKHR", XR_KHR_VULKAN_ENABLE_EXTENSION_NAME},
      {"xrGetVulkanDeviceExtensionsKHR", XR_KHR_VULKAN_ENABLE_EXTENSION_NAME},
      {"xrGetVulkanGraphicsDeviceKHR", XR_KHR_VULKAN_ENABLE_EXTENSION_NAME},
      {"xrGetVulkanGraphicsRequirementsKHR", XR_KHR_VULKAN_ENABLE_EXTENSION_NAME},
      {"xrCreateHandTrackerEXT", XR_EXT_HAND_TRACKING_EXTENSION_NAME},
      {"xrDestroyHandTrackerEXT", XR_EXT_HAND_TRACKING_EXTENSION_NAME},
      {"xrLocateHandJointsEXT", XR_EXT_HAND_TRACKING_EXTENSION_NAME},
      {"xrConvertTimespecTimeToTimeKHR", XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME},
      {"xrConvertTimeToTimespecTimeKHR", XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME},
  };
  auto it = map.find(name);
  return it == map.end() ? nullptr : it->second;
}

XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance instance, const char* name, PFN_xrVoidFunction* function) {
  if (!function) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
  if (!name) return XR_ERROR_VALIDATION_FAILURE;
  const std::string n = name;
  if (instance == XR_NULL_HANDLE) {
    if (!allowedWithoutInstance(n) && n != "xrGetInstanceProcAddr") return XR_ERROR_HANDLE_INVALID;
  } else {
    Instance* inst = findInstance(instance);
    if (!inst) return XR_ERROR_HANDLE_INVALID;
    // The function of an extension the application did not enable is "unsupported" (spec).
    if (const char* ext = extensionOf(n); ext && !inst->extension(ext)) return XR_ERROR_FUNCTION_UNSUPPORTED;
  }
  if (n == "xrGetInstanceProcAddr") {
    *function = reinterpret_cast<PFN_xrVoidFunction>(&GetInstanceProcAddr);
    return XR_SUCCESS;
  }
  const PFN_xrVoidFunction fn = lookupFunction(n);
  if (!fn) return XR_ERROR_FUNCTION_UNSUPPORTED;
  *function = fn;
  return XR_SUCCESS;
}

template <typename T>
T* findIn(void* handle, Instance** instOut, std::set<T*> Session::*member) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  for (Instance* inst : reg.instances)
    for (Session* s : inst->sessions)
      if ((s->*member).count(static_cast<T*>(handle))) {
        if (instOut) *instOut = inst;
        return static_cast<T*>(handle);
      }
  return nullptr;
}

}  // namespace

EntryRegistrar::EntryRegistrar(const char* name, PFN_xrVoidFunction fn) {
  entryTable()[name] = fn;
}

PFN_xrVoidFunction lookupFunction(const std::string& name) {
  auto it = entryTable().find(name);
  return it == entryTable().end() ? nullptr : it->second;
}

Registry& registry() {
  static Registry r;
  return r;
}

Instance* findInstance(XrInstance h) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  auto* p = reinterpret_cast<Instance*>(h);
  return reg.instances.count(p) ? p : nullptr;
}

Session* findSession(XrSession h, Instance** instOut) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  auto* p = reinterpret_cast<Session*>(h);
  for (Instance* inst : reg.instances)
    if (inst->sessions.count(p)) {
      if (instOut) *instOut = inst;
      return p;
    }
  return nullptr;
}

Space* findSpace(XrSpace h, Instance** inst) {
  return findIn<Space>(h, inst, &Session::spaces);
}
Swapchain* findSwapchain(XrSwapchain h, Instance** inst) {
  return findIn<Swapchain>(h, inst, &Session::swapchains);
}
HandTracker* findHandTracker(XrHandTrackerEXT h, Instance** inst) {
  return findIn<HandTracker>(h, inst, &Session::handTrackers);
}

ActionSet* findActionSet(XrActionSet h, Instance** instOut) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  auto* p = reinterpret_cast<ActionSet*>(h);
  for (Instance* inst : reg.instances)
    if (inst->actionSets.count(p)) {
      if (instOut) *instOut = inst;
      return p;
    }
  return nullptr;
}

Action* findAction(XrAction h, Instance** instOut) {
  auto& reg = registry();
  std::lock_guard lock(reg.mutex);
  auto* p = reinterpret_cast<Action*>(h);
  for (Instance* inst : reg.instances)
    if (inst->actions.count(p)) {
      if (instOut) *instOut = inst;
      return p;
    }
  return nullptr;
}

// The registry's X-macros expand to case labels, which clang-format cannot lay out.
// clang-format off
const char* resultName(XrResult r) {
  switch (r) {
#define EMBODY_XR_ENUM_CASE(name, value) case name: return #name;
    XR_LIST_ENUM_XrResult(EMBODY_XR_ENUM_CASE)
    default: return nullptr;
  }
}

const char* structureTypeName(XrStructureType t) {
  switch (t) {
    XR_LIST_ENUM_XrStructureType(EMBODY_XR_ENUM_CASE)
#undef EMBODY_XR_ENUM_CASE
    default: return nullptr;
  }
}
// clang-format on

}  // namespace embody::xr_runtime

extern "C" XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* loaderInfo,
                                                      XrNegotiateRuntimeRequest* runtimeRequest) {
  if (!loaderInfo || !runtimeRequest) return XR_ERROR_INITIALIZATION_FAILED;
  if (loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      loaderInfo->structVersion != kLoaderInfoStructVersion ||
      loaderInfo->structSize != sizeof(XrNegotiateLoaderInfo))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (runtimeRequest->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST ||
      runtimeRequest->structVersion != kRuntimeInfoStructVersion ||
      runtimeRequest->structSize != sizeof(XrNegotiateRuntimeRequest))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (loaderInfo->minInterfaceVersion > kLoaderRuntimeInterfaceVersion ||
      loaderInfo->maxInterfaceVersion < kLoaderRuntimeInterfaceVersion)
    return XR_ERROR_INITIALIZATION_FAILED;
  // We implement OpenXR 1.0; the loader asks for a range of API versions.
  const XrVersion ours = XR_CURRENT_API_VERSION;
  if (XR_VERSION_MAJOR(loaderInfo->minApiVersion) > 1 || XR_VERSION_MAJOR(loaderInfo->maxApiVersion) < 1)
    return XR_ERROR_INITIALIZATION_FAILED;
  runtimeRequest->runtimeInterfaceVersion = kLoaderRuntimeInterfaceVersion;
  runtimeRequest->runtimeApiVersion = ours;
  runtimeRequest->getInstanceProcAddr = &embody::xr_runtime::GetInstanceProcAddr;
  return XR_SUCCESS;
}
