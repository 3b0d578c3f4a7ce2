// BVH import across conventions: one walking clip rewritten into every common convention (names,
// helper bones, world axes, bone axes, units, channel orders, frame rates, a T-pose first frame)
// gives the same trackers to 1 mm; the hand-written fixtures in fixtures/ map in each convention;
// a body that cannot be mapped or oriented stops with one line.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <fstream>

#include "avatar/bvh/bvh_body.h"
#include "avatar/humanoid/humanoid_map.h"
#include "bvh_convention_writer.h"
#include "test_paths.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_source.h"

using namespace embody;
using namespace embody::tracking;

namespace {

Result<Trace> traceOf(const std::string& text, const BvhTrackerOptions& options = {}, BvhMapping* map = nullptr) {
  auto clip = avatar::parseBvh(text, "clip.bvh");
  if (!clip) return Error{clip.error()};
  return bvhToTrace(*clip, options, map);
}

float angleBetween(const glm::quat& a, const glm::quat& b) {
  return 2.0f * std::acos(std::min(1.0f, std::abs(glm::dot(a, b))));
}

}  // namespace

TEST_CASE("one clip in every BVH convention gives the same trackers to 1 mm") {
  const auto& conventions = test::bvhConventions();
  BvhMapping refMap;
  auto ref = traceOf(test::writeConventionClip(conventions[0]), {}, &refMap);
  REQUIRE(ref.ok());
  REQUIRE(ref->trackers == TrackerMask::all());
  REQUIRE(ref->samples.size() == static_cast<size_t>(test::kConventionClipFrames));
  CHECK(refMap.upAxis == "+Y");
  CHECK(refMap.facingAxis == "+Z");
  CHECK(refMap.heightUnits == Approx(171.0).margin(3.0));  // head top 171 cm, the hips bobbing
  // Upright and facing -Z: the head at eye height above the feet, the left hand on -X.
  CHECK(ref->samples[0][TrackerId::Head].position.y == Approx(0.933f * 1.75f).margin(0.03));
  CHECK(ref->samples[0][TrackerId::LeftHand].position.x < ref->samples[0][TrackerId::RightHand].position.x);
  CHECK(ref->samples.back()[TrackerId::Hips].position.z < -0.5f);  // walked forward
  for (size_t c = 1; c < conventions.size(); ++c) {
    const auto& conv = conventions[c];
    INFO("convention " << conv.name);
    BvhMapping map;
    auto got = traceOf(test::writeConventionClip(conv), {}, &map);
    REQUIRE(got.ok());
    CHECK(got->trackers == TrackerMask::all());
    REQUIRE(got->samples.size() == ref->samples.size());
    CHECK(map.body.firstFrame == (conv.tposeFirst ? 1u : 0u));
    float worst = 0.0f, worstAngle = 0.0f;
    for (size_t f = 0; f < ref->samples.size(); ++f)
      for (auto id : kAllTrackers) {
        worst = std::max(worst, glm::length(got->samples[f][id].position - ref->samples[f][id].position));
        worstAngle = std::max(worstAngle, angleBetween(got->samples[f][id].orientation, ref->samples[f][id].orientation));
      }
    CHECK(worst < 1e-3f);
    CHECK(worstAngle < glm::radians(0.1f));
    CHECK(map.scale * map.heightUnits == Approx(1.75).epsilon(1e-6));
    // The clip as an avatar (eval, render --avatar CLIP.bvh) maps every limb bone to the
    // convention's joint: Daz Genesis 3's in-chain twist bones once sent the whole map to the
    // topology mapper, which took lCollar for the upper arm and rShldrTwist for the left hand.
    auto clip = avatar::parseBvh(test::writeConventionClip(conv), "clip.bvh");
    REQUIRE(clip.ok());
    const avatar::Skeleton skeleton = avatar::bvhSkeleton(*clip);
    avatar::HumanoidInputs in;
    in.skeleton = &skeleton;
    auto humanoid = avatar::mapHumanoid(in);
    REQUIRE(humanoid.ok());
    CHECK(humanoid->usable());
    using avatar::HumanBone;
    for (auto [bone, role] : {std::pair{HumanBone::leftUpperArm, test::kLUpperArm}, std::pair{HumanBone::leftLowerArm, test::kLLowerArm},
                              std::pair{HumanBone::leftHand, test::kLHand}, std::pair{HumanBone::rightHand, test::kRHand},
                              std::pair{HumanBone::leftUpperLeg, test::kLUpperLeg}, std::pair{HumanBone::rightFoot, test::kRFoot}}) {
      INFO(avatar::humanBoneName(bone));
      REQUIRE(humanoid->has(bone));
      CHECK(skeleton.joints[size_t(humanoid->joint(bone))].name == conv.names[size_t(role)]);
    }
  }
}

