#pragma once
// Runs the built `embody` binary (path from CTest's EMBODY_BIN) and captures its output; the
// output folders, JSON and PNG readers and the test clips the CLI tests share.
#include <array>
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <utility>
#include <vector>

#include "test_paths.h"

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

// A test's output folder under the build tree (test-output/cli/NAME), removed first.
inline std::filesystem::path outDir(const std::string& name) {
  const std::filesystem::path d = std::filesystem::path(kBinaryDir) / "test-output" / "cli" / name;
  std::filesystem::remove_all(d);
  return d;
}

inline nlohmann::json readJson(const std::filesystem::path& p) {
  std::ifstream in(p);
  REQUIRE(in.good());
  return nlohmann::json::parse(in);
}

// Width/height from a PNG's IHDR chunk (bytes 16..23, big-endian); {0, 0} when unreadable.
inline std::pair<uint32_t, uint32_t> pngSize(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  unsigned char h[24] = {};
  f.read(reinterpret_cast<char*>(h), sizeof(h));
  if (!f) return {0, 0};
  auto be = [&](int o) { return uint32_t(h[o]) << 24 | uint32_t(h[o + 1]) << 16 | uint32_t(h[o + 2]) << 8 | h[o + 3]; };
  return {be(16), be(20)};
}

// A fixture clip from tests/tracking/fixtures (`name`, e.g. "cmu.bvh") played `frames` frames
// long, its frames looped; with `spinDegrees`, its root spun about one axis by that much a frame
// (the sixth root channel). Written to `path`; returns it.
inline std::string loopedClip(const std::string& name, const std::filesystem::path& path, int frames,
                              double spinDegrees = 0.0) {
  std::ifstream in(std::string(kSourceDir) + "/tests/tracking/fixtures/" + name);
  const std::string fixture((std::istreambuf_iterator<char>(in)), {});
  const size_t motion = fixture.find("MOTION"), time = fixture.find("Frame Time:"), data = fixture.find('\n', time) + 1;
  REQUIRE(motion != std::string::npos);
  std::vector<std::string> rows;
  std::istringstream lines(fixture.substr(data));
  for (std::string line; std::getline(lines, line);)
    if (!line.empty()) rows.push_back(line);
  REQUIRE(!rows.empty());
  std::string clip = fixture.substr(0, motion) + "MOTION\nFrames: " + std::to_string(frames) + "\n" + fixture.substr(time, data - time);
  for (int k = 0; k < frames; ++k) {
    std::istringstream values(rows[size_t(k) % rows.size()]);
    std::string v;
    for (int c = 0; values >> v; ++c) clip += (c ? " " : "") + (c == 5 && spinDegrees != 0.0 ? std::to_string(spinDegrees * k) : v);
    clip += "\n";
  }
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << clip;
  return path.string();
}

// The fixture spun 7.5 degrees a frame over 48 frames: no direction keeps the head above the
// feet, so the import cannot measure the axes and asks for --bvh-up and --bvh-forward.
inline std::string tumblingClip(const std::string& name, const std::filesystem::path& path) {
  return loopedClip(name, path, 48, 7.5);
}

}  // namespace embody::test
