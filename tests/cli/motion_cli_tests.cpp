// embody motion: list, info (text and JSON) and record, end to end through the built CLI.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "cli/cli_support.h"
#include "test_paths.h"

using embody::test::runEmbody;

TEST_CASE("embody motion list names the seven synthetic motions", "[cli]") {
  auto r = runEmbody("motion list");
  REQUIRE(r.exitCode == 0);
  for (const char* m : {"idle", "reach", "look", "bow", "figure8", "squat", "seated"})
    CHECK(r.output.find(std::string("synthetic:") + m) != std::string::npos);
}

TEST_CASE("embody motion record writes a trace that motion info reads back", "[cli]") {
  const auto path = std::filesystem::temp_directory_path() / "embody_motion_cli_test.jsonl";
  auto rec = runEmbody("motion record --motion synthetic:squat --out " + path.string() + " --frames 45 --fps 90 --three-point");
  REQUIRE(rec.exitCode == 0);
  CHECK(rec.output.find("wrote 45 samples") != std::string::npos);
  std::ifstream in(path);
  std::string header, first;
  std::getline(in, header);
  std::getline(in, first);
  CHECK(nlohmann::json::parse(header)["source"] == "synthetic:squat");
  const auto j = nlohmann::json::parse(first);
  CHECK(j["t"] == 0.0);
  CHECK(j["head"]["q"].size() == 4);
  CHECK_FALSE(j.contains("hips"));
  auto info = runEmbody("motion info " + path.string() + " --json");
  std::filesystem::remove(path);
  REQUIRE(info.exitCode == 0);
  const auto i = nlohmann::json::parse(info.output);
  CHECK(i["frames"] == 45);
  CHECK(i["native_rate_hz"].get<double>() == Approx(90.0));
  CHECK(i["trackers"] == nlohmann::json({"head", "left", "right"}));
  CHECK(i["inferred_lower_body"] == true);
  CHECK(i["per_tracker"]["head"]["valid_fraction"].get<double>() == Approx(1.0));
}

TEST_CASE("embody motion info on the CMU walk reports the scale, the skipped T-pose and the walk", "[cli]") {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  auto r = runEmbody("motion info " + bvh + " --json --bvh-scale 0.0564");
  REQUIRE(r.exitCode == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["frames"] == 523);
  CHECK(j["per_tracker"]["hips"]["displacement_m"].get<double>() == Approx(3.85).margin(0.1));
  bool scale = false;
  for (const auto& n : j["notes"]) scale = scale || n.get<std::string>().find("0.0564 m/unit (given)") != std::string::npos;
  CHECK(scale);
}

TEST_CASE("embody motion errors: usage errors exit 2, broken inputs exit 1 with the line", "[cli]") {
  CHECK(runEmbody("motion").exitCode == 2);
  CHECK(runEmbody("motion dance").exitCode == 2);
  CHECK(runEmbody("motion record --motion synthetic:idle").exitCode == 2);
  CHECK(runEmbody("motion info synthetic:idle --user-height tall").exitCode == 2);
  CHECK(runEmbody("motion info synthetic:idle --lose elbow@1-2").exitCode == 2);
  // --user-height: the range of every command (0.5 .. 2.6 m, avatar/body/calibration.h); motion
  // and the BVH/synthetic sources said 2.5 while render's help and check said 2.6.
  CHECK(runEmbody("motion info synthetic:idle --user-height 2.55").exitCode == 0);
  auto tall = runEmbody("motion info synthetic:idle --user-height 2.7", true);
  CHECK(tall.exitCode == 2);
  CHECK(tall.output.find("--user-height must be 0.5 .. 2.6 m") != std::string::npos);
  auto unknown = runEmbody("motion info synthetic:dance", true);
  CHECK(unknown.exitCode == 1);
  CHECK(unknown.output.find("known: synthetic:idle") != std::string::npos);
  const auto path = std::filesystem::temp_directory_path() / "embody_motion_cli_broken.jsonl";
  {
    std::ofstream out(path);
    out << "{\"t\": 0, \"head\": {\"p\": [0, 1.6, 0], \"q\": [0, 0, 0, 1]}}\n{\"t\": 0.1, \"head\": oops}\n";
  }
  auto broken = runEmbody("motion info " + path.string(), true);
  std::filesystem::remove(path);
  CHECK(broken.exitCode == 1);
  CHECK(broken.output.find("embody_motion_cli_broken.jsonl:2: not valid JSON") != std::string::npos);
}

TEST_CASE("embody motion record --lose writes a trace with the hands invalid for a second", "[cli]") {
  const auto path = std::filesystem::temp_directory_path() / "embody_motion_cli_loss.jsonl";
  auto rec = runEmbody("motion record --motion synthetic:reach --out " + path.string() +
                       " --frames 360 --fps 90 --three-point --lose left,right@2-3");
  REQUIRE(rec.exitCode == 0);
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // header
  int invalid = 0, lines = 0;
  while (std::getline(in, line)) {
    const auto j = nlohmann::json::parse(line);
    const double t = j["t"].get<double>();
    const bool lost = !j["left"]["valid"].get<bool>();
    CHECK(lost == (t >= 2.0 && t < 3.0));
    CHECK(j["left"]["p"][0].is_null() == lost);
    CHECK(j["head"]["valid"].get<bool>());
    invalid += lost ? 1 : 0;
    ++lines;
  }
  std::filesystem::remove(path);
  CHECK(lines == 360);
  CHECK(invalid == 90);
}
