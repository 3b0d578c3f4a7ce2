// The spine description: embedded defaults, JSON round trip, and one clear error per kind of
// broken file (ozz-style: every invalid input tried).
#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "ik/spine/spine_description.h"

using namespace embody::ik::spine;
using nlohmann::json;

TEST_CASE("the embedded full spine is the 24 H-Anim vertebral joints, caudal to cranial") {
  const SpineDescription& d = defaultFullSpine();
  REQUIRE(d.vertebrae.size() == 24);
  const char* expected[] = {"vl5", "vl4", "vl3", "vl2", "vl1", "vt12", "vt11", "vt10", "vt9", "vt8", "vt7", "vt6",
                            "vt5", "vt4", "vt3", "vt2", "vt1", "vc7", "vc6", "vc5", "vc4", "vc3", "vc2", "vc1"};
  for (int i = 0; i < 24; ++i) CHECK(d.vertebrae[i].name == expected[i]);
  CHECK(d.vertebrae[0].level == "L5-S1");
  CHECK(d.vertebrae[23].level == "C1-C2");
  CHECK(d.swingCount() == 18);
  CHECK(d.revoluteCount() == 6);
  CHECK(d.findVertebra("skullbase") < 0);  // the head joint is not one of the 24
}

TEST_CASE("a description survives toJson -> parse unchanged") {
  for (const SpineDescription* d : {&defaultFullSpine(), &defaultSimplifiedSpine()}) {
    auto again = parseSpineDescription(toJson(*d));
    REQUIRE(again.ok());
    CHECK(toJson(*again) == toJson(*d));
  }
}

TEST_CASE("a user file loads, e.g. a stiffer spine") {
  json j = toJson(defaultFullSpine());
  j["name"] = "elderly";
  for (auto& v : j["vertebrae"])
    for (auto& r : v["range_deg"]) r = r.get<double>() * 0.5;
  const auto path = std::filesystem::temp_directory_path() / "embody_spine_test_elderly.json";
  std::ofstream(path) << j.dump();
  auto d = loadSpineModel(path.string());
  std::filesystem::remove(path);
  REQUIRE(d.ok());
  CHECK(d->name == "elderly");
  CHECK(d->vertebrae[0].range[0] == Approx(defaultFullSpine().vertebrae[0].range[0] * 0.5));
}

TEST_CASE("broken descriptions give errors that name the problem") {
  const json good = toJson(defaultFullSpine());
  auto expectError = [](const json& j, const std::string& fragment) {
    auto r = parseSpineDescription(j);
    INFO("expected an error containing: " << fragment);
    REQUIRE_FALSE(r.ok());
    CHECK_THAT(r.error(), Catch::Contains(fragment));
  };
  {
    json j = good;
    j["format"] = "something";
    expectError(j, "format must be");
  }
  {
    json j = good;
    j.erase("vertebrae");
    expectError(j, "\"vertebrae\" must be an array");
  }
  {
    json j = good;
    j["vertebrae"][3]["range_deg"] = {1, 2};
    expectError(j, "vertebrae[3] (vl2): \"range_deg\" must be an array of 3 numbers");
  }
  {
    json j = good;
    j["vertebrae"][3]["range_deg"][0] = -4;
    expectError(j, "every range must be > 0");
  }
  {
    json j = good;
    j["vertebrae"][5]["region"] = "sacral";
    expectError(j, "region \"sacral\"");
  }
  {
    json j = good;
    j["vertebrae"][0]["region"] = "cervical";
    expectError(j, "regions must go caudal to cranial");
  }
  {
    json j = good;
    j["vertebrae"][1]["name"] = "vl5";
    j["sites"][1]["first"] = j["sites"][1]["last"] = "vl5";
    expectError(j, "duplicate name");
  }
  {
    json j = good;
    j["vertebrae"][2]["length_m"] = 0;
    expectError(j, "length_m must be > 0");
  }
  {
    json j = good;
    j["sites"].erase(4);
    expectError(j, "expected it to start at vl1");
  }
  {
    json j = good;
    j["sites"][3]["joints"] = "swing";  // vl2 was the only lumbar revolute
    expectError(j, "lumbar region has no revolute joint");
  }
  {
    json j = good;
    j["sites"][4]["last"] = "vt12";  // vl1 and vt12 in one site
    expectError(j, "must not span two regions");
  }
  {
    json j = good;
    j["sites"][0]["first"] = "L5";
    expectError(j, "unknown vertebra \"L5\"");
  }
  {
    json j = good;
    j["sites"][0]["joints"] = "hinge";
    expectError(j, "is not one of swing, revolute, swing+revolute");
  }
  {
    json j = good;
    j["axis_coupling"][0]["side"] = "left";
    expectError(j, "side must be");
  }
  {
    json j = good;
    j["flexion_share"] = 1.5;
    expectError(j, "flexion_share must be in (0, 1)");
  }
  CHECK_THAT(parseSpineDescriptionText("{ not json").error(), Catch::Contains("not valid JSON"));
  CHECK_THAT(loadSpineModel("/nonexistent/spine.json").error(), Catch::Contains("cannot open"));
}
