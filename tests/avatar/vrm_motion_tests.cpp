// VRM motion (avatar/vrm): the project's test bust (tests/support/vrm_test_avatar.h) written as
// a .vrm, validated by the Khronos validator, loaded back, and its spring bones, expressions,
// look-at and blinking checked by numbers. Hostile extension JSON gets defaults and warnings.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "avatar/gltf/gltf_loader.h"
#include "avatar/vrm/secondary_motion.h"
#include "tests/support/gltf_validator_checks.h"
#include "tests/support/vrm_test_avatar.h"

using namespace embody;
using namespace embody::avatar;

namespace {

std::string tempPath(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("embody_" + std::to_string(::getpid()) + "_" + name)).string();
}

AvatarAsset loadTestVrm(const test::VrmTestAvatarOptions& o = {}, const std::string& extensionsOverride = "") {
  test::VrmTestAvatar t = test::buildVrmTestAvatar(o);
  if (!extensionsOverride.empty()) t.extensionsJson = extensionsOverride;
  const std::string path = tempPath("vrm_motion.vrm");
  REQUIRE(test::writeVrmTestAvatar(t, path).ok());
  auto a = loadAvatarFile(path);
  std::filesystem::remove(path);
  REQUIRE(a.ok());
  return std::move(a.value());
}

glm::vec3 jointPosition(const AvatarAsset& a, const SkeletonPose& pose, int joint) {
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, pose, g);
  return glm::vec3(g[static_cast<size_t>(joint)][3]);
}

// The pose with the head turned `yaw` radians about +Y (the neck takes none of it).
SkeletonPose headTurned(const AvatarAsset& a, float yaw) {
  SkeletonPose p = SkeletonPose::rest(a.skeleton);
  const int head = a.humanoid.joint(HumanBone::head);
  p.local[static_cast<size_t>(head)].rotation = glm::angleAxis(yaw, glm::vec3(0, 1, 0));
  return p;
}

// Tip joint position of strand k in the rigid (no spring) version of `pose`.
glm::vec3 rigidTip(const AvatarAsset& a, const SkeletonPose& pose, const std::vector<int>& strand) {
  return jointPosition(a, pose, strand.back());
}

}  // namespace

TEST_CASE("vrm test avatar: passes the Khronos glTF validator", "[vrm]") {
  for (bool vrm0 : {false, true}) {
    test::VrmTestAvatarOptions o;
    o.vrm0 = vrm0;
    const std::string path = tempPath(vrm0 ? "validate0.vrm" : "validate1.vrm");
    REQUIRE(test::writeVrmTestAvatar(test::buildVrmTestAvatar(o), path).ok());
    if (!test::requireNoGltfErrors(path)) return;
  }
}

TEST_CASE("vrm 1.0: spring bones, expressions, look-at and morph targets are read", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  CHECK(a.format == AvatarFormat::Vrm1);
  INFO((a.vrmWarnings.empty() ? std::string() : a.vrmWarnings.front()));
  CHECK(a.vrmWarnings.empty());
  REQUIRE(a.springBones.chains.size() == 8);
  for (const auto& c : a.springBones.chains) {
    CHECK(c.joints.size() == 4);  // five joints: the last is the tail
    CHECK(c.colliders.size() == 2);
    CHECK(c.joints[0].settings.stiffness == Approx(1.5f));
    CHECK(c.joints[0].settings.dragForce == Approx(0.4f));
    CHECK(c.joints[0].settings.hitRadius == Approx(0.01f));
  }
  REQUIRE(a.springBones.colliders.size() == 2);
  CHECK(a.springBones.colliders[0].shape == SpringCollider::Shape::Sphere);
  CHECK(a.springBones.colliders[1].shape == SpringCollider::Shape::Capsule);
  CHECK(a.springBones.colliders[1].tail.y == Approx(0.2f));
  REQUIRE(a.mesh.morphChannels.size() == 6);
  CHECK(a.mesh.morphChannels[0].name == "blink");
  CHECK_FALSE(a.mesh.morphDeltas.empty());
  CHECK(a.expressions.expressions.size() == 9);
  CHECK(a.expressions.find(ExpressionPreset::Blink) >= 0);
  CHECK(a.expressions.find(ExpressionPreset::LookLeft) >= 0);
  CHECK(a.expressions.find("wink") >= 0);
  CHECK(a.lookAt.type == LookAtSetup::Type::Expression);
  CHECK(a.lookAt.horizontalOuter.inputMaxValue == Approx(45.0f));
  CHECK(a.lookAt.offsetFromHead.z == Approx(0.07f));
}

