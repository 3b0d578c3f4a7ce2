#include "tests/support/gltf_validator.h"

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>

#include "test_paths.h"

namespace embody::test {
namespace {

std::string runCapture(const std::string& cmd, int& exitCode) {
  std::string out;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) {
    exitCode = -1;
    return out;
  }
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) out.append(buf, n);
  const int status = pclose(p);
  exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return out;
}

}  // namespace

GltfValidation validateGltfFile(const std::string& path) {
  GltfValidation v;
  int rc = 0;
  runCapture("command -v node >/dev/null 2>&1", rc);
  if (rc != 0) {
    v.skipReason = "node is not installed (scripts/install-deps.sh installs it)";
    return v;
  }
  const std::filesystem::path src = kSourceDir;
  const std::filesystem::path tools = src / ".tools";
  if (!std::filesystem::exists(tools / "node_modules" / "gltf-validator" / "package.json")) {
    v.skipReason = "gltf-validator not installed under " + tools.string() + " (run scripts/install-deps.sh)";
    return v;
  }
  v.report = runCapture("node '" + (src / "scripts" / "validate_gltf.js").string() + "' '" + path + "' '" +
                            tools.string() + "' 2>&1",
                        v.exitCode);
  return v;
}

}  // namespace embody::test
