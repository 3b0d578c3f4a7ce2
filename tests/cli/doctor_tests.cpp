#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "cli/cli_support.h"

using embody::test::runEmbody;

TEST_CASE("embody doctor reports lavapipe, the validation layer and the OpenXR loader", "[cli]") {
  auto r = runEmbody("doctor --json");
  REQUIRE(r.exitCode == 0);
  auto j = nlohmann::json::parse(r.output);
  CHECK(j["vulkan"]["validation_layer"].get<bool>());
  bool lavapipe = false;
  for (const auto& d : j["vulkan"]["devices"]) lavapipe |= d["driver"].get<std::string>().find("llvmpipe") != std::string::npos;
  CHECK(lavapipe);
  CHECK(j["openxr"]["header_version"] == "1.0.20");
  CHECK(j["openxr"]["loader_library"].get<std::string>().find("libopenxr_loader") != std::string::npos);
  CHECK(j["display"].contains("DISPLAY"));
}

TEST_CASE("embody doctor says 'none' when no OpenXR runtime is configured", "[cli]") {
  auto r = runEmbody("doctor --json", false);
  // CTest runs without XR_RUNTIME_JSON; a developer machine may have a runtime installed.
  if (std::getenv("XR_RUNTIME_JSON")) return;
  auto j = nlohmann::json::parse(r.output);
  if (!j["openxr"]["runtime_manifest"].get<std::string>().empty()) return;
  CHECK(j["openxr"]["runtime"] == "none");
}

TEST_CASE("the CLI rejects unknown commands and options with exit code 2", "[cli]") {
  CHECK(runEmbody("no-such-command").exitCode == 2);
  CHECK(runEmbody("doctor --no-such-option").exitCode == 2);
  auto help = runEmbody("doctor --help");
  CHECK(help.exitCode == 0);
  CHECK(help.output.find("usage: embody doctor") != std::string::npos);
  auto top = runEmbody("--help");
  CHECK(top.exitCode == 0);
  CHECK(top.output.find("doctor") != std::string::npos);
}