TEST_CASE("vrm 0.x: secondaryAnimation and blend shape groups are read", "[vrm]") {
  test::VrmTestAvatarOptions o;
  o.vrm0 = true;
  const AvatarAsset a = loadTestVrm(o);
  CHECK(a.format == AvatarFormat::Vrm0);
  REQUIRE(a.springBones.chains.size() == 8);
  for (const auto& c : a.springBones.chains) {
    REQUIRE(c.joints.size() == 5);  // the whole subtree sways; the leaf gets a 7 cm virtual tail
    CHECK(c.joints.back().child == -1);
    CHECK(glm::length(c.joints.back().tail) == Approx(0.07f));
    CHECK(c.joints[0].settings.stiffness == Approx(1.5f));  // from "stiffiness"
  }
  REQUIRE(a.springBones.colliders.size() == 2);
  CHECK(a.springBones.colliders[0].offset.y == Approx(0.1f));
  const int blink = a.expressions.find(ExpressionPreset::Blink);
  REQUIRE(blink >= 0);
  REQUIRE(a.expressions.expressions[static_cast<size_t>(blink)].morphBinds.size() == 1);
  CHECK(a.expressions.expressions[static_cast<size_t>(blink)].morphBinds[0].weight == Approx(1.0f));  // 100 -> 1
  CHECK(a.expressions.find(ExpressionPreset::Aa) >= 0);  // "a"
  CHECK(a.lookAt.type == LookAtSetup::Type::Expression);  // BlendShape
  CHECK(a.lookAt.offsetFromHead.z == Approx(0.07f));     // z flipped from Unity's
}

TEST_CASE("spring bones: hair swings after a head turn and settles, colliders hold", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  test::VrmTestAvatar t = test::buildVrmTestAvatar();
  SecondaryMotion motion(a, {.blink = false});
  const double dt = 1.0 / 90.0;
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  for (int i = 0; i < 180; ++i) {  // settle 2 s at rest
    pose = SkeletonPose::rest(a.skeleton);
    motion.update(pose, dt, std::nullopt);
  }
  const SkeletonPose rest = SkeletonPose::rest(a.skeleton);
  float settled = 0.0f;
  for (const auto& s : t.strands) settled = std::max(settled, glm::length(jointPosition(a, pose, s.back()) - rigidTip(a, rest, s)));
  CHECK(settled < 0.03f);  // gravity sags it a little, no more
  // Turn the head 60 degrees in 0.15 s, then hold.
  float maxLag = 0.0f, lagAfter3s = 0.0f;
  int steps = 0;
  for (int i = 0; i < 360; ++i) {
    const float yaw = glm::radians(60.0f) * std::min(1.0f, float(i) / 13.5f);
    pose = headTurned(a, yaw);
    const SkeletonPose rigid = pose;
    motion.update(pose, dt, std::nullopt);
    steps += motion.lastSpringJob().stepsRun;
    float lag = 0.0f;
    for (const auto& s : t.strands) {
      lag = std::max(lag, glm::length(jointPosition(a, pose, s.back()) - rigidTip(a, rigid, s)));
      // No joint inside the head sphere (radius 0.095 around head + (0, 0.1, 0)).
      std::vector<glm::mat4> g;
      computeGlobals(a.skeleton, pose, g);
      const glm::vec3 c(g[5] * glm::vec4(0, 0.1f, 0, 1));
      for (size_t j = 1; j < s.size(); ++j) CHECK(glm::length(glm::vec3(g[static_cast<size_t>(s[j])][3]) - c) > 0.095f);
      for (const auto& tr : pose.local) REQUIRE(std::isfinite(tr.rotation.w + tr.rotation.x + tr.rotation.y + tr.rotation.z));
    }
    if (i < 60) maxLag = std::max(maxLag, lag);
    if (i == 359) lagAfter3s = lag;
  }
  CHECK(maxLag > 0.03f);          // the tips trail the turn by centimetres
  CHECK(lagAfter3s < settled + 0.01f);  // and come back to where they hung
  CHECK(std::abs(steps - 480) <= 1);    // 4 s at the fixed 120 Hz sub-step
}

TEST_CASE("spring bones: a teleport resets the springs instead of flinging the hair", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  test::VrmTestAvatar t = test::buildVrmTestAvatar();
  SecondaryMotion motion(a, {.blink = false});
  SkeletonPose pose;
  for (int i = 0; i < 90; ++i) {
    pose = headTurned(a, glm::radians(30.0f) * std::sin(float(i) * 0.2f));
    motion.update(pose, 1.0 / 90.0, std::nullopt);
  }
  // Jump 25 m and turn 170 degrees in one frame (a recenter or teleport).
  SkeletonPose jumped = SkeletonPose::rest(a.skeleton);
  jumped.local[1].translation += glm::vec3(25.0f, 0.0f, -3.0f);
  jumped.local[1].rotation = glm::angleAxis(glm::radians(170.0f), glm::vec3(0, 1, 0));
  const SkeletonPose rigid = jumped;
  motion.update(jumped, 1.0 / 90.0, std::nullopt);
  CHECK(motion.lastSpringJob().wasReset);
  for (const auto& s : t.strands)
    CHECK(glm::length(jointPosition(a, jumped, s.back()) - rigidTip(a, rigid, s)) < 0.01f);
  // An explicit reset (recenter) does the same.
  motion.reset();
  SkeletonPose again = rigid;
  motion.update(again, 1.0 / 90.0, std::nullopt);
  CHECK(motion.lastSpringJob().wasReset);
  // A long stall (2 s in one frame) is capped, not integrated as one huge step.
  SkeletonPose stalled = rigid;
  motion.update(stalled, 2.0, std::nullopt);
  CHECK(motion.lastSpringJob().stepsRun == motion.lastSpringJob().maxStepsPerRun);
  for (const auto& tr : stalled.local) CHECK(std::isfinite(tr.rotation.w + tr.rotation.x));
}

