// `embody mirror` end to end under Xvfb: the window opens, renders N frames through the whole
// runtime (pose source -> IK thread -> skinning -> the window's swapchain), and the window's last
// image (read back from the swapchain, --screenshot) shows the avatar in the middle and the
// background at the corners. Without a display the command fails with a clear message.
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "engine/image_io.h"
#include "test_paths.h"
#include "tracking/space_transform.h"
#include "tracking/synthetic_source.h"
#include "tracking/trace.h"

namespace fs = std::filesystem;

namespace {

struct Run {
  int exitCode = -1;
  std::string output;
};

// Runs a shell command line (stdout and stderr together), at most two minutes.
Run shell(const std::string& command) {
  Run r;
  FILE* p = popen(("timeout 120 " + command + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(p);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string embodyBin() {
  if (const char* b = std::getenv("EMBODY_BIN")) return b;
  return EMBODY_BIN;
}

// The command prefix that gives the child a display: the current one, else a private Xvfb.
std::string withDisplay() {
  const char* d = std::getenv("DISPLAY");
  if (d && *d) return "";
  return "xvfb-run -a -s '-screen 0 1280x1024x24' ";
}

bool canRun() {
  const char* d = std::getenv("DISPLAY");
  return (d && *d) || fs::exists("/usr/bin/xvfb-run");
}

std::string outDir(const std::string& name) {
  const auto dir = fs::path(embody::test::kBinaryDir) / "test-output" / "window" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

const uint8_t* pixel(const embody::avatar::Image& img, int x, int y) {
  return &img.rgba[(size_t(y) * size_t(img.width) + size_t(x)) * 4];
}

// The default avatar's lit grey skin (neutral, bright); the background is a darker blue-grey.
bool isAvatar(const uint8_t* px) {
  return px[0] >= 150 && std::abs(px[0] - px[1]) <= 6 && std::abs(px[2] - px[0]) <= 8;
}

int countAvatar(const embody::avatar::Image& img, int x0, int y0, int x1, int y1) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += isAvatar(pixel(img, x, y));
  return n;
}

bool sameColor(const uint8_t* a, const uint8_t* b) {
  return std::abs(a[0] - b[0]) <= 2 && std::abs(a[1] - b[1]) <= 2 && std::abs(a[2] - b[2]) <= 2;
}

// Records synthetic:idle as a trace, with the whole tracking space moved by `move` (another room
// setup: the user stands elsewhere, facing elsewhere).
void writeMovedIdle(const std::string& path, const embody::tracking::SpaceTransform& move) {
  using namespace embody::tracking;
  auto src = SyntheticSource::create("idle").value();
  TraceWriter w;
  REQUIRE(w.open(path, TrackerMask::threePoint(), "synthetic:idle", 1.75f).ok());
  for (int i = 0; i <= 90; ++i) {
    PoseSample s = src->sample(i / 90.0);
    move.apply(s);
    REQUIRE(w.write(s).ok());
  }
  REQUIRE(w.close().ok());
}

// Pixels whose colour differs by more than `tolerance` in some channel, as a fraction of the image.
double differingFraction(const embody::avatar::Image& a, const embody::avatar::Image& b, int tolerance) {
  size_t n = 0;
  for (size_t i = 0; i + 3 < a.rgba.size(); i += 4)
    for (size_t c = 0; c < 3; ++c)
      if (std::abs(int(a.rgba[i + c]) - int(b.rgba[i + c])) > tolerance) {
        ++n;
        break;
      }
  return double(n) / double(a.rgba.size() / 4);
}

}  // namespace

TEST_CASE("embody mirror opens a window, renders N frames, and its screenshot shows the avatar", "[window]") {
  if (!canRun()) {
    WARN("SKIPPED: no display and no xvfb-run (Debian package xvfb)");
    return;
  }
  const std::string dir = outDir("third");
  const std::string shot = dir + "/mirror.png";
  const Run r = shell(withDisplay() + embodyBin() +
                      " mirror --motion synthetic:idle --frames 24 --size 320x320 --no-grid --validate --screenshot " +
                      shot);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(r.output.find("mirror: 24 frames shown") != std::string::npos);
  CHECK(r.output.find("validation messages: 0") != std::string::npos);
  auto img = embody::engine::readPng(shot);
  REQUIRE(img.ok());
  REQUIRE(img->width == 320);
  REQUIRE(img->height == 320);
  // Background at the four corners (one colour, not the avatar's)...
  const uint8_t* corner = pixel(*img, 2, 2);
  CHECK_FALSE(isAvatar(corner));
  CHECK(sameColor(corner, pixel(*img, 317, 2)));
  CHECK(sameColor(corner, pixel(*img, 2, 317)));
  CHECK(sameColor(corner, pixel(*img, 317, 317)));
  // ...and the avatar in the middle: the orbit camera frames the whole body, so a central column
  // is mostly skin, and the side strips are bare.
  const int middle = countAvatar(*img, 140, 60, 180, 260);
  CHECK(middle > 40 * 200 / 3);
  CHECK(countAvatar(*img, 0, 0, 40, 320) == 0);
  CHECK(countAvatar(*img, 280, 0, 320, 320) == 0);
}

TEST_CASE("embody mirror --view first shows the own body from the eyes, head hidden", "[window]") {
  if (!canRun()) {
    WARN("SKIPPED: no display and no xvfb-run (Debian package xvfb)");
    return;
  }
  const std::string dir = outDir("first");
  const std::string shot = dir + "/mirror.png";
  const Run r = shell(withDisplay() + embodyBin() +
                      " mirror --motion synthetic:idle --view first --frames 8 --size 256x256 --no-grid --screenshot " +
                      shot);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  auto img = embody::engine::readPng(shot);
  REQUIRE(img.ok());
  // Looking down from the eyes: the chest fills the bottom of the view, the upper half is sky.
  CHECK(countAvatar(*img, 64, 216, 192, 256) > 128 * 40 / 2);
  CHECK(countAvatar(*img, 0, 0, 256, 96) == 0);
}

TEST_CASE("embody mirror without a display fails with a clear message, bad options exit 2", "[window]") {
  const Run r = shell("env -u DISPLAY -u WAYLAND_DISPLAY " + embodyBin() + " mirror --frames 3");
  INFO(r.output);
  CHECK(r.exitCode == 1);
  CHECK(r.output.find("needs a display") != std::string::npos);
  CHECK(shell(embodyBin() + " mirror --view sideways --frames 3").exitCode == 2);
  CHECK(shell(embodyBin() + " mirror --size 12x12 --frames 3").exitCode == 2);
  CHECK(shell(embodyBin() + " mirror --screenshot x.png").exitCode == 2);
  const Run missing = shell(embodyBin() + " mirror --avatar /nonexistent.glb --frames 3");
  CHECK(missing.exitCode == 1);
  CHECK(missing.output.find("error:") != std::string::npos);
}

TEST_CASE("embody demo opens the mirror window when a display is available", "[window]") {
  if (!canRun()) {
    WARN("SKIPPED: no display and no xvfb-run (Debian package xvfb)");
    return;
  }
  const std::string dir = outDir("demo");
  // 90 mirror frames: the window opens, shows the motion and closes (the default 900 took 40 s
  // of lavapipe under Xvfb).
  const Run r = shell(withDisplay() + embodyBin() + " demo --frames 3 --size 64x64 --mirror-frames 90 --out " + dir);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  CHECK(fs::exists(dir + "/stats.json"));
  CHECK(r.output.find("embody mirror:") != std::string::npos);
  CHECK(r.output.find("mirror: 90 frames shown") != std::string::npos);
}

TEST_CASE("embody mirror --recenter: a user standing elsewhere, facing elsewhere, is seen as at the origin", "[window]") {
  if (!canRun()) {
    WARN("SKIPPED: no display and no xvfb-run (Debian package xvfb)");
    return;
  }
  const std::string dir = outDir("recenter");
  writeMovedIdle(dir + "/here.jsonl", {});
  writeMovedIdle(dir + "/elsewhere.jsonl", {glm::angleAxis(glm::radians(120.0f), glm::vec3(0, 1, 0)), {3.0f, 0.0f, -2.0f}});
  auto mirror = [&](const std::string& motion, const std::string& flags, const std::string& shot) {
    const Run r = shell(withDisplay() + embodyBin() + " mirror --motion " + dir + "/" + motion +
                        " --frames 12 --ik-iterations 20 --size 192x192 --no-grid " + flags + " --screenshot " + dir +
                        "/" + shot);
    INFO(r.output);
    REQUIRE(r.exitCode == 0);
    auto img = embody::engine::readPng(dir + "/" + shot);
    REQUIRE(img.ok());
    return std::pair{r.output, *img};
  };
  const auto [hereOut, here] = mirror("here.jsonl", "--recenter", "here.png");
  const auto [movedOut, moved] = mirror("elsewhere.jsonl", "--recenter", "elsewhere_recentered.png");
  const auto [rawOut, raw] = mirror("elsewhere.jsonl", "", "elsewhere.png");
  CHECK(movedOut.find("recentered: the head at (") != std::string::npos);
  CHECK(movedOut.find("; 1 recenters") != std::string::npos);
  CHECK(rawOut.find("; 0 recenters") != std::string::npos);
  // Recentered, the moved user looks as the one at the origin does (the orbit camera is fixed in
  // the world, so the body's heading shows); not recentered, the body is seen from another side.
  CHECK(differingFraction(here, moved, 24) < 0.003);
  CHECK(differingFraction(here, raw, 24) > 0.02);
}
