#pragma once
// The desktop mirror of `embody xr --mirror`: a GLFW window on the runtime's VkInstance/VkDevice
// whose swapchain the renderer draws into as one more pass of the frame (the left eye again, or
// a third-person view of the avatar; V switches). Keys: V view, R recenter (and recalibrate),
// C recalibrate the height, Esc/close: end the
// session.
#include <vulkan/vulkan.h>
// after Vulkan, so GLFW declares glfwCreateWindowSurface
#include <GLFW/glfw3.h>

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/result.h"
#include "engine/camera.h"
#include "engine/renderer.h"

namespace embody::xr {

class MirrorWindow {
 public:
  // glfwInit and the instance extensions a surface needs; call before the VkInstance exists.
  static Result<std::vector<std::string>> requiredInstanceExtensions();
  static Result<std::unique_ptr<MirrorWindow>> create(VkInstance instance, VkPhysicalDevice physical,
                                                      VkDevice device, uint32_t queueFamily, uint32_t width,
                                                      uint32_t height);
  ~MirrorWindow();
  MirrorWindow(const MirrorWindow&) = delete;
  MirrorWindow& operator=(const MirrorWindow&) = delete;

  void pollEvents();
  bool closeRequested() const;
  bool thirdPerson() const { return keys_.thirdPerson; }
  bool takeRecenterRequest() { return std::exchange(keys_.recenter, false); }
  bool takeCalibrateRequest() { return std::exchange(keys_.calibrate, false); }

  // Inside an open renderer frame (`frameNumber`: renderer frames begun so far): acquires a
  // window image and draws `camera` into it. Returns false (no error) when the window cannot show
  // a frame now (minimised, resized, no image free): the headset never waits for the mirror.
  Result<bool> draw(gfx::Renderer& renderer, uint64_t frameNumber, const gfx::Camera& camera,
                    gfx::SubmitSync& sync);
  // After renderer.endFrame(sync): presents what draw() rendered.
  Status present(VkQueue queue);
  float aspect() const { return extent_.height ? float(extent_.width) / float(extent_.height) : 1.0f; }

 private:
  MirrorWindow() = default;
  Status createSwapchain();
  void destroySwapchain();

  GLFWwindow* window_ = nullptr;
  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkSurfaceKHR surface_ = VK_NULL_HANDLE;
  VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
  VkFormat format_ = VK_FORMAT_UNDEFINED;
  VkExtent2D extent_{0, 0};
  std::vector<VkImage> images_;
  std::vector<VkImageView> views_;
  std::vector<VkSemaphore> renderDone_;  // one per swapchain image
  // Acquire semaphores and the renderer frame that last waited on each: one is reused only when
  // that frame has retired (the renderer keeps kFramesInFlight frames in flight).
  std::vector<VkSemaphore> acquired_;
  std::vector<uint64_t> acquiredUsedAt_;
  uint32_t imageIndex_ = 0;
  bool pending_ = false, needsRecreate_ = false;

 public:
  struct Keys {
    bool thirdPerson = false, recenter = false, calibrate = false;
  };

 private:
  Keys keys_;
};

}  // namespace embody::xr
