#include "xr/openxr/mirror_window.h"

#include <algorithm>

#include "engine/resources.h"

namespace embody::xr {

namespace {
void keyCallback(GLFWwindow* w, int key, int, int action, int) {
  if (action != GLFW_PRESS) return;
  auto* keys = static_cast<MirrorWindow::Keys*>(glfwGetWindowUserPointer(w));
  if (key == GLFW_KEY_V) keys->thirdPerson = !keys->thirdPerson;
  if (key == GLFW_KEY_R) keys->recenter = true;
  if (key == GLFW_KEY_C) keys->calibrate = true;
  if (key == GLFW_KEY_ESCAPE) glfwSetWindowShouldClose(w, GLFW_TRUE);
}
}  // namespace

Result<std::vector<std::string>> MirrorWindow::requiredInstanceExtensions() {
  glfwSetErrorCallback(nullptr);
  if (glfwInit() != GLFW_TRUE)
    return Error{"--mirror needs a display (DISPLAY or WAYLAND_DISPLAY); none is usable"};
  if (glfwVulkanSupported() != GLFW_TRUE) return Error{"--mirror: GLFW finds no Vulkan loader"};
  uint32_t n = 0;
  const char** names = glfwGetRequiredInstanceExtensions(&n);
  std::vector<std::string> out;
  for (uint32_t i = 0; i < n; ++i) out.emplace_back(names[i]);
  return out;
}

Result<std::unique_ptr<MirrorWindow>> MirrorWindow::create(VkInstance instance, VkPhysicalDevice physical,
                                                           VkDevice device, uint32_t queueFamily,
                                                           uint32_t width, uint32_t height) {
  std::unique_ptr<MirrorWindow> m(new MirrorWindow());
  m->instance_ = instance;
  m->physical_ = physical;
  m->device_ = device;
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  m->window_ = glfwCreateWindow(int(width), int(height), "embody xr (mirror)", nullptr, nullptr);
  if (!m->window_) return Error{"--mirror: cannot open a window"};
  glfwSetWindowUserPointer(m->window_, &m->keys_);
  glfwSetKeyCallback(m->window_, keyCallback);
  if (glfwCreateWindowSurface(instance, m->window_, nullptr, &m->surface_) != VK_SUCCESS)
    return Error{"--mirror: cannot create a Vulkan surface for the window"};
  VkBool32 present = VK_FALSE;
  vkGetPhysicalDeviceSurfaceSupportKHR(physical, queueFamily, m->surface_, &present);
  if (!present) return Error{"--mirror: the runtime's queue cannot present to the window"};
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  m->acquired_.resize(gfx::kFramesInFlight + 2);
  m->acquiredUsedAt_.assign(m->acquired_.size(), 0);
  for (auto& s : m->acquired_)
    if (vkCreateSemaphore(device, &si, nullptr, &s) != VK_SUCCESS)
      return Error{"--mirror: vkCreateSemaphore failed"};
  if (auto s = m->createSwapchain(); !s) return Error{s.error()};
  return m;
}

Status MirrorWindow::createSwapchain() {
  VkSurfaceCapabilitiesKHR caps{};
  vkGetPhysicalDeviceSurfaceCapabilitiesKHR(physical_, surface_, &caps);
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  extent_ =
      caps.currentExtent.width != UINT32_MAX ? caps.currentExtent : VkExtent2D{uint32_t(w), uint32_t(h)};
  if (extent_.width == 0 || extent_.height == 0) return {};  // minimised: try again later
  uint32_t n = 0;
  vkGetPhysicalDeviceSurfaceFormatsKHR(physical_, surface_, &n, nullptr);
  std::vector<VkSurfaceFormatKHR> formats(n);
  vkGetPhysicalDeviceSurfaceFormatsKHR(physical_, surface_, &n, formats.data());
  if (formats.empty()) return Error{"--mirror: the window offers no surface formats"};
  VkSurfaceFormatKHR chosen = formats[0];
  for (const auto& f : formats)
    if ((f.format == VK_FORMAT_B8G8R8A8_SRGB || f.format == VK_FORMAT_R8G8B8A8_SRGB) &&
        f.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR)
      chosen = f;
  format_ = chosen.format;
  // FIFO would tie the headset loop to the desktop's refresh: prefer a mode that never blocks.
  vkGetPhysicalDeviceSurfacePresentModesKHR(physical_, surface_, &n, nullptr);
  std::vector<VkPresentModeKHR> modes(n);
  vkGetPhysicalDeviceSurfacePresentModesKHR(physical_, surface_, &n, modes.data());
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
  ci.imageUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  ci.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.preTransform = caps.currentTransform;
  ci.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
  ci.presentMode = mode;
  ci.clipped = VK_TRUE;
  if (vkCreateSwapchainKHR(device_, &ci, nullptr, &swapchain_) != VK_SUCCESS)
    return Error{"--mirror: vkCreateSwapchainKHR failed"};
  vkGetSwapchainImagesKHR(device_, swapchain_, &n, nullptr);
  images_.resize(n);
  vkGetSwapchainImagesKHR(device_, swapchain_, &n, images_.data());
  VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
  for (VkImage img : images_) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = img;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = format_;
    vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    VkImageView view = VK_NULL_HANDLE;
    VkSemaphore sem = VK_NULL_HANDLE;
    if (vkCreateImageView(device_, &vi, nullptr, &view) != VK_SUCCESS ||
        vkCreateSemaphore(device_, &si, nullptr, &sem) != VK_SUCCESS)
      return Error{"--mirror: cannot create the window's image views"};
    views_.push_back(view);
    renderDone_.push_back(sem);
  }
  return {};
}

