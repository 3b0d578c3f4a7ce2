// The validation plumbing every GPU test relies on: the layer loads, lavapipe is there, and a
// deliberate API misuse is caught by the messenger (so a silent messenger cannot pass tests).
#include <catch2/catch.hpp>

#include "tests/support/vulkan_test_instance.h"

using embody::test::TestInstance;

TEST_CASE("validated test instance finds lavapipe with the validation layer on", "[gpu][validation]") {
  TestInstance t;
  REQUIRE(t.instance().validationEnabled());
  REQUIRE(t.device() != VK_NULL_HANDLE);
  bool found = false;
  for (const auto& d : t.instance().physicalDevices()) {
    if (d.handle == t.device()) {
      found = true;
      if (embody::test::testsOnLavapipe()) CHECK(d.driverName.find("llvmpipe") != std::string::npos);
      CHECK(VK_API_VERSION_MINOR(d.apiVersion) >= 3);
    }
  }
  CHECK(found);
  CHECK(t.messages().empty());
}

TEST_CASE("the messenger catches a deliberate misuse", "[gpu][validation]") {
  TestInstance t;
  VkPhysicalDevice pd = t.device();
  float prio = 1.0f;
  VkDeviceQueueCreateInfo q{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  q.queueFamilyIndex = 0;
  q.queueCount = 1;
  q.pQueuePriorities = &prio;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &q;
  VkDevice device = VK_NULL_HANDLE;
  REQUIRE(vkCreateDevice(pd, &dci, nullptr, &device) == VK_SUCCESS);

  // Misuse: a buffer of size 0 is invalid usage (VUID-VkBufferCreateInfo-size-00912).
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = 0;
  bci.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  (void)vkCreateBuffer(device, &bci, nullptr, &buffer);
  if (buffer != VK_NULL_HANDLE) vkDestroyBuffer(device, buffer, nullptr);
  vkDestroyDevice(device, nullptr);

  const auto msgs = t.messages();
  REQUIRE_FALSE(msgs.empty());
  bool named = false;
  for (const auto& m : msgs) named |= m.find("VUID-VkBufferCreateInfo-size-00912") != std::string::npos;
  CHECK(named);
  t.clearMessages();  // expected: this test provoked them on purpose
}
