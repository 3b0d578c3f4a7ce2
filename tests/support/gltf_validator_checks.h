#pragma once
// The Khronos glTF validator inside a test case: one place for the skip, the report parsing and
// the "no errors" check that every export test makes.
#include <catch2/catch.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "tests/support/gltf_validator.h"

namespace embody::test {

// Validates `path` and removes the file when `removeAfter`. nullopt (after a WARN naming why) when
// the validator is not installed; otherwise requires a JSON report with no errors and returns it
// (numErrors, numWarnings, warnings[].code, ...) for the caller's further checks.
inline std::optional<nlohmann::json> requireNoGltfErrors(const std::string& path, bool removeAfter = true) {
  const GltfValidation v = validateGltfFile(path);
  if (removeAfter) std::filesystem::remove(path);
  if (!v.skipReason.empty()) {
    WARN("SKIPPED: " << v.skipReason);
    return std::nullopt;
  }
  INFO(v.report);
  REQUIRE(v.exitCode != 3);
  nlohmann::json report = nlohmann::json::parse(v.report, nullptr, false);
  REQUIRE_FALSE(report.is_discarded());
  CHECK(report["numErrors"].get<int>() == 0);
  CHECK(v.exitCode == 0);
  return report;
}

}  // namespace embody::test
