#include "engine_test_support.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "engine/image_io.h"
#include "test_paths.h"

namespace embody::test {

GpuContext::GpuContext() {
  auto d = engine::Device::create(vk.instance(), vk.lavapipe());
  if (!d) FAIL("could not create a lavapipe device: " << d.error());
  device = std::move(d).value();
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
