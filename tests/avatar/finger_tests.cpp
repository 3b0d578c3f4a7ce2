// Finger bones: mapping (H-Anim mannequin, Mixamo, VRM 1.0, VRM 0.x) and the retargeting job
// that drives them from XR_EXT_hand_tracking's 26 joints.
#include <catch2/catch.hpp>
#include <cmath>
#include <tuple>

#include "avatar/avatar_loader.h"
#include "avatar/body/body_model.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/hand/finger_retarget.h"
#include "avatar/procedural/default_avatar.h"
#include "humanoid_test_files.h"

using namespace embody::avatar;
using embody::test::HumanoidFile;

namespace {

constexpr float kRad = 57.29578f;

const AvatarAsset& fingerAvatar() {
  static const AvatarAsset a = buildDefaultAvatar(DefaultAvatarOptions{.fingers = true});
  return a;
}

size_t idx(HandJoint j) {
  return static_cast<size_t>(j);
}

// The headless runtime's synthetic hand (tools/xr_runtime/poses.cpp, handJointsFromGrip) in its palm
// frame, with the bend per finger joint given directly (the runtime's curl c is 12 + 60 c
// degrees), then moved by a rigid transform: only the joints' relative placement may matter.
TrackedHandJoints syntheticHand(bool left, float bendDeg, const glm::quat& q = glm::quat(1, 0, 0, 0),
                                const glm::vec3& at = glm::vec3(0.0f)) {
  TrackedHandJoints h;
  h.active = true;
  auto& p = h.position;
  p[idx(HandJoint::Palm)] = {0, 0, 0};
  p[idx(HandJoint::Wrist)] = {0, 0, 0.055f};
  struct Finger {
    HandJoint first;
    float x, baseZ, knuckleZ, lengths[3];
  };
  const Finger fingers[4] = {
      {HandJoint::IndexMetacarpal, -0.022f, 0.04f, -0.035f, {0.040f, 0.025f, 0.022f}},
      {HandJoint::MiddleMetacarpal, 0.0f, 0.04f, -0.038f, {0.045f, 0.028f, 0.024f}},
      {HandJoint::RingMetacarpal, 0.019f, 0.038f, -0.034f, {0.042f, 0.026f, 0.023f}},
      {HandJoint::LittleMetacarpal, 0.036f, 0.035f, -0.027f, {0.032f, 0.018f, 0.020f}}};
  const float bend = bendDeg / kRad;
  for (const auto& f : fingers) {
    const size_t first = idx(f.first);
    p[first] = {f.x * 0.6f, 0.0f, f.baseZ};
    glm::vec3 x{f.x, 0.0f, f.knuckleZ};
    p[first + 1] = x;
    float angle = 0.0f;
    for (size_t k = 0; k < 3; ++k) {
      angle += bend;
      x += f.lengths[k] * glm::vec3(0.0f, -std::sin(angle), -std::cos(angle));
      p[first + 2 + k] = x;
    }
  }
  p[idx(HandJoint::ThumbMetacarpal)] = {-0.02f, -0.012f, 0.032f};
  p[idx(HandJoint::ThumbProximal)] = {-0.042f, -0.018f, 0.0f};
  p[idx(HandJoint::ThumbDistal)] = {-0.056f, -0.022f, -0.028f};
  p[idx(HandJoint::ThumbTip)] = {-0.064f, -0.024f, -0.05f};
  if (left)
    for (auto& v : p) v.x = -v.x;
  for (auto& o : h.orientation) o = glm::quat(1, 0, 0, 0);
  for (size_t start : {2u, 6u, 11u, 16u, 21u}) {
    const size_t last = start == 2 ? 5 : start + 4;
    glm::vec3 back(0, 1, 0);
    for (size_t j = start; j < last; ++j) {
      const glm::vec3 z = -glm::normalize(p[j + 1] - p[j]);
      const glm::vec3 x = glm::normalize(glm::cross(back, z));
      back = glm::cross(z, x);
      h.orientation[j] = glm::quat_cast(glm::mat3(x, back, z));
    }
    h.orientation[last] = h.orientation[last - 1];
  }
  for (size_t j = 0; j < p.size(); ++j) {
    p[j] = q * p[j] + at;
    h.orientation[j] = q * h.orientation[j];
    h.valid[j] = true;
  }
  return h;
}

// A tracked hand that is exactly the avatar's rest hand (tips continue the distal bones).
TrackedHandJoints handFromAvatarRest(const AvatarAsset& a, const FingerRig& rig, int side, const glm::quat& q,
                                     const glm::vec3& at) {
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, SkeletonPose::rest(a.skeleton), g);
  auto pos = [&](int j) { return glm::vec3(g[static_cast<size_t>(j)][3]); };
  const FingerRigHand& rh = rig.hands[static_cast<size_t>(side)];
  TrackedHandJoints h;
  h.active = true;
  h.position[idx(HandJoint::Wrist)] = pos(rh.hand);
  const glm::quat handFrame = glm::quat_cast(glm::mat3(g[static_cast<size_t>(rh.hand)])) * rh.handFrame;
  for (int f = 0; f < kFingerCount; ++f) {
    for (int s = 0; s < kFingerSegments; ++s) {
      const FingerBone& b = rh.bones[static_cast<size_t>(f * 3 + s)];
      REQUIRE(b.joint >= 0);
      h.position[idx(b.trackedFrom)] = pos(b.joint);
      if (s == 2) {
        const glm::vec3 dir = glm::mat3(g[static_cast<size_t>(b.joint)]) * b.axis;
        h.position[idx(b.trackedTo)] = pos(b.joint) + 0.02f * glm::normalize(dir);
      }
    }
    if (f > 0)
      h.position[idx(rh.bones[static_cast<size_t>(f * 3)].trackedFrom) - 1] =
          0.5f * (pos(rh.hand) + pos(rh.bones[static_cast<size_t>(f * 3)].joint));
  }
  h.position[idx(HandJoint::Palm)] = pos(rh.bones[6].joint);
  for (size_t j = 0; j < h.position.size(); ++j) {
    h.orientation[j] = q * handFrame;
    h.position[j] = q * h.position[j] + at;
    h.valid[j] = true;
  }
  return h;
}

