// BVH: parsing (channel order, frame time, end sites), broken files, tracker derivation, and the
// shared CMU walk.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/gtc/quaternion.hpp>

#include "avatar/bvh/bvh.h"
#include "core/percentile.h"
#include "test_paths.h"
#include "tracking/body_dimensions.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_source.h"

using namespace embody;
using namespace embody::tracking;
using avatar::BvhClip;

namespace {

// A 45-unit-tall figure facing +Z, +Y up, the usual BVH layout. `names` picks a naming style.
std::string figure(const std::string& style, int frames = 3, bool withFeet = true) {
  auto n = [&](const std::string& cmu, const std::string& mixamo, const std::string& bandai) {
    return style == "mixamo" ? mixamo : style == "bandai" ? bandai : cmu;
  };
  std::string s = "HIERARCHY\nROOT " + n("Hips", "mixamorig:Hips", "Hips") + "\n{\n  OFFSET 0 0 0\n"
                  "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                  "  JOINT " + n("Spine", "mixamorig:Spine", "Chest") + "\n  {\n    OFFSET 0 10 0\n"
                  "    CHANNELS 3 Xrotation Zrotation Yrotation\n"
                  "    JOINT " + n("Head", "mixamorig:Head", "Head") + "\n    {\n      OFFSET 0 10 0\n"
                  "      CHANNELS 3 Zrotation Yrotation Xrotation\n      End Site\n      {\n        OFFSET 0 5 0\n      }\n    }\n";
  for (int side = 0; side < 2; ++side) {
    const std::string sx = side == 0 ? "" : "-";
    const std::string arm = side == 0 ? n("LeftArm", "mixamorig:LeftArm", "UpperArm_L") : n("RightArm", "mixamorig:RightArm", "UpperArm_R");
    const std::string hand = side == 0 ? n("LeftHand", "mixamorig:LeftHand", "Hand_L") : n("RightHand", "mixamorig:RightHand", "Hand_R");
    s += "    JOINT " + arm + "\n    {\n      OFFSET " + sx + "5 8 0\n      CHANNELS 3 Zrotation Yrotation Xrotation\n"
         "      JOINT " + hand + "\n      {\n        OFFSET " + sx + "8 0 0\n        CHANNELS 3 Zrotation Yrotation Xrotation\n"
         "        End Site\n        {\n          OFFSET " + sx + "2 0 0\n        }\n      }\n    }\n";
  }
  s += "  }\n";
  for (int side = 0; side < 2; ++side) {
    const std::string sx = side == 0 ? "" : "-";
    const std::string leg = side == 0 ? n("LeftUpLeg", "mixamorig:LeftUpLeg", "UpperLeg_L") : n("RightUpLeg", "mixamorig:RightUpLeg", "UpperLeg_R");
    const std::string foot = side == 0 ? n("LeftFoot", "mixamorig:LeftFoot", "Foot_L") : n("RightFoot", "mixamorig:RightFoot", "Foot_R");
    s += "  JOINT " + leg + "\n  {\n    OFFSET " + sx + "3 0 0\n    CHANNELS 3 Zrotation Yrotation Xrotation\n";
    if (withFeet)
      s += "    JOINT " + foot + "\n    {\n      OFFSET 0 -18 0\n      CHANNELS 3 Zrotation Yrotation Xrotation\n"
           "      End Site\n      {\n        OFFSET 0 -2 3\n      }\n    }\n";
    else
      s += "    End Site\n    {\n      OFFSET 0 -20 0\n    }\n";
    s += "  }\n";
  }
  s += "}\nMOTION\nFrames: " + std::to_string(frames) + "\nFrame Time: 0.0333333\n";
  const int channels = withFeet ? 36 : 30;
  for (int f = 0; f < frames; ++f) {
    // The root walks forward (+Z in the file) 10 units per frame at 20 units height.
    s += "0 20 " + std::to_string(10 * f);
    for (int c = 3; c < channels; ++c) s += " 0";
    s += "\n";
  }
  return s;
}

glm::dquat rot(char axis, double deg) {
  const glm::dvec3 a(axis == 'X', axis == 'Y', axis == 'Z');
  return glm::angleAxis(glm::radians(deg), a);
}

}  // namespace

TEST_CASE("BVH parsing keeps the hierarchy, channel order and frame time") {
  auto clip = avatar::parseBvh(figure("cmu"), "fig.bvh");
  REQUIRE(clip.ok());
  CHECK(clip->joints.size() == 16);  // 11 joints + 5 end sites
  CHECK(clip->channelCount == 36);
  CHECK(clip->frameCount == 3);
  CHECK(clip->frameTime == Approx(0.0333333));
  CHECK(clip->find("Head_End") >= 0);
  CHECK(clip->joints[static_cast<size_t>(clip->find("Head_End"))].endSite);
  CHECK(clip->joints[static_cast<size_t>(clip->find("Spine"))].firstChannel == 6);

  // Channels are applied in the order listed: Spine is "X Z Y", Head "Z Y X".
  std::vector<float> values(36, 0.0f);
  values[6] = 30, values[7] = 40, values[8] = 50;     // Spine X, Z, Y
  values[9] = 30, values[10] = 40, values[11] = 50;   // Head Z, Y, X
  std::vector<avatar::BvhGlobal> g;
  avatar::bvhGlobals(*clip, values, g);
  const glm::dquat spine = rot('X', 30) * rot('Z', 40) * rot('Y', 50);
  const glm::dquat head = spine * rot('Z', 30) * rot('Y', 40) * rot('X', 50);
  CHECK(std::abs(glm::dot(g[1].rotation, spine)) == Approx(1.0).margin(1e-9));
  CHECK(std::abs(glm::dot(g[2].rotation, head)) == Approx(1.0).margin(1e-9));
  CHECK(glm::length(g[2].position - spine * glm::dvec3(0, 10, 0) - glm::dvec3(0, 10, 0)) < 1e-9);
  // Root position channels add to the offset.
  avatar::bvhGlobals(*clip, clip->frame(2), g);
  CHECK(g[0].position.z == Approx(20.0));
}

TEST_CASE("broken BVH files give an error with the line, never a crash") {
  const std::string good = figure("cmu");
  struct Case {
    std::string text, expect;
  };
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  const Case cases[] = {
      {"", "empty file"},
      {"HIERARCHI\n", "fig.bvh:1: expected HIERARCHY"},
      {replace("OFFSET 0 10 0", "OFFSET 0 ten 0"), "fig.bvh:8: OFFSET value 'ten'"},
      {replace("CHANNELS 3 Xrotation Zrotation", "CHANNELS 3 Wrotation Zrotation"), "fig.bvh:9: unknown channel 'Wrotation'"},
      {replace("CHANNELS 3 Xrotation Zrotation Yrotation", "CHANNELS 7 Xrotation"), "fig.bvh:9: CHANNELS needs a count"},
      {replace("CHANNELS 3 Xrotation Zrotation Yrotation", "CHANNELS 3 Xrotation"), "fig.bvh:9: CHANNELS declares 3"},
      {replace("Frames: 3", "Frames: 99999999999"), "more than this loader accepts"},
      {replace("Frame Time: 0.0333333", "Frame Time: 0"), "'Frame Time:' needs a positive"},
      {replace("0 20 10", "0 20 10 0"), "fig.bvh:81: frame 1 has 37 values, expected 36"},
      {replace("0 20 20", "0 20 nan"), "fig.bvh:82: frame value 'nan'"},
      {replace("MOTION", "MOTIONS"), "fig.bvh:77: expected ROOT, found 'MOTIONS'"},
      {good.substr(0, good.find("MOTION")), "unexpected end of file in HIERARCHY"},
      {replace("  JOINT Spine\n  {", "  JOINT Spine\n  ("), "fig.bvh:7: expected '{'"},
  };
  for (const auto& c : cases) {
    INFO(c.expect);
    auto clip = avatar::parseBvh(c.text, "fig.bvh");
    REQUIRE_FALSE(clip.ok());
    CHECK_THAT(clip.error(), Catch::Contains(c.expect));
  }
  // Every truncation of a valid file parses or fails cleanly.
  for (size_t n = 0; n < good.size(); n += 3) {
    auto clip = avatar::parseBvh(good.substr(0, n), "cut.bvh");
    if (!clip.ok()) CHECK(clip.error().rfind("cut.bvh:", 0) == 0);
  }
  // Declared frames missing at the end: a warning, the frames present are used.
  auto fewer = avatar::parseBvh(replace("Frames: 3", "Frames: 5"), "fig.bvh");
  REQUIRE(fewer.ok());
  CHECK(fewer->frameCount == 3);
  CHECK(fewer->warnings.size() == 1);
  // Joint limits bound the allocation.
  avatar::BvhLimits tiny;
  tiny.maxJoints = 4;
  auto limited = avatar::parseBvh(good, "fig.bvh", tiny);
  REQUIRE_FALSE(limited.ok());
  CHECK_THAT(limited.error(), Catch::Contains("more than 4 joints"));
}

TEST_CASE("BVH text from other tools: a byte order mark, CR-only lines, no space after the header colon") {
  const std::string good = figure("cmu");
  auto expectSame = [&](const std::string& text) {
    auto clip = avatar::parseBvh(text, "fig.bvh");
    REQUIRE(clip.ok());
    CHECK(clip->joints.size() == 16);
    CHECK(clip->frameCount == 3);
    CHECK(clip->frameTime == Approx(0.0333333));
    CHECK(clip->values == avatar::parseBvh(good, "fig.bvh")->values);
  };
  SECTION("a UTF-8 byte order mark is skipped") { expectSame("\xEF\xBB\xBF" + good); }
  SECTION("lines ended by CR alone, or by CR LF") {
    std::string cr = good, crlf;
    std::replace(cr.begin(), cr.end(), '\n', '\r');
    expectSame(cr);
    for (char c : good) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
    expectSame(crlf);
    // Line numbers count CR-only lines too.
    std::string bad = cr;
    bad.replace(bad.find("OFFSET 0 10 0"), 13, "OFFSET 0 ten 0");
    CHECK_THAT(avatar::parseBvh(bad, "fig.bvh").error(), Catch::Contains("fig.bvh:8: OFFSET value 'ten'"));
  }
  SECTION("'Frames:361' and 'Frame Time:0.033' without a space after the colon") {
    std::string s = good;
    s.replace(s.find("Frames: 3"), 9, "Frames:3");
    s.replace(s.find("Frame Time: "), 12, "frame  time:");
    expectSame(s);
  }
}

TEST_CASE("BVH header values over the loader's limits say the limit, and quoted lines are cut short") {
  const std::string good = figure("cmu");
  auto replace = [&](const std::string& from, const std::string& to) {
    std::string s = good;
    s.replace(s.find(from), from.size(), to);
    return s;
  };
  auto error = [](const std::string& text) {
    auto clip = avatar::parseBvh(text, "fig.bvh");
    REQUIRE_FALSE(clip.ok());
    return clip.error();
  };
  // A count that is a non-negative integer, only too large: was "needs a non-negative integer".
  const std::string frames = error(replace("Frames: 3", "Frames: 99999999999999"));
  CHECK_THAT(frames, Catch::Contains("'Frames: 99999999999999' is more than this loader accepts: at most"));
  CHECK_THAT(frames, !Catch::Contains("non-negative integer"));
  CHECK_THAT(error(replace("Frames: 3", "Frames: -3")), Catch::Contains("'Frames:' needs a non-negative integer, found '-3'"));
  // A frame time that is positive, only too long: was "needs a positive number of seconds".
  const std::string time = error(replace("Frame Time: 0.0333333", "Frame Time: 99"));
  CHECK_THAT(time, Catch::Contains("'Frame Time: 99'"));
  CHECK_THAT(time, Catch::Contains("1 .. 1000 Hz"));
  CHECK_THAT(time, !Catch::Contains("positive number"));
  // The first frame in place of the missing 'Frame Time:' line: quoted to 80 characters, not whole.
  std::string longFrame = "0 20 0";
  for (int c = 3; c < 36; ++c) longFrame += " 0.000000";
  const std::string missing = error(replace("Frame Time: 0.0333333\n0 20 0", longFrame));
  CHECK_THAT(missing, Catch::Contains("expected 'Frames: N' and 'Frame Time: SECONDS', found '0 20 0"));
  CHECK_THAT(missing, Catch::Contains("...' ("));
  CHECK_THAT(missing, Catch::EndsWith(" characters)"));
  CHECK(missing.size() < 220);
  const std::string token = error(replace("OFFSET 0 10 0", "OFFSET 0 " + std::string(500, '7') + "x 0"));
  CHECK(token.size() < 200);
}

TEST_CASE("a BVH frame time outside the rates --fps takes (1 .. 1000 Hz) is refused, 1000 Hz itself is read") {
  const std::string good = figure("cmu");
  auto withTime = [&](const std::string& t) {
    std::string s = good;
    s.replace(s.find("Frame Time: 0.0333333"), 21, "Frame Time: " + t);
    return avatar::parseBvh(s, "fig.bvh");
  };
  // "Frame Time: 1e-9" was read as 10^9 Hz (a 3 s walk in microseconds, eval at exit 0).
  for (const char* t : {"1e-9", "0.0005", "1.5", "10"}) {
    INFO(t);
    auto clip = withTime(t);
    REQUIRE_FALSE(clip.ok());
    CHECK_THAT(clip.error(), Catch::Contains(std::string("fig.bvh:79: 'Frame Time: ") + t + "' is "));
    CHECK_THAT(clip.error(), Catch::Contains("this loader accepts 1 .. 1000 Hz (Frame Time 0.001 .. 1 s)"));
  }
  // 1000 Hz and 1 Hz are rates --fps takes; a rounded 1/1000 (0.00099) is 1000 Hz too.
  for (const char* t : {"0.001", "0.00099", "1", "0.0083333", "0.0416667"}) {
    INFO(t);
    CHECK(withTime(t).ok());
  }
}

TEST_CASE("BVH trackers in OpenXR conventions from CMU, Mixamo and Bandai-Namco namings") {
  for (const std::string style : {"cmu", "mixamo", "bandai"}) {
    INFO(style);
    auto clip = avatar::parseBvh(figure(style), "fig.bvh");
    REQUIRE(clip.ok());
    BvhMapping map;
    auto trace = bvhToTrace(*clip, {}, &map);
    REQUIRE(trace.ok());
    CHECK(trace->trackers == TrackerMask::all());
    for (int j : map.joint) CHECK(j >= 0);
    CHECK(map.upAxis == "+Y");
    CHECK(map.facingAxis == "+Z");
    CHECK(map.heightUnits == Approx(45.0));
    CHECK(map.scale == Approx(1.75 / 45.0));
    const PoseSample& s0 = trace->samples[0];
    // Rotated 180 deg about Y: the performer's left is -X, forward -Z; the lowest point (the toe
    // end site) on the floor; the hips over the origin.
    CHECK(s0[TrackerId::LeftHand].position.x < -0.3f);
    CHECK(s0[TrackerId::RightHand].position.x > 0.3f);
    CHECK(s0[TrackerId::Hips].position.x == Approx(0.0f).margin(1e-6));
    CHECK(s0[TrackerId::Hips].position.z == Approx(0.0f).margin(1e-6));
    CHECK(s0[TrackerId::LeftFoot].position.y == Approx(2.0f * 1.75f / 45.0f).margin(1e-4));
    CHECK(s0[TrackerId::Head].position.y == Approx(kEyeHeightRatio * 1.75f).margin(0.01));
    CHECK(s0[TrackerId::Head].position.z < s0[TrackerId::Hips].position.z);  // eyes ahead
    CHECK(std::abs(glm::angle(s0[TrackerId::Head].orientation)) < 1e-4f);   // rest = identity
    // T-pose hands: thumbs (grip -Z) forward.
    CHECK(glm::length(s0[TrackerId::LeftHand].orientation * glm::vec3(0, 0, -1) - glm::vec3(0, 0, -1)) < 1e-4f);
    // Walking along the file's +Z is walking forward: -Z in OpenXR.
    CHECK(trace->samples[2][TrackerId::Hips].position.z == Approx(-20.0f * 1.75f / 45.0f).margin(1e-4));
  }
}

TEST_CASE("the BVH floor is where the feet stand, not a glitch frame's lowest point") {
  // 40 frames; in one the whole figure drops 5 units (a marker glitch, or an end site
  // extrapolated through the floor). The floor is the 5th percentile of each frame's lowest
  // point, so the feet stand on it in the other 39; the clip's lowest point would have stood them
  // 5 units (19 cm) in the air.
  auto clip = avatar::parseBvh(figure("cmu", 40), "glitch.bvh");
  REQUIRE(clip.ok());
  clip->values[7 * 36 + 1] = 15.0f;
  auto trace = bvhToTrace(*clip, {}, nullptr);
  REQUIRE(trace.ok());
  const float unit = 1.75f / 45.0f;
  for (int f : {0, 6, 8, 39}) CHECK(trace->samples[size_t(f)][TrackerId::LeftFoot].position.y == Approx(2.0f * unit).margin(1e-4));
  CHECK(trace->samples[7][TrackerId::LeftFoot].position.y == Approx(-3.0f * unit).margin(1e-4));
  // Three glitch frames in 40 (7.5 %) are more than the percentile ignores: the floor follows them.
  for (int f : {7, 17, 27}) clip->values[size_t(f) * 36 + 1] = 15.0f;
  auto glitchy = bvhToTrace(*clip, {}, nullptr);
  REQUIRE(glitchy.ok());
  CHECK(glitchy->samples[0][TrackerId::LeftFoot].position.y == Approx(7.0f * unit).margin(1e-4));
}

TEST_CASE("a BVH tracker whose joint is missing is absent and reported") {
  auto clip = avatar::parseBvh(figure("cmu", 2, false), "nofeet.bvh");
  REQUIRE(clip.ok());
  BvhMapping map;
  auto trace = bvhToTrace(*clip, {}, &map);
  REQUIRE(trace.ok());
  CHECK_FALSE(trace->trackers.has(TrackerId::LeftFoot));
  CHECK_FALSE(trace->samples[0][TrackerId::LeftFoot].valid);
  bool reported = false;
  for (const auto& n : map.notes) reported = reported || n.rfind("left_foot: no joint", 0) == 0;
  CHECK(reported);
}

TEST_CASE("a Z-up BVH is turned upright") {
  // The same figure with every offset and position rotated into Z-up (y -> z, z -> -y).
  auto clip = avatar::parseBvh(figure("cmu"), "fig.bvh");
  REQUIRE(clip.ok());
  for (auto& j : clip->joints) j.offset = glm::dvec3(j.offset.x, -j.offset.z, j.offset.y);
  for (size_t f = 0; f < clip->frameCount; ++f) {
    float* v = clip->values.data() + f * 36;
    const float y = v[1], z = v[2];
    v[1] = -z;
    v[2] = y;
  }
  BvhMapping map;
  auto trace = bvhToTrace(*clip, {}, &map);
  REQUIRE(trace.ok());
  CHECK(map.upAxis == "+Z");
  const PoseSample& s = trace->samples[0];
  CHECK(s[TrackerId::Head].position.y == Approx(kEyeHeightRatio * 1.75f).margin(0.01));
  CHECK(s[TrackerId::LeftHand].position.x < -0.3f);
}

TEST_CASE("a body standing over its feet along no axis of the file is refused unless --bvh-up says how") {
  // The figure turned 20 degrees about X stands in a tilted capture volume and reads (snapped to
  // +Y); turned 50 degrees it is what a quadruped with human names or a lying performer measures
  // (43-55 degrees): refused, and read as told with --bvh-up.
  for (const double degrees : {20.0, 50.0}) {
    auto clip = avatar::parseBvh(figure("cmu"), "fig.bvh");
    REQUIRE(clip.ok());
    const double a = glm::radians(degrees), c = std::cos(a), s = std::sin(a);
    auto tilt = [&](glm::dvec3 v) { return glm::dvec3(v.x, c * v.y - s * v.z, s * v.y + c * v.z); };
    for (auto& j : clip->joints) j.offset = tilt(j.offset);
    for (size_t f = 0; f < clip->frameCount; ++f) {
      float* v = clip->values.data() + f * 36;
      const glm::dvec3 p = tilt(glm::dvec3(v[0], v[1], v[2]));
      v[0] = float(p.x), v[1] = float(p.y), v[2] = float(p.z);
    }
    INFO(degrees << " degrees");
    auto trace = bvhToTrace(*clip, {}, nullptr);
    if (degrees < 25.0) {
      CHECK(trace.ok());
      continue;
    }
    REQUIRE_FALSE(trace.ok());
    CHECK(trace.error().find("not a standing humanoid") != std::string::npos);
    CHECK(trace.error().find("--bvh-up") != std::string::npos);
    BvhTrackerOptions told;
    told.body.up = "+Y";
    CHECK(bvhToTrace(*clip, told, nullptr).ok());
  }
}

TEST_CASE("the CMU walk: 524 frames at 120 Hz, a plausible head height, about 3.8 m walked") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "cmu_12_01_walk.bvh");
  BvhMapping map;
  auto src = openBvhSource(path, {}, &map);
  REQUIRE(src.ok());
  auto& s = **src;
  auto clip = avatar::loadBvh(path);
  REQUIRE(clip.ok());
  CHECK(clip->frameCount == 524);
  CHECK(clip->frameTime == Approx(1.0 / 120.0).epsilon(0.001));
  // Frame 0 of CMU's conversions is a T-pose reference, skipped with a note.
  CHECK(s.frameCount() == 523);
  bool noted = false;
  for (const auto& n : s.notes()) noted = noted || n.rfind("frame 0 is a reference pose", 0) == 0;
  CHECK(noted);
  CHECK(s.nativeRate() == Approx(120.0).epsilon(0.001));
  CHECK(s.duration() == Approx(522.0 / 120.0).epsilon(0.001));
  CHECK(s.trackers() == TrackerMask::all());
  // Standing height about 25 units (sole to the top of the head over the walk), fitted to 1.75 m.
  CHECK(map.heightUnits == Approx(25.0).margin(0.3));
  float minHead = 10, maxHead = 0, minFoot = 10, maxSpeed = 0;
  float forward = 0;
  glm::vec3 prevHand = s.trace().samples[0][TrackerId::RightHand].position;
  for (const auto& f : s.trace().samples) {
    minHead = std::min(minHead, f[TrackerId::Head].position.y);
    maxHead = std::max(maxHead, f[TrackerId::Head].position.y);
    minFoot = std::min({minFoot, f[TrackerId::LeftFoot].position.y, f[TrackerId::RightFoot].position.y});
    forward += -(f[TrackerId::Head].orientation * glm::vec3(0, 0, -1)).z;
    CHECK(f[TrackerId::LeftHand].position.x < f[TrackerId::RightHand].position.x);
    maxSpeed = std::max(maxSpeed, glm::length(f[TrackerId::RightHand].position - prevHand) * 120.0f);
    prevHand = f[TrackerId::RightHand].position;
  }
  CHECK(maxSpeed < 3.0f);  // no reference-pose jump left
  CHECK(minHead > 1.5f);
  CHECK(maxHead < 1.8f);
  CHECK(minFoot > 0.02f);
  CHECK(minFoot < 0.15f);
  CHECK(forward / 523.0f > 0.9f);  // looking where it walks: along -Z
  const auto& samples = s.trace().samples;
  const glm::vec3 walked = samples.back()[TrackerId::Hips].position - samples.front()[TrackerId::Hips].position;
  CHECK(walked.z < 0.0f);
  // In CMU's own units (5.64 cm per unit) the walk is about 3.8 m.
  BvhTrackerOptions cmuUnits;
  cmuUnits.scale = 0.0564;
  auto real = openBvhSource(path, cmuUnits);
  REQUIRE(real.ok());
  const auto& rs = (*real)->trace().samples;
  const glm::vec3 d = rs.back()[TrackerId::Hips].position - rs.front()[TrackerId::Hips].position;
  CHECK(std::hypot(d.x, d.z) == Approx(3.85).margin(0.1));
  // Fitted to 1.75 m the same walk is proportionally longer.
  CHECK(std::hypot(walked.x, walked.z) == Approx(3.85 * map.scale / 0.0564).margin(0.15));
}