TEST_CASE("spring bones: a chain that skips a joint aims at the deeper joint", "[vrm]") {
  test::VrmTestAvatar t = test::buildVrmTestAvatar();
  auto ext = nlohmann::json::parse(t.extensionsJson);
  auto& joints = ext["VRMC_springBone"]["springs"][0]["joints"];
  joints.erase(2);  // strand 0: joints 0, 1, 3, 4 (1 swings towards 3 over 2)
  const AvatarAsset a = loadTestVrm({}, ext.dump());
  CHECK(a.vrmWarnings.empty());
  const SpringChain& c = a.springBones.chains[0];
  REQUIRE(c.joints.size() == 3);
  CHECK(c.joints[1].child == t.strands[0][3]);
  CHECK(glm::length(c.joints[1].tail) == Approx(2.0f * std::sqrt(0.055f * 0.055f + 0.012f * 0.012f)).epsilon(1e-4));
  // At rest with no gravity and no motion nothing moves.
  SecondaryMotion motion(a, {.blink = false});
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  motion.update(pose, 0.0, std::nullopt);
  for (size_t j = 0; j < pose.local.size(); ++j)
    CHECK(std::abs(glm::dot(pose.local[j].rotation, a.skeleton.joints[j].rest.rotation)) == Approx(1.0f).margin(1e-6));
}

TEST_CASE("spring bones: with a centre node, moving with it does not swing the hair", "[vrm]") {
  test::VrmTestAvatar t = test::buildVrmTestAvatar({.gravityPower = 0.0f});  // at rest nothing moves
  auto ext = nlohmann::json::parse(t.extensionsJson);
  for (auto& spring : ext["VRMC_springBone"]["springs"]) spring["center"] = 1;  // the hips
  float lag[2] = {0.0f, 0.0f};
  for (int withCentre = 0; withCentre < 2; ++withCentre) {
    const AvatarAsset a = loadTestVrm({}, withCentre ? ext.dump() : t.extensionsJson);
    CHECK(a.springBones.chains[0].center == (withCentre ? 1 : -1));
    SecondaryMotion motion(a, {.blink = false});
    for (int i = 0; i < 60; ++i) {  // rest, then the body slides 8 cm a frame (7 m/s) for 12 frames
      SkeletonPose pose = SkeletonPose::rest(a.skeleton);
      pose.local[1].translation.z += 0.08f * float(std::max(0, i - 40));
      const SkeletonPose rigid = pose;
      motion.update(pose, 1.0 / 90.0, std::nullopt);
      for (const auto& s : t.strands)
        lag[withCentre] = std::max(lag[withCentre], glm::length(jointPosition(a, pose, s.back()) - rigidTip(a, rigid, s)));
    }
  }
  CHECK(lag[0] > 0.02f);   // world inertia: the hair streams behind
  CHECK(lag[1] < 0.002f);  // centre space: it rides along
}

TEST_CASE("spring bone job: Validate rejects malformed inputs", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  SpringBoneState state;
  state.resize(a.springBones, a.skeleton.joints.size());
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, pose, g);
  SpringBoneJob job;
  job.setup = &a.springBones;
  job.skeleton = &a.skeleton;
  job.pose = &pose;
  job.globals = g;
  job.state = &state;
  job.deltaTime = 1.0 / 90.0;
  CHECK(job.Validate());
  job.deltaTime = std::nan("");
  CHECK_FALSE(job.Validate());
  CHECK_FALSE(job.Run());
  job.deltaTime = 0.01;
  job.rootJoint = 10000;
  CHECK_FALSE(job.Validate());
  job.rootJoint = 0;
  SpringBoneState small;
  job.state = &small;
  CHECK_FALSE(job.Validate());
  job.state = &state;
  SkeletonPose wrong;
  job.pose = &wrong;
  CHECK_FALSE(job.Validate());
}

