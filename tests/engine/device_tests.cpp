// Device selection (pure), device creation on lavapipe, and the OpenXR path: adopting a device
// created elsewhere and rendering into images the renderer does not own.
#include <catch2/catch.hpp>
#include <cstring>

#include "engine/avatar_renderer.h"
#include "engine/image_io.h"
#include "tests/support/test_avatar.h"
#include "engine_test_support.h"

using namespace embody;

namespace {

engine::PhysicalDeviceInfo fakeDevice(const char* name, VkPhysicalDeviceType type, uint32_t minor = 3) {
  engine::PhysicalDeviceInfo d;
  d.name = name;
  d.type = type;
  d.apiVersion = VK_MAKE_API_VERSION(0, 1, minor, 0);
  return d;
}

}  // namespace

TEST_CASE("device selection prefers discrete, then integrated, then lavapipe", "[unit][device]") {
  const std::vector<engine::PhysicalDeviceInfo> devices = {
      fakeDevice("llvmpipe (LLVM 15.0.6, 256 bits)", VK_PHYSICAL_DEVICE_TYPE_CPU),
      fakeDevice("Intel(R) UHD Graphics 630", VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU),
      fakeDevice("NVIDIA GeForce RTX 4090", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU),
      fakeDevice("Old Discrete", VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU, 2)};
  CHECK(engine::choosePhysicalDevice(devices, "").value() == 2);
  CHECK(engine::choosePhysicalDevice(devices, "auto").value() == 2);
  CHECK(engine::choosePhysicalDevice(devices, "lavapipe").value() == 0);
  CHECK(engine::choosePhysicalDevice(devices, "cpu").value() == 0);
  CHECK(engine::choosePhysicalDevice(devices, "intel").value() == 1);
  CHECK(engine::choosePhysicalDevice(devices, "1").value() == 1);
  const std::vector<engine::PhysicalDeviceInfo> noDiscrete = {devices[0], devices[1]};
  CHECK(engine::choosePhysicalDevice(noDiscrete, "").value() == 1);
  const std::vector<engine::PhysicalDeviceInfo> onlyCpu = {devices[0], devices[3]};
  CHECK(engine::choosePhysicalDevice(onlyCpu, "").value() == 0);  // the 1.2 discrete GPU is skipped

  auto bad = engine::choosePhysicalDevice(devices, "radeon");
  REQUIRE_FALSE(bad);
  CHECK_THAT(bad.error(), Catch::Contains("NVIDIA GeForce RTX 4090"));  // lists what exists
  CHECK_FALSE(engine::choosePhysicalDevice(devices, "7"));
  CHECK_FALSE(engine::choosePhysicalDevice({}, ""));
}

TEST_CASE("a device is created on lavapipe with the 1.3 features", "[gpu][device]") {
  test::TestInstance vk;
  auto d = engine::Device::create(vk.instance(), test::testDeviceSelector());
  REQUIRE(d);
  CHECK((*d)->owned());
  if (test::testsOnLavapipe()) {
    CHECK((*d)->info().type == VK_PHYSICAL_DEVICE_TYPE_CPU);
    CHECK_THAT((*d)->driverString(), Catch::Contains("llvmpipe"));
  }
  CHECK(engine::missingRequiredFeatures((*d)->physical()).empty());
  CHECK((*d)->supportsSamples(VK_SAMPLE_COUNT_4_BIT));
}

