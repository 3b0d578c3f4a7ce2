// `embody avatar` end to end: info --json fields, export-default, usage errors.
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "cli/cli_support.h"
#include "test_paths.h"

using embody::test::runEmbody;

TEST_CASE("embody avatar info --json reports the default avatar's mapping and spine", "[avatar]") {
  const auto r = runEmbody("avatar info default --json");
  REQUIRE(r.exitCode == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["format"] == "procedural");
  CHECK(j["mapping"] == "names");
  CHECK(j["bones"]["hips"] == "humanoid_root");
  CHECK(j["bones"]["head"] == "skullbase");
  CHECK(j["unmapped_required"].empty());
  CHECK(j["joints"].get<int>() == 43);
  CHECK(j["triangles"].get<int>() >= 10000);
  REQUIRE(j["spine"].size() == 25);
  CHECK(j["spine"][0]["vertebrae"] == nlohmann::json::array({"vl5"}));
  CHECK(j["first_person"]["mode"] == "auto");
}

TEST_CASE("embody avatar info maps CesiumMan by topology", "[avatar]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  const auto r = runEmbody("avatar info '" + path + "' --json");
  REQUIRE(r.exitCode == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["format"] == "gltf");
  CHECK(j["mapping"] == "topology");
  CHECK(j["joints"].get<int>() == 19);
  CHECK(j["unmapped_required"].empty());
  CHECK(j["bones"]["leftHand"] == "Skeleton_arm_joint_L__2_");
}

TEST_CASE("embody avatar export-default writes a GLB that info reads back", "[avatar]") {
  const auto file =
      std::filesystem::temp_directory_path() / ("embody_cli_default_" + std::to_string(::getpid()) + ".glb");
  REQUIRE(runEmbody("avatar export-default '" + file.string() + "'").exitCode == 0);
  const auto r = runEmbody("avatar info '" + file.string() + "' --json");
  std::filesystem::remove(file);
  REQUIRE(r.exitCode == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["format"] == "gltf");
  CHECK(j["mapping"] == "names");
  CHECK(j["joints"].get<int>() == 43);
}

TEST_CASE("embody avatar export-default --fingers writes a mannequin whose 30 finger bones info finds",
          "[avatar]") {
  const auto plain = nlohmann::json::parse(runEmbody("avatar info default --json").output);
  CHECK(plain["finger_bones"]["mapped"] == 0);
  CHECK(plain["finger_bones"]["driven"] == 0);
  const auto file =
      std::filesystem::temp_directory_path() / ("embody_cli_fingers_" + std::to_string(::getpid()) + ".glb");
  REQUIRE(runEmbody("avatar export-default --fingers '" + file.string() + "'").exitCode == 0);
  const auto r = runEmbody("avatar info '" + file.string() + "' --json");
  const auto text = runEmbody("avatar info '" + file.string() + "'");
  std::filesystem::remove(file);
  REQUIRE(r.exitCode == 0);
  const auto j = nlohmann::json::parse(r.output);
  CHECK(j["joints"].get<int>() == 73);
  CHECK(j["finger_bones"]["mapped"] == 30);
  CHECK(j["finger_bones"]["left"] == 15);
  CHECK(j["finger_bones"]["right"] == 15);
  CHECK(j["finger_bones"]["driven"] == 30);
  CHECK(j["bones"]["leftThumbMetacarpal"] == "l_thumb1");
  CHECK(j["bones"]["rightLittleDistal"] == "r_pinky3");
  CHECK(j["body_model"]["dofs"] == plain["body_model"]["dofs"]);  // the IK does not see the fingers
  CHECK(text.output.find("finger bones: 30 of 30 mapped (left 15, right 15); 30 driven") != std::string::npos);
  const auto direct = nlohmann::json::parse(runEmbody("avatar info default --fingers --json").output);
  CHECK(direct["finger_bones"]["mapped"] == 30);
}

TEST_CASE("embody avatar reports usage and file errors with the right exit codes", "[avatar]") {
  CHECK(runEmbody("avatar").exitCode == 2);
  CHECK(runEmbody("avatar frobnicate").exitCode == 2);
  CHECK(runEmbody("avatar info").exitCode == 2);
  const auto missing = runEmbody("avatar info /nonexistent.glb", true);
  CHECK(missing.exitCode == 1);
  CHECK_THAT(missing.output, Catch::Contains("cannot open"));
  const auto badMap = runEmbody("avatar info default --bone-map /nonexistent.json", true);
  CHECK(badMap.exitCode == 1);
}

TEST_CASE("embody avatar info reports the body model, --spine and calibration profiles apply", "[avatar]") {
  auto j = nlohmann::json::parse(runEmbody("avatar info default --json").output);
  CHECK(j["body_model"]["spine_model"] == "full");
  CHECK(j["body_model"]["spine_sites"].size() == 25);
  CHECK(j["body_model"]["mass_kg"].get<double>() == Approx(75.0));
  j = nlohmann::json::parse(runEmbody("avatar info default --json --spine simplified").output);
  CHECK(j["body_model"]["spine_model"] == "simplified");
  CHECK(runEmbody("avatar info default --spine sideways").exitCode == 2);

  const auto profile =
      std::filesystem::temp_directory_path() / ("embody_cli_profile_" + std::to_string(::getpid()) + ".json");
  REQUIRE(
      runEmbody("avatar calibrate default --user-height 1.9 --profile '" + profile.string() + "'").exitCode ==
      0);
  j = nlohmann::json::parse(
      runEmbody("avatar info default --json --profile '" + profile.string() + "'").output);
  std::filesystem::remove(profile);
  CHECK(j["body_model"]["scale"].get<double>() == Approx(1.9 / 1.755).epsilon(0.01));
  CHECK(runEmbody("avatar calibrate default --profile /tmp/x.json").exitCode == 2);
  CHECK(runEmbody("avatar calibrate default --user-height 40 --profile /tmp/x.json").exitCode == 2);
}

TEST_CASE("a profile's arm span reaches the runtime, and arms beyond twice the avatar's stop the run", "[avatar]") {
  const auto dir = std::filesystem::temp_directory_path() / ("embody_cli_arms_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string longArms = (dir / "long.json").string(), absurd = (dir / "absurd.json").string();
  REQUIRE(runEmbody("avatar calibrate default --user-height 1.75 --arm-span 2.0 --profile '" + longArms + "'").exitCode == 0);
  REQUIRE(runEmbody("avatar calibrate default --user-height 1.0 --arm-span 2.5 --profile '" + absurd + "'").exitCode == 0);
  const auto ok = runEmbody("render --motion synthetic:reach --frames 30 --ik-iterations 10 --size 32x32 --out '" +
                            (dir / "ok").string() + "' --profile '" + longArms + "'");
  CHECK(ok.exitCode == 0);
  const auto bad = runEmbody("render --motion synthetic:reach --frames 3 --ik-iterations 2 --size 32x32 --out '" +
                                 (dir / "bad").string() + "' --profile '" + absurd + "'",
                             true);
  std::filesystem::remove_all(dir);
  CHECK(bad.exitCode == 1);
  CHECK(bad.output.find("an arm span of 2.5") != std::string::npos);
  CHECK(bad.output.find("outside half to twice this avatar's") != std::string::npos);
}