struct Run {
  SkeletonPose pose;
  FingerRetargetOutput out;
};

// Runs the job once with a step long enough to blend fully in.
void runJob(const AvatarAsset& a, const FingerRig& rig, FingerRetargetState& state, SkeletonPose& pose,
            const TrackedHandJoints* left, const TrackedHandJoints* right, float dt,
            FingerRetargetOutput* out) {
  FingerRetargetJob job;
  job.skeleton = &a.skeleton;
  job.rig = &rig;
  job.hands = {left, right};
  job.deltaTime = dt;
  job.state = &state;
  job.pose = &pose;
  job.output = out;
  REQUIRE(job.Validate());
  REQUIRE(job.Run());
}

glm::quat rotationOf(const glm::mat4& m) {
  return glm::normalize(glm::quat_cast(glm::mat3(
      glm::normalize(glm::vec3(m[0])), glm::normalize(glm::vec3(m[1])), glm::normalize(glm::vec3(m[2])))));
}

// Model-space direction of a finger bone in a pose.
glm::vec3 boneDirection(const std::vector<glm::mat4>& g, const FingerBone& b) {
  return glm::normalize(rotationOf(g[static_cast<size_t>(b.joint)]) * b.axis);
}

float angleDeg(const glm::vec3& a, const glm::vec3& b) {
  return std::atan2(glm::length(glm::cross(a, b)), glm::dot(a, b)) * kRad;
}

bool allFinite(const SkeletonPose& p) {
  for (const auto& t : p.local)
    if (!std::isfinite(t.rotation.w) || !std::isfinite(t.rotation.x) || !std::isfinite(t.rotation.y) ||
        !std::isfinite(t.rotation.z))
      return false;
  return true;
}

}  // namespace