TEST_CASE("the BVH fixtures map head, hands, hips and feet in every convention") {
  struct Expect {
    const char* file;
    const char* head;
    const char* left;
    const char* hips;
    const char* foot;
    const char* up;
  };
  // One small file per convention, written for these tests (tests/tracking/fixtures/README.md).
  const Expect fixtures[] = {
      {"cmu.bvh", "Head", "LeftHand", "Hips", "LeftFoot", "+Y"},
      {"cgspeed.bvh", "Head", "LeftWrist", "Hips", "LeftAnkle", "+Y"},
      {"humanik.bvh", "Character1_Head", "Character1_LeftHand", "Character1_Hips", "Character1_LeftFoot", "+Y"},
      {"biped.bvh", "Bip01 Head", "Bip01 L Hand", "Bip01 Pelvis", "Bip01 L Foot", "+Z"},
      {"mixamo.bvh", "mixamorig:Head", "mixamorig:LeftHand", "mixamorig:Hips", "mixamorig:LeftFoot", "+Y"},
      {"ccbase.bvh", "CC_Base_Head", "CC_Base_L_Hand", "CC_Base_Hip", "CC_Base_L_Foot", "+Y"},
      {"bandai.bvh", "Head", "Hand_L", "Hips", "Foot_L", "+Y"},
      {"rokoko.bvh", "Head", "LeftHand", "Hips", "LeftFoot", "+Y"},
      {"neuron.bvh", "Head", "LeftHand", "Hips", "LeftFoot", "+Y"},
      {"xsens.bvh", "Head", "LeftHand", "Pelvis", "LeftFoot", "+Y"},
      {"optitrack.bvh", "Skeleton1_Head", "Skeleton1_LHand", "Skeleton1_Hip", "Skeleton1_LFoot", "+Y"},
      {"unreal.bvh", "head", "hand_l", "pelvis", "foot_l", "+Z"},
      {"vrm.bvh", "head", "leftHand", "hips", "leftFoot", "+Y"},
  };
  for (const Expect& e : fixtures) {
    INFO(e.file);
    const std::string path = std::string(test::kSourceDir) + "/tests/tracking/fixtures/" + e.file;
    BvhMapping map;
    auto src = openBvhSource(path, {}, &map);
    REQUIRE(src.ok());
    auto clip = avatar::loadBvh(path);
    REQUIRE(clip.ok());
    auto name = [&](TrackerId id) { return clip->joints[static_cast<size_t>(map.joint[static_cast<size_t>(index(id))])].name; };
    CHECK(name(TrackerId::Head) == e.head);
    CHECK(name(TrackerId::LeftHand) == e.left);
    CHECK(name(TrackerId::Hips) == e.hips);
    CHECK(name(TrackerId::LeftFoot) == e.foot);
    CHECK(map.upAxis == e.up);
    const PoseSample& s = (*src)->trace().samples[0];
    CHECK(s[TrackerId::Head].position.y > 1.5f);
    CHECK(s[TrackerId::LeftHand].position.x < s[TrackerId::RightHand].position.x);
  }
}

