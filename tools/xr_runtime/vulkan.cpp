// XR_KHR_vulkan_enable2 (and enable), swapchains on the application's VkDevice, and the
// left-eye capture to PNG.
#include <stb_image_write.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "tools/xr_runtime/runtime.h"
#include "tools/xr_runtime/two_call.h"

namespace embody::xr_runtime {

namespace {

constexpr uint32_t kSwapchainLength = 3;

bool isDepthFormat(VkFormat f) {
  return f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D16_UNORM || f == VK_FORMAT_D24_UNORM_S8_UINT ||
         f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}
bool hasStencil(VkFormat f) {
  return f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT;
}

// Formats in the runtime's order of preference: sRGB colour first (the compositor expects
// display-referred sRGB), then UNORM, then depth.
std::vector<VkFormat> supportedFormats(VkPhysicalDevice pd) {
  const VkFormat candidates[] = {VK_FORMAT_R8G8B8A8_SRGB,     VK_FORMAT_B8G8R8A8_SRGB,
                                 VK_FORMAT_R8G8B8A8_UNORM,    VK_FORMAT_B8G8R8A8_UNORM,
                                 VK_FORMAT_D32_SFLOAT,        VK_FORMAT_D16_UNORM,
                                 VK_FORMAT_D24_UNORM_S8_UINT, VK_FORMAT_D32_SFLOAT_S8_UINT};
  std::vector<VkFormat> out;
  for (VkFormat f : candidates) {
    VkFormatProperties props{};
    vkGetPhysicalDeviceFormatProperties(pd, f, &props);
    const VkFormatFeatureFlags need =
        isDepthFormat(f) ? VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT
                         : (VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_TRANSFER_SRC_BIT);
    if ((props.optimalTilingFeatures & need) == need) out.push_back(f);
  }
  return out;
}

uint32_t findMemoryType(VkPhysicalDevice pd, uint32_t bits, VkMemoryPropertyFlags want) {
  VkPhysicalDeviceMemoryProperties mp{};
  vkGetPhysicalDeviceMemoryProperties(pd, &mp);
  for (uint32_t i = 0; i < mp.memoryTypeCount; ++i)
    if ((bits & (1u << i)) && (mp.memoryTypes[i].propertyFlags & want) == want) return i;
  return UINT32_MAX;
}

// One-shot command buffer on the application's queue. Only called from the functions during
// which the OpenXR Vulkan bindings allow the runtime to use that queue (acquire, end frame).
class OneShot {
 public:
  explicit OneShot(Session& s) : s_(s) {
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = s.cmdPool;
    ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    ai.commandBufferCount = 1;
    ok_ = vkAllocateCommandBuffers(s.vkDevice, &ai, &cmd_) == VK_SUCCESS;
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    ok_ = ok_ && vkBeginCommandBuffer(cmd_, &bi) == VK_SUCCESS;
  }
  ~OneShot() {
    if (cmd_) vkFreeCommandBuffers(s_.vkDevice, s_.cmdPool, 1, &cmd_);
  }
  OneShot(const OneShot&) = delete;
  OneShot& operator=(const OneShot&) = delete;
  VkCommandBuffer cmd() const { return cmd_; }
  bool ok() const { return ok_; }
  bool submitAndWait() {
    if (!ok_ || vkEndCommandBuffer(cmd_) != VK_SUCCESS) return false;
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkFence fence = VK_NULL_HANDLE;
    if (vkCreateFence(s_.vkDevice, &fi, nullptr, &fence) != VK_SUCCESS) return false;
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd_;
    bool good = vkQueueSubmit(s_.queue, 1, &si, fence) == VK_SUCCESS &&
                vkWaitForFences(s_.vkDevice, 1, &fence, VK_TRUE, 10ull * 1000000000ull) == VK_SUCCESS;
    vkDestroyFence(s_.vkDevice, fence, nullptr);
    return good;
  }

