#include "xr/xr_system.h"

#include <cstdio>
#include <cstring>

#include "engine/device.h"
#include "engine/instance.h"

namespace embody::xr {

namespace {

// Same rule as engine::Instance: loader notices are not validation findings.
VKAPI_ATTR VkBool32 VKAPI_CALL countMessage(VkDebugUtilsMessageSeverityFlagBitsEXT,
                                            VkDebugUtilsMessageTypeFlagsEXT type,
                                            const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  if (type == VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT && data->pMessageIdName &&
      std::strcmp(data->pMessageIdName, "Loader Message") == 0)
    return VK_FALSE;
  static_cast<std::atomic<uint32_t>*>(user)->fetch_add(1);
  std::fprintf(stderr, "[vulkan] %s: %s\n", data->pMessageIdName ? data->pMessageIdName : "",
               data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

bool hasExtension(const std::vector<XrExtensionProperties>& exts, const char* name) {
  for (const auto& e : exts)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

}  // namespace

Result<std::unique_ptr<XrSystem>> XrSystem::create(const XrSystemOptions& options) {
  std::unique_ptr<XrSystem> s(new XrSystem());
  if (auto st = s->createInstance(options); !st) return Error{st.error()};
  if (auto st = s->createVulkan(options); !st) return Error{st.error()};
  return s;
}

Status XrSystem::createInstance(const XrSystemOptions& o) {
  uint32_t n = 0;
  if (XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &n, nullptr); XR_FAILED(r))
    return Error{"no OpenXR runtime is available (" + resultString(XR_NULL_HANDLE, r) +
                 "); set XR_RUNTIME_JSON or install a runtime (embody doctor shows what the loader finds)"};
  std::vector<XrExtensionProperties> exts(n, {XR_TYPE_EXTENSION_PROPERTIES});
  xrEnumerateInstanceExtensionProperties(nullptr, n, &n, exts.data());
  if (!hasExtension(exts, XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME))
    return Error{"the OpenXR runtime does not offer XR_KHR_vulkan_enable2, which Embody renders through"};
  std::vector<const char*> enable = {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME};
  handTracking_ = o.handTracking && hasExtension(exts, XR_EXT_HAND_TRACKING_EXTENSION_NAME);
  if (handTracking_) enable.push_back(XR_EXT_HAND_TRACKING_EXTENSION_NAME);
  depthLayer_ = hasExtension(exts, XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
  if (depthLayer_) enable.push_back(XR_KHR_COMPOSITION_LAYER_DEPTH_EXTENSION_NAME);
  // Tracker-to-photon ages need the runtime's "now" (XrTime); optional.
  const bool timespec = hasExtension(exts, XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME);
  if (timespec) enable.push_back(XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME);

  XrInstanceCreateInfo ci{XR_TYPE_INSTANCE_CREATE_INFO};
  std::snprintf(ci.applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE, "%s", o.appName.c_str());
  std::snprintf(ci.applicationInfo.engineName, XR_MAX_ENGINE_NAME_SIZE, "embody");
  ci.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
  ci.enabledExtensionCount = static_cast<uint32_t>(enable.size());
  ci.enabledExtensionNames = enable.data();
  if (XrResult r = xrCreateInstance(&ci, &instance_); XR_FAILED(r))
    return Error{"xrCreateInstance failed: " + resultString(XR_NULL_HANDLE, r)};
  if (timespec)
    convertTimespec_ =
        reinterpret_cast<PFN_xrConvertTimespecTimeToTimeKHR>(proc("xrConvertTimespecTimeToTimeKHR"));
  XrInstanceProperties ip{XR_TYPE_INSTANCE_PROPERTIES};
  if (XR_SUCCEEDED(xrGetInstanceProperties(instance_, &ip))) runtimeName_ = ip.runtimeName;

  XrSystemGetInfo gi{XR_TYPE_SYSTEM_GET_INFO};
  gi.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  if (XrResult r = xrGetSystem(instance_, &gi, &systemId_); XR_FAILED(r))
    return Error{"no head-mounted display is available (" + result(r) + "); is the headset connected?"};
  XrSystemHandTrackingPropertiesEXT hand{XR_TYPE_SYSTEM_HAND_TRACKING_PROPERTIES_EXT};
  XrSystemProperties sp{XR_TYPE_SYSTEM_PROPERTIES, handTracking_ ? &hand : nullptr};
  if (XR_SUCCEEDED(xrGetSystemProperties(instance_, systemId_, &sp))) systemName_ = sp.systemName;
  handTracking_ = handTracking_ && hand.supportsHandTracking;

  uint32_t count = 0;
  if (XrResult r = xrEnumerateViewConfigurationViews(
          instance_, systemId_, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &count, nullptr);
      XR_FAILED(r) || count != 2)
    return Error{"the HMD has no primary stereo view configuration with two views"};
  views_.fill({XR_TYPE_VIEW_CONFIGURATION_VIEW});
  xrEnumerateViewConfigurationViews(instance_, systemId_, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 2,
                                    &count, views_.data());
  return {};
}

Status XrSystem::createVulkan(const XrSystemOptions& o) {
  if (auto s = checkVulkanVersion(); !s) return s;
  if (auto s = createVulkanInstance(o); !s) return s;
  return createVulkanDevice(o);
}

Status XrSystem::checkVulkanVersion() {
  auto requirements =
      reinterpret_cast<PFN_xrGetVulkanGraphicsRequirements2KHR>(proc("xrGetVulkanGraphicsRequirements2KHR"));
  if (!requirements || !proc("xrCreateVulkanInstanceKHR") || !proc("xrGetVulkanGraphicsDevice2KHR") ||
      !proc("xrCreateVulkanDeviceKHR"))
    return Error{"the runtime lists XR_KHR_vulkan_enable2 but does not provide its functions"};
  XrGraphicsRequirementsVulkan2KHR req{XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR};
  if (XrResult r = requirements(instance_, systemId_, &req); XR_FAILED(r))
    return Error{"xrGetVulkanGraphicsRequirements2KHR failed: " + result(r)};
  // The renderer needs Vulkan 1.3 (dynamic rendering, synchronization2).
  if (XR_VERSION_MAJOR(req.maxApiVersionSupported) < 1 ||
      (XR_VERSION_MAJOR(req.maxApiVersionSupported) == 1 && XR_VERSION_MINOR(req.maxApiVersionSupported) < 3))
    return Error{"the runtime supports Vulkan only up to " +
                 std::to_string(XR_VERSION_MAJOR(req.maxApiVersionSupported)) + "." +
                 std::to_string(XR_VERSION_MINOR(req.maxApiVersionSupported)) + "; Embody needs 1.3"};
  return {};
}

Status XrSystem::createVulkanInstance(const XrSystemOptions& o) {
  auto createInstance = reinterpret_cast<PFN_xrCreateVulkanInstanceKHR>(proc("xrCreateVulkanInstanceKHR"));
  const bool validate = o.vulkanValidation && engine::Instance::validationLayerAvailable();
  if (o.vulkanValidation && !validate)
    std::fprintf(stderr, "warning: the Vulkan validation layer is not installed (vulkan-validationlayers)\n");
  std::vector<const char*> exts;
  for (const auto& e : o.vulkanInstanceExtensions) exts.push_back(e.c_str());
  if (validate) exts.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  const char* layer = "VK_LAYER_KHRONOS_validation";
  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity =
      VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mci.pfnUserCallback = countMessage;
  mci.pUserData = messages_.get();
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = o.appName.c_str();
  app.pEngineName = "embody";
  app.apiVersion = VK_API_VERSION_1_3;
  VkInstanceCreateInfo vci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  vci.pNext = validate ? &mci : nullptr;
  vci.pApplicationInfo = &app;
  vci.enabledExtensionCount = static_cast<uint32_t>(exts.size());
  vci.ppEnabledExtensionNames = exts.data();
  vci.enabledLayerCount = validate ? 1 : 0;
  vci.ppEnabledLayerNames = &layer;
  XrVulkanInstanceCreateInfoKHR xci{XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR};
  xci.systemId = systemId_;
  xci.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  xci.vulkanCreateInfo = &vci;
  VkResult vr = VK_SUCCESS;
  if (XrResult r = createInstance(instance_, &xci, &vkInstance_, &vr); XR_FAILED(r) || vr != VK_SUCCESS)
    return Error{"xrCreateVulkanInstanceKHR failed: " + result(r) + " / VkResult " + std::to_string(vr)};
  if (validate) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(vkInstance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create || create(vkInstance_, &mci, nullptr, &messenger_) != VK_SUCCESS)
      return Error{"could not create the Vulkan debug messenger"};
  }
  return {};
}

Status XrSystem::createVulkanDevice(const XrSystemOptions& o) {
  auto getDevice = reinterpret_cast<PFN_xrGetVulkanGraphicsDevice2KHR>(proc("xrGetVulkanGraphicsDevice2KHR"));
  auto createDevice = reinterpret_cast<PFN_xrCreateVulkanDeviceKHR>(proc("xrCreateVulkanDeviceKHR"));
  XrVulkanGraphicsDeviceGetInfoKHR gi{XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR};
  gi.systemId = systemId_;
  gi.vulkanInstance = vkInstance_;
  if (XrResult r = getDevice(instance_, &gi, &vkPhysical_); XR_FAILED(r))
    return Error{"xrGetVulkanGraphicsDevice2KHR failed: " + result(r)};
  if (const std::string missing = engine::missingRequiredFeatures(vkPhysical_); !missing.empty())
    return Error{"the runtime's Vulkan device lacks features the renderer needs:" + missing};
  uint32_t nq = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(vkPhysical_, &nq, nullptr);
  std::vector<VkQueueFamilyProperties> families(nq);
  vkGetPhysicalDeviceQueueFamilyProperties(vkPhysical_, &nq, families.data());
  queueFamily_ = UINT32_MAX;
  for (uint32_t i = 0; i < nq && queueFamily_ == UINT32_MAX; ++i)
    if ((families[i].queueFlags & VK_QUEUE_GRAPHICS_BIT) && (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT))
      queueFamily_ = i;
  if (queueFamily_ == UINT32_MAX) return Error{"the runtime's Vulkan device has no graphics+compute queue"};
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = queueFamily_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  engine::RequiredDeviceFeatures features;
  std::vector<const char*> deviceExts;
  for (const auto& e : o.vulkanDeviceExtensions) deviceExts.push_back(e.c_str());
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &features.features2;
  dci.enabledExtensionCount = static_cast<uint32_t>(deviceExts.size());
  dci.ppEnabledExtensionNames = deviceExts.data();
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  XrVulkanDeviceCreateInfoKHR xdi{XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR};
  xdi.systemId = systemId_;
  xdi.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
  xdi.vulkanPhysicalDevice = vkPhysical_;
  xdi.vulkanCreateInfo = &dci;
  VkResult vr = VK_SUCCESS;
  if (XrResult r = createDevice(instance_, &xdi, &vkDevice_, &vr); XR_FAILED(r) || vr != VK_SUCCESS)
    return Error{"xrCreateVulkanDeviceKHR failed: " + result(r) + " / VkResult " + std::to_string(vr)};
  return {};
}

XrSystem::~XrSystem() {
  if (vkDevice_) {
    vkDeviceWaitIdle(vkDevice_);
    vkDestroyDevice(vkDevice_, nullptr);
  }
  if (messenger_) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(vkInstance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(vkInstance_, messenger_, nullptr);
  }
  if (vkInstance_) vkDestroyInstance(vkInstance_, nullptr);
  if (instance_) xrDestroyInstance(instance_);
}

XrPath XrSystem::path(const char* s) const {
  XrPath p = XR_NULL_PATH;
  return XR_SUCCEEDED(xrStringToPath(instance_, s, &p)) ? p : XR_NULL_PATH;
}

std::string XrSystem::pathString(XrPath p) const {
  char buf[XR_MAX_PATH_LENGTH] = {};
  uint32_t n = 0;
  return XR_SUCCEEDED(xrPathToString(instance_, p, sizeof(buf), &n, buf)) ? std::string(buf) : std::string();
}

XrTime XrSystem::now() const {
  if (!convertTimespec_) return 0;
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  XrTime t = 0;
  return XR_SUCCEEDED(convertTimespec_(instance_, &ts, &t)) ? t : 0;
}

PFN_xrVoidFunction XrSystem::proc(const char* name) const {
  PFN_xrVoidFunction f = nullptr;
  return XR_SUCCEEDED(xrGetInstanceProcAddr(instance_, name, &f)) ? f : nullptr;
}

}  // namespace embody::xr
