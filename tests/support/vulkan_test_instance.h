#pragma once
// Every Vulkan instance a test creates comes from here: lavapipe (the test main pins the loader to
// it unless VK_DRIVER_FILES / VK_ICD_FILENAMES is set), the Khronos validation layer required (the test fails if it cannot load), and a messenger
// that records every validation warning or error. Call expectNoValidationMessages() at the end
// of a test; TestInstance's destructor also fails the test on any message not yet reported.
#include <mutex>
#include <string>
#include <vector>

#include "engine/instance.h"

namespace embody::test {

// EMBODY_TEST_DEVICE, a --device selector ("nvidia", "1"), runs the GPU suites on other hardware
// (docs/renderer.md, "On real hardware"); "lavapipe" when unset. Goldens are lavapipe's.
std::string testDeviceSelector();
// Whether the GPU tests run on lavapipe (checks that name lavapipe's driver apply only then).
bool testsOnLavapipe();

class TestInstance {
 public:
  // Creates the instance; REQUIREs success (so a missing layer fails the test).
  explicit TestInstance(std::vector<std::string> extensions = {});
  ~TestInstance();
  TestInstance(const TestInstance&) = delete;
  TestInstance& operator=(const TestInstance&) = delete;

  engine::Instance& instance() { return instance_; }
  VkInstance handle() const { return instance_.handle(); }
  // The physical device the GPU tests run on (REQUIREs that there is one): lavapipe, or what
  // testDeviceSelector() names.
  VkPhysicalDevice device() const;

  std::vector<std::string> messages() const;
  // Fails the current test (with the messages) if validation reported anything.
  void expectNoValidationMessages();
  // For the one test that proves the messenger works: forget recorded messages.
  void clearMessages();

  static engine::InstanceOptions options(std::vector<std::string> extensions = {});

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> messages_;
  engine::Instance instance_;
  size_t reported_ = 0;  // messages already turned into failures
};

}  // namespace embody::test
