#include "engine_test_support.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <sstream>

#include "engine/image_io.h"
#include "test_paths.h"

namespace embody::test {

GpuContext::GpuContext() {
  auto d = engine::Device::create(vk.instance(), vk.device());
  if (!d) FAIL("could not create the test device (" << testDeviceSelector() << "): " << d.error());
  device = std::move(d).value();
}

glm::vec2 TileGrid::corner(int column, int row) const {
  return {(float(column) - float(columns) * 0.5f) * kPitch + kGap * 0.5f,
          (float(rows) * 0.5f - float(row + 1)) * kPitch + kGap * 0.5f};
}

engine::Camera TileGrid::camera() const {
  const float halfHeight = float(rows) * kPitch * 0.5f, distance = 10.0f;
  const auto fov = engine::FovAngles::symmetric(2.0f * std::atan(halfHeight / distance), float(columns) / float(rows));
  return engine::cameraFromPose(glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, distance)), fov, 1.0f, 20.0f);
}

glm::ivec2 TileGrid::pixel(const engine::Camera& cam, int column, int row, glm::vec2 f, uint32_t width,
                           uint32_t height) const {
  const glm::vec2 c = corner(column, row) + f * kTile;
  const glm::vec4 clip = cam.viewProjection() * glm::vec4(c, 0.0f, 1.0f);
  const glm::vec2 ndc = glm::vec2(clip) / clip.w;
  return {int((ndc.x * 0.5f + 0.5f) * float(width)), int((ndc.y * 0.5f + 0.5f) * float(height))};
}

glm::ivec4 rgbaAt(const avatar::Image& img, glm::ivec2 p) {
  const uint8_t* px = &img.rgba[(size_t(p.y) * size_t(img.width) + size_t(p.x)) * 4];
  return {px[0], px[1], px[2], px[3]};
}

avatar::SkeletonPose wobblePose(const avatar::Skeleton& skeleton, float amount) {
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(skeleton);
  for (size_t j = 0; j < skeleton.joints.size(); ++j) {
    if (skeleton.joints[j].parent < 0) continue;
    const float a = amount * std::sin(1.7f * float(j) + 0.3f);
    const glm::vec3 axis = glm::normalize(glm::vec3(1.0f, float(j % 3) - 1.0f, 0.5f));
    pose.local[j].rotation = pose.local[j].rotation * glm::angleAxis(a, axis);
  }
  return pose;
}

void checkGolden(const std::string& name, const avatar::Image& image, const std::string& driver) {
  namespace fs = std::filesystem;
  const fs::path golden = fs::path(kSourceDir) / "tests" / "golden" / (name + ".png");
  const fs::path driverFile = fs::path(kSourceDir) / "tests" / "golden" / (name + ".driver.txt");
  if (const char* u = std::getenv("EMBODY_UPDATE_GOLDENS"); u && std::string(u) == "1") {
    REQUIRE(engine::writePng(golden.string(), image));
    std::ofstream(driverFile) << driver << "\n";
    WARN("updated golden " << golden.string());
    return;
  }
  auto expected = engine::readPng(golden.string());
  if (!expected)
    FAIL("golden image missing: " << golden.string() << " (run scripts/update-goldens.sh to create it on purpose)");
  std::string recordedDriver;
  {
    std::ifstream in(driverFile);
    std::getline(in, recordedDriver);
  }
  const auto diff = engine::compareImages(image, *expected, 5);
  const bool pass = diff.sameSize && diff.failingFraction() <= 0.001;
  if (!pass) {
    const fs::path outDir = fs::path(kBinaryDir) / "test-output" / "golden";
    fs::create_directories(outDir);
    const fs::path actualPath = outDir / (name + ".actual.png"), diffPath = outDir / (name + ".diff.png");
    (void)engine::writePng(actualPath.string(), image);
    if (diff.sameSize) (void)engine::writePng(diffPath.string(), diff.diff);
    FAIL("golden '" << name << "' differs: " << diff.failingPixels << " of " << diff.totalPixels
                    << " pixels beyond 5/255 (max delta " << diff.maxChannelDelta << ")"
                    << (diff.sameSize ? "" : ", size differs") << "\n  actual: " << actualPath.string()
                    << "\n  diff:   " << diffPath.string() << "\n  golden driver:  " << recordedDriver
                    << "\n  current driver: " << driver);
  }
  if (recordedDriver != driver)
    WARN("golden '" << name << "' was recorded on '" << recordedDriver << "', this is '" << driver << "'");
}

}  // namespace embody::test
