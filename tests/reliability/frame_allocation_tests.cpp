// The whole runtime frame allocates nothing after warm-up: pose source -> One Euro filter ->
// tracking-loss guard -> tasks -> budgeted solve -> skeleton pose -> skinning palette, for the
// default mannequin (standing and seated), glTF avatars and a BVH clip's own skeleton (`--avatar CLIP.bvh`), through the faults the guard handles (a lost hand, a NaN
// burst, the head lost while the hands stay live, a 10 m teleport).
#include <catch2/catch.hpp>

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "allocation_counter.h"
#include "avatar/avatar_loader.h"
#include "avatar/gltf/glb_writer.h"
#include "avatar/gltf/gltf_loader.h"
#include "avatar/vrm/secondary_motion.h"
#include "avatar/humanoid_test_files.h"
#include "avatar/procedural/default_avatar.h"
#include "runtime/tracked_avatar_body.h"
#include "test_paths.h"
#include "tracking/bvh_avatar.h"
#include "tracking/pose_source.h"
#include "tests/support/vrm_test_avatar.h"

using namespace embody;
using tracking::TrackerId;

namespace {

// What a frame of `embody xr` does between xrWaitFrame and recording the draw.
struct RuntimeFrame {
  const avatar::AvatarAsset& asset;
  tracking::PoseSource& source;
  runtime::TrackedAvatarBody& body;
  avatar::SkeletonPose pose;
  std::vector<glm::mat4> globals, palette;

  void run(int frame) {
    tracking::PoseSample s = source.sample(frame / 72.0);
    injectFault(frame, s);
    body.solve(s, pose);
    avatar::computeGlobals(asset.skeleton, pose, globals);
    avatar::computeSkinningPalette(asset, globals, palette);
  }

  static void injectFault(int frame, tracking::PoseSample& s) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    switch ((frame / 12) % 6) {
      case 1: s[TrackerId::LeftHand].valid = false; break;
      case 2: s[TrackerId::RightHand].position = glm::vec3(nan); break;
      case 3: s[TrackerId::Head].valid = false; break;
      case 4: s[TrackerId::LeftHand].position += glm::vec3(10.0f, 0.0f, 0.0f); break;
      default: break;
    }
  }
};

long allocationsPerFrameLoop(const avatar::AvatarAsset& asset, const char* motion, bool threePoint, bool seated = false) {
  auto source = tracking::openPoseSource(motion);
  REQUIRE(source.ok());
  runtime::TrackedBodyOptions o;
  o.body.trackers = threePoint ? tracking::TrackerMask::threePoint() : tracking::TrackerMask::all();
  o.body.seat.enabled = seated;
  if (seated) o.body.userHeight = 1.75f;
  auto body = runtime::TrackedAvatarBody::create(asset, o);
  REQUIRE(body.ok());
  RuntimeFrame f{asset, **source, **body, avatar::SkeletonPose::rest(asset.skeleton), {}, {}};
  // Warm-up: every fault once (the guard's and the solver's buffers reach their sizes).
  for (int i = 0; i < 96; ++i) f.run(i);
  test::CountAllocations counter;
  for (int i = 96; i < 96 + 144; ++i) f.run(i);
  const long n = counter.counts().count;
  CHECK(std::isfinite(f.palette.at(0)[3][1]));
  return n;
}

const avatar::AvatarAsset& mannequin() {
  static const avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  return a;
}

}  // namespace

TEST_CASE("a runtime frame allocates nothing: default mannequin, three-point", "[reliability][allocation]") {
  CHECK(allocationsPerFrameLoop(mannequin(), "synthetic:reach", true) == 0);
}

TEST_CASE("a runtime frame allocates nothing: default mannequin, six trackers", "[reliability][allocation]") {
  CHECK(allocationsPerFrameLoop(mannequin(), "synthetic:squat", false) == 0);
}

// Seated mode's frame (the seat's jobs: hips, knees and feet on the seat placed in the warm-up).
TEST_CASE("a runtime frame allocates nothing: default mannequin, seated", "[reliability][allocation]") {
  CHECK(allocationsPerFrameLoop(mannequin(), "synthetic:reach", true, true) == 0);
}