TEST_CASE("vrm parsers: hostile extension values take defaults with warnings, never crash", "[vrm]") {
  test::VrmTestAvatar t = test::buildVrmTestAvatar();
  auto ext = nlohmann::json::parse(t.extensionsJson);
  auto& springs = ext["VRMC_springBone"]["springs"];
  springs[0]["joints"][0]["stiffness"] = "stiff";
  springs[0]["joints"][0]["dragForce"] = 7.5;
  springs[0]["joints"][0]["gravityDir"] = {0, 0, 0};
  springs[1]["joints"][1]["node"] = 99999;          // the chain ends at joint 1
  springs[2]["joints"][2]["node"] = 0;              // not below joint 1
  springs[3]["colliderGroups"] = {42, -1, "x"};
  springs[4]["joints"] = springs[5]["joints"];       // claimed twice: the second is skipped
  ext["VRMC_springBone"]["colliders"][1]["shape"] = {{"cone", {}}};
  ext["VRMC_vrm"]["expressions"]["preset"]["blink"]["morphTargetBinds"][0]["index"] = 77;
  ext["VRMC_vrm"]["expressions"]["preset"]["aa"]["overrideMouth"] = "sometimes";
  ext["VRMC_vrm"]["lookAt"]["rangeMapHorizontalOuter"]["inputMaxValue"] = -3;
  const AvatarAsset a = loadTestVrm({}, ext.dump());
  CHECK(a.vrmWarnings.size() >= 8);
  REQUIRE(a.springBones.chains.size() >= 5);
  const auto& s0 = a.springBones.chains[0].joints[0].settings;
  CHECK(s0.stiffness == 1.0f);  // the specification's default
  CHECK(s0.dragForce == 0.5f);
  CHECK(s0.gravityDir == glm::vec3(0, -1, 0));
  CHECK(a.springBones.colliders.size() == 1);
  CHECK(a.expressions.expressions[static_cast<size_t>(a.expressions.find(ExpressionPreset::Blink))].morphBinds.empty());
  CHECK(a.lookAt.horizontalOuter.inputMaxValue == 90.0f);
  // And it still runs.
  SecondaryMotion motion(a);
  for (int i = 0; i < 30; ++i) {
    SkeletonPose p = headTurned(a, 0.05f * float(i));
    motion.update(p, 1.0 / 90.0, glm::vec3(1, 1.6f, 1));
    for (const auto& tr : p.local) REQUIRE(std::isfinite(tr.rotation.w + tr.rotation.x + tr.rotation.y + tr.rotation.z));
  }
  // Garbage in every VRM object: no crash, no motion data.
  for (const char* junk : {R"({"VRMC_springBone": [1,2], "VRMC_vrm": {"expressions": 5, "lookAt": "x"}})",
                           R"({"VRM": {"secondaryAnimation": {"boneGroups": [{"bones": [1e300, -5, null]}], "colliderGroups": 3},
                                       "blendShapeMaster": {"blendShapeGroups": [{"binds": [{"mesh": 0, "index": 0, "weight": 1e9}]}]},
                                       "firstPerson": {"lookAtTypeName": 3}}})"}) {
    const AvatarAsset j = loadTestVrm({}, junk);
    CHECK(j.springBones.chains.empty());
  }
}

TEST_CASE("expressions: binary, overrides and morph weights", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  const ExpressionSet& set = a.expressions;
  std::vector<float> w(set.expressions.size(), 0.0f), eff(w.size()), morph(a.mesh.morphChannels.size());
  const std::vector<float> defaults = defaultMorphWeights(a.mesh);
  ExpressionEvaluateJob job{&set, defaults, w, eff, morph};
  const size_t blink = static_cast<size_t>(set.find(ExpressionPreset::Blink)), happy = static_cast<size_t>(set.find(ExpressionPreset::Happy)),
               wink = static_cast<size_t>(set.find("wink")), aa = static_cast<size_t>(set.find(ExpressionPreset::Aa));
  w[blink] = 0.7f;
  REQUIRE(job.Run());
  CHECK(morph[0] == Approx(0.7f));
  w[happy] = 1.0f;  // happy blocks blinking: only happy's own half blink remains
  REQUIRE(job.Run());
  CHECK(eff[blink] == 0.0f);
  CHECK(morph[0] == Approx(0.5f));
  CHECK(morph[5] == Approx(0.3f));
  w[happy] = 0.0f;
  w[blink] = 0.0f;
  w[wink] = 0.4f;
  REQUIRE(job.Run());
  CHECK(morph[0] == 0.0f);  // binary: below half is off
  w[wink] = 0.6f;
  w[aa] = 0.9f;
  REQUIRE(job.Run());
  CHECK(morph[0] == Approx(0.8f));
  CHECK(morph[5] == Approx(0.9f));
  w[aa] = std::nanf("");
  REQUIRE(job.Run());
  CHECK(morph[5] == 0.0f);
  std::vector<float> shortWeights(2);
  job.weights = shortWeights;
  CHECK_FALSE(job.Validate());
}

TEST_CASE("look-at: expression type maps yaw and pitch through the range maps", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  SecondaryMotion motion(a, {.springBones = false, .blink = false});
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  const glm::vec3 eyes(0, 1.66f, 0.07f);
  const auto weightOf = [&](ExpressionPreset p) {
    return motion.effectiveExpressionWeights()[static_cast<size_t>(a.expressions.find(p))];
  };
  motion.update(pose, 0.01, eyes + glm::vec3(1.0f, 0.0f, 1.0f));  // 45 degrees to the avatar's left
  CHECK(motion.lastGaze().yawDegrees == Approx(45.0f).margin(0.1));
  CHECK(weightOf(ExpressionPreset::LookLeft) == Approx(1.0f).margin(0.01));
  CHECK(weightOf(ExpressionPreset::LookRight) == 0.0f);
  CHECK(motion.morphWeights()[1] == Approx(1.0f).margin(0.01));
  motion.update(pose, 0.01, eyes + glm::vec3(-0.2f, 0.0f, 1.0f));  // 11.3 degrees right: a quarter of 45
  CHECK(weightOf(ExpressionPreset::LookRight) == Approx(0.2513f).margin(0.01));
  motion.update(pose, 0.01, eyes + glm::vec3(0.0f, -1.0f, 1.0f));  // 45 down
  CHECK(weightOf(ExpressionPreset::LookDown) == Approx(1.0f).margin(0.01));
  // The head turned 90 degrees left: a target straight ahead of the body is 90 degrees to its right.
  SkeletonPose turned = headTurned(a, glm::radians(90.0f));
  motion.update(turned, 0.01, glm::vec3(0, 1.66f, 5.0f));
  CHECK(motion.lastGaze().yawDegrees < -80.0f);
  CHECK(weightOf(ExpressionPreset::LookRight) == Approx(1.0f));
}

