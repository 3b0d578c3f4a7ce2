// The one translation unit that holds Catch2's main. Before any test runs it pins the Vulkan
// loader to lavapipe (goldens must match on every machine) unless the caller already chose a
// driver, and caps lavapipe's threads at the CI machine's two cores.
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>
#include <cstdlib>

int main(int argc, char* argv[]) {
#ifdef EMBODY_LAVAPIPE_ICD
  if (!std::getenv("VK_ICD_FILENAMES") && !std::getenv("VK_DRIVER_FILES"))
    setenv("VK_ICD_FILENAMES", EMBODY_LAVAPIPE_ICD, 0);
#endif
  setenv("LP_NUM_THREADS", "2", 0);
  return Catch::Session().run(argc, argv);
}
