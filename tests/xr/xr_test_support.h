#pragma once
// Helpers for the xr tests: paths of the built runtime and CLI, and a child-process runner that
// sets environment variables, holds the child's stdin open (hello_xr quits when it closes) and
// enforces a timeout.
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace embody::test {

std::string runtimeManifest();  // <build>/embody_headless_runtime.json
std::string embodyBin();        // the built CLI
std::string helloXr();          // Debian's hello_xr, "" when not installed

struct ProcessResult {
  int exitCode = -1;  // -1 when killed or not started
  int termSignal = 0;  // the signal that ended the child (SIGSEGV = 11), 0 when it exited
  bool timedOut = false;
  bool signalSent = false;  // SignalPlan's signal went out
  std::string output;  // stdout and stderr interleaved
};

// Runs argv[0] (searched in PATH) with `env` added to this process's environment. stdin is a
// pipe this process keeps open until the child exits.
ProcessResult runProcess(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env,
                         int timeoutSeconds);
// The same, sending `signal` to the child once `when()` is true (checked every 200 ms at most).
struct SignalPlan {
  int signal = 0;
  std::function<bool()> when;
};
ProcessResult runProcess(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env,
                         int timeoutSeconds, const SignalPlan& plan);

// Environment that selects the headless runtime with the core validation layer.
std::map<std::string, std::string> headlessRuntimeEnv();

// A fresh empty folder under the build tree's test output.
std::string freshTestDir(const std::string& name);

size_t countOccurrences(const std::string& text, const std::string& what);

}  // namespace embody::test