TEST_CASE("the mannequin with --fingers maps all 30 finger bones by H-Anim names, the default has none",
          "[fingers]") {
  const AvatarAsset plain = buildDefaultAvatar();
  const AvatarAsset& fingers = fingerAvatar();
  CHECK(countFingerBones(plain.humanoid) == 0);
  CHECK(buildFingerRig(plain.skeleton, plain.humanoid).mappedBones() == 0);
  CHECK(countFingerBones(fingers.humanoid) == 30);
  const FingerRig rig = buildFingerRig(fingers.skeleton, fingers.humanoid);
  CHECK(rig.mappedBones() == 30);
  CHECK(rig.notes.empty());
  CHECK(fingers.humanoid.usable());
  CHECK(fingers.humanoid.joint(HumanBone::leftIndexProximal) == fingers.skeleton.find("l_index1"));
  CHECK(fingers.humanoid.joint(HumanBone::rightThumbMetacarpal) == fingers.skeleton.find("r_thumb1"));
  CHECK(fingers.humanoid.joint(HumanBone::rightLittleDistal) == fingers.skeleton.find("r_pinky3"));
  // The standard joints are untouched (same order, names, parents and rest), fingers come after.
  REQUIRE(fingers.skeleton.joints.size() == plain.skeleton.joints.size() + 30);
  for (size_t j = 0; j < plain.skeleton.joints.size(); ++j) {
    CHECK(fingers.skeleton.joints[j].name == plain.skeleton.joints[j].name);
    CHECK(fingers.skeleton.joints[j].parent == plain.skeleton.joints[j].parent);
    CHECK(glm::length(fingers.skeleton.joints[j].rest.translation -
                      plain.skeleton.joints[j].rest.translation) == 0.0f);
  }
  // Every finger bone carries skin (some vertex mostly weighted to it), and the body model is the
  // same size: the IK does not see the fingers.
  std::vector<int> heavy(fingers.skeleton.joints.size(), 0);
  for (const auto& v : fingers.mesh.vertices)
    if (v.weights0[0] > 0.5f) ++heavy[v.joints0[0]];
  for (size_t j = plain.skeleton.joints.size(); j < heavy.size(); ++j) {
    INFO(fingers.skeleton.joints[j].name);
    CHECK(heavy[j] >= 20);
  }
  auto a = buildBodyModel(plain, {}), b = buildBodyModel(fingers, {});
  REQUIRE(a.ok());
  REQUIRE(b.ok());
  CHECK(a->model.dofs == b->model.dofs);
}

namespace {
std::map<std::string, std::string> meaninglessFingerNames() {
  std::map<std::string, std::string> m;
  int i = 0;
  for (const auto& s : embody::test::humanoidJointSpecs()) m[s.bone] = "J" + std::to_string(100 + i++);
  for (const auto& s : embody::test::humanoidFingerSpecs()) m[s.bone] = "J" + std::to_string(100 + i++);
  return m;
}

void checkFingersMapped(const AvatarAsset& a, HumanoidFile& f) {
  for (const auto& s : embody::test::humanoidFingerSpecs()) {
    HumanBone b;
    REQUIRE(parseHumanBone(s.bone, b));
    INFO(s.bone);
    CHECK(a.humanoid.joint(b) == a.gltfNodeToJoint[static_cast<size_t>(f.nodeOfBone[s.bone])]);
  }
  CHECK(countFingerBones(a.humanoid) == 30);
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  CHECK(rig.mappedBones() == 30);
  CHECK(rig.notes.empty());
}

using embody::test::loadPrepared;
}  // namespace

TEST_CASE("Mixamo, VRM 1.0 and VRM 0.x finger bones all map", "[fingers][humanoid]") {
  SECTION("Mixamo names: mixamorig:LeftHandThumb1..3, LeftHandIndex1..3 ... LeftHandPinky1..3") {
    HumanoidFile f(embody::test::mixamoBoneNames(), false, /*fingers=*/true);
    auto a = loadPrepared(f);
    REQUIRE(a.ok());
    CHECK(a->humanoid.method == MappingMethod::Names);
    checkFingersMapped(*a, f);
  }
  SECTION("VRM 1.0 humanBones: leftThumbMetacarpal/Proximal/Distal") {
    HumanoidFile f(meaninglessFingerNames(), false, true);
    nlohmann::json bones = nlohmann::json::object();
    for (const auto& [bone, node] : f.nodeOfBone) bones[bone] = {{"node", node}};
    f.doc["extensionsUsed"] = {"VRMC_vrm"};
    f.doc["extensions"]["VRMC_vrm"] = {{"specVersion", "1.0"}, {"humanoid", {{"humanBones", bones}}}};
    auto a = loadPrepared(f);
    REQUIRE(a.ok());
    CHECK(a->humanoid.method == MappingMethod::Vrm);
    checkFingersMapped(*a, f);
  }
  SECTION("VRM 0.x humanBones: leftThumbProximal/Intermediate/Distal, facing -Z") {
    HumanoidFile f(meaninglessFingerNames(), /*facesMinusZ=*/true, true);
    nlohmann::json bones = nlohmann::json::array();
    for (const auto& [bone, node] : f.nodeOfBone) {
      std::string name = bone;  // VRM 0.x thumb names are one step further out than VRM 1.0's
      for (const std::string side : {"left", "right"}) {
        if (bone == side + "ThumbMetacarpal") name = side + "ThumbProximal";
        if (bone == side + "ThumbProximal") name = side + "ThumbIntermediate";
      }
      bones.push_back({{"bone", name}, {"node", node}});
    }
    f.doc["extensionsUsed"] = {"VRM"};
    f.doc["extensions"]["VRM"] = {{"humanoid", {{"humanBones", bones}}}};
    auto a = loadPrepared(f);
    REQUIRE(a.ok());
    CHECK(a->humanoid.method == MappingMethod::Vrm);
    checkFingersMapped(*a, f);
  }
}

