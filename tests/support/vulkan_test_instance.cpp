#include "tests/support/vulkan_test_instance.h"

#include <catch2/catch.hpp>
#include <cstdlib>

#include "engine/device.h"

namespace embody::test {

engine::InstanceOptions TestInstance::options(std::vector<std::string> extensions) {
  engine::InstanceOptions o;
  o.appName = "embody-tests";
  o.validation = engine::Validation::Required;
  o.extensions = std::move(extensions);
  return o;
}

TestInstance::TestInstance(std::vector<std::string> extensions) {
  auto o = options(std::move(extensions));
  o.onMessage = [this](const engine::ValidationMessage& m) {
    std::lock_guard lock(mutex_);
    messages_.push_back(m.idName + ": " + m.text);
  };
  auto r = engine::Instance::create(o);
  if (!r) FAIL("could not create a validated Vulkan instance: " << r.error());
  instance_ = std::move(r).value();
  REQUIRE(instance_.validationEnabled());
}

TestInstance::~TestInstance() {
  // Destroying the instance can itself report leaks of child objects; check after it is gone.
  instance_ = engine::Instance();
  expectNoValidationMessages();
}

std::string testDeviceSelector() {
  const char* env = std::getenv("EMBODY_TEST_DEVICE");
  return env && *env ? env : "lavapipe";
}

bool testsOnLavapipe() { return testDeviceSelector() == "lavapipe"; }

VkPhysicalDevice TestInstance::device() const {
  const auto& devices = instance_.physicalDevices();
  auto chosen = engine::choosePhysicalDevice(devices, testDeviceSelector());
  if (!chosen) FAIL(chosen.error() << (testsOnLavapipe() ? "; install mesa-vulkan-drivers" : ""));
  return devices[*chosen].handle;
}

std::vector<std::string> TestInstance::messages() const {
  std::lock_guard lock(mutex_);
  return messages_;
}

void TestInstance::expectNoValidationMessages() {
  std::lock_guard lock(mutex_);
  for (; reported_ < messages_.size(); ++reported_)
    FAIL_CHECK("Vulkan validation message: " << messages_[reported_]);
}

void TestInstance::clearMessages() {
  std::lock_guard lock(mutex_);
  messages_.clear();
  reported_ = 0;
}

}  // namespace embody::test
