#include "engine/desktop_window.h"

#include <algorithm>
#include <cstring>

namespace embody::engine {

namespace {
void keyCallback(GLFWwindow* w, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  auto* keys = static_cast<DesktopWindow::Keys*>(glfwGetWindowUserPointer(w));
  if (key == GLFW_KEY_V) keys->thirdPerson = !keys->thirdPerson;
  if (key == GLFW_KEY_SPACE) keys->paused = !keys->paused;
  if (key == GLFW_KEY_R) keys->recenter = true;
  if (key == GLFW_KEY_C) keys->calibrate = true;
  if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(w, GLFW_TRUE);
}

// The acquired swapchain image, from whatever it held, to a colour attachment.
void toColorAttachment(VkCommandBuffer cmd, VkImage image) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
  b.dstStageMask = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
  b.dstAccessMask = VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  b.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &dep);
}
}  // namespace

Result<std::vector<std::string>> DesktopWindow::requiredInstanceExtensions() {
  glfwSetErrorCallback(nullptr);
  if (glfwInit() != GLFW_TRUE)
    return Error{"the mirror window needs a display (DISPLAY or WAYLAND_DISPLAY); none is usable"};
  if (glfwVulkanSupported() != GLFW_TRUE) return Error{"mirror window: GLFW finds no Vulkan loader"};
  uint32_t n = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&n);
  std::vector<std::string> out;
  for (uint32_t i = 0; i < n; ++i) out.emplace_back(names[i]);
  return out;
}

Result<std::unique_ptr<WindowDevice>> WindowDevice::create(const Instance& instance, std::string_view selector) {
  const auto devices = instance.physicalDevices();
  auto chosen = choosePhysicalDevice(devices, selector);
  if (!chosen) return Error{chosen.error()};
  const VkPhysicalDevice physical = devices[*chosen].handle;
  if (auto missing = missingRequiredFeatures(physical); !missing.empty())
    return Error{devices[*chosen].name + " lacks required features:" + missing};
  // A graphics+compute family that can also present to a GLFW window.
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(physical, &n, families.data());
  constexpr VkQueueFlags kNeeded = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  uint32_t family = UINT32_MAX;
  for (uint32_t i = 0; i < n && family == UINT32_MAX; ++i)
    if ((families[i].queueFlags & kNeeded) == kNeeded &&
        glfwGetPhysicalDevicePresentationSupport(instance.handle(), physical, i) == GLFW_TRUE)
      family = i;
  if (family == UINT32_MAX) return Error{devices[*chosen].name + " has no queue that can present to a window"};
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  RequiredDeviceFeatures features;
  const char* extensions[] = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &features.features2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = 1;
  dci.ppEnabledExtensionNames = extensions;
  std::unique_ptr<WindowDevice> w(new WindowDevice());
  if (VkResult r = vkCreateDevice(physical, &dci, nullptr, &w->handle_); r != VK_SUCCESS)
    return Error{"vkCreateDevice (with VK_KHR_swapchain) failed on " + devices[*chosen].name + ": " + vkResultName(r)};
  auto adopted = Device::adopt({instance.handle(), physical, w->handle_, family, 0});
  if (!adopted) return Error{adopted.error()};
  w->device_ = std::move(adopted).value();
  return w;
}

WindowDevice::~WindowDevice() {
  device_.reset();  // waits for the device and frees its pool first
  if (handle_) vkDestroyDevice(handle_, nullptr);
}

Result<std::unique_ptr<DesktopWindow>> DesktopWindow::create(const Device& device, uint32_t width, uint32_t height,
                                                             const std::string& title, const Keys& initial) {
  std::unique_ptr<DesktopWindow> m(new DesktopWindow());
  m->device_ = &device;
  m->keys_ = initial;
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  m->window_ = glfwCreateWindow(int(width), int(height), title.c_str(), nullptr, nullptr);
  if (!m->window_) return Error{"mirror window: cannot open a window"};
  glfwSetWindowUserPointer(m->window_, &m->keys_);
  glfwSetKeyCallback(m->window_, keyCallback);
  if (glfwCreateWindowSurface(device.instance(), m->window_, nullptr, &m->surface_) != VK_SUCCESS)
    return Error{"mirror window: cannot create a Vulkan surface for the window"};
  VkBool32 present = VK_FALSE;
  vkGetPhysicalDeviceSurfaceSupportKHR(device.physical(), device.queueFamily(), m->surface_, &present);
  if (!present) return Error{"mirror window: the device's queue cannot present to the window"};
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  m->acquired_.resize(kFramesInFlight + 2);
  m->acquiredUsedAt_.assign(m->acquired_.size(), 0);
  for (auto& s : m->acquired_)
    if (vkCreateSemaphore(device.handle(), &si, nullptr, &s) != VK_SUCCESS)
      return Error{"mirror window: vkCreateSemaphore failed"};
  if (auto s = m->createSwapchain(); !s) return Error{s.error()};
  return m;
}

