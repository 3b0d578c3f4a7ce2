#include "engine/device.h"

#include <algorithm>
#include <cctype>
#include <charconv>

namespace embody::engine {

const char* vkResultName(VkResult r) {
  switch (r) {
    case VK_SUCCESS: return "VK_SUCCESS";
    case VK_NOT_READY: return "VK_NOT_READY";
    case VK_TIMEOUT: return "VK_TIMEOUT";
    case VK_ERROR_OUT_OF_HOST_MEMORY: return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY: return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED: return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST: return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_EXTENSION_NOT_PRESENT: return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT: return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_FORMAT_NOT_SUPPORTED: return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    default: return "VkResult error";
  }
}

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return out;
}

int typeRank(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 0;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 1;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 3;
    default: return 4;
  }
}

bool supports13(const PhysicalDeviceInfo& d) {
  return VK_API_VERSION_MAJOR(d.apiVersion) > 1 || VK_API_VERSION_MINOR(d.apiVersion) >= 3;
}

std::string listDevices(const std::vector<PhysicalDeviceInfo>& devices) {
  std::string s;
  for (size_t i = 0; i < devices.size(); ++i)
    s += "\n  " + std::to_string(i) + ": " + devices[i].name + " (" + devices[i].typeName() + ", Vulkan " +
         devices[i].apiVersionString() + ")";
  return s.empty() ? std::string(" (none; install mesa-vulkan-drivers for lavapipe)") : s;
}

// A queue family with graphics and compute (every Vulkan graphics device has one).
int findQueueFamily(VkPhysicalDevice physical) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, families.data());
  for (uint32_t i = 0; i < n; ++i)
    if ((families[i].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) ==
        (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT))
      return static_cast<int>(i);
  return -1;
}

}  // namespace

Result<size_t> choosePhysicalDevice(const std::vector<PhysicalDeviceInfo>& devices, std::string_view selector) {
  const std::string sel = lower(selector);
  if (devices.empty()) return Error{"no Vulkan device found" + listDevices(devices)};
  if (sel.empty() || sel == "auto") {
    size_t best = devices.size();
    for (size_t i = 0; i < devices.size(); ++i) {
      if (!supports13(devices[i])) continue;
      if (best == devices.size() || typeRank(devices[i].type) < typeRank(devices[best].type)) best = i;
    }
    if (best == devices.size()) return Error{"no Vulkan 1.3 device found; devices:" + listDevices(devices)};
    return best;
  }
  size_t index = 0;
  const auto [end, ec] = std::from_chars(sel.data(), sel.data() + sel.size(), index);
  if (ec == std::errc() && end == sel.data() + sel.size()) {
    if (index >= devices.size())
      return Error{"--device " + sel + " is out of range; devices:" + listDevices(devices)};
    return index;
  }
  const bool wantCpu = sel == "cpu" || sel == "lavapipe" || sel == "llvmpipe";
  for (size_t i = 0; i < devices.size(); ++i) {
    if (wantCpu ? devices[i].type == VK_PHYSICAL_DEVICE_TYPE_CPU : lower(devices[i].name).find(sel) != std::string::npos)
      return i;
  }
  return Error{"no Vulkan device matches '" + std::string(selector) + "'; devices:" + listDevices(devices)};
}

RequiredDeviceFeatures::RequiredDeviceFeatures() {
  features13.dynamicRendering = VK_TRUE;
  features13.synchronization2 = VK_TRUE;
  // glslang's Vulkan 1.3 output declares compute workgroup sizes with LocalSizeId.
  features13.maintenance4 = VK_TRUE;
  features11.multiview = VK_TRUE;
  features11.shaderDrawParameters = VK_FALSE;
  features2.features.fillModeNonSolid = VK_FALSE;
  features2.pNext = &features11;
  features11.pNext = &features13;
}

std::string missingRequiredFeatures(VkPhysicalDevice physical) {
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  f11.pNext = &f13;
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  f2.pNext = &f11;
  vkGetPhysicalDeviceFeatures2(physical, &f2);
  std::string missing;
  if (!f13.dynamicRendering) missing += " dynamicRendering";
  if (!f13.synchronization2) missing += " synchronization2";
  if (!f13.maintenance4) missing += " maintenance4";
  if (!f11.multiview) missing += " multiview";
  return missing;
}

Result<std::unique_ptr<Device>> Device::create(const Instance& instance, std::string_view selector) {
  const auto devices = instance.physicalDevices();
  auto chosen = choosePhysicalDevice(devices, selector);
  if (!chosen) return Error{chosen.error()};
  return create(instance, devices[*chosen].handle);
}