TEST_CASE("finger bones do not turn the IK hand: it points at the middle knuckle, not at the thumb",
          "[fingers][body]") {
  // The synthetic file lists the thumb first, so the hand's first child is the thumb metacarpal.
  HumanoidFile f(embody::test::mixamoBoneNames(), false, true);
  auto a = loadPrepared(f);
  REQUIRE(a.ok());
  auto body = buildBodyModel(*a, {});
  REQUIRE(body.ok());
  std::vector<glm::mat4> g;
  computeGlobals(a->skeleton, SkeletonPose::rest(a->skeleton), g);
  auto pos = [&](HumanBone b) { return glm::vec3(g[static_cast<size_t>(a->humanoid.joint(b))][3]); };
  for (const auto& [hand, lowerArm, middle, thumb] :
       {std::tuple{HumanBone::leftHand, HumanBone::leftLowerArm, HumanBone::leftMiddleProximal,
                   HumanBone::leftThumbMetacarpal},
        std::tuple{HumanBone::rightHand, HumanBone::rightLowerArm, HumanBone::rightMiddleProximal,
                   HumanBone::rightThumbMetacarpal}}) {
    REQUIRE(a->skeleton.children(a->humanoid.joint(hand)).front() == a->humanoid.joint(thumb));
    const int ik = body->ikJointOfAvatar[static_cast<size_t>(a->humanoid.joint(hand))];
    REQUIRE(ik >= 0);
    const Eigen::Vector3d y = body->ikRestRotation[static_cast<size_t>(ik)] * Eigen::Vector3d::UnitY();
    const glm::vec3 axis(float(y.x()), float(y.y()), float(y.z()));
    CHECK(angleDeg(axis, glm::normalize(pos(middle) - pos(hand))) < 0.1f);
    CHECK(angleDeg(axis, glm::normalize(pos(hand) - pos(lowerArm))) < 5.0f);  // along the forearm
  }
}

TEST_CASE("a user bone map names finger bones the other methods cannot find", "[fingers][humanoid]") {
  // Meaningless names, no VRM data: the body maps by topology, the fingers only through the map.
  HumanoidFile f(meaninglessFingerNames(), false, true);
  auto glb = f.glb();
  auto a = loadGltfFromMemory(glb, "");
  REQUIRE(a.ok());
  nlohmann::json map = nlohmann::json::object();
  for (const auto& s : embody::test::humanoidFingerSpecs()) map[s.bone] = meaninglessFingerNames()[s.bone];
  REQUIRE(prepareAvatar(a.value(), map.dump()).ok());
  CHECK(a->humanoid.method == MappingMethod::BoneMap);
  CHECK(a->humanoid.missingRequired.empty());
  checkFingersMapped(*a, f);
}

