// `embody doctor` names the active OpenXR runtime when XR_RUNTIME_JSON points at one.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <nlohmann/json.hpp>

#include "xr/loader_info.h"
#include "xr_test_support.h"

using namespace embody::test;

TEST_CASE("embody doctor names the headless runtime when XR_RUNTIME_JSON points at it", "[xr]") {
  auto env = headlessRuntimeEnv();
  env.erase("XR_ENABLE_API_LAYERS");
  const auto text = runProcess({embodyBin(), "doctor"}, env, 60);
  INFO(text.output);
  REQUIRE(text.exitCode == 0);
  CHECK(text.output.find("active runtime: Embody headless runtime 0.1.0") != std::string::npos);
  CHECK(text.output.find(runtimeManifest()) != std::string::npos);

  const auto json = runProcess({embodyBin(), "doctor", "--json"}, env, 60);
  REQUIRE(json.exitCode == 0);
  // stderr is interleaved (loader notices): the JSON object is the outermost braces.
  const auto start = json.output.find('{'), end = json.output.rfind('}');
  REQUIRE(start != std::string::npos);
  REQUIRE(end != std::string::npos);
  const auto j = nlohmann::json::parse(json.output.substr(start, end - start + 1), nullptr, false);
  REQUIRE_FALSE(j.is_discarded());
  CHECK(j["openxr"]["runtime"] == "Embody headless runtime");
  CHECK(j["openxr"]["runtime_manifest"] == runtimeManifest());
}

TEST_CASE("embody doctor reports a broken runtime manifest without failing", "[xr]") {
  const auto r = runProcess({embodyBin(), "doctor"}, {{"XR_RUNTIME_JSON", "/nonexistent/runtime.json"}}, 60);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(r.output.find("active runtime: none") != std::string::npos);
}

TEST_CASE("probeOpenXR lists the runtime's extensions, its HMD and the installed API layers", "[xr]") {
  setenv("XR_RUNTIME_JSON", runtimeManifest().c_str(), 1);
  const auto info = embody::xr::probeOpenXR();
  CHECK(info.runtimeName == "Embody headless runtime");
  CHECK(info.systemName == "Embody headless HMD");
  CHECK(info.vulkanEnable2);
  CHECK(std::find(info.runtimeExtensions.begin(), info.runtimeExtensions.end(), "XR_EXT_hand_tracking") !=
        info.runtimeExtensions.end());
  bool coreValidation = false;
  for (const auto& l : info.apiLayers)
    coreValidation = coreValidation || l.rfind("XR_APILAYER_LUNARG_core_validation", 0) == 0;
  CHECK(coreValidation);
}