TEST_CASE("look-at: bone type turns the eyes, each by its range map", "[vrm]") {
  test::VrmTestAvatarOptions o;
  o.boneLookAt = true;
  const AvatarAsset a = loadTestVrm(o);
  REQUIRE(a.lookAt.type == LookAtSetup::Type::Bone);
  SecondaryMotion motion(a, {.springBones = false, .blink = false});
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  motion.update(pose, 0.01, glm::vec3(0, 1.66f, 0.07f) + glm::vec3(0.2f, 0.0f, 1.0f));  // 11.3 degrees left
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, pose, g);
  for (int eye : {6, 7}) {
    const glm::vec3 fwd = glm::normalize(glm::vec3(g[static_cast<size_t>(eye)] * glm::vec4(0, 0, 1, 0)));
    const float yaw = glm::degrees(std::atan2(fwd.x, fwd.z));
    CHECK(yaw == Approx(12.0f * 11.31f / 45.0f).margin(0.1));  // outputScale 12 at 45 degrees in
    CHECK(std::abs(fwd.y) < 1e-4f);
  }
}

TEST_CASE("blinking: a natural, deterministic schedule", "[vrm]") {
  BlinkSchedule a(7), b(7), c(8);
  int blinks = 0;
  double lastStart = -1.0, minGap = 1e9, maxGap = 0.0;
  bool closed = false, differs = false;
  for (int i = 0; i < 90 * 600; ++i) {  // 10 minutes at 90 Hz
    const float wa = a.advance(1.0 / 90.0), wb = b.advance(1.0 / 90.0), wc = c.advance(1.0 / 90.0);
    REQUIRE(wa == wb);
    differs |= wa != wc;
    REQUIRE(wa >= 0.0f);
    REQUIRE(wa <= 1.0f);
    if (wa > 0.99f && !closed) {
      ++blinks;
      const double start = a.nextBlinkStart();
      if (lastStart >= 0.0) minGap = std::min(minGap, start - lastStart), maxGap = std::max(maxGap, start - lastStart);
      lastStart = start;
    }
    closed = wa > 0.99f;
  }
  CHECK(differs);
  CHECK(blinks >= 100);  // 10 to 25 a minute
  CHECK(blinks <= 250);
  CHECK(minGap >= 0.25 + 0.2);
  CHECK(maxGap <= 10.0 + 0.23);
}

TEST_CASE("morph targets: the CPU skinner applies weights before skinning", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  std::vector<glm::mat4> g, palette;
  computeGlobals(a.skeleton, SkeletonPose::rest(a.skeleton), g);
  computeSkinningPalette(a, g, palette);
  std::vector<glm::vec3> base, n0, moved, n1;
  skinOnCpu(a.mesh, palette, base, n0);
  std::vector<float> w(a.mesh.morphChannels.size(), 0.0f);
  w[1] = 1.0f;  // lookLeft: pupils 8 mm towards +X
  skinOnCpu(a.mesh, palette, moved, n1, w);
  // The writer shares one vertex array between its primitives and the loader copies it per
  // primitive: count the vertices the draw lists use.
  std::vector<bool> drawn(base.size(), false);
  for (uint32_t i : a.mesh.indices) drawn[i] = true;
  size_t movedCount = 0;
  for (size_t i = 0; i < base.size(); ++i) {
    if (!drawn[i]) continue;
    const glm::vec3 d = moved[i] - base[i];
    if (glm::length(d) > 1e-6f) {
      ++movedCount;
      CHECK(d.x == Approx(0.008f).margin(1e-5));
    }
  }
  CHECK(movedCount == 34);  // two pupils of 17 vertices
}

TEST_CASE("first person: spring hair stays out of the HMD's draw list", "[vrm]") {
  for (const char* type : {"auto", "thirdPersonOnly"}) {
    test::VrmTestAvatar t = test::buildVrmTestAvatar();
    auto ext = nlohmann::json::parse(t.extensionsJson);
    ext["VRMC_vrm"]["firstPerson"]["meshAnnotations"][0]["type"] = type;
    const AvatarAsset a = loadTestVrm({}, ext.dump());
    INFO(type);
    CHECK(a.mesh.firstPersonIndices.size() < a.mesh.indices.size());
    for (uint32_t i : a.mesh.firstPersonIndices) {
      const auto& v = a.mesh.vertices[i];
      for (const auto& s : t.strands)
        for (int j : s) CHECK((v.joints0[0] != static_cast<uint32_t>(j) || v.weights0[0] == 0.0f));
    }
  }
}