 private:
  Session& s_;
  VkCommandBuffer cmd_ = VK_NULL_HANDLE;
  bool ok_ = false;
};

VkImageLayout attachmentLayout(const Swapchain& sc) {
  return sc.depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL
                  : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
}

VkImageSubresourceRange fullRange(const Swapchain& sc) {
  VkImageSubresourceRange r{};
  r.aspectMask = sc.depth
                     ? (VK_IMAGE_ASPECT_DEPTH_BIT | (hasStencil(sc.format) ? VK_IMAGE_ASPECT_STENCIL_BIT : 0))
                     : VK_IMAGE_ASPECT_COLOR_BIT;
  r.levelCount = VK_REMAINING_MIP_LEVELS;
  r.layerCount = VK_REMAINING_ARRAY_LAYERS;
  return r;
}

// ---- graphics requirements and device creation -----------------------------------------------

XrResult requirements(XrInstance instance, XrSystemId systemId, XrGraphicsRequirementsVulkanKHR* req) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (!req || req->type != XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN_KHR) return XR_ERROR_VALIDATION_FAILURE;
  req->minApiVersionSupported = XR_MAKE_VERSION(1, 0, 0);
  req->maxApiVersionSupported = XR_MAKE_VERSION(1, 3, 0);
  std::lock_guard lock(inst->mutex);
  inst->graphicsRequirementsQueried = true;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetVulkanGraphicsRequirements2KHR(XrInstance instance, XrSystemId systemId,
                                                      XrGraphicsRequirementsVulkanKHR* req) {
  return requirements(instance, systemId, req);
}
EMBODY_XR_ENTRY(GetVulkanGraphicsRequirements2KHR)

XrResult XRAPI_CALL GetVulkanGraphicsRequirementsKHR(XrInstance instance, XrSystemId systemId,
                                                     XrGraphicsRequirementsVulkanKHR* req) {
  return requirements(instance, systemId, req);
}
EMBODY_XR_ENTRY(GetVulkanGraphicsRequirementsKHR)

XrResult XRAPI_CALL CreateVulkanInstanceKHR(XrInstance instance, const XrVulkanInstanceCreateInfoKHR* ci,
                                            VkInstance* vkInstance, VkResult* vkResult) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !vkInstance || !vkResult || ci->type != XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR ||
      !ci->pfnGetInstanceProcAddr || !ci->vulkanCreateInfo)
    return XR_ERROR_VALIDATION_FAILURE;
  if (ci->systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  auto create =
      reinterpret_cast<PFN_vkCreateInstance>(ci->pfnGetInstanceProcAddr(VK_NULL_HANDLE, "vkCreateInstance"));
  if (!create) return XR_ERROR_RUNTIME_FAILURE;
  // This runtime needs no instance extensions of its own: the application's request goes as is.
  *vkResult = create(ci->vulkanCreateInfo, ci->vulkanAllocator, vkInstance);
  if (*vkResult == VK_SUCCESS) {
    std::lock_guard lock(inst->mutex);
    inst->createdVkInstance = *vkInstance;
  }
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(CreateVulkanInstanceKHR)

// The physical device: EMBODY_XR_VK_DEVICE (a substring of the device name) or the first one.
XrResult pickPhysicalDevice(VkInstance vk, VkPhysicalDevice* out) {
  uint32_t n = 0;
  if (vkEnumeratePhysicalDevices(vk, &n, nullptr) != VK_SUCCESS || n == 0) return XR_ERROR_RUNTIME_FAILURE;
  std::vector<VkPhysicalDevice> devices(n);
  vkEnumeratePhysicalDevices(vk, &n, devices.data());
  *out = devices[0];
  if (const char* want = std::getenv("EMBODY_XR_VK_DEVICE"); want && *want)
    for (VkPhysicalDevice d : devices) {
      VkPhysicalDeviceProperties p{};
      vkGetPhysicalDeviceProperties(d, &p);
      if (std::strstr(p.deviceName, want)) {
        *out = d;
        break;
      }
    }
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetVulkanGraphicsDevice2KHR(XrInstance instance,
                                                const XrVulkanGraphicsDeviceGetInfoKHR* info,
                                                VkPhysicalDevice* pd) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!info || !pd || info->type != XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR || !info->vulkanInstance)
    return XR_ERROR_VALIDATION_FAILURE;
  if (info->systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  {
    std::lock_guard lock(inst->mutex);
    inst->createdVkInstance = info->vulkanInstance;
  }
  return pickPhysicalDevice(info->vulkanInstance, pd);
}
EMBODY_XR_ENTRY(GetVulkanGraphicsDevice2KHR)

XrResult XRAPI_CALL GetVulkanGraphicsDeviceKHR(XrInstance instance, XrSystemId systemId, VkInstance vk,
                                               VkPhysicalDevice* pd) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  if (!vk || !pd) return XR_ERROR_VALIDATION_FAILURE;
  return pickPhysicalDevice(vk, pd);
}
EMBODY_XR_ENTRY(GetVulkanGraphicsDeviceKHR)

XrResult XRAPI_CALL CreateVulkanDeviceKHR(XrInstance instance, const XrVulkanDeviceCreateInfoKHR* ci,
                                          VkDevice* device, VkResult* vkResult) {
  Instance* inst = findInstance(instance);
  if (!inst) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !device || !vkResult || ci->type != XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR ||
      !ci->pfnGetInstanceProcAddr || !ci->vulkanCreateInfo || !ci->vulkanPhysicalDevice)
    return XR_ERROR_VALIDATION_FAILURE;
  if (ci->systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  VkInstance vk;
  {
    std::lock_guard lock(inst->mutex);
    vk = inst->createdVkInstance;
  }
  auto create = reinterpret_cast<PFN_vkCreateDevice>(ci->pfnGetInstanceProcAddr(vk, "vkCreateDevice"));
  if (!create) create = &vkCreateDevice;
  *vkResult = create(ci->vulkanPhysicalDevice, ci->vulkanCreateInfo, ci->vulkanAllocator, device);
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(CreateVulkanDeviceKHR)

// XR_KHR_vulkan_enable: the runtime needs no extra Vulkan extensions (an empty list).
XrResult emptyExtensionList(XrInstance instance, XrSystemId systemId, uint32_t capacity, uint32_t* count,
                            char* buffer) {
  if (!findInstance(instance)) return XR_ERROR_HANDLE_INVALID;
  if (systemId != kSystemId) return XR_ERROR_SYSTEM_INVALID;
  return twoCall(capacity, count, buffer, 1, [](char* c, size_t) { *c = '\0'; });
}
XrResult XRAPI_CALL GetVulkanInstanceExtensionsKHR(XrInstance instance, XrSystemId systemId,
                                                   uint32_t capacity, uint32_t* count, char* buffer) {
  return emptyExtensionList(instance, systemId, capacity, count, buffer);
}
EMBODY_XR_ENTRY(GetVulkanInstanceExtensionsKHR)
XrResult XRAPI_CALL GetVulkanDeviceExtensionsKHR(XrInstance instance, XrSystemId systemId, uint32_t capacity,
                                                 uint32_t* count, char* buffer) {
  return emptyExtensionList(instance, systemId, capacity, count, buffer);
}
EMBODY_XR_ENTRY(GetVulkanDeviceExtensionsKHR)

// ---- swapchains ---------------------------------------------------------------------------------

XrResult XRAPI_CALL EnumerateSwapchainFormats(XrSession session, uint32_t capacity, uint32_t* count,
                                              int64_t* formats) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  const auto list = supportedFormats(s->vkPhysicalDevice);
  return twoCall(capacity, count, formats, list.size(), [&](int64_t* f, size_t i) { *f = list[i]; });
}
EMBODY_XR_ENTRY(EnumerateSwapchainFormats)

// XR_SUCCESS when the runtime can make a swapchain of this description, else the error.
XrResult swapchainSupported(const Session& s, const XrSwapchainCreateInfo& ci) {
  const auto formats = supportedFormats(s.vkPhysicalDevice);
  const auto format = static_cast<VkFormat>(ci.format);
  if (std::find(formats.begin(), formats.end(), format) == formats.end())
    return XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED;
  if (ci.width == 0 || ci.height == 0 || ci.width > 4096 || ci.height > 4096 || ci.arraySize == 0 ||
      ci.mipCount == 0 || (ci.faceCount != 1 && ci.faceCount != 6) || ci.sampleCount != 1)
    return XR_ERROR_VALIDATION_FAILURE;
  const bool depth = isDepthFormat(format);
  if (depth && (ci.usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT)) return XR_ERROR_FEATURE_UNSUPPORTED;
  if (!depth && (ci.usageFlags & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT)) return XR_ERROR_FEATURE_UNSUPPORTED;
  return XR_SUCCESS;
}

// The images' create info: OpenXR's usage flags in Vulkan's, plus what the runtime needs (the
// capture reads images back) and the attachment the format implies.
VkImageCreateInfo swapchainImageInfo(const XrSwapchainCreateInfo& ci, bool depth) {
  VkImageUsageFlags usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT) usage |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT)
    usage |= VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT) usage |= VK_IMAGE_USAGE_STORAGE_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_TRANSFER_SRC_BIT) usage |= VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT) usage |= VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_SAMPLED_BIT) usage |= VK_IMAGE_USAGE_SAMPLED_BIT;
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_INPUT_ATTACHMENT_BIT_KHR) usage |= VK_IMAGE_USAGE_INPUT_ATTACHMENT_BIT;
  if (depth && !(usage & VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT))
    usage |= VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
  if (!depth && !(usage & VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT)) usage |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  VkImageCreateInfo ii{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  if (ci.usageFlags & XR_SWAPCHAIN_USAGE_MUTABLE_FORMAT_BIT) ii.flags |= VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT;
  if (ci.faceCount == 6) ii.flags |= VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT;
  ii.imageType = VK_IMAGE_TYPE_2D;
  ii.format = static_cast<VkFormat>(ci.format);
  ii.extent = {ci.width, ci.height, 1};
  ii.mipLevels = ci.mipCount;
  ii.arrayLayers = ci.arraySize * ci.faceCount;
  ii.samples = VK_SAMPLE_COUNT_1_BIT;
  ii.tiling = VK_IMAGE_TILING_OPTIMAL;
  ii.usage = usage;
  ii.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  return ii;
}

