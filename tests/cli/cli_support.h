#pragma once
// Runs the built `embody` binary (path from CTest's EMBODY_BIN) and captures its output.
#include <array>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <sys/wait.h>

namespace embody::test {

struct CommandResult {
  int exitCode = -1;
  std::string output;  // stdout (stderr too when mergeStderr)
};

inline std::string embodyBinary() {
  if (const char* b = std::getenv("EMBODY_BIN")) return b;
#ifdef EMBODY_BIN
  return EMBODY_BIN;
#else
  return "embody";
#endif
}

// Runs a shell command line; its stdout is the output.
inline CommandResult runShell(const std::string& cmd) {
  CommandResult r;
  FILE* p = popen(cmd.c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  int status = pclose(p);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline CommandResult runEmbody(const std::string& args, bool mergeStderr = false) {
  return runShell(embodyBinary() + " " + args + (mergeStderr ? " 2>&1" : " 2>/dev/null"));
}

// stderr only (stdout discarded).
inline CommandResult runEmbodyStderr(const std::string& args) {
  return runShell(embodyBinary() + " " + args + " 2>&1 >/dev/null");
}

}  // namespace embody::test