TEST_CASE("a BVH body that cannot be mapped or oriented stops with one line naming the override") {
  const auto& canonical = test::bvhConventions()[0];
  SECTION("no head joint") {
    test::BvhConvention c = canonical;
    c.names[test::kHead] = "Thing";
    c.names[test::kNeck] = "Stalk";
    auto t = traceOf(test::writeConventionClip(c, 8));
    // Topology still finds a head on this clear skeleton; unnamed and shapeless it would not.
    if (!t.ok()) CHECK_THAT(t.error(), Catch::Contains("--bvh-bone-map"));
  }
  SECTION("no hands: required, so an error naming the bones and --bvh-bone-map") {
    std::string text = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
                       " JOINT Head\n {\n  OFFSET 0 60 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 15 0\n  }\n }\n"
                       " JOINT LeftFoot\n {\n  OFFSET 10 -90 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 0 10\n  }\n }\n"
                       " JOINT RightFoot\n {\n  OFFSET -10 -90 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  End Site\n  {\n   OFFSET 0 0 10\n  }\n }\n}\n"
                       "MOTION\nFrames: 2\nFrame Time: 0.0333333\n0 95 0 0 0 0 0 0 0 0 0 0 0 0 0\n0 95 1 0 0 0 0 0 0 0 0 0 0 0 0\n";
    auto t = traceOf(text);
    REQUIRE_FALSE(t.ok());
    CHECK_THAT(t.error(), Catch::Contains("leftHand") && Catch::Contains("rightHand") && Catch::Contains("--bvh-bone-map"));
    CHECK(t.error().find('\n') == std::string::npos);
    // Head only is fine when only the head is required.
    BvhTrackerOptions headOnly;
    headOnly.required = TrackerMask{TrackerId::Head};
    auto ok = traceOf(text, headOnly);
    REQUIRE(ok.ok());
    CHECK_FALSE(ok->trackers.has(TrackerId::LeftHand));
  }
  SECTION("axes that stay ambiguous: the performer tumbles, no up is steady") {
    // The canonical clip with the whole body spinning about X: head above, beside and below the feet.
    auto clip = avatar::parseBvh(test::writeConventionClip(canonical, 48), "tumble.bvh");
    REQUIRE(clip.ok());
    for (size_t f = 0; f < clip->frameCount; ++f) clip->values[f * static_cast<size_t>(clip->channelCount) + 5] = static_cast<float>(f) * 7.5f;
    auto t = bvhToTrace(*clip, {});
    REQUIRE_FALSE(t.ok());
    CHECK_THAT(t.error(), Catch::Contains("ambiguous") && Catch::Contains("--bvh-up"));
    // Given the axes, the same clip converts.
    BvhTrackerOptions given;
    given.body.up = "+Y";
    given.body.forward = "+Z";
    auto g = bvhToTrace(*clip, given);
    REQUIRE(g.ok());
  }
  SECTION("a bad override is an error") {
    BvhTrackerOptions o;
    o.body.up = "up";
    CHECK_THAT(traceOf(test::writeConventionClip(canonical, 4), o).error(), Catch::Contains("--bvh-up"));
    o.body.up = "+Y";
    o.body.forward = "+Y";
    CHECK_THAT(traceOf(test::writeConventionClip(canonical, 4), o).error(), Catch::Contains("not perpendicular"));
  }
}