TEST_CASE("material binds: the test avatar's angry expression is read in 1.0 and 0.x alike", "[vrm]") {
  for (bool vrm0 : {false, true}) {
    INFO((vrm0 ? "VRM 0.x" : "VRM 1.0"));
    test::VrmTestAvatarOptions o;
    o.vrm0 = vrm0;
    const AvatarAsset a = loadTestVrm(o);
    INFO((a.vrmWarnings.empty() ? std::string() : a.vrmWarnings.front()));
    CHECK(a.vrmWarnings.empty());
    CHECK(a.expressions.boundMaterials == std::vector<int>{0, 4});  // skin, shirt
    const int angry = a.expressions.find(ExpressionPreset::Angry);
    REQUIRE(angry >= 0);
    const Expression& e = a.expressions.expressions[static_cast<size_t>(angry)];
    REQUIRE(e.colorBinds.size() == 1);
    CHECK(e.colorBinds[0].material == 0);
    CHECK(e.colorBinds[0].type == MaterialColorType::Color);
    // 0.x: written sRGB-encoded, decoded back to the linear target.
    CHECK(glm::length(glm::vec3(e.colorBinds[0].target) - test::kAngrySkin) < 1e-4f);
    CHECK(e.colorBinds[0].target.a == 1.0f);
    REQUIRE(e.textureTransformBinds.size() == 1);
    CHECK(e.textureTransformBinds[0].material == 4);
    // 0.x: Unity's _MainTex_ST [2, 1, 0, 0] -> scale (2, 1), offset (0, 1 - 0 - 1).
    CHECK(e.textureTransformBinds[0].scale == glm::vec2(2.0f, 1.0f));
    CHECK(glm::length(e.textureTransformBinds[0].offset) < 1e-6f);
  }
}

TEST_CASE("material binds: value = base + sum of weight x (target - base), per type", "[vrm]") {
  // Material 1: MToon-like values; expression A moves every colour type and the texture
  // transform, B moves the base colour and the transform the other way. Material 0 is unbound.
  std::vector<Material> mats(2);
  Material& m = mats[1];
  m.baseColorFactor = {0.5f, 0.5f, 0.5f, 1.0f};
  m.emissiveFactor = glm::vec3(0.0f);
  m.mtoon.shadeColor = glm::vec3(0.2f);
  m.mtoon.matcapFactor = glm::vec3(1.0f);
  m.mtoon.rimColor = glm::vec3(0.0f);
  m.mtoon.outlineColor = glm::vec3(0.0f);
  ExpressionSet set;
  Expression a, b;
  using T = MaterialColorType;
  a.colorBinds = {{1, T::Color, {1, 0, 0, 0.5f}},  {1, T::EmissionColor, {0, 1, 0, 1}}, {1, T::ShadeColor, {0, 0, 1, 1}},
                  {1, T::MatcapColor, {0, 0, 0, 1}}, {1, T::RimColor, {1, 1, 0, 1}},     {1, T::OutlineColor, {0, 1, 1, 1}}};
  a.textureTransformBinds = {{1, {2.0f, 2.0f}, {0.5f, 0.0f}}};
  b.colorBinds = {{1, T::Color, {0, 0, 0, 1}}};
  b.textureTransformBinds = {{1, {1.0f, 1.0f}, {0.0f, 0.5f}}};
  set.expressions = {a, b};
  set.boundMaterials = {1};
  std::vector<float> w = {0.5f, 0.25f};
  std::vector<MaterialBindState> states(1);
  MaterialBindEvaluateJob job{&set, mats, w, states};
  REQUIRE(job.Run());
  const MaterialBindState& s = states[0];
  // r: 0.5 + 0.5 (1 - 0.5) + 0.25 (0 - 0.5); g, b: 0.5 + 0.5 (0 - 0.5) + 0.25 (0 - 0.5)
  CHECK(glm::length(s.color(T::Color) - glm::vec3(0.625f, 0.125f, 0.125f)) < 1e-6f);
  CHECK(s.alpha == Approx(0.75f));  // 1 + 0.5 (0.5 - 1) + 0.25 (1 - 1)
  CHECK(glm::length(s.color(T::EmissionColor) - glm::vec3(0.0f, 0.5f, 0.0f)) < 1e-6f);
  CHECK(glm::length(s.color(T::ShadeColor) - glm::vec3(0.1f, 0.1f, 0.6f)) < 1e-6f);
  CHECK(glm::length(s.color(T::MatcapColor) - glm::vec3(0.5f)) < 1e-6f);
  CHECK(glm::length(s.color(T::RimColor) - glm::vec3(0.5f, 0.5f, 0.0f)) < 1e-6f);
  CHECK(glm::length(s.color(T::OutlineColor) - glm::vec3(0.0f, 0.5f, 0.5f)) < 1e-6f);
  // Texture transforms: each texture moves from its own base. Identity base:
  // scale 1 + 0.5 (2 - 1) + 0.25 (1 - 1) = 1.5, offset (0.5 x 0.5, 0.25 x 0.5).
  const TextureTransform t = s.transform(TextureTransform{});
  CHECK(glm::length(t.scale - glm::vec2(1.5f)) < 1e-6f);
  CHECK(glm::length(t.offset - glm::vec2(0.25f, 0.125f)) < 1e-6f);
  // A base with its own scale, rotation and set: 0.25 + 0.5 (2 - 0.25) + 0.25 (1 - 0.25) = 1.3125.
  TextureTransform base;
  base.scale = {0.25f, 0.25f};
  base.offset = {0.125f, 0.0f};
  base.rotation = 0.3f;
  base.texCoord = 1;
  const TextureTransform moved = s.transform(base);
  CHECK(moved.scale.x == Approx(1.3125f));
  CHECK(moved.offset.x == Approx(0.125f + 0.5f * (0.5f - 0.125f) + 0.25f * (0.0f - 0.125f)));
  CHECK(moved.rotation == 0.3f);
  CHECK(moved.texCoord == 1);
  // Off: exactly the material (the renderer's blocks are then the loaded ones, bit for bit).
  w = {0.0f, 0.0f};
  REQUIRE(job.Run());
  CHECK(states[0].color(T::Color) == glm::vec3(0.5f));
  CHECK(states[0].transform(base).scale == base.scale);
  CHECK(states[0].transform(base).offset == base.offset);
  // Both at 1: the deltas add; green would go to -0.5 and is clamped to 0.
  w = {1.0f, 1.0f};
  REQUIRE(job.Run());
  CHECK(states[0].color(T::Color).r == Approx(0.5f));
  CHECK(states[0].color(T::Color).g == 0.0f);
  // Malformed jobs are refused.
  std::vector<float> shortWeights(1);
  job.effectiveWeights = shortWeights;
  CHECK_FALSE(job.Validate());
  job.effectiveWeights = w;
  set.boundMaterials = {7};
  CHECK_FALSE(job.Validate());
  set.boundMaterials = {0};  // bound list without material 1 that the binds name
  CHECK_FALSE(job.Validate());
}

