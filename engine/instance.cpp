#include "engine/instance.h"

#include <cstdio>
#include <cstring>

namespace embody::engine {

namespace {
constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";
}

struct Instance::Shared {
  std::atomic<uint32_t> count{0};
  std::function<void(const ValidationMessage&)> onMessage;
  bool print = true;
};

namespace {

// The loader (1.3.239) reports its own notices through the same messenger as GENERAL messages
// with the id name "Loader Message" (message id 0), e.g. when VK_ICD_FILENAMES pins a driver.
// They are not validation findings, so they are not counted; everything else is.
bool isLoaderNotice(VkDebugUtilsMessageTypeFlagsEXT type, const VkDebugUtilsMessengerCallbackDataEXT* data) {
  return type == VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT && data->pMessageIdName &&
         std::strcmp(data->pMessageIdName, "Loader Message") == 0;
}

VKAPI_ATTR VkBool32 VKAPI_CALL messengerCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                 VkDebugUtilsMessageTypeFlagsEXT type,
                                                 const VkDebugUtilsMessengerCallbackDataEXT* data,
                                                 void* user) {
  auto* shared = static_cast<Instance::Shared*>(user);  // NOLINT
  if (isLoaderNotice(type, data)) return VK_FALSE;
  shared->count.fetch_add(1, std::memory_order_relaxed);
  ValidationMessage msg{severity, type, data->pMessageIdName ? data->pMessageIdName : "",
                        data->pMessage ? data->pMessage : ""};
  if (shared->print) std::fprintf(stderr, "[vulkan] %s: %s\n", msg.idName.c_str(), msg.text.c_str());
  if (shared->onMessage) shared->onMessage(msg);
  return VK_FALSE;
}

}  // namespace

bool Instance::validationLayerAvailable() {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (const auto& l : layers)
    if (std::strcmp(l.layerName, kValidationLayer) == 0) return true;
  return false;
}

uint32_t Instance::loaderApiVersion() {
  uint32_t v = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&v);
  return v;
}

Result<Instance> Instance::create(const InstanceOptions& options) {
  Instance inst;
  inst.shared_ = std::make_unique<Shared>();
  inst.shared_->onMessage = options.onMessage;
  inst.shared_->print = options.printMessages;

  bool validate = false;
  if (options.validation != Validation::Off) {
    validate = validationLayerAvailable();
    if (!validate && options.validation == Validation::Required)
      return Error{"the Khronos validation layer (VK_LAYER_KHRONOS_validation) is required but not "
                   "installed; install the Debian package vulkan-validationlayers"};
  }

  std::vector<const char*> exts;
  for (const auto& e : options.extensions) exts.push_back(e.c_str());
  if (validate) exts.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  std::vector<const char*> layers;
  if (validate) layers.push_back(kValidationLayer);

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = options.appName.c_str();
  app.pEngineName = "embody";
  app.apiVersion = VK_API_VERSION_1_3;

  // Chain a messenger into instance creation too, so messages from vkCreateInstance and
  // vkDestroyInstance are counted.
  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                        VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mci.pfnUserCallback = messengerCallback;
  mci.pUserData = inst.shared_.get();

  VkInstanceCreateInfo ci{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ci.pNext = validate ? &mci : nullptr;
  ci.pApplicationInfo = &app;
  ci.enabledExtensionCount = static_cast<uint32_t>(exts.size());
  ci.ppEnabledExtensionNames = exts.data();
  ci.enabledLayerCount = static_cast<uint32_t>(layers.size());
  ci.ppEnabledLayerNames = layers.data();
  VkResult r = vkCreateInstance(&ci, nullptr, &inst.instance_);
  if (r != VK_SUCCESS) return Error{"vkCreateInstance failed (VkResult " + std::to_string(r) + ")"};
  inst.owned_ = true;

  if (validate) {
    auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(inst.instance_, "vkCreateDebugUtilsMessengerEXT"));
    if (!create || create(inst.instance_, &mci, nullptr, &inst.messenger_) != VK_SUCCESS)
      return Error{"could not create the debug-utils messenger"};
  }
  return inst;
}

Instance Instance::borrow(VkInstance instance) {
  Instance inst;
  inst.instance_ = instance;
  inst.owned_ = false;
  return inst;
}

Instance::Instance() = default;
Instance::Instance(Instance&& o) noexcept { *this = std::move(o); }

Instance& Instance::operator=(Instance&& o) noexcept {
  if (this != &o) {
    reset();
    instance_ = std::exchange(o.instance_, VK_NULL_HANDLE);
    messenger_ = std::exchange(o.messenger_, VK_NULL_HANDLE);
    shared_ = std::move(o.shared_);
    owned_ = std::exchange(o.owned_, false);
  }
  return *this;
}

Instance::~Instance() { reset(); }

void Instance::reset() {
  if (messenger_ != VK_NULL_HANDLE) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(instance_, messenger_, nullptr);
    messenger_ = VK_NULL_HANDLE;
  }
  if (instance_ != VK_NULL_HANDLE && owned_) vkDestroyInstance(instance_, nullptr);
  instance_ = VK_NULL_HANDLE;
}

uint32_t Instance::messageCount() const {
  return shared_ ? shared_->count.load(std::memory_order_relaxed) : 0;
}

PhysicalDeviceInfo describePhysicalDevice(VkPhysicalDevice d) {
  VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props.pNext = &driver;
  vkGetPhysicalDeviceProperties2(d, &props);
  PhysicalDeviceInfo info;
  info.handle = d;
  info.name = props.properties.deviceName;
  info.driverName = driver.driverName;
  info.driverInfo = driver.driverInfo;
  info.type = props.properties.deviceType;
  info.apiVersion = props.properties.apiVersion;
  return info;
}

std::vector<PhysicalDeviceInfo> Instance::physicalDevices() const {
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(instance_, &n, nullptr);
  std::vector<VkPhysicalDevice> devs(n);
  vkEnumeratePhysicalDevices(instance_, &n, devs.data());
  std::vector<PhysicalDeviceInfo> out;
  for (VkPhysicalDevice d : devs) out.push_back(describePhysicalDevice(d));
  return out;
}

std::string PhysicalDeviceInfo::typeName() const {
  switch (type) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

std::string PhysicalDeviceInfo::apiVersionString() const {
  return std::to_string(VK_API_VERSION_MAJOR(apiVersion)) + "." +
         std::to_string(VK_API_VERSION_MINOR(apiVersion)) + "." +
         std::to_string(VK_API_VERSION_PATCH(apiVersion));
}

}  // namespace embody::engine