Status DesktopWindow::createSwapchain() {
  VkSurfaceCapabilitiesKHR caps{};
  vkGetPhysicalDeviceSurfaceCapabilitiesKHR(device_->physical(), surface_, &caps);
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  extent_ =
      caps.currentExtent.width != UINT32_MAX ? caps.currentExtent : VkExtent2D{uint32_t(w), uint32_t(h)};
  if (extent_.width == 0 || extent_.height == 0) return {};  // minimised: try again later
  uint32_t n = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(device_->physical(), surface_, &n, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(n);
  vkGetPhysicalDeviceSurfaceFormatsKHR(device_->physical(), surface_, &n, formats.data());
  if (formats.empty()) return Error{"mirror window: the window offers no surface formats"};
  VkSurfaceFormatKHR chosen = formats[0];
  for (const auto& f : formats)
    if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
        f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR)
      chosen = f;
  format_ = chosen.format;
  // FIFO would tie the headset loop to the desktop's refresh: prefer a mode that never blocks.
  vkGetPhysicalDeviceSurfacePresentModesKHR(device_->physical(), surface_, &n, nullptr);
  std::vector<VkPresentModeKHR> modes(n);
  vkGetPhysicalDeviceSurfacePresentModesKHR(device_->physical(), surface_, &n, modes.data());
  VkPresentModeKHR mode = VK_PRESENT_MODE_FIFO_KHR;
  for (VkPresentModeKHR m : {VK_PRESENT_MODE_IMMEDIATE_KHR, VK_PRESENT_MODE_MAILBOX_KHR})
    if (std::find(modes.begin(), modes.end(), m) != modes.end()) mode = m;
  VkSwapchainCreateInfoKHR ci{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
  ci.surface = surface_;
  ci.minImageCount = std::max(caps.minImageCount, 3u);
  if (caps.maxImageCount) ci.minImageCount = std::min(ci.minImageCount, caps.maxImageCount);
  ci.imageFormat = chosen.format;
  ci.imageColorSpace = chosen.colorSpace;
  ci.imageExtent = extent_;
  ci.imageArrayLayers = 1;
  // Readable for screenshots where the surface allows it (lavapipe/X11 does).
  readable_ = (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT) != 0;
  ci.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | (readable_ ? VK_IMAGE_USAGE_TRANSFER_SRC_BIT : 0);
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  ci.presentMode = mode;
  ci.clipped = VK_TRUE;
  if (vkCreateSwapchainKHR(device_->handle(), &ci, nullptr, &swapchain_) != VK_SUCCESS)
    return Error{"mirror window: vkCreateSwapchainKHR failed"};
  vkGetSwapchainImagesKHR(device_->handle(), swapchain_, &n, nullptr);
  images_.resize(n);
  vkGetSwapchainImagesKHR(device_->handle(), swapchain_, &n, images_.data());
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  for (VkImage img : images_) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = img;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format_;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    VkSemaphore sem = VK_NULL_HANDLE;
    if (vkCreateImageView(device_->handle(), &vi, nullptr, &view) != VK_SUCCESS ||
        vkCreateSemaphore(device_->handle(), &si, nullptr, &sem) != VK_SUCCESS)
      return Error{"mirror window: cannot create the window's image views"};
    views_.push_back(view);
    renderDone_.push_back(sem);
  }
  return {};
}