TEST_CASE("material binds: SecondaryMotion hands out the angry expression's states", "[vrm]") {
  const AvatarAsset a = loadTestVrm();
  SecondaryMotion motion(a, {.springBones = false, .blink = false, .lookAt = false});
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  REQUIRE(motion.materialStates().size() == 2);
  motion.update(pose, 0.01, std::nullopt);
  CHECK(glm::length(motion.materialStates()[0].color(MaterialColorType::Color) - glm::vec3(a.materials[0].baseColorFactor)) < 1e-7f);
  motion.expressionWeights()[static_cast<size_t>(a.expressions.find(ExpressionPreset::Angry))] = 0.5f;
  motion.update(pose, 0.01, std::nullopt);
  const glm::vec3 half = 0.5f * (glm::vec3(a.materials[0].baseColorFactor) + test::kAngrySkin);
  CHECK(glm::length(motion.materialStates()[0].color(MaterialColorType::Color) - half) < 1e-6f);
  const TextureTransform shirt = motion.materialStates()[1].transform(a.materials[4].baseColorTransform);
  CHECK(shirt.scale.x == Approx(0.5f * 0.25f + 0.5f * 2.0f));  // 1.125
  CHECK(shirt.offset.x == Approx(0.5f * 0.125f));
}

TEST_CASE("material binds: hostile binds are dropped with warnings", "[vrm]") {
  test::VrmTestAvatar t = test::buildVrmTestAvatar();
  auto ext = nlohmann::json::parse(t.extensionsJson);
  auto& angry = ext["VRMC_vrm"]["expressions"]["preset"]["angry"];
  angry["materialColorBinds"].push_back({{"material", 1}, {"type", "glow"}, {"targetValue", {1, 0, 0, 1}}});
  angry["materialColorBinds"].push_back({{"material", 1}, {"type", "rimColor"}, {"targetValue", {1, 0}}});
  angry["materialColorBinds"].push_back({{"material", 99}, {"type", "color"}, {"targetValue", {1, 0, 0, 1}}});
  angry["textureTransformBinds"].push_back({{"material", 2}, {"scale", "big"}});
  const AvatarAsset a = loadTestVrm({}, ext.dump());
  CHECK(a.vrmWarnings.size() >= 4);
  const Expression& e = a.expressions.expressions[static_cast<size_t>(a.expressions.find(ExpressionPreset::Angry))];
  CHECK(e.colorBinds.size() == 1);
  CHECK(e.textureTransformBinds.size() == 1);
  CHECK(a.expressions.boundMaterials == std::vector<int>{0, 4});
  // 0.x: a Unity _MainTex_ST with offsets, an unsupported float property, an unknown material.
  test::VrmTestAvatarOptions o;
  o.vrm0 = true;
  test::VrmTestAvatar t0 = test::buildVrmTestAvatar(o);
  auto ext0 = nlohmann::json::parse(t0.extensionsJson);
  auto& groups = ext0["VRM"]["blendShapeMaster"]["blendShapeGroups"];
  auto& values = groups.back()["materialValues"];
  values[1]["targetValue"] = {1.0, 0.5, 0.2, 0.1};
  values.push_back({{"materialName", "shirt"}, {"propertyName", "_OutlineWidth"}, {"targetValue", {1, 0, 0, 0}}});
  values.push_back({{"materialName", "nobody"}, {"propertyName", "_Color"}, {"targetValue", {1, 0, 0, 1}}});
  const AvatarAsset a0 = loadTestVrm(o, ext0.dump());
  CHECK(a0.vrmWarnings.size() == 2);
  const Expression& e0 = a0.expressions.expressions[static_cast<size_t>(a0.expressions.find(ExpressionPreset::Angry))];
  REQUIRE(e0.textureTransformBinds.size() == 1);
  CHECK(e0.textureTransformBinds[0].scale == glm::vec2(1.0f, 0.5f));
  CHECK(e0.textureTransformBinds[0].offset.x == Approx(0.2f));
  CHECK(e0.textureTransformBinds[0].offset.y == Approx(1.0f - 0.1f - 0.5f));  // v from the top
}

