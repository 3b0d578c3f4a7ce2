// The job commands share one option set (app/job_options.h): for each command, every bad value of
// a shared option (and of the command's own options) exits 2 with exactly one stderr line naming
// the option, before any file, GPU, window or OpenXR runtime is touched.
#include <catch2/catch.hpp>
#include <string>
#include <vector>

#include "cli/cli_support.h"

namespace {

using embody::test::CommandResult;

struct BadValue {
  std::string args;    // after the command
  std::string option;  // the option the one line must name
};

// The shared options: the same bad values for every command that takes them.
const std::vector<BadValue> kBodyAndBudget = {
    {"--user-height 3", "--user-height"},      {"--user-height abc", "--user-height"},
    {"--user-height 0.2", "--user-height"},    {"--spine sideways", "--spine"},
    {"--ik-budget-ms 0", "--ik-budget-ms"},    {"--ik-budget-ms 2000", "--ik-budget-ms"},
    {"--ik-budget-ms nan", "--ik-budget-ms"},  {"--no-such-option", "--no-such-option"},
    {"--avatar", "--avatar"},
};
const std::vector<BadValue> kMotionAndFrame = {
    {"--fps 0", "--fps"},           {"--fps 5000", "--fps"},         {"--fps x", "--fps"},
    {"--size 12x12", "--size"},     {"--size 640", "--size"},        {"--size 99999x10", "--size"},
    {"--size 64x64x", "--size"},    {"--bvh-scale -1", "--bvh-scale"},
};

void checkOneLine(const std::string& command, const BadValue& bad) {
  const CommandResult r = embody::test::runEmbodyStderr(command + " " + bad.args);
  INFO("embody " << command << " " << bad.args << "\n" << r.output);
  CHECK(r.exitCode == 2);
  REQUIRE_FALSE(r.output.empty());
  CHECK(r.output.find('\n') == r.output.size() - 1);  // exactly one line
  CHECK(r.output.rfind("error: ", 0) == 0);            // one prefix style
  CHECK(r.output.find(bad.option) != std::string::npos);
}

}  // namespace

TEST_CASE("render, mirror, demo and xr reject each bad shared option value with one line naming it", "[cli]") {
  const std::vector<std::string> commands = {"render --out /tmp/embody_bad_values", "render --motion synthetic:idle --out /tmp/embody_bad_values",
                                             "mirror --frames 1", "demo --no-mirror --out /tmp/embody_bad_values", "xr --frames 1"};
  for (const std::string& command : commands) {
    for (const BadValue& bad : kBodyAndBudget) checkOneLine(command, bad);
    if (command.rfind("xr", 0) != 0)
      for (const BadValue& bad : kMotionAndFrame) checkOneLine(command, bad);
  }
}

TEST_CASE("each command's own bad values exit 2 with one line naming the option", "[cli]") {
  const std::vector<std::pair<std::string, BadValue>> own = {
      {"render --motion synthetic:idle --out /tmp/embody_bad_values", {"--frames 0", "--frames"}},
      {"render --out /tmp/embody_bad_values", {"--view sideways", "--view"}},
      {"render --out /tmp/embody_bad_values", {"--stereo-mode default", "--stereo-mode"}},
      {"render --out /tmp/embody_bad_values", {"--width 8", "--width"}},
      {"render", {"--avatar default", "--out"}},
      {"mirror", {"--frames -1", "--frames"}},
      {"mirror", {"--view stereo", "--view"}},
      {"mirror", {"--screenshot /tmp/x.png", "--screenshot"}},
      {"demo --no-mirror", {"--frames 0", "--frames"}},
      {"demo --no-mirror", {"--mirror-frames 0", "--mirror-frames"}},
      {"xr", {"--frames -1", "--frames"}},
      {"xr", {"--frames 2147483648", "--frames is out of range"}},  // was "expects an integer"
      {"xr", {"--body sideways", "--body"}},
      {"xr", {"--height 9", "--height"}},
      {"xr", {"--seat-height 0.5", "--seat-height"}},
      {"motion record --motion synthetic:idle --out /tmp/embody_bad_values.jsonl", {"--fps 5000", "--fps"}},
      {"avatar info default", {"--user-height 40", "--user-height"}},
      {"avatar calibrate default --profile /tmp/embody_bad_values.json", {"--user-height 40", "--user-height"}},
      {"avatar calibrate default --profile /tmp/embody_bad_values.json", {"--eye-height 9", "--eye-height"}},
      {"spine describe", {"--height x", "--height"}},
  };
  for (const auto& [command, bad] : own) checkOneLine(command, bad);
}

TEST_CASE("embody avatar --help lists every action's options with their descriptions", "[cli]") {
  const CommandResult r = embody::test::runEmbody("avatar --help");
  CHECK(r.exitCode == 0);
  for (const char* text : {"usage: embody avatar info", "usage: embody avatar calibrate", "usage: embody avatar export-default",
                           "--user-height METRES", "scale the body model to this user height", "--eye-height METRES"})
    CHECK(r.output.find(text) != std::string::npos);
}

TEST_CASE("no help text says \"(default: default)\" and mirror's spine is coupled unless asked", "[cli]") {
  for (const char* command : {"render", "mirror", "demo", "xr", "motion record", "avatar"}) {
    const CommandResult r = embody::test::runEmbody(std::string(command) + " --help");
    INFO(command);
    CHECK(r.exitCode == 0);
    CHECK(r.output.find("(default: default)") == std::string::npos);
    CHECK(r.output.find("--coupled-spine") == std::string::npos);
  }
  for (const char* command : {"render", "mirror", "demo", "xr"})
    CHECK(embody::test::runEmbody(std::string(command) + " --help").output.find("--uncoupled-spine") != std::string::npos);
}