TEST_CASE("a tracked hand shaped like the avatar's rest hand leaves the fingers at rest", "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  // Tracked somewhere else entirely (turned, moved): only the hand's own shape matters.
  const glm::quat q = glm::angleAxis(1.1f, glm::normalize(glm::vec3(0.3f, -1.0f, 0.5f)));
  const TrackedHandJoints left = handFromAvatarRest(a, rig, 0, q, {0.4f, 1.2f, -0.3f});
  const TrackedHandJoints right = handFromAvatarRest(a, rig, 1, q, {-0.4f, 1.2f, -0.3f});
  FingerRetargetState state;
  FingerRetargetOutput out;
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  runJob(a, rig, state, pose, &left, &right, 1.0f, &out);
  for (int h = 0; h < 2; ++h)
    for (int b = 0; b < kFingerBonesPerHand; ++b) {
      INFO("hand " << h << " bone " << b);
      CHECK(out.weight[static_cast<size_t>(h)][static_cast<size_t>(b / 3)] == 1.0f);
      CHECK(out.bend[static_cast<size_t>(h)][static_cast<size_t>(b)] * kRad < 0.3f);
    }
}

TEST_CASE("a curled tracked hand (the headless runtime's curl) bends the avatar's fingers along it",
          "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  const float curl = GENERATE(0.0f, 0.5f, 1.0f);
  const float bend = 12.0f + 60.0f * curl;  // degrees per finger joint (tools/xr_runtime/poses.cpp)
  INFO("curl " << curl);
  const glm::quat q = glm::angleAxis(-0.7f, glm::normalize(glm::vec3(1.0f, 0.2f, 0.1f)));
  const TrackedHandJoints left = syntheticHand(true, bend, q, {-0.2f, 1.3f, -0.3f});
  const TrackedHandJoints right = syntheticHand(false, bend, q, {0.2f, 1.3f, -0.3f});
  // The avatar's hands are posed (as the IK would): the fingers follow relative to them.
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  pose.local[static_cast<size_t>(a.skeleton.find("l_wrist"))].rotation =
      glm::angleAxis(0.9f, glm::normalize(glm::vec3(0.2f, 1.0f, -0.4f)));
  pose.local[static_cast<size_t>(a.skeleton.find("r_elbow"))].rotation =
      glm::angleAxis(-1.2f, glm::vec3(1, 0, 0));
  FingerRetargetState state;
  FingerRetargetOutput out;
  runJob(a, rig, state, pose, &left, &right, 1.0f, &out);
  REQUIRE(allFinite(pose));
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, pose, g);
  for (int h = 0; h < 2; ++h) {
    const TrackedHandJoints& t = h == 0 ? left : right;
    const FingerRigHand& rh = rig.hands[static_cast<size_t>(h)];
    glm::quat trackedFrame;
    REQUIRE(handFrameFromKnuckles(
        t.position[idx(HandJoint::Wrist)],
        {t.position[idx(HandJoint::IndexProximal)], t.position[idx(HandJoint::MiddleProximal)],
         t.position[idx(HandJoint::RingProximal)], t.position[idx(HandJoint::LittleProximal)]},
        {true, true, true, true}, h == 0, trackedFrame));
    const glm::quat avatarFrame = rotationOf(g[static_cast<size_t>(rh.hand)]) * rh.handFrame;
    for (int f = 0; f < kFingerCount; ++f)
      for (int s = 0; s < kFingerSegments; ++s) {
        const FingerBone& b = rh.bones[static_cast<size_t>(f * 3 + s)];
        INFO("hand " << h << " finger " << f << " segment " << s);
        // Each segment points where the tracked one does, both seen from their own hand.
        const glm::vec3 tracked =
            glm::conjugate(trackedFrame) *
            glm::normalize(t.position[idx(b.trackedTo)] - t.position[idx(b.trackedFrom)]);
        const glm::vec3 avatar = glm::conjugate(avatarFrame) * boneDirection(g, b);
        CHECK(angleDeg(tracked, avatar) < 0.05f);  // no limit is reached here
        if (f == 0) continue;
        // The joint angles themselves (no hand frame involved): each phalanx bends by `bend`
        // against the previous one, as the tracked finger does.
        if (s > 0) {
          const glm::vec3 prev = boneDirection(g, rh.bones[static_cast<size_t>(f * 3 + s - 1)]);
          CHECK(std::abs(angleDeg(prev, boneDirection(g, b)) - bend) < 0.05f);
          CHECK(std::abs(out.bend[static_cast<size_t>(h)][static_cast<size_t>(f * 3 + s)] * kRad - bend) <
                0.05f);
        }
      }
  }
  // Bones keep the avatar's lengths: only rotations were written.
  const SkeletonPose rest = SkeletonPose::rest(a.skeleton);
  for (size_t j = 0; j < pose.local.size(); ++j)
    CHECK(pose.local[j].translation == rest.local[j].translation);
}