TEST_CASE("BVH overrides: --bvh-up/--bvh-forward turn the clip, a bone map picks joints, topology maps unnamed rigs") {
  const auto& canonical = test::bvhConventions()[0];
  const std::string text = test::writeConventionClip(canonical, 8);
  SECTION("forward given the other way round: the performer faces +Z after the turn") {
    BvhTrackerOptions o;
    o.body.forward = "-Z";
    BvhMapping map;
    auto t = traceOf(text, o, &map);
    REQUIRE(t.ok());
    CHECK(map.body.forwardFrom == "--bvh-forward");
    CHECK(t->samples[0][TrackerId::LeftHand].position.x > t->samples[0][TrackerId::RightHand].position.x);
  }
  SECTION("a bone map wins over names") {
    BvhTrackerOptions o;
    o.body.boneMapJson = R"({"head": "Neck"})";
    BvhMapping map;
    REQUIRE(traceOf(text, o, &map).ok());
    auto clip = avatar::parseBvh(text, "c.bvh");
    CHECK(map.joint[static_cast<size_t>(index(TrackerId::Head))] == clip->find("Neck"));
    o.body.boneMapJson = R"({"head": "NoSuchJoint"})";
    CHECK_THAT(traceOf(text, o).error(), Catch::Contains("NoSuchJoint"));
  }
  SECTION("a bone map value that is not a joint name, or two bones on one joint, is refused by name") {
    BvhTrackerOptions o;
    // A number was taken as a joint index: {"leftHand": 5} put the hand tracker on a toe.
    o.body.boneMapJson = R"({"leftHand": 5})";
    auto number = traceOf(text, o);
    REQUIRE_FALSE(number.ok());
    CHECK_THAT(number.error(), Catch::Contains("bone map: leftHand: expected a joint name (a string)"));
    o.body.boneMapJson = R"({"leftHand": true})";
    CHECK_THAT(traceOf(text, o).error(), Catch::Contains("bone map: leftHand: expected a joint name (a string)"));
    // Two bones on one joint said "no joint for leftHand": the second took the joint from the first.
    o.body.boneMapJson = R"({"leftHand": "LeftHand", "rightHand": "LeftHand"})";
    auto dup = traceOf(text, o);
    REQUIRE_FALSE(dup.ok());
    CHECK_THAT(dup.error(), Catch::Contains("both map to 'LeftHand'"));
    CHECK_THAT(dup.error(), !Catch::Contains("no joint for"));
    // null still unmaps, and a name still maps.
    o.body.boneMapJson = R"({"leftFoot": null, "head": "Neck"})";
    CHECK(traceOf(text, o).ok());
  }
  SECTION("names that say nothing: the topology mapper finds the body") {
    test::BvhConvention c = canonical;
    for (size_t r = 0; r < c.names.size(); ++r) c.names[r] = "j" + std::to_string(r);
    BvhMapping map;
    auto t = traceOf(test::writeConventionClip(c, 8), {}, &map);
    REQUIRE(t.ok());
    CHECK(map.body.humanoid.method == avatar::MappingMethod::Topology);
    CHECK(map.joint[static_cast<size_t>(index(TrackerId::Head))] >= 0);
    auto ref = traceOf(text);
    REQUIRE(ref.ok());
    CHECK(glm::length(t->samples[3][TrackerId::LeftHand].position - ref->samples[3][TrackerId::LeftHand].position) < 1e-3f);
  }
}

// Writes the fixtures (once, by hand: EMBODY_WRITE_BVH_FIXTURES=DIR ./embody_tests_tracking "[.write]").
TEST_CASE("write the BVH convention fixtures", "[.write]") {
  const char* dir = std::getenv("EMBODY_WRITE_BVH_FIXTURES");
  REQUIRE(dir != nullptr);
  for (size_t c = 1; c < test::bvhConventions().size(); ++c) {
    const auto& conv = test::bvhConventions()[c];
    std::ofstream(std::string(dir) + "/" + conv.name + ".bvh") << test::writeConventionClip(conv, 4);
  }
}