// Whether the device can create these images: the format's limits for this usage and these flags,
// and a mip chain no longer than the image's (Vulkan's valid usage, which the runtime must check
// for the application: a client asking 64 mip levels of a 64 x 64 image had them passed to
// vkCreateImage, which corrupted lavapipe's heap; 100000 layers and storage on an sRGB format
// were created "successfully" against the valid usage). A cube needs square faces.
XrResult imageSupported(const Session& s, const VkImageCreateInfo& ii) {
  if ((ii.flags & VK_IMAGE_CREATE_CUBE_COMPATIBLE_BIT) && ii.extent.width != ii.extent.height)
    return XR_ERROR_VALIDATION_FAILURE;
  const uint32_t longest = std::max(ii.extent.width, ii.extent.height);
  uint32_t fullChain = 1;
  while ((longest >> fullChain) > 0) ++fullChain;  // floor(log2(longest)) + 1
  if (ii.mipLevels > fullChain) return XR_ERROR_VALIDATION_FAILURE;
  VkImageFormatProperties p{};
  if (vkGetPhysicalDeviceImageFormatProperties(s.vkPhysicalDevice, ii.format, ii.imageType, ii.tiling, ii.usage,
                                               ii.flags, &p) != VK_SUCCESS)
    return XR_ERROR_FEATURE_UNSUPPORTED;
  if (ii.extent.width > p.maxExtent.width || ii.extent.height > p.maxExtent.height || ii.mipLevels > p.maxMipLevels ||
      ii.arrayLayers > p.maxArrayLayers)
    return XR_ERROR_FEATURE_UNSUPPORTED;
  return XR_SUCCESS;
}