TEST_CASE("invalid joints, lost tracking and NaN input blend the fingers back to the input pose",
          "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  const SkeletonPose rest = SkeletonPose::rest(a.skeleton);
  TrackedHandJoints left = syntheticHand(true, 60.0f), right = syntheticHand(false, 60.0f);
  FingerRetargetState state;
  FingerRetargetOutput out;
  SkeletonPose pose = rest;
  const float blend = 0.15f;  // the job's default blendTime
  runJob(a, rig, state, pose, &left, &right, blend, &out);
  const SkeletonPose curled = pose;
  const int index2 = rig.hands[0].bones[4].joint;  // left index intermediate
  const int middle2 = rig.hands[0].bones[7].joint;
  CHECK(out.bend[0][4] * kRad == Approx(60.0f).margin(1.0));

  // The left index finger's joints become invalid: it eases back over blendTime, the others stay.
  left.valid[idx(HandJoint::IndexIntermediate)] = false;
  pose = rest;
  runJob(a, rig, state, pose, &left, &right, 0.5f * blend, &out);
  CHECK(out.weight[0][1] == Approx(0.5f));
  CHECK(out.weight[0][2] == 1.0f);
  CHECK(out.bend[0][4] * kRad == Approx(30.0f).margin(1.5));  // half way from the held curl
  CHECK(glm::dot(pose.local[static_cast<size_t>(middle2)].rotation,
                 curled.local[static_cast<size_t>(middle2)].rotation) == Approx(1.0f).margin(1e-5));
  pose = rest;
  runJob(a, rig, state, pose, &left, &right, 0.5f * blend, &out);
  CHECK(out.weight[0][1] == 0.0f);
  CHECK(pose.local[static_cast<size_t>(index2)].rotation == rest.local[static_cast<size_t>(index2)].rotation);

  // NaN in a joint flagged valid counts as invalid; nothing downstream turns NaN.
  right.position[idx(HandJoint::MiddleTip)] = glm::vec3(std::nanf(""));
  right.orientation[idx(HandJoint::RingDistal)] = glm::quat(std::nanf(""), 0, 0, 0);
  for (int i = 0; i < 2; ++i) {
    pose = rest;
    runJob(a, rig, state, pose, &left, &right, blend, &out);
  }
  CHECK(allFinite(pose));
  CHECK(out.weight[1][2] == 0.0f);
  CHECK(out.weight[1][3] == 0.0f);
  CHECK(out.weight[1][1] == 1.0f);

  // The whole hand lost (isActive false), then no hand tracking at all: every finger at rest.
  left.active = false;
  pose = rest;
  runJob(a, rig, state, pose, &left, nullptr, blend, &out);
  CHECK(allFinite(pose));
  CHECK_FALSE(out.handTracked[0]);
  CHECK_FALSE(out.handTracked[1]);
  for (int h = 0; h < 2; ++h)
    for (int f = 0; f < kFingerCount; ++f)
      CHECK(out.weight[static_cast<size_t>(h)][static_cast<size_t>(f)] == 0.0f);
  for (size_t j = 0; j < pose.local.size(); ++j) CHECK(pose.local[j].rotation == rest.local[j].rotation);
}