TEST_CASE("look-at 0.x curves: Unity's cubic Hermite between keys", "[vrm]") {
  const std::vector<float> ease = {0, 0, 0, 0, 1, 1, 0, 0};  // flat tangents: smoothstep
  CHECK(evaluateUnityCurve(ease, 0.5f) == Approx(0.5f));
  CHECK(evaluateUnityCurve(ease, 0.25f) == Approx(0.15625f));  // 3 t^2 - 2 t^3
  CHECK(evaluateUnityCurve(ease, -0.1f) == 0.0f);              // clamped to the end keys
  CHECK(evaluateUnityCurve(ease, 1.5f) == 1.0f);
  // Tangents are slopes, scaled by the key interval: keys 2 apart, out tangent 1 at the first.
  const std::vector<float> wide = {0, 0, 1, 1, 2, 1, 0, 0};
  CHECK(evaluateUnityCurve(wide, 1.0f) == Approx(0.75f));  // h10 (0.5) x 2 x 1 + h01 (0.5) x 1 = 0.25 + 0.5
  const std::vector<float> linear = {0, 0, 1, 1, 1, 1, 1, 1};
  CHECK(evaluateUnityCurve(linear, 0.3f) == Approx(0.3f));
  const std::vector<float> bump = {0, 0, 0, 0, 0.5f, 1, 0, 0, 1, 0, 0, 0};
  CHECK(evaluateUnityCurve(bump, 0.5f) == 1.0f);
  CHECK(evaluateUnityCurve(bump, 0.75f) == Approx(0.5f));
  CHECK(evaluateUnityCurve(bump, 0.625f) == Approx(1.0f - 0.15625f));
  LookAtRangeMap m;
  m.inputMaxValue = 30.0f;
  m.outputScale = 10.0f;
  m.curve = ease;
  CHECK(m.map(15.0f) == Approx(5.0f));
  CHECK(m.map(7.5f) == Approx(1.5625f));
  CHECK(m.map(60.0f) == Approx(10.0f));
  m.curve.clear();
  CHECK(m.map(7.5f) == Approx(2.5f));  // no curve: linear
}

TEST_CASE("look-at 0.x curves: read from the file, bad ones fall back to linear", "[vrm]") {
  test::VrmTestAvatarOptions o;
  o.vrm0 = true;
  auto ext = nlohmann::json::parse(test::buildVrmTestAvatar(o).extensionsJson);
  auto& fp = ext["VRM"]["firstPerson"];
  fp["lookAtHorizontalOuter"]["curve"] = {0, 0, 0, 0, 1, 1, 0, 0};  // ease in-out
  fp["lookAtHorizontalInner"]["curve"] = {0, 0, 0, 0, 1, 1};        // not a multiple of four
  fp["lookAtVerticalDown"]["curve"] = {0, 0, 0, 0, 0, 1, 0, 0};     // times not increasing
  fp["lookAtVerticalUp"]["curve"] = {0, 0, 0, "x", 1, 1, 0, 0};     // not a number
  const AvatarAsset a = loadTestVrm(o, ext.dump());
  CHECK(a.vrmWarnings.size() == 3);
  CHECK(a.lookAt.horizontalOuter.curve.size() == 8);
  CHECK(a.lookAt.horizontalInner.curve.empty());
  CHECK(a.lookAt.verticalDown.curve.empty());
  CHECK(a.lookAt.verticalUp.curve.empty());
  CHECK(a.lookAt.horizontalInner.map(22.5f) == Approx(0.5f));  // linear: half of xRange 45 -> half of yRange 1
  // Through the whole look-at: 11.31 degrees to the avatar's left, x = 0.2513 of xRange, gives
  // smoothstep(0.2513) = 0.1577 (the linear map gave 0.2513). (The test bust faces +Z in 0.x too.)
  SecondaryMotion motion(a, {.springBones = false, .blink = false});
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  motion.update(pose, 0.01, glm::vec3(0, 1.66f, 0.07f) + glm::vec3(0.2f, 0.0f, 1.0f));
  CHECK(motion.lastGaze().yawDegrees == Approx(11.31f).margin(0.01));
  const float x = 11.3099f / 45.0f;
  CHECK(motion.effectiveExpressionWeights()[static_cast<size_t>(a.expressions.find(ExpressionPreset::LookLeft))] ==
        Approx(3 * x * x - 2 * x * x * x).margin(1e-3));
}