Result<std::unique_ptr<Device>> Device::create(const Instance& instance, VkPhysicalDevice physical) {
  std::unique_ptr<Device> d(new Device());
  d->instance_ = instance.handle();
  d->physical_ = physical;
  d->info_ = describePhysicalDevice(physical);
  if (!supports13(d->info_))
    return Error{d->info_.name + " supports only Vulkan " + d->info_.apiVersionString() + "; Embody needs 1.3"};
  if (auto missing = missingRequiredFeatures(physical); !missing.empty())
    return Error{d->info_.name + " lacks required features:" + missing};
  const int family = findQueueFamily(physical);
  if (family < 0) return Error{d->info_.name + " has no graphics+compute queue"};
  d->queueFamily_ = static_cast<uint32_t>(family);

  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = d->queueFamily_;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  RequiredDeviceFeatures features;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &features.features2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  if (VkResult r = vkCreateDevice(physical, &dci, nullptr, &d->device_); r != VK_SUCCESS)
    return Error{std::string("vkCreateDevice failed on ") + d->info_.name + ": " + vkResultName(r)};
  d->owned_ = true;
  vkGetDeviceQueue(d->device_, d->queueFamily_, 0, &d->queue_);
  if (auto s = d->finishSetup(); !s) return Error{s.error()};
  return d;
}

Result<std::unique_ptr<Device>> Device::adopt(const AdoptedDevice& external) {
  if (external.device == VK_NULL_HANDLE || external.physical == VK_NULL_HANDLE)
    return Error{"Device::adopt needs a VkPhysicalDevice and a VkDevice"};
  std::unique_ptr<Device> d(new Device());
  d->instance_ = external.instance;
  d->physical_ = external.physical;
  d->device_ = external.device;
  d->queueFamily_ = external.queueFamily;
  d->owned_ = false;
  d->info_ = describePhysicalDevice(external.physical);
  vkGetDeviceQueue(d->device_, d->queueFamily_, external.queueIndex, &d->queue_);
  if (d->queue_ == VK_NULL_HANDLE) return Error{"the adopted device has no queue at the given family/index"};
  if (auto s = d->finishSetup(); !s) return Error{s.error()};
  return d;
}

Status Device::finishSetup() {
  vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical_, &props);
  limits_ = props.limits;
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  pci.queueFamilyIndex = queueFamily_;
  VkCommandPool pool = VK_NULL_HANDLE;
  if (VkResult r = vkCreateCommandPool(device_, &pci, nullptr, &pool); r != VK_SUCCESS)
    return Error{std::string("vkCreateCommandPool failed: ") + vkResultName(r)};
  oneShotPool_ = UniqueCommandPool(device_, pool);
  return {};
}

Device::~Device() {
  if (device_ == VK_NULL_HANDLE) return;
  vkDeviceWaitIdle(device_);
  oneShotPool_.reset();
  if (owned_) vkDestroyDevice(device_, nullptr);
}

uint32_t Device::memoryType(uint32_t typeBits, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred) const {
  uint32_t fallback = UINT32_MAX;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(typeBits & (1u << i))) continue;
    const VkMemoryPropertyFlags f = memory_.memoryTypes[i].propertyFlags;
    if ((f & required) != required) continue;
    if ((f & preferred) == preferred) return i;
    if (fallback == UINT32_MAX) fallback = i;
  }
  return fallback;
}

bool Device::supportsSamples(VkSampleCountFlagBits samples) const {
  return (limits_.framebufferColorSampleCounts & limits_.framebufferDepthSampleCounts & samples) != 0;
}

bool Device::supportsLinearBlit(VkFormat format) const {
  VkFormatProperties props{};
  vkGetPhysicalDeviceFormatProperties(physical_, format, &props);
  const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_BLIT_SRC_BIT | VK_FORMAT_FEATURE_BLIT_DST_BIT |
                                    VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
  return (props.optimalTilingFeatures & need) == need;
}

Status Device::submitAndWait(const std::function<void(VkCommandBuffer)>& record) const {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = oneShotPool_.get();
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateCommandBuffers(device_, &ai, &cmd); r != VK_SUCCESS)
    return Error{std::string("vkAllocateCommandBuffers: ") + vkResultName(r)};
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vkBeginCommandBuffer(cmd, &bi);
  record(cmd);
  vkEndCommandBuffer(cmd);

  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  VkFence fenceRaw = VK_NULL_HANDLE;
  vkCreateFence(device_, &fci, nullptr, &fenceRaw);
  UniqueFence fence(device_, fenceRaw);
  VkCommandBufferSubmitInfo cbi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_SUBMIT_INFO};
  cbi.commandBuffer = cmd;
  VkSubmitInfo2 si{VK_STRUCTURE_TYPE_SUBMIT_INFO_2};
  si.commandBufferInfoCount = 1;
  si.pCommandBufferInfos = &cbi;
  VkResult r = vkQueueSubmit2(queue_, 1, &si, fence.get());
  if (r == VK_SUCCESS) r = vkWaitForFences(device_, 1, &fenceRaw, VK_TRUE, UINT64_MAX);
  vkFreeCommandBuffers(device_, oneShotPool_.get(), 1, &cmd);
  if (r != VK_SUCCESS) return Error{std::string("one-shot submit failed: ") + vkResultName(r)};
  return {};
}

void Device::waitIdle() const {
  if (device_ != VK_NULL_HANDLE) vkDeviceWaitIdle(device_);
}

}  // namespace embody::engine
