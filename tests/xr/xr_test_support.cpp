#include "xr_test_support.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>

#include "cli/cli_support.h"  // embodyBinary()
#include "test_paths.h"

namespace embody::test {

std::string runtimeManifest() {
#ifdef EMBODY_XR_RUNTIME_JSON
  return EMBODY_XR_RUNTIME_JSON;
#else
  return std::string(kBinaryDir) + "/embody_headless_runtime.json";
#endif
}

std::string embodyBin() { return embodyBinary(); }

std::string helloXr() {
#ifdef EMBODY_HELLO_XR
  if (std::filesystem::exists(EMBODY_HELLO_XR)) return EMBODY_HELLO_XR;
#endif
  return "";
}

std::map<std::string, std::string> headlessRuntimeEnv() {
  return {{"XR_RUNTIME_JSON", runtimeManifest()},
          {"XR_ENABLE_API_LAYERS", "XR_APILAYER_LUNARG_core_validation"}};
}

std::string freshTestDir(const std::string& name) {
  const auto dir = std::filesystem::path(kBinaryDir) / "test-output" / "xr" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

size_t countOccurrences(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + what.size())) ++n;
  return n;
}

ProcessResult runProcess(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env,
                         int timeoutSeconds) {
  return runProcess(argv, env, timeoutSeconds, SignalPlan{});
}

ProcessResult runProcess(const std::vector<std::string>& argv, const std::map<std::string, std::string>& env,
                         int timeoutSeconds, const SignalPlan& plan) {
  ProcessResult r;
  int in[2], out[2];
  if (pipe(in) != 0) return r;
  if (pipe(out) != 0) {
    close(in[0]);
    close(in[1]);
    return r;
  }
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(in[0], STDIN_FILENO);
    dup2(out[1], STDOUT_FILENO);
    dup2(out[1], STDERR_FILENO);
    close(in[0]);
    close(in[1]);
    close(out[0]);
    close(out[1]);
    for (const auto& [k, v] : env) setenv(k.c_str(), v.c_str(), 1);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    _exit(127);
  }
  close(in[0]);
  close(out[1]);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(timeoutSeconds);
  char buf[4096];
  for (;;) {
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      r.timedOut = true;
      kill(pid, SIGKILL);
      break;
    }
    if (plan.signal && !r.signalSent && plan.when && plan.when()) {
      kill(pid, plan.signal);
      r.signalSent = true;
    }
    pollfd pfd{out[0], POLLIN, 0};
    if (poll(&pfd, 1, static_cast<int>(std::min<long>(left.count(), 200))) > 0) {
      const ssize_t n = read(out[0], buf, sizeof(buf));
      if (n <= 0) break;  // the child closed its output: it is exiting
      r.output.append(buf, static_cast<size_t>(n));
    }
  }
  int status = 0;
  waitpid(pid, &status, 0);
  close(out[0]);
  close(in[1]);  // stdin stays open until the child is gone
  if (!r.timedOut && WIFEXITED(status)) r.exitCode = WEXITSTATUS(status);
  if (!r.timedOut && WIFSIGNALED(status)) r.termSignal = WTERMSIG(status);
  return r;
}

}  // namespace embody::test
