#pragma once
// Shared by the engine tests: a validated lavapipe device, a deterministic non-rest pose for any
// skeleton, and the golden-image check (tests/golden/<name>.png + <name>.driver.txt).
#include <catch2/catch.hpp>
#include <memory>
#include <string>

#include "avatar/avatar_asset.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "tests/support/vulkan_test_instance.h"

namespace embody::test {

// A lavapipe device on a validated instance. Members destruct device first, then the instance
// (whose destructor fails the test on any validation message).
struct GpuContext {
  TestInstance vk;
  std::unique_ptr<engine::Device> device;
  GpuContext();
};

// Every joint but the roots turned by a small joint-dependent rotation: a fixed non-rest pose.
avatar::SkeletonPose wobblePose(const avatar::Skeleton& skeleton, float amount = 0.35f);

// Tiles of 1 m (0.12 m apart) in the z = 0 plane, row 0 at the top, seen head-on from z = 10 m
// by a camera whose frame they fill (columns x rows in a 4:3 or other aspect).
struct TileGrid {
  int columns = 4, rows = 3;
  static constexpr float kTile = 1.0f, kGap = 0.12f, kPitch = kTile + kGap;
  glm::vec2 corner(int column, int row) const;  // lower-left corner
  engine::Camera camera() const;
  // Pixel of a point given in tile fractions (x right, y up), in a width x height frame.
  glm::ivec2 pixel(const engine::Camera& cam, int column, int row, glm::vec2 f, uint32_t width, uint32_t height) const;
};

glm::ivec4 rgbaAt(const avatar::Image& img, glm::ivec2 p);

// Compares `image` with tests/golden/<name>.png (per channel tolerance 5/255, at most 0.1 % of
// pixels failing). With EMBODY_UPDATE_GOLDENS=1 it (re)writes the golden and its driver string
// instead. On failure writes <name>.actual.png and <name>.diff.png under the build folder's
// test-output/golden/ and prints their paths.
void checkGolden(const std::string& name, const avatar::Image& image, const std::string& driver);

}  // namespace embody::test