TEST_CASE("a T-pose held for several leading frames is skipped like one, a still take is not cut") {
  // Some exporters hold the reference pose for a few frames; two were played as motion (the
  // hands 65 cm and 81 degrees off at t = 0; the robustness probe, session 20).
  test::BvhConvention conv = test::bvhConventions()[0];
  conv.tposeFirst = true;
  const std::string once = test::writeConventionClip(conv);
  BvhMapping onceMap;
  auto ref = traceOf(once, {}, &onceMap);
  REQUIRE(ref.ok());
  REQUIRE(onceMap.body.firstFrame == 1u);
  // The T-pose line repeated: 1 + k reference frames, then the same take.
  const size_t header = once.find("Frame Time:");
  const size_t firstLine = once.find('\n', header) + 1;
  const std::string tpose = once.substr(firstLine, once.find('\n', firstLine) + 1 - firstLine);
  for (int extra : {1, 3}) {
    INFO(1 + extra << " reference frames");
    std::string text = once;
    for (int k = 0; k < extra; ++k) text.insert(firstLine, tpose);
    const std::string frames = "Frames: " + std::to_string(test::kConventionClipFrames + 1);
    text.replace(text.find(frames), frames.size(), "Frames: " + std::to_string(test::kConventionClipFrames + 1 + extra));
    BvhMapping map;
    auto got = traceOf(text, {}, &map);
    REQUIRE(got.ok());
    CHECK(map.body.firstFrame == size_t(1 + extra));
    REQUIRE(got->samples.size() == ref->samples.size());
    float worst = 0.0f;
    for (size_t f = 0; f < ref->samples.size(); ++f)
      for (auto id : kAllTrackers) worst = std::max(worst, glm::length(got->samples[f][id].position - ref->samples[f][id].position));
    CHECK(worst < 1e-4f);
  }
  // A take that starts still (no jump after the still frames) keeps its first frame.
  BvhMapping stillMap;
  REQUIRE(traceOf(test::writeConventionClip(test::bvhConventions()[0]), {}, &stillMap).ok());
  CHECK(stillMap.body.firstFrame == 0u);
}

TEST_CASE("a BVH clip without toes stands on soles 0.039 of the height under its ankles, with the height and feet of the clip with toes") {
  // s_no_toes (the CMU walk without toe joints) stood on its ankles: the feet trackers 4 cm low and
  // the performer measured 3 % short, so the whole walk scaled 3 % up (session 20 probe).
  test::BvhConvention withToes = test::bvhConventions()[0];
  // The toes straight under the ankles, 0.039 of the ~169 cm height: the sole wherever the foot turns.
  withToes.toesCm = {0, -6.6, 0};
  withToes.toesEndCm = {0, 0, 0};
  test::BvhConvention bare = withToes;
  bare.toes = false;
  BvhMapping toesMap, bareMap;
  auto ref = traceOf(test::writeConventionClip(withToes), {}, &toesMap);
  auto got = traceOf(test::writeConventionClip(bare), {}, &bareMap);
  if (!ref) FAIL(ref.error());
  REQUIRE(got.ok());
  CHECK(toesMap.body.soleBelowFoot[0] == 0.0);  // toes: their lowest point is the sole, as before
  CHECK(bareMap.body.soleBelowFoot[0] == Approx(0.039 * bareMap.heightUnits).epsilon(1e-6));
  CHECK(bareMap.body.soleBelowFoot[1] == bareMap.body.soleBelowFoot[0]);
  CHECK(bareMap.heightUnits == Approx(toesMap.heightUnits).epsilon(0.005));
  bool noted = false;
  for (const auto& n : bareMap.notes) noted = noted || n.find("no toes or End Site below the feet") != std::string::npos;
  CHECK(noted);
  REQUIRE(got->samples.size() == ref->samples.size());
  float worstFoot = 0.0f, worstHips = 0.0f;
  for (size_t f = 0; f < ref->samples.size(); ++f) {
    for (auto id : {TrackerId::LeftFoot, TrackerId::RightFoot})
      worstFoot = std::max(worstFoot, std::abs(got->samples[f][id].position.y - ref->samples[f][id].position.y));
    worstHips = std::max(worstHips, std::abs(got->samples[f][TrackerId::Hips].position.y - ref->samples[f][TrackerId::Hips].position.y));
  }
  CHECK(worstFoot < 0.01f);
  CHECK(worstHips < 0.01f);
  // The clip as an avatar stands on the same soles: its ankles where the clip's stand, no lift needed.
  auto avatarClip = avatar::parseBvh(test::writeConventionClip(bare), "clip.bvh");
  REQUIRE(avatarClip.ok());
  auto asAvatar = buildBvhAvatar(std::move(*avatarClip), {});
  REQUIRE(asAvatar.ok());
  CHECK(std::abs(asAvatar->restLift) < 0.01);
}

