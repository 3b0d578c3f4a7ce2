// `embody spine describe` and `embody experiment isolated-spine` end to end.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/cli_support.h"

using embody::test::runEmbody;
namespace fs = std::filesystem;

TEST_CASE("embody spine describe --json reports vertebrae, joints, dofs and rows", "[cli]") {
  struct Case {
    const char* args;
    int sites, swing, revolute, dofTotal, dofFree, equalities;
  };
  const Case cases[] = {{"", 24, 18, 6, 42, 9, 33},
                        {"--model simplified", 8, 8, 5, 21, 9, 12},
                        {"--uncoupled", 24, 0, 0, 72, 72, 0},
                        {"--axis-coupling", 24, 18, 6, 42, 7, 35}};
  for (const Case& c : cases) {
    INFO(c.args);
    auto r = runEmbody(std::string("spine describe --json ") + c.args);
    REQUIRE(r.exitCode == 0);
    const auto j = nlohmann::json::parse(r.output);
    CHECK(j["vertebrae"] == 24);
    CHECK(j["sites"] == c.sites);
    CHECK(j["swing_joints"] == c.swing);
    CHECK(j["revolute_joints"] == c.revolute);
    CHECK(j["dof_total"] == c.dofTotal);
    CHECK(j["dof_free"] == c.dofFree);
    CHECK(j["equalities"] == c.equalities);
    CHECK(j["inequalities"].get<int>() > 0);
  }
  auto text = runEmbody("spine describe");
  REQUIRE(text.exitCode == 0);
  CHECK(text.output.find("42 before coupling, 9 free after") != std::string::npos);
}

TEST_CASE("embody spine: a user file round-trips through --dump, bad input fails clearly", "[cli]") {
  const fs::path dir = fs::temp_directory_path() / "embody_spine_cli_test";
  fs::create_directories(dir);
  auto dump = runEmbody("spine describe --model simplified --dump");
  REQUIRE(dump.exitCode == 0);
  std::ofstream(dir / "mine.json") << dump.output;
  auto mine = runEmbody("spine describe --json --model " + (dir / "mine.json").string());
  REQUIRE(mine.exitCode == 0);
  CHECK(nlohmann::json::parse(mine.output)["sites"] == 8);

  std::ofstream(dir / "broken.json") << "{\"format\": \"embody-spine\", \"version\": 1}";
  auto broken = runEmbody("spine describe --model " + (dir / "broken.json").string(), true);
  CHECK(broken.exitCode == 1);
  CHECK(broken.output.find("missing \"name\"") != std::string::npos);
  CHECK(runEmbody("spine describe --model /nonexistent.json").exitCode == 1);
  CHECK(runEmbody("spine explain").exitCode == 2);
  CHECK(runEmbody("spine describe --no-such-flag").exitCode == 2);
  fs::remove_all(dir);
}

TEST_CASE("embody experiment isolated-spine writes CSV, summary.json and the figures", "[cli]") {
  const fs::path dir = fs::temp_directory_path() / "embody_isolated_spine_cli_test";
  fs::remove_all(dir);
  auto r = runEmbody("experiment isolated-spine --iterations 60 --out " + dir.string(), true);
  INFO(r.output);
  REQUIRE(r.exitCode == 0);
  std::ifstream in(dir / "summary.json");
  const auto s = nlohmann::json::parse(in);
  for (const char* v : {"coupled", "uncoupled"})
    for (const char* key : {"final_position_error_m", "final_orientation_error_deg", "mean_iteration_us",
                            "swing_spread", "torsion_sign_changes_within_regions"})
      CHECK(s[v].contains(key));
  CHECK(s["uncoupled"]["final_position_error_m"].get<double>() < s["coupled"]["final_position_error_m"].get<double>());
  std::ifstream csv(dir / "coupled_iterations.csv");
  std::string header;
  std::getline(csv, header);
  CHECK(header == "iteration,time_us,position_error_m,orientation_error_deg,dq_norm_rad");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  CHECK(rows == 60);
  // The band-slack sweep: 0..5° in 0.5° steps, rigid bands reach least.
  REQUIRE(s["band_slack_sweep"].size() == 11);
  CHECK(s["band_slack_sweep"][0]["final_position_error_m"].get<double>() >
        s["band_slack_sweep"][10]["final_position_error_m"].get<double>());
  std::ifstream sweep(dir / "band_slack_sweep.csv");
  std::getline(sweep, header);
  CHECK(header == "band_slack_deg,position_error_m,orientation_error_deg,swing_spread,torsion_sign_changes");
  for (const char* png : {"fig6_shapes.png", "fig7_convergence.png", "fig8_swing.png", "fig_band_slack.png"}) {
    INFO(png);
    std::ifstream f(dir / png, std::ios::binary);
    REQUIRE(f);
    char magic[8] = {};
    f.read(magic, 8);
    CHECK(std::string(magic + 1, 3) == "PNG");
    CHECK(fs::file_size(dir / png) > 20000);  // a real plot, not an empty canvas
  }
  CHECK(runEmbody("experiment isolated-spine").exitCode == 2);  // --out missing
  CHECK(runEmbody("experiment no-such-experiment --out " + dir.string()).exitCode == 2);
  fs::remove_all(dir);
}