void MirrorWindow::destroySwapchain() {
  vkDeviceWaitIdle(device_);
  for (VkImageView v : views_) vkDestroyImageView(device_, v, nullptr);
  for (VkSemaphore s : renderDone_) vkDestroySemaphore(device_, s, nullptr);
  views_.clear();
  renderDone_.clear();
  images_.clear();
  if (swapchain_) vkDestroySwapchainKHR(device_, swapchain_, nullptr);
  swapchain_ = VK_NULL_HANDLE;
}

MirrorWindow::~MirrorWindow() {
  if (device_) {
    destroySwapchain();
    for (VkSemaphore s : acquired_) vkDestroySemaphore(device_, s, nullptr);
  }
  if (surface_) vkDestroySurfaceKHR(instance_, surface_, nullptr);
  if (window_) glfwDestroyWindow(window_);
  glfwTerminate();
}

void MirrorWindow::pollEvents() {
  glfwPollEvents();
}
bool MirrorWindow::closeRequested() const {
  return glfwWindowShouldClose(window_) == GLFW_TRUE;
}

Result<bool> MirrorWindow::draw(gfx::Renderer& renderer, uint64_t frameNumber, const gfx::Camera& camera,
                                gfx::SubmitSync& sync) {
  pending_ = false;
  if (needsRecreate_ || !swapchain_) {
    destroySwapchain();
    if (auto s = createSwapchain(); !s) return Error{s.error()};
    needsRecreate_ = false;
    if (!swapchain_) return false;
  }
  size_t slot = acquired_.size();
  for (size_t i = 0; i < acquired_.size() && slot == acquired_.size(); ++i)
    if (acquiredUsedAt_[i] == 0 || acquiredUsedAt_[i] + gfx::kFramesInFlight <= frameNumber) slot = i;
  if (slot == acquired_.size()) return false;
  const VkSemaphore acquired = acquired_[slot];
  const VkResult r = vkAcquireNextImageKHR(device_, swapchain_, 0, acquired, VK_NULL_HANDLE, &imageIndex_);
  if (r == VK_ERROR_OUT_OF_DATE_KHR) {
    needsRecreate_ = true;
    return false;
  }
  if (r == VK_NOT_READY || r == VK_TIMEOUT) return false;  // never stall the headset for the mirror
  if (r != VK_SUCCESS && r != VK_SUBOPTIMAL_KHR) return Error{"--mirror: vkAcquireNextImageKHR failed"};
  if (r == VK_SUBOPTIMAL_KHR) needsRecreate_ = true;
  acquiredUsedAt_[slot] = frameNumber;
  // Transition after the acquire semaphore's wait stage, then draw without another transition.
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
  b.dstStageMask = VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT;
  b.dstAccessMask = VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT;
  b.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  b.newLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = images_[imageIndex_];
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
  VkDependencyInfo dep{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  dep.imageMemoryBarrierCount = 1;
  dep.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(renderer.commandBuffer(), &dep);
  gfx::PassTarget target;
  target.color = {images_[imageIndex_],
                  views_[imageIndex_],
                  format_,
                  extent_,
                  0,
                  1,
                  VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                  VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
  if (auto s = renderer.drawPass(std::span<const gfx::Camera>(&camera, 1), target); !s)
    return Error{s.error()};
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

Status MirrorWindow::present(VkQueue queue) {
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
    return Error{"--mirror: vkQueuePresentKHR failed"};
  return {};
}

}  // namespace embody::xr