TEST_CASE("a mirrored BVH clip or one with Left and Right swapped is refused naming --bvh-mirror, which reads the mirrored one right") {
  // Both read as "facing -Z, walks backwards" and played the performer walking backwards with his
  // toes behind him at exit 0 (eval 4.2 cm where the clean clip gives 0.84; session 20 probe).
  const test::BvhConvention& canonical = test::bvhConventions()[0];
  const std::string text = test::writeConventionClip(canonical);
  BvhMapping refMap;
  auto ref = traceOf(text, {}, &refMap);
  REQUIRE(ref.ok());
  CHECK(refMap.body.walking == "walks forward");
  SECTION("a left-handed file: refused, and --bvh-mirror reads it as the original") {
    auto clip = avatar::parseBvh(text, "clip.bvh");
    REQUIRE(clip.ok());
    avatar::mirrorBvhClip(*clip);
    auto refused = bvhToTrace(*clip, {});
    REQUIRE_FALSE(refused.ok());
    CHECK_THAT(refused.error(), Catch::Contains("left and right are mirrored: the toes point behind"));
    CHECK_THAT(refused.error(), Catch::Contains("--bvh-mirror"));
    CHECK_THAT(refused.error(), Catch::Contains("--bvh-bone-map"));
    BvhTrackerOptions o;
    o.body.mirror = true;
    auto got = bvhToTrace(*clip, o);
    REQUIRE(got.ok());
    float worst = 0.0f;
    for (size_t f = 0; f < ref->samples.size(); ++f)
      for (auto id : kAllTrackers) worst = std::max(worst, glm::length(got->samples[f][id].position - ref->samples[f][id].position));
    CHECK(worst < 1e-3f);
    // The clip as an avatar is mirrored with it.
    auto asAvatar = buildBvhAvatar(*clip, o);
    REQUIRE(asAvatar.ok());
    CHECK(asAvatar->mapping.body.walking == "walks forward");
    // A right-handed file given --bvh-mirror is the one mirrored, and refused.
    auto original = avatar::parseBvh(text, "clip.bvh");
    CHECK_FALSE(bvhToTrace(*original, o).ok());
  }
  SECTION("Left and Right names exchanged: refused with the same line") {
    test::BvhConvention swapped = canonical;
    for (int k = 0; k < 4; ++k) {
      std::swap(swapped.names[static_cast<size_t>(test::kLShoulder + k)], swapped.names[static_cast<size_t>(test::kRShoulder + k)]);
      std::swap(swapped.names[static_cast<size_t>(test::kLUpperLeg + k)], swapped.names[static_cast<size_t>(test::kRUpperLeg + k)]);
    }
    auto refused = traceOf(test::writeConventionClip(swapped));
    REQUIRE_FALSE(refused.ok());
    CHECK_THAT(refused.error(), Catch::Contains("left and right are mirrored"));
  }
  SECTION("feet without toes or End Sites cannot be checked: a mirrored clip without them still reads") {
    test::BvhConvention bare = canonical;
    bare.toes = false;
    auto clip = avatar::parseBvh(test::writeConventionClip(bare), "clip.bvh");
    REQUIRE(clip.ok());
    avatar::mirrorBvhClip(*clip);
    CHECK(bvhToTrace(*clip, {}).ok());
  }
}