// kSwapchainLength images with their memory; false (and nothing left) when one fails.
bool createSwapchainImages(const Session& s, const VkImageCreateInfo& ii, Swapchain& sc) {
  for (uint32_t i = 0; i < kSwapchainLength; ++i) {
    VkImage image = VK_NULL_HANDLE;
    if (vkCreateImage(s.vkDevice, &ii, nullptr, &image) != VK_SUCCESS) {
      destroySwapchainImages(sc);
      return false;
    }
    sc.images.push_back(image);
    VkMemoryRequirements mr{};
    vkGetImageMemoryRequirements(s.vkDevice, image, &mr);
    VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
    ai.allocationSize = mr.size;
    ai.memoryTypeIndex = findMemoryType(s.vkPhysicalDevice, mr.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (ai.memoryTypeIndex == UINT32_MAX) ai.memoryTypeIndex = findMemoryType(s.vkPhysicalDevice, mr.memoryTypeBits, 0);
    VkDeviceMemory mem = VK_NULL_HANDLE;
    if (vkAllocateMemory(s.vkDevice, &ai, nullptr, &mem) != VK_SUCCESS) {
      destroySwapchainImages(sc);
      return false;
    }
    sc.memory.push_back(mem);
    vkBindImageMemory(s.vkDevice, image, mem, 0);
  }
  return true;
}

XrResult XRAPI_CALL CreateSwapchain(XrSession session, const XrSwapchainCreateInfo* ci, XrSwapchain* out) {
  Instance* inst = nullptr;
  Session* s = findSession(session, &inst);
  if (!s) return XR_ERROR_HANDLE_INVALID;
  if (!ci || !out || ci->type != XR_TYPE_SWAPCHAIN_CREATE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (s->lost) return XR_ERROR_SESSION_LOST;
  if (XrResult r = swapchainSupported(*s, *ci); XR_FAILED(r)) return r;
  const VkImageCreateInfo imageInfo = swapchainImageInfo(*ci, isDepthFormat(static_cast<VkFormat>(ci->format)));
  if (XrResult r = imageSupported(*s, imageInfo); XR_FAILED(r)) return r;
  auto sc = std::make_unique<Swapchain>();
  sc->session = s;
  sc->info = *ci;
  sc->info.next = nullptr;
  sc->format = static_cast<VkFormat>(ci->format);
  sc->depth = isDepthFormat(sc->format);
  if (!createSwapchainImages(*s, imageInfo, *sc)) return XR_ERROR_RUNTIME_FAILURE;
  sc->initialized.assign(kSwapchainLength, false);
  Swapchain* raw = sc.release();
  return publishHandle(s->swapchains, raw, out);
}
EMBODY_XR_ENTRY(CreateSwapchain)

XrResult XRAPI_CALL DestroySwapchain(XrSwapchain swapchain) {
  Instance* inst = nullptr;
  Swapchain* sc = findSwapchain(swapchain, &inst);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  unregisterHandle(sc->session->swapchains, sc);
  destroySwapchainImages(*sc);
  delete sc;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(DestroySwapchain)

XrResult XRAPI_CALL EnumerateSwapchainImages(XrSwapchain swapchain, uint32_t capacity, uint32_t* count,
                                             XrSwapchainImageBaseHeader* images) {
  Instance* inst = nullptr;
  Swapchain* sc = findSwapchain(swapchain, &inst);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  std::lock_guard lock(inst->mutex);
  auto* vk = reinterpret_cast<XrSwapchainImageVulkanKHR*>(images);
  if (vk)
    for (uint32_t i = 0; i < capacity && i < sc->images.size(); ++i)
      if (vk[i].type != XR_TYPE_SWAPCHAIN_IMAGE_VULKAN_KHR) return XR_ERROR_VALIDATION_FAILURE;
  return twoCall(capacity, count, vk, sc->images.size(),
                 [&](XrSwapchainImageVulkanKHR* img, size_t i) { img->image = sc->images[i]; });
}
EMBODY_XR_ENTRY(EnumerateSwapchainImages)

XrResult XRAPI_CALL AcquireSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageAcquireInfo* info,
                                          uint32_t* index) {
  Instance* inst = nullptr;
  Swapchain* sc = findSwapchain(swapchain, &inst);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (!index || (info && info->type != XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO))
    return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  Session& s = *sc->session;
  if (s.lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.size() >= sc->images.size()) return XR_ERROR_CALL_ORDER_INVALID;
  const uint32_t i = sc->nextIndex;
  sc->nextIndex = (sc->nextIndex + 1) % static_cast<uint32_t>(sc->images.size());
  // First use: move the image into the layout the application expects on acquire. The Vulkan
  // binding lets the runtime use the application's queue during this call.
  if (!sc->initialized[i]) {
    OneShot os(s);
    if (!os.ok()) return XR_ERROR_RUNTIME_FAILURE;
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    b.newLayout = attachmentLayout(*sc);
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = sc->images[i];
    b.subresourceRange = fullRange(*sc);
    b.dstAccessMask =
        sc->depth ? VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT : VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT;
    const VkPipelineStageFlags dst =
        sc->depth ? (VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT)
                  : VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT;
    vkCmdPipelineBarrier(os.cmd(), VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, dst, 0, 0, nullptr, 0, nullptr, 1, &b);
    if (!os.submitAndWait()) return XR_ERROR_RUNTIME_FAILURE;
    sc->initialized[i] = true;
  }
  sc->acquired.push_back(i);
  *index = i;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(AcquireSwapchainImage)

XrResult XRAPI_CALL WaitSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageWaitInfo* info) {
  Instance* inst = nullptr;
  Swapchain* sc = findSwapchain(swapchain, &inst);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (!info || info->type != XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (sc->session->lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.empty() || sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->waited = true;  // no compositor reads our images: they are ready at once
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(WaitSwapchainImage)

XrResult XRAPI_CALL ReleaseSwapchainImage(XrSwapchain swapchain, const XrSwapchainImageReleaseInfo* info) {
  Instance* inst = nullptr;
  Swapchain* sc = findSwapchain(swapchain, &inst);
  if (!sc) return XR_ERROR_HANDLE_INVALID;
  if (info && info->type != XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO) return XR_ERROR_VALIDATION_FAILURE;
  std::lock_guard lock(inst->mutex);
  if (sc->session->lost) return XR_ERROR_SESSION_LOST;
  if (sc->acquired.empty() || !sc->waited) return XR_ERROR_CALL_ORDER_INVALID;
  sc->lastReleased = sc->acquired.front();
  sc->acquired.pop_front();
  sc->waited = false;
  return XR_SUCCESS;
}
EMBODY_XR_ENTRY(ReleaseSwapchainImage)

}  // namespace

void destroySwapchainImages(Swapchain& sc) {
  Session& s = *sc.session;
  if (!s.vkDevice) return;
  // The application may still have work in flight on these images (spec: it must not, but a
  // runtime should not crash if it does).
  vkDeviceWaitIdle(s.vkDevice);
  for (VkImage i : sc.images) vkDestroyImage(s.vkDevice, i, nullptr);
  for (VkDeviceMemory m : sc.memory) vkFreeMemory(s.vkDevice, m, nullptr);
  sc.images.clear();
  sc.memory.clear();
}

void releaseSessionVulkan(Session& s) {
  if (s.vkDevice && s.cmdPool) vkDestroyCommandPool(s.vkDevice, s.cmdPool, nullptr);
  s.cmdPool = VK_NULL_HANDLE;
}

bool initSessionVulkan(Session& s) {
  vkGetDeviceQueue(s.vkDevice, s.queueFamily, s.queueIndex, &s.queue);
  VkCommandPoolCreateInfo pi{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pi.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT;
  pi.queueFamilyIndex = s.queueFamily;
  return s.queue && vkCreateCommandPool(s.vkDevice, &pi, nullptr, &s.cmdPool) == VK_SUCCESS;
}

namespace {

// Records the copy of the left eye's rect into `buffer`, with the layout changes around it.
void recordCapture(VkCommandBuffer cmd, Swapchain& sc, uint32_t imageIndex, const XrRect2Di& rect,
                   uint32_t arrayIndex, VkBuffer buffer) {
  // The application released the image in COLOR_ATTACHMENT_OPTIMAL after its rendering was
  // submitted to this same queue: queue order plus this barrier make the copy see it.
  VkImageMemoryBarrier b{.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
                         .srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT,
                         .dstAccessMask = VK_ACCESS_TRANSFER_READ_BIT,
                         .oldLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                         .newLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                         .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                         .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                         .image = sc.images[imageIndex],
                         .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, arrayIndex, 1}};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                       nullptr, 0, nullptr, 1, &b);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, arrayIndex, 1};
  region.imageOffset = {rect.offset.x, rect.offset.y, 0};
  region.imageExtent = {static_cast<uint32_t>(rect.extent.width), static_cast<uint32_t>(rect.extent.height), 1};
  vkCmdCopyImageToBuffer(cmd, sc.images[imageIndex], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer, 1, &region);
  b.srcAccessMask = VK_ACCESS_TRANSFER_READ_BIT;
  b.dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_COLOR_ATTACHMENT_READ_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
  b.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  const VkBufferMemoryBarrier hb{.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER,
                                 .srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT,
                                 .dstAccessMask = VK_ACCESS_HOST_READ_BIT,
                                 .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                 .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                 .buffer = buffer,
                                 .size = VK_WHOLE_SIZE};
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1, &hb, 0,
                       nullptr);
  vkCmdPipelineBarrier(cmd, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0,
                       nullptr, 0, nullptr, 1, &b);
}

// Writes the read-back pixels (RGBA or BGRA) as captureDir/left_NNNNN.png, opaque.
void writeCapture(Session& s, VkFormat f, const uint8_t* data, uint32_t w, uint32_t h) {
  std::vector<uint8_t> rgba(data, data + size_t(w) * h * 4);
  if (f == VK_FORMAT_B8G8R8A8_SRGB || f == VK_FORMAT_B8G8R8A8_UNORM)
    for (size_t i = 0; i < rgba.size(); i += 4) std::swap(rgba[i], rgba[i + 2]);
  for (size_t i = 3; i < rgba.size(); i += 4) rgba[i] = 255;  // the display ignores alpha
  std::error_code ec;
  std::filesystem::create_directories(s.captureDir, ec);
  char name[64];
  std::snprintf(name, sizeof(name), "left_%05u.png", s.capturedFrames);
  const std::string path = (std::filesystem::path(s.captureDir) / name).string();
  if (stbi_write_png(path.c_str(), static_cast<int>(w), static_cast<int>(h), 4, rgba.data(), static_cast<int>(w * 4)))
    ++s.capturedFrames;
  else
    std::fprintf(stderr, "embody headless runtime: cannot write %s\n", path.c_str());
}

}  // namespace

void captureLeftEye(Session& s, Swapchain& sc, uint32_t imageIndex, const XrRect2Di& rect,
                    uint32_t arrayIndex) {
  if (s.captureDir.empty() || sc.depth || imageIndex >= sc.images.size()) return;
  const VkFormat f = sc.format;
  if (f != VK_FORMAT_R8G8B8A8_SRGB && f != VK_FORMAT_R8G8B8A8_UNORM && f != VK_FORMAT_B8G8R8A8_SRGB &&
      f != VK_FORMAT_B8G8R8A8_UNORM)
    return;
  const uint32_t w = static_cast<uint32_t>(rect.extent.width), h = static_cast<uint32_t>(rect.extent.height);
  const VkDeviceSize size = VkDeviceSize(w) * h * 4;
  VkBufferCreateInfo bi{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bi.size = size;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory mem = VK_NULL_HANDLE;
  if (vkCreateBuffer(s.vkDevice, &bi, nullptr, &buffer) != VK_SUCCESS) return;
  VkMemoryRequirements mr{};
  vkGetBufferMemoryRequirements(s.vkDevice, buffer, &mr);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = mr.size;
  ai.memoryTypeIndex = findMemoryType(s.vkPhysicalDevice, mr.memoryTypeBits,
                                      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  bool ok = ai.memoryTypeIndex != UINT32_MAX && vkAllocateMemory(s.vkDevice, &ai, nullptr, &mem) == VK_SUCCESS &&
            vkBindBufferMemory(s.vkDevice, buffer, mem, 0) == VK_SUCCESS;
  if (ok) {
    OneShot os(s);
    ok = os.ok();
    if (ok) {
      recordCapture(os.cmd(), sc, imageIndex, rect, arrayIndex, buffer);
      ok = os.submitAndWait();
    }
  }
  void* data = nullptr;
  if (ok && vkMapMemory(s.vkDevice, mem, 0, size, 0, &data) == VK_SUCCESS) {
    writeCapture(s, f, static_cast<const uint8_t*>(data), w, h);
    vkUnmapMemory(s.vkDevice, mem);
  }
  if (buffer) vkDestroyBuffer(s.vkDevice, buffer, nullptr);
  if (mem) vkFreeMemory(s.vkDevice, mem, nullptr);
}

}  // namespace embody::xr_runtime
