#pragma once
// Runs the Khronos glTF validator (scripts/validate_gltf.js with the npm package that
// scripts/install-deps.sh puts in .tools/) on a file. Tests skip with `skipReason` when node or
// the package is missing.
#include <string>

namespace embody::test {

struct GltfValidation {
  std::string skipReason;  // non-empty: the validator is not installed, nothing was run
  int exitCode = -1;       // validate_gltf.js: 0 no errors, 1 errors, 3 package missing
  std::string report;      // its JSON summary (numErrors, numWarnings, errors, warnings)
};

GltfValidation validateGltfFile(const std::string& path);

}  // namespace embody::test
