// Proof that the headless runtime behaves like a runtime for a third-party application: Debian's
// hello_xr (the Khronos sample) runs against it through the real loader, with the core validation
// layer, reaches FOCUSED, renders, and exits when the runtime ends the session.
#include <catch2/catch.hpp>
#include <filesystem>

#include "xr_test_support.h"

namespace fs = std::filesystem;
using namespace embody::test;

TEST_CASE("hello_xr -g Vulkan2 runs against the headless runtime until the runtime ends the session",
          "[xr]") {
  const std::string hello = helloXr();
  if (hello.empty()) {
    WARN("SKIPPED: hello_xr not installed (Debian package libopenxr-utils)");
    return;
  }
  const std::string capture = freshTestDir("hello_xr");
  auto env = headlessRuntimeEnv();
  env["EMBODY_XR_FRAMES"] = "45";
  env["EMBODY_XR_CAPTURE"] = capture;
  env["EMBODY_XR_VIEW_SIZE"] = "256x280";
  const auto r = runProcess({hello, "-g", "Vulkan2", "-v"}, env, 30);
  INFO(r.output.substr(r.output.size() > 6000 ? r.output.size() - 6000 : 0));
  REQUIRE_FALSE(r.timedOut);
  CHECK(r.exitCode == 0);
  // The core validation layer was loaded and found nothing.
  CHECK(countOccurrences(r.output, "Core Validation output type") == 1);
  CHECK(countOccurrences(r.output, "VALID_ERROR") == 0);
  CHECK(countOccurrences(r.output, "VALID_WARNING") == 0);
  CHECK(countOccurrences(r.output, "VUID-") == 0);
  // The full state sequence, in order, ending with the runtime-initiated exit.
  const char* states[] = {"->XR_SESSION_STATE_READY",    "->XR_SESSION_STATE_SYNCHRONIZED",
                          "->XR_SESSION_STATE_VISIBLE",  "->XR_SESSION_STATE_FOCUSED",
                          "->XR_SESSION_STATE_STOPPING", "->XR_SESSION_STATE_IDLE",
                          "->XR_SESSION_STATE_EXITING"};
  size_t at = 0;
  for (const char* s : states) {
    const size_t p = r.output.find(s, at);
    CHECK(p != std::string::npos);
    if (p != std::string::npos) at = p;
  }
  // hello_xr rendered: one left-eye capture per frame it submitted (all but the first, which
  // came before the session was visible), and the cubes are not the background colour.
  size_t pngs = 0;
  for (const auto& e : fs::directory_iterator(capture)) pngs += e.path().extension() == ".png";
  CHECK(pngs >= 40);
  CHECK(pngs <= 45);
}
