// `embody render` end to end: a PNG of the right size, zero validation messages, clear errors.
#include <catch2/catch.hpp>
#include <filesystem>

#include "cli/cli_support.h"
#include "test_paths.h"

using embody::test::outDir;
using embody::test::pngSize;
using embody::test::readJson;
using embody::test::runEmbody;
namespace fs = std::filesystem;

TEST_CASE("embody render writes one validated frame of the default avatar", "[cli][render]") {
  const auto out = outDir("render_default");
  auto r = runEmbody("render --avatar default --out " + out.string() + " --width 96 --height 64 --gizmos --skeleton "
                     "--validate --device lavapipe", true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(r.output.find("validation messages: 0") != std::string::npos);
  CHECK(r.output.find("llvmpipe") != std::string::npos);
  CHECK(pngSize(out / "frame_0000.png") == std::pair<uint32_t, uint32_t>(96, 64));
}

TEST_CASE("embody render draws CesiumMan in first person and as a stereo pair", "[cli][render]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  const auto out = outDir("render_cesium");
  auto fp = runEmbody("render --avatar " + path + " --out " + out.string() + " --view first-person --width 64 "
                      "--height 64 --validate", true);
  INFO(fp.output);
  CHECK(fp.exitCode == 0);
  CHECK(fp.output.find("validation messages: 0") != std::string::npos);
  auto st = runEmbody("render --avatar " + path + " --out " + out.string() + " --view stereo --width 64 --height 72 "
                      "--msaa --validate", true);
  INFO(st.output);
  CHECK(st.exitCode == 0);
  CHECK(st.output.find("validation messages: 0") != std::string::npos);
  CHECK(pngSize(out / "frame_0000_left.png") == std::pair<uint32_t, uint32_t>(64, 72));
  CHECK(pngSize(out / "frame_0000_right.png") == std::pair<uint32_t, uint32_t>(64, 72));
}

TEST_CASE("embody render reports bad input with exit codes 1 and 2", "[cli][render]") {
  const auto out = outDir("render_errors");
  auto missingFile = runEmbody("render --avatar /nonexistent/avatar.glb --out " + out.string(), true);
  CHECK(missingFile.exitCode == 1);
  CHECK(missingFile.output.find("error:") != std::string::npos);
  CHECK(runEmbody("render --avatar default").exitCode == 2);  // no --out
  CHECK(runEmbody("render --out " + out.string() + " --view sideways").exitCode == 2);
  CHECK(runEmbody("render --out " + out.string() + " --width 0").exitCode == 2);
  auto noDevice = runEmbody("render --out " + out.string() + " --device no-such-gpu", true);
  CHECK(noDevice.exitCode == 1);
  CHECK(noDevice.output.find("llvmpipe") != std::string::npos);  // lists the devices there are
}
