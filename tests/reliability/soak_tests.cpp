// The soak's short run (CI): embody_soak for 12 s over every synthetic motion with every fault,
// with assertions on its JSON figures. The long run (30 min) is `embody_soak` by hand
// (docs/reliability.md).
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "test_paths.h"

#ifdef EMBODY_SOAK_BIN
TEST_CASE("a 12 s soak under injected faults: no NaN, every fault recovered, memory flat", "[reliability][soak]") {
  const std::filesystem::path out = std::filesystem::path(embody::test::kBinaryDir) / "soak_ci.json";
  std::filesystem::remove(out);
  const std::string cmd = std::string(EMBODY_SOAK_BIN) + " --seconds 12 --synthetic-only --json " + out.string() +
                          " > /dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream f(out);
  const auto j = nlohmann::json::parse(f);
  INFO(j.dump(2));
  CHECK(j["nan_frames"] == 0);
  CHECK(j["faults_injected"].get<int>() >= 7);
  for (const auto& [name, fault] : j["faults"].items()) {
    INFO(name);
    CHECK(fault["injected"].get<int>() >= 1);
    CHECK(fault["recovered"] == fault["injected"]);
  }
  // Rendered frames: at least a third of the 90 Hz display rate on a loaded CI machine.
  CHECK(j["frames_rendered"].get<double>() > 0.33 * 90.0 * j["seconds"].get<double>());
  CHECK(j["frames_solved"].get<double>() > 0.33 * 72.0 * j["seconds"].get<double>());
  CHECK(j["rss_end_mb"].get<double>() - j["rss_start_mb"].get<double>() < 8.0);
}
#endif