// What the OpenXR layer does with XR_KHR_vulkan_enable2: the runtime creates the VkDevice, the
// swapchain owns the images (here a 2-layer B8G8R8A8_SRGB array like an XR swapchain); the
// renderer adopts the device and draws into those images, leaving them in
// COLOR_ATTACHMENT_OPTIMAL for xrReleaseSwapchainImage.
TEST_CASE("an adopted device renders into externally owned images", "[gpu][device][xr]") {
  test::TestInstance vk;
  const VkPhysicalDevice physical = vk.device();
  engine::RequiredDeviceFeatures features;
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo q{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  q.queueFamilyIndex = 0;
  q.queueCount = 1;
  q.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  dci.pNext = &features.features2;
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &q;
  VkDevice rawDevice = VK_NULL_HANDLE;
  REQUIRE(vkCreateDevice(physical, &dci, nullptr, &rawDevice) == VK_SUCCESS);

  const auto asset = test::makeTestAvatar();
  const auto pose = test::bentTestPose(asset.skeleton, 0.2f);
  avatar::Image external[2], reference[2];
  {
    auto device = engine::Device::adopt({vk.handle(), physical, rawDevice, 0, 0});
    REQUIRE(device);
    CHECK_FALSE((*device)->owned());
    const uint32_t w = 96, h = 104;

    // The "swapchain" image and a depth image, owned outside the renderer.
    engine::ImageDesc cd;
    cd.extent = {w, h};
    cd.format = VK_FORMAT_B8G8R8A8_SRGB;
    cd.layers = 2;
    cd.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    auto color = engine::Image::create(**device, cd);
    engine::ImageDesc dd = cd;
    dd.format = VK_FORMAT_D32_SFLOAT;
    dd.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT;
    auto depth = engine::Image::create(**device, dd);
    REQUIRE(color);
    REQUIRE(depth);
    auto readback = engine::Buffer::create(**device, VkDeviceSize(w) * h * 4 * 2, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                                        engine::MemoryUse::HostReadback);
    REQUIRE(readback);

    auto renderer = engine::Renderer::create(**device);
    REQUIRE(renderer);
    auto gpu = (*renderer)->upload(asset);
    REQUIRE(gpu);
    std::vector<glm::mat4> globals, palette;
    avatar::computeGlobals(asset.skeleton, pose, globals);
    avatar::computeSkinningPalette(asset, globals, palette);
    const glm::mat4 head = glm::inverse(glm::lookAt(glm::vec3(0.0f, 1.3f, 2.2f), glm::vec3(0.0f, 1.0f, 0.0f),
                                                    glm::vec3(0.0f, 1.0f, 0.0f)));
    const auto eyes = engine::stereoCameras(head, 0.064f, engine::FovAngles{-0.9f, 0.7f, 0.8f, -0.85f},
                                         engine::FovAngles{-0.7f, 0.9f, 0.8f, -0.85f});

    REQUIRE((*renderer)->beginFrame());
    engine::SceneFrame scene;
    scene.avatar = gpu->get();
    scene.palette = palette;
    REQUIRE((*renderer)->setScene(scene));
    for (uint32_t eye = 0; eye < 2; ++eye) {
      // Per-eye single-layer views, as an app with an array swapchain and two passes makes.
      VkImageViewCreateInfo vci{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
      vci.image = color->handle();
      vci.viewType = VK_IMAGE_VIEW_TYPE_2D;
      vci.format = cd.format;
      vci.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, eye, 1};
      VkImageView cv = VK_NULL_HANDLE, dv = VK_NULL_HANDLE;
      REQUIRE(vkCreateImageView(rawDevice, &vci, nullptr, &cv) == VK_SUCCESS);
      vci.image = depth->handle();
      vci.format = dd.format;
      vci.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, eye, 1};
      REQUIRE(vkCreateImageView(rawDevice, &vci, nullptr, &dv) == VK_SUCCESS);
      engine::PassTarget t;
      t.color = {color->handle(), cv, cd.format, {w, h}, eye, 1, VK_IMAGE_LAYOUT_UNDEFINED,
                 VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL};
      t.depth = engine::TargetImage{depth->handle(), dv, dd.format, {w, h}, eye, 1, VK_IMAGE_LAYOUT_UNDEFINED,
                                 VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL};
      REQUIRE((*renderer)->drawPass(std::span(&eyes[eye], 1), t));
      // The views belong to this frame: release them when it has retired.
      (*renderer)->retire(engine::UniqueImageView(rawDevice, cv));
      (*renderer)->retire(engine::UniqueImageView(rawDevice, dv));
    }
    // What the compositor would read: copy both layers out (COLOR_ATTACHMENT -> TRANSFER_SRC).
    const VkCommandBuffer cmd = (*renderer)->commandBuffer();
    engine::transitionImage(cmd, color->handle(), VK_IMAGE_ASPECT_COLOR_BIT, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                         VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL);
    VkBufferImageCopy regions[2] = {};
    for (uint32_t eye = 0; eye < 2; ++eye) {
      regions[eye].bufferOffset = VkDeviceSize(w) * h * 4 * eye;
      regions[eye].imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, eye, 1};
      regions[eye].imageExtent = {w, h, 1};
    }
    vkCmdCopyImageToBuffer(cmd, color->handle(), VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback->handle(), 2, regions);
    engine::SubmitSync sync;
    sync.waitForCompletion = true;
    REQUIRE((*renderer)->endFrame(sync));
    for (int eye = 0; eye < 2; ++eye) {
      external[eye].width = int(w);
      external[eye].height = int(h);
      external[eye].rgba.resize(size_t(w) * h * 4);
      std::memcpy(external[eye].rgba.data(), static_cast<const uint8_t*>(readback->mapped()) + size_t(w) * h * 4 * eye,
                  external[eye].rgba.size());
      for (size_t i = 0; i < external[eye].rgba.size(); i += 4) std::swap(external[eye].rgba[i], external[eye].rgba[i + 2]);
    }

    // The same views through the high-level path on the same adopted device.
    engine::AvatarRendererOptions o;
    o.width = w;
    o.height = h;
    o.stereo = true;
    o.stereoMode = engine::StereoMode::TwoPass;
    auto r = engine::AvatarRenderer::create(**device, asset, o);
    REQUIRE(r);
    engine::FrameOptions fo;
    fo.clearColor = engine::PassTarget{}.clearColor;
    auto pair = (*r)->renderStereo(pose, eyes, fo);
    REQUIRE(pair);
    reference[0] = (*pair)[0];
    reference[1] = (*pair)[1];
  }  // everything of ours is gone before the "runtime" destroys its device
  vkDestroyDevice(rawDevice, nullptr);

  for (int eye = 0; eye < 2; ++eye) {
    const auto d = engine::compareImages(external[eye], reference[eye], 1);
    CHECK(d.failingPixels == 0);
  }
  CHECK(engine::compareImages(external[0], external[1], 5).failingPixels > 50);
}

TEST_CASE("image comparison counts pixels beyond the tolerance and marks them", "[unit][image]") {
  avatar::Image a;
  a.width = 4;
  a.height = 2;
  a.rgba.assign(4 * 2 * 4, 100);
  avatar::Image b = a;
  b.rgba[0] = 105;   // within 5
  b.rgba[4 * 3 + 1] = 94;  // pixel 3, off by 6
  const auto d = engine::compareImages(a, b, 5);
  CHECK(d.sameSize);
  CHECK(d.failingPixels == 1);
  CHECK(d.maxChannelDelta == 6);
  CHECK(d.diff.rgba[4 * 3] == 255);
  CHECK(d.diff.rgba[0] == 105 / 4);
  avatar::Image c = a;
  c.width = 2;
  c.height = 4;
  CHECK_FALSE(engine::compareImages(a, c, 5).sameSize);
}