TEST_CASE("percentileByRank: the value at rank floor(p n), as the BVH floor reads it", "[tracking][bvh]") {
  std::vector<double> v;
  for (int i = 99; i >= 0; --i) v.push_back(double(i));  // 100 values, reversed
  CHECK(embody::percentileByRank(v, 0.05) == 5.0);
  CHECK(embody::percentileByRank(v, 0.0) == 0.0);
  CHECK(embody::percentileByRank(v, 1.0) == 99.0);  // rank clamped to the last value
  std::vector<double> three{3.0, 1.0, 2.0};
  CHECK(embody::percentileByRank(three, 0.05) == 1.0);  // floor(0.15) = rank 0: the lowest
  std::vector<double> none;
  CHECK(std::isnan(embody::percentileByRank(none, 0.05)));
}

TEST_CASE("a BVH scale (--bvh-scale) must make the performer a plausible height, and --user-height has one range", "[tracking][bvh]") {
  auto clip = avatar::parseBvh(figure("cmu", 4), "fig.bvh");  // 45 units tall
  REQUIRE(clip.ok());
  // 1e30 and 1e-30 reached the body solver ("a rest frame is not finite"), 1e6 scored 2.4e9 cm.
  for (double scale : {1e30, 1e-30, 1e6, 0.001, 0.1}) {
    INFO(scale);
    BvhTrackerOptions o;
    o.scale = scale;
    auto t = bvhToTrace(*clip, o);
    REQUIRE_FALSE(t.ok());
    CHECK_THAT(t.error(), Catch::StartsWith("--bvh-scale "));
    CHECK_THAT(t.error(), Catch::Contains("m tall (45 units standing), not 0.5 .. 2.6 m"));
    CHECK_THAT(t.error(), Catch::Contains("give 0.0111 .. 0.0578 m/unit"));
  }
  BvhTrackerOptions plausible;
  plausible.scale = 0.04;  // 1.8 m
  CHECK(bvhToTrace(*clip, plausible).ok());
  // --user-height: the range of every CLI option (0.5 .. 2.6 m), not 2.5 here; the message names
  // the option, not the clip (openBvhSource checks it before the file).
  BvhTrackerOptions tall;
  tall.userHeight = 2.55f;
  CHECK(bvhToTrace(*clip, tall).ok());
  tall.userHeight = 2.7f;
  auto refused = bvhToTrace(*clip, tall);
  REQUIRE_FALSE(refused.ok());
  CHECK_THAT(refused.error(), Catch::Contains("--user-height 2.7 m is outside 0.5 .. 2.6 m"));
  auto opened = openBvhSource("no_such_clip.bvh", tall);
  REQUIRE_FALSE(opened.ok());
  CHECK_THAT(opened.error(), Catch::StartsWith("--user-height 2.7 m"));
}