TEST_CASE("a runtime frame allocates nothing: a generated glTF humanoid", "[reliability][allocation]") {
  test::HumanoidFile file;
  auto asset = avatar::loadGltfFromMemory(file.glb(), ".");
  REQUIRE(asset.ok());
  REQUIRE(avatar::prepareAvatar(asset.value(), "").ok());
  REQUIRE(asset->humanoid.usable());
  CHECK(allocationsPerFrameLoop(asset.value(), "synthetic:reach", true) == 0);
}

TEST_CASE("a runtime frame allocates nothing: CesiumMan", "[reliability][allocation]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  auto asset = avatar::loadAvatarFile(path);
  REQUIRE(asset.ok());
  CHECK(allocationsPerFrameLoop(asset.value(), "synthetic:reach", true) == 0);
}

// `--avatar CLIP.bvh`: the clip's skeleton with a capsule mesh per bone, driven by a synthetic
// motion and by the clip itself (as `--avatar CLIP.bvh --motion CLIP.bvh` does).
TEST_CASE("a runtime frame allocates nothing: a BVH clip as the avatar", "[reliability][allocation]") {
  for (const char* convention : {"cmu", "unreal"}) {
    INFO(convention);
    const std::string clip = std::string(test::kSourceDir) + "/tests/tracking/fixtures/" + convention + ".bvh";
    auto bvh = tracking::loadBvhAvatar(clip, {});
    REQUIRE(bvh.ok());
    REQUIRE(bvh->asset.humanoid.usable());
    CHECK(allocationsPerFrameLoop(bvh->asset, "synthetic:reach", true) == 0);
    CHECK(allocationsPerFrameLoop(bvh->asset, clip.c_str(), false) == 0);
  }
}

TEST_CASE("VRM secondary motion allocates nothing: spring bones, look-at, expressions, blinking", "[reliability][allocation]") {
  for (bool boneLookAt : {false, true}) {
    const test::VrmTestAvatar bust = test::buildVrmTestAvatar({.boneLookAt = boneLookAt});
    auto bytes = avatar::encodeGlb(bust.asset, nullptr, bust.extensionsJson);
    REQUIRE(bytes.ok());
    auto asset = avatar::loadGltfFromMemory(*bytes, ".");
    REQUIRE(asset.ok());
    REQUIRE(avatar::prepareAvatar(*asset, "").ok());
    REQUIRE(asset->springBones.chains.size() == 8);
    avatar::SecondaryMotion motion(*asset);
    avatar::SkeletonPose pose = avatar::SkeletonPose::rest(asset->skeleton);
    const avatar::SkeletonPose rest = pose;
    const int head = asset->humanoid.joint(avatar::HumanBone::head);
    auto frame = [&](int i) {
      pose = rest;  // same size: copies into the existing storage
      pose.local[static_cast<size_t>(head)].rotation = glm::angleAxis(0.8f * std::sin(0.07f * float(i)), glm::vec3(0, 1, 0));
      if (i % 50 == 25) pose.local[1].translation.x += 20.0f;  // a teleport
      if (i % 70 == 0) motion.reset();                          // a recenter
      motion.update(pose, i % 33 == 0 ? 0.5 : 1.0 / 90.0, glm::vec3(std::sin(0.1f * float(i)), 1.6f, 1.0f));
    };
    for (int i = 0; i < 10; ++i) frame(i);
    test::CountAllocations counter;
    for (int i = 10; i < 400; ++i) frame(i);
    CHECK(counter.counts().count == 0);
  }
}

TEST_CASE("the allocation counter sees operator new and Eigen's malloc", "[reliability][allocation]") {
  test::AllocationCounts counts;
  {
    test::CountAllocations counter;
    std::vector<int> v(1000);
    Eigen::MatrixXd m = Eigen::MatrixXd::Identity(40, 40);
    CHECK(v.size() + static_cast<size_t>(m.rows()) == 1040);
    counts = counter.counts();
  }
  CHECK(counts.count == 2);
  CHECK(counts.largestBytes == 40 * 40 * sizeof(double));
}
