#pragma once
// A desktop mirror window: a GLFW window whose Vulkan swapchain the renderer draws into as one
// more pass of a frame. Shared by `embody mirror` (its own instance and device) and
// `embody xr --mirror` (the OpenXR runtime's instance and device).
//
//   auto exts = DesktopWindow::requiredInstanceExtensions();   // before the VkInstance exists
//   ... instance with *exts, a device with VK_KHR_swapchain (createWindowDevice below) ...
//   auto window = DesktopWindow::create(device, 960, 720, "embody mirror");
//   each frame: pollEvents(); renderer.beginFrame(); setScene(); window->draw(renderer, n, cam, sync);
//               renderer.endFrame(sync); window->present(device.queue());
//
// Keys: V view (first/third person), Space pause, R recenter, C recalibrate, Esc/close: quit. The
// window never blocks the caller: no free image, a minimised or resized window skip the frame.
#include <vulkan/vulkan.h>
// after Vulkan, so GLFW declares glfwCreateWindowSurface
#include <GLFW/glfw3.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "avatar/avatar_asset.h"
#include "core/result.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "engine/instance.h"
#include "engine/renderer.h"
#include "engine/resources.h"

namespace embody::engine {

// A VkDevice with the renderer's required features plus VK_KHR_swapchain, owned (destroyed with
// this object, after the engine::Device that adopts it).
class WindowDevice {
 public:
  static Result<std::unique_ptr<WindowDevice>> create(const Instance& instance, std::string_view selector = "");
  ~WindowDevice();
  WindowDevice(const WindowDevice&) = delete;
  WindowDevice& operator=(const WindowDevice&) = delete;
  Device& device() { return *device_; }

 private:
  WindowDevice() = default;
  VkDevice handle_ = VK_NULL_HANDLE;
  std::unique_ptr<Device> device_;
};

class DesktopWindow {
 public:
  struct Keys {
    bool thirdPerson = false, paused = false, recenter = false, calibrate = false;
  };

  // glfwInit and the instance extensions a surface needs; call before the VkInstance exists.
  // Fails with "... needs a display ..." when no X11/Wayland display can be opened.
  static Result<std::vector<std::string>> requiredInstanceExtensions();
  // `device` must have VK_KHR_swapchain enabled and outlive the window.
  static Result<std::unique_ptr<DesktopWindow>> create(const Device& device, uint32_t width, uint32_t height,
                                                       const std::string& title, const Keys& initial);
  ~DesktopWindow();
  DesktopWindow(const DesktopWindow&) = delete;
  DesktopWindow& operator=(const DesktopWindow&) = delete;

  void pollEvents();
  bool closeRequested() const;
  const Keys& keys() const { return keys_; }
  bool thirdPerson() const { return keys_.thirdPerson; }
  bool paused() const { return keys_.paused; }
  bool takeRecenterRequest() { return std::exchange(keys_.recenter, false); }
  bool takeCalibrateRequest() { return std::exchange(keys_.calibrate, false); }

  // Inside an open renderer frame (`frameNumber`: renderer frames begun so far): acquires a
  // window image and draws `camera` into it. Returns false (no error) when the window cannot show
  // a frame now (minimised, resized, no image free): the caller never waits for the window.
  Result<bool> draw(Renderer& renderer, uint64_t frameNumber, const Camera& camera, SubmitSync& sync);
  // After renderer.endFrame(sync): presents what draw() rendered.
  Status present(VkQueue queue);
  float aspect() const { return extent_.height ? float(extent_.width) / float(extent_.height) : 1.0f; }
  VkExtent2D extent() const { return extent_; }

  // Screenshot: the next successful draw() also copies the window image to host memory; after
  // that frame's endFrame, takeScreenshot() waits for the device and returns it as RGBA8.
  // Fails when the surface cannot be read back (no TRANSFER_SRC usage) or nothing was captured.
  void requestScreenshot() { screenshotRequested_ = true; }
  bool screenshotReady() const { return screenshotPending_; }
  Result<avatar::Image> takeScreenshot();

 private:
  DesktopWindow() = default;
  Status createSwapchain();
  void destroySwapchain();
  Status copyForScreenshot(VkCommandBuffer cmd);

  const Device* device_ = nullptr;
  GLFWwindow* window_ = nullptr;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{0, 0};
  bool readable_ = false;  // swapchain images have TRANSFER_SRC usage
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkSemaphore> renderDone_;  // one per swapchain image
  // Acquire semaphores and the renderer frame that last waited on each: one is reused only when
  // that frame has retired (the renderer keeps kFramesInFlight frames in flight).
  std::vector<VkSemaphore> acquired_;
  std::vector<uint64_t> acquiredUsedAt_;
  uint32_t imageIndex_ = 0;
  bool pending_ = false, needsRecreate_ = false;
  bool screenshotRequested_ = false, screenshotPending_ = false;
  Buffer screenshot_;
  VkExtent2D screenshotExtent_{0, 0};
  VkFormat screenshotFormat_ = VK_FORMAT_UNDEFINED;
  Keys keys_;
};

}  // namespace embody::engine