void DesktopWindow::destroySwapchain() {
  vkDeviceWaitIdle(device_->handle());
  for (VkImageView v : views_) vkDestroyImageView(device_->handle(), v, nullptr);
  for (VkSemaphore s : renderDone_) vkDestroySemaphore(device_->handle(), s, nullptr);
  views_.clear();
  renderDone_.clear();
  images_.clear();
  if (swapchain_) vkDestroySwapchainKHR(device_->handle(), swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
}

DesktopWindow::~DesktopWindow() {
  if (device_) {
    destroySwapchain();
    for (VkSemaphore s : acquired_) vkDestroySemaphore(device_->handle(), s, nullptr);
  }
  if (surface_) vkDestroySurfaceKHR(device_->instance(), surface_, nullptr);
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void DesktopWindow::pollEvents() {
  glfwPollEvents();
}
bool DesktopWindow::closeRequested() const {
  return glfwWindowShouldClose(window_) == GLFW_TRUE;
}

// Copies the finished image out in the same command buffer, then hands it back for presenting.
Status DesktopWindow::copyForScreenshot(VkCommandBuffer cmd) {
  const VkDeviceSize bytes = VkDeviceSize(extent_.width) * extent_.height * 4;
  if (!screenshot_ || screenshot_.size() < bytes) {
    auto buf = Buffer::create(*device_, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::HostReadback);
    if (!buf) return Error{buf.error()};
    screenshot_ = std::move(buf).value();
  }
  transitionImage(cmd, images_[imageIndex_], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR,
                  VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
  VkBufferImageCopy region{};
  region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
  region.imageExtent = {extent_.width, extent_.height, 1};
  vkCmdCopyImageToBuffer(cmd, images_[imageIndex_], VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                         screenshot_.handle(), 1, &region);
  memoryBarrier(cmd, VK_PIPELINE_STAGE_2_COPY_BIT, VK_ACCESS_2_TRANSFER_WRITE_BIT,
                VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT);
  transitionImage(cmd, images_[imageIndex_], VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                  VK_IMAGE_LAYOUT_PRESENT_SRC_KHR);
  screenshotRequested_ = false;
  screenshotPending_ = true;
  screenshotExtent_ = extent_;
  screenshotFormat_ = format_;
  return {};
}

Result<bool> DesktopWindow::draw(Renderer& renderer, uint64_t frameNumber, const Camera& camera,
                                SubmitSync& sync) {
  pending_ = false;
  if (needsRecreate_ || !swapchain_) {
    destroySwapchain();
    if (auto s = createSwapchain(); !s) return Error{s.error()};
    needsRecreate_ = false;
    if (!swapchain_) return false;
  }
  size_t slot = acquired_.size();
  for (size_t i = 0; i < acquired_.size() && slot == acquired_.size(); ++i)
    if (acquiredUsedAt_[i] == 0 || acquiredUsedAt_[i] + kFramesInFlight <= frameNumber) slot = i;
  if (slot == acquired_.size()) return false;
  const VkSemaphore acquired = acquired_[slot];
  const VkResult r = vkAcquireNextImageKHR(device_->handle(), swapchain_, 0, acquired, VK_NULL_HANDLE, &imageIndex_);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    needsRecreate_ = true;
    return false;
  }
  if (r == VK_NOT_READY || r == VK_TIMEOUT) return false;  // never stall the headset for the mirror
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return Error{"mirror window: vkAcquireNextImageKHR failed"};
  if (r == VK_SUBOPTIMAL_KHR) needsRecreate_ = true;
  acquiredUsedAt_[slot] = frameNumber;
  // Transition after the acquire semaphore's wait stage, then draw without another transition.
  toColorAttachment(renderer.commandBuffer(), images_[imageIndex_]);
  PassTarget target;
  target.color = {images_[imageIndex_],
                  views_[imageIndex_],
                  format_,
                  extent_,
                  0,
                  1,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                  VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
  if (auto s = renderer.drawPass(std::span<const Camera>(&camera, 1), target); !s)
    return Error{s.error()};
  if (screenshotRequested_ && readable_)
    if (auto s = copyForScreenshot(renderer.commandBuffer()); !s) return Error{s.error()};
  VkSemaphoreSubmitInfo wait{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  wait.semaphore = acquired;
  wait.stageMask = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
  VkSemaphoreSubmitInfo signal{VK_STRUCTURE_TYPE_SEMAPHORE_SUBMIT_INFO};
  signal.semaphore = renderDone_[imageIndex_];
  signal.stageMask = VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT;
  sync.wait.push_back(wait);
  sync.signal.push_back(signal);
  pending_ = true;
  return true;
}

Status DesktopWindow::present(VkQueue queue) {
  if (!pending_) return {};
  pending_ = false;
  VkPresentInfoKHR pi{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
  pi.waitSemaphoreCount = 1;
  pi.pWaitSemaphores = &renderDone_[imageIndex_];
  pi.swapchainCount = 1;
  pi.pSwapchains = &swapchain_;
  pi.pImageIndices = &imageIndex_;
  const VkResult r = vkQueuePresentKHR(queue, &pi);
  if (r == VK_ERROR_OUT_OF_DATE_KHR || r == VK_SUBOPTIMAL_KHR)
    needsRecreate_ = true;
  else if (r != VK_SUCCESS)
    return Error{"mirror window: vkQueuePresentKHR failed"};
  return {};
}

Result<avatar::Image> DesktopWindow::takeScreenshot() {
  if (!screenshotPending_)
    return Error{readable_ ? "mirror window: no frame was captured"
                           : "mirror window: the surface does not allow reading its images back (no TRANSFER_SRC)"};
  screenshotPending_ = false;
  vkDeviceWaitIdle(device_->handle());
  screenshot_.invalidate();
  avatar::Image img;
  img.width = int(screenshotExtent_.width);
  img.height = int(screenshotExtent_.height);
  img.rgba.resize(size_t(img.width) * size_t(img.height) * 4);
  std::memcpy(img.rgba.data(), screenshot_.mapped(), img.rgba.size());
  const bool bgra = screenshotFormat_ == VK_FORMAT_B8G8R8A8_SRGB || screenshotFormat_ == VK_FORMAT_B8G8R8A8_UNORM;
  for (size_t i = 0; i < img.rgba.size(); i += 4) {
    if (bgra) std::swap(img.rgba[i], img.rgba[i + 2]);
    img.rgba[i + 3] = 255;  // the window is opaque whatever alpha the pass wrote
  }
  return img;
}

}  // namespace embody::engine