TEST_CASE("finger flexion beyond the human range is clamped", "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  const FingerLimits pip = defaultFingerLimits(1, 1), mcp = defaultFingerLimits(1, 0);
  SECTION("a fist folded tighter than a hand can: the middle joints stop at their limit") {
    const TrackedHandJoints t = syntheticHand(false, 125.0f);
    FingerRetargetState state;
    FingerRetargetOutput out;
    SkeletonPose pose = SkeletonPose::rest(a.skeleton);
    runJob(a, rig, state, pose, nullptr, &t, 1.0f, &out);
    REQUIRE(allFinite(pose));
    for (int f = 1; f < kFingerCount; ++f) {
      CHECK(out.bend[1][static_cast<size_t>(f * 3)] <= mcp.maxFlexion + 1e-3f);
      CHECK(out.bend[1][static_cast<size_t>(f * 3 + 1)] == Approx(pip.maxFlexion).margin(0.01));
    }
  }
  SECTION("fingers bent backwards: hyperextension stops at the knuckle's limit") {
    const TrackedHandJoints t = syntheticHand(true, -40.0f);
    FingerRetargetState state;
    FingerRetargetOutput out;
    SkeletonPose pose = SkeletonPose::rest(a.skeleton);
    runJob(a, rig, state, pose, &t, nullptr, 1.0f, &out);
    REQUIRE(allFinite(pose));
    for (int f = 1; f < kFingerCount; ++f) {
      CHECK(out.bend[0][static_cast<size_t>(f * 3)] == Approx(-mcp.minFlexion).margin(0.02));
      CHECK(out.bend[0][static_cast<size_t>(f * 3 + 1)] <= -pip.minFlexion + 0.02f);
    }
  }
}

TEST_CASE("a finger's twist follows the tracked joint's roll, clamped to a few degrees", "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  const FingerBone& index1 = rig.hands[1].bones[3];
  const FingerLimits limits = defaultFingerLimits(1, 0);
  for (const float rollDeg : {4.0f, -6.0f, 30.0f}) {
    INFO("roll " << rollDeg);
    TrackedHandJoints t = syntheticHand(false, 0.0f);
    auto& q = t.orientation[idx(HandJoint::IndexProximal)];
    q = q * glm::angleAxis(rollDeg / kRad, glm::vec3(0, 0, 1));  // about the bone (its -Z)
    FingerRetargetState state;
    SkeletonPose pose = SkeletonPose::rest(a.skeleton);
    runJob(a, rig, state, pose, nullptr, &t, 1.0f, nullptr);
    const glm::quat delta =
        glm::conjugate(a.skeleton.joints[static_cast<size_t>(index1.joint)].rest.rotation) *
        pose.local[static_cast<size_t>(index1.joint)].rotation;
    const float twist =
        2.0f * std::atan2(glm::dot(glm::vec3(delta.x, delta.y, delta.z), index1.axis), delta.w);
    const float expected = std::min(std::abs(rollDeg), limits.maxTwist * kRad);
    CHECK(std::abs(twist) * kRad == Approx(expected).margin(0.5));
    // The neighbours do not twist: the middle finger's knuckle stays at rest.
    const int middle1 = rig.hands[1].bones[6].joint;
    CHECK(std::abs(glm::dot(pose.local[static_cast<size_t>(middle1)].rotation,
                            a.skeleton.joints[static_cast<size_t>(middle1)].rest.rotation)) > 0.9999f);
  }
}

TEST_CASE("FingerRetargetJob::Validate rejects every malformed input", "[fingers]") {
  const AvatarAsset& a = fingerAvatar();
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  FingerRetargetState state;
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  FingerRetargetJob ok;
  ok.skeleton = &a.skeleton;
  ok.rig = &rig;
  ok.state = &state;
  ok.pose = &pose;
  CHECK(ok.Validate());
  FingerRetargetJob j = ok;
  j.skeleton = nullptr;
  CHECK_FALSE(j.Validate());
  j = ok;
  j.rig = nullptr;
  CHECK_FALSE(j.Validate());
  j = ok;
  j.state = nullptr;
  CHECK_FALSE(j.Validate());
  j = ok;
  j.pose = nullptr;
  CHECK_FALSE(j.Validate());
  SkeletonPose shortPose = pose;
  shortPose.local.pop_back();
  j = ok;
  j.pose = &shortPose;
  CHECK_FALSE(j.Validate());
  j = ok;
  j.deltaTime = -0.01f;
  CHECK_FALSE(j.Validate());
  j.deltaTime = std::nanf("");
  CHECK_FALSE(j.Validate());
  j = ok;
  j.blendTime = 0.0f;
  CHECK_FALSE(j.Validate());
  // A rig built for another skeleton (joint indices past this one's end).
  const AvatarAsset plain = buildDefaultAvatar();
  SkeletonPose plainPose = SkeletonPose::rest(plain.skeleton);
  j = ok;
  j.skeleton = &plain.skeleton;
  j.pose = &plainPose;
  CHECK_FALSE(j.Validate());
}