namespace {

bool hasNote(const std::vector<std::string>& notes, const std::string& text) {
  return std::any_of(notes.begin(), notes.end(), [&](const std::string& n) { return n.find(text) != std::string::npos; });
}

}  // namespace

TEST_CASE("a BVH root that jumps away faster than any body moves and comes back is repaired, with a note", "[tracking][bvh]") {
  // The figure walks 10 units a frame at 30 Hz; its skeleton reaches 25 units from the root.
  auto parsed = avatar::parseBvh(figure("cmu", 40), "glitch.bvh");
  REQUIRE(parsed.ok());
  const BvhClip clean = *parsed;
  auto rootY = [](const BvhClip& c, size_t f) { return c.values[f * 36 + 1]; };
  SECTION("one frame at a lost-marker sentinel (99999) or 1e30: interpolated, noted in the trace and the mapping") {
    for (float bad : {99999.0f, 1e30f}) {
      INFO(bad);
      BvhClip clip = clean;
      clip.values[20 * 36 + 1] = bad;
      BvhMapping map;
      auto trace = bvhToTrace(clip, {}, &map);
      REQUIRE(trace.ok());
      auto ref = bvhToTrace(clean, {});
      REQUIRE(ref.ok());
      // The glitch frame's hips are where the clean clip's are (the line between frames 19 and 21).
      CHECK(glm::length(trace->samples[20][TrackerId::Hips].position - ref->samples[20][TrackerId::Hips].position) < 1e-4f);
      CHECK(trace->samples[0][TrackerId::LeftFoot].position.y == Approx(ref->samples[0][TrackerId::LeftFoot].position.y));
      CHECK(hasNote(map.notes, "root glitch in frame 20 (1 of 40)"));
      CHECK(hasNote(trace->notes, "root glitch in frame 20"));
      CHECK(rootY(clip, 20) == bad);  // the caller's clip is left as it was
      auto repaired = repairBvhGlitches(clip);
      REQUIRE(repaired.ok());
      CHECK(*repaired == 1);
      CHECK(rootY(clip, 20) == Approx(20.0f));
      CHECK(findBvhGlitches(clip)->empty());
    }
  }
  SECTION("ten frames with the root zeroed, the last frames, the first frame") {
    BvhClip clip = clean;
    for (size_t f = 10; f < 15; ++f) clip.values[f * 36 + 0] = clip.values[f * 36 + 1] = clip.values[f * 36 + 2] = 0.0f;
    for (size_t f = 37; f < 40; ++f) clip.values[f * 36 + 1] = 99999.0f;
    clip.values[1] = 1e30f;
    auto spans = findBvhGlitches(clip);
    REQUIRE(spans.ok());
    REQUIRE(spans->size() == 3);
    CHECK((*spans)[0].first == 0);
    CHECK((*spans)[0].last == 0);
    CHECK((*spans)[1].first == 10);
    CHECK((*spans)[1].last == 14);
    CHECK((*spans)[2].first == 37);
    CHECK((*spans)[2].last == 39);
    REQUIRE(repairBvhGlitches(clip).ok());
    CHECK(clip.values[12 * 36 + 2] == Approx(120.0f));  // on the line between frames 9 and 15
    CHECK(rootY(clip, 0) == Approx(20.0f));            // frame 1's
    CHECK(rootY(clip, 39) == Approx(20.0f));           // held at frame 36
    CHECK(clip.values[39 * 36 + 2] == Approx(360.0f));
    CHECK_THAT(clip.warnings.back(), Catch::Contains("root glitch in frames 0, 10-14, 37-39 (9 of 40)"));
  }
  SECTION("a cut (the root jumps and stays) is the clip's motion; a jump beyond any capture volume that stays is refused") {
    BvhClip cut = clean;
    for (size_t f = 15; f < 40; ++f) cut.values[f * 36 + 0] += 200.0f;
    CHECK(findBvhGlitches(cut)->empty());
    auto longer = avatar::parseBvh(figure("cmu", 80), "broken.bvh");
    REQUIRE(longer.ok());
    for (size_t f = 10; f < 80; ++f) longer->values[f * 36 + 1] = 1e30f;
    auto broken = bvhToTrace(*longer, {});
    REQUIRE_FALSE(broken.ok());
    CHECK_THAT(broken.error(), Catch::Contains("frame 10: the root jumps 1e+30 units"));
  }
  SECTION("the clip as an avatar (embody eval) is repaired too: its joints are what the body is scored against") {
    BvhClip clip = clean;
    clip.values[20 * 36 + 1] = 99999.0f;
    auto avatar = buildBvhAvatar(clip, {});
    REQUIRE(avatar.ok());
    CHECK(rootY(avatar->clip, 20) == Approx(20.0f));
    CHECK(hasNote(avatar->mapping.notes, "root glitch in frame 20"));  // eval's metrics.json notes
    CHECK(hasNote(avatar->clip.warnings, "root glitch in frame 20"));  // printed by embody eval
  }
}
