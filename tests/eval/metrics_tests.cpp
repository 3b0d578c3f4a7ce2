// The eval metrics on constructed cases with known answers (eval/metrics.h).
#include <catch2/catch.hpp>
#include <glm/gtc/constants.hpp>

#include "eval/metrics.h"

using namespace embody::eval;

namespace {

// A chain of three joints standing up (root at the origin, 1 m bones), `frames` frames.
JointTrack chain(int frames) {
  JointTrack t;
  t.joints = 3;
  for (int f = 0; f < frames; ++f)
    for (int j = 0; j < 3; ++j) {
      t.position.emplace_back(0.0, double(j), 0.0);
      t.rotation.emplace_back(1.0, 0.0, 0.0, 0.0);
    }
  return t;
}

ScoredSkeleton chainSkeleton() {
  ScoredSkeleton s;
  s.groups[kAll] = {0, 1, 2};
  s.groups[kRoot] = {0};
  s.groups[kHands] = {2};
  return s;
}

}  // namespace

TEST_CASE("eval metrics: a clip against itself scores zero everywhere", "[eval]") {
  JointTrack t = chain(20);
  for (int f = 0; f < 20; ++f) t.position[size_t(f) * 3 + 2].x = 0.01 * f * f;  // some motion
  const Metrics m = score(t, t, chainSkeleton(), 30.0);
  CHECK(m.frames == 20);
  for (int g = 0; g < kGroupCount; ++g) CHECK(m.mpjpe[size_t(g)].mean == 0.0);
  CHECK(m.mpjpe[kAll].p95 == 0.0);
  CHECK(m.mpjreDegrees == 0.0);
  CHECK(m.mpjve == 0.0);
  CHECK(m.jitter == m.clipJitter);
  CHECK(m.kneeReverseFrames == 0);
  CHECK(m.collapsedFrames == 0);
}

TEST_CASE("eval metrics: a joint rotated by 90 degrees", "[eval]") {
  // Joint 1 turns 90° about Z: joint 2 moves from (0,2,0) to (-1,1,0); joints 1 and 2 are both
  // turned by 90° in the world.
  const JointTrack clip = chain(5);
  JointTrack solved = clip;
  const glm::dquat turn = glm::angleAxis(glm::half_pi<double>(), glm::dvec3(0, 0, 1));
  for (int f = 0; f < 5; ++f) {
    solved.position[size_t(f) * 3 + 2] = glm::dvec3(-1.0, 1.0, 0.0);
    solved.rotation[size_t(f) * 3 + 1] = turn;
    solved.rotation[size_t(f) * 3 + 2] = turn;
  }
  const Metrics m = score(solved, clip, chainSkeleton(), 30.0);
  CHECK(m.mpjpe[kAll].mean == Approx(std::sqrt(2.0) / 3.0));
  CHECK(m.mpjpe[kHands].mean == Approx(std::sqrt(2.0)));
  CHECK(m.mpjpe[kRoot].mean == 0.0);
  CHECK(m.mpjreDegrees == Approx(60.0));  // (0 + 90 + 90) / 3, geodesic
  CHECK(m.perJointError[2] == Approx(std::sqrt(2.0)));
  CHECK(m.mpjve == Approx(0.0).margin(1e-12));
}

TEST_CASE("eval metrics: a shifted root shifts every joint by the same amount", "[eval]") {
  const JointTrack clip = chain(10);
  JointTrack solved = clip;
  for (auto& p : solved.position) p += glm::dvec3(0.1, 0.0, 0.0);
  const Metrics m = score(solved, clip, chainSkeleton(), 90.0);
  CHECK(m.mpjpe[kAll].mean == Approx(0.1));
  CHECK(m.mpjpe[kAll].p95 == Approx(0.1));
  CHECK(m.mpjpe[kRoot].mean == Approx(0.1));
  CHECK(m.mpjreDegrees == 0.0);
  CHECK(m.mpjve == Approx(0.0).margin(1e-9));  // a constant offset has no velocity error
}

TEST_CASE("eval metrics: jitter of a cubic is its third derivative", "[eval]") {
  // x = t^3: the third difference is exactly 6 dt^3, so jitter = 6 m/s^3 at any rate.
  for (double fps : {30.0, 90.0}) {
    JointTrack t = chain(12);
    for (int f = 0; f < 12; ++f)
      for (int j = 0; j < 3; ++j) t.position[size_t(f) * 3 + size_t(j)].x = std::pow(double(f) / fps, 3.0);
    const Metrics m = score(t, t, chainSkeleton(), fps);
    CHECK(m.clipJitter == Approx(6.0).epsilon(1e-6));
  }
}

TEST_CASE("eval metrics: jitter per group finds the joint that shakes", "[eval]") {
  // The solution's root alternates +-d from frame to frame (a period-2 cycle); the rest is still.
  // Its third difference is d (1 + 3 + 3 + 1) = 8 d every frame: root jitter 8 d fps^3, hands 0,
  // the mean over the three joints 8 d fps^3 / 3; the clip's is 0 everywhere.
  const double fps = 90.0, d = 0.001;
  const JointTrack clip = chain(12);
  JointTrack solved = clip;
  for (int f = 0; f < 12; ++f) solved.position[size_t(f) * 3].x = f % 2 == 0 ? d : -d;
  const Metrics m = score(solved, clip, chainSkeleton(), fps);
  const double root = 8.0 * d * fps * fps * fps;
  CHECK(m.groupJitter[kRoot] == Approx(root));
  CHECK(m.groupJitter[kHands] == 0.0);
  CHECK(m.groupJitter[kFeet] == 0.0);  // an empty group
  CHECK(m.groupJitter[kAll] == Approx(root / 3.0));
  CHECK(m.jitter == m.groupJitter[kAll]);
  for (int g = 0; g < kGroupCount; ++g) CHECK(m.clipGroupJitter[size_t(g)] == 0.0);
}

TEST_CASE("eval metrics: a solved foot sliding while the clip's is planted", "[eval]") {
  // Joint 0 = ankle at 3 cm (in contact), joint 1 a toe on the floor; the solution slides 10 cm/s.
  JointTrack clip;
  clip.joints = 2;
  const double fps = 50.0;
  for (int f = 0; f < 20; ++f) {
    clip.position.emplace_back(0.0, 0.03, 0.0), clip.position.emplace_back(0.0, 0.0, 0.1);
    clip.rotation.resize(clip.position.size(), glm::dquat(1, 0, 0, 0));
  }
  JointTrack solved = clip;
  for (int f = 0; f < 20; ++f) solved.position[size_t(f) * 2].z += 0.1 * double(f) / fps;
  ScoredSkeleton s;
  s.groups[kAll] = {0, 1};
  s.soles[0] = {0, 1};
  const Metrics m = score(solved, clip, s, fps);
  CHECK(m.contactFrames == 19);
  CHECK(m.footSkating == Approx(0.1));
  CHECK(m.clipFootSkating == 0.0);
}

TEST_CASE("eval metrics: a knee bent the other way round is a reverse bend, a fallen pelvis is a collapse", "[eval]") {
  JointTrack clip;
  clip.joints = 3;  // hip, knee, ankle: the clip's knee bends forward (+Z)
  clip.position = {{0, 1, 0}, {0, 0.5, 0.2}, {0, 0, 0}};
  clip.rotation.assign(3, glm::dquat(1, 0, 0, 0));
  JointTrack solved = clip;
  solved.position[1].z = -0.2;  // bent backwards
  ScoredSkeleton s;
  s.groups[kAll] = {0, 1, 2};
  s.legs[0] = {0, 1, 2};
  s.pelvis = 0;
  s.standingPelvisHeight = 1.0;
  CHECK(score(solved, clip, s, 30.0).kneeReverseFrames == 1);
  CHECK(score(clip, clip, s, 30.0).kneeReverseFrames == 0);
  solved = clip;
  solved.position[0].y = 0.4;
  CHECK(score(solved, clip, s, 30.0).collapsedFrames == 1);

  // Per frame, which count each frame went to (frames.csv's 0/1 columns): a second frame with
  // the knee reversed and the pelvis fallen, after the first that is both.
  JointTrack twoClip = clip, twoSolved = solved;
  twoClip.position.insert(twoClip.position.end(), clip.position.begin(), clip.position.end());
  twoClip.rotation.assign(6, glm::dquat(1, 0, 0, 0));
  twoSolved.position.insert(twoSolved.position.end(), clip.position.begin(), clip.position.end());
  twoSolved.position[1].z = -0.2;  // frame 0: reversed and fallen
  twoSolved.position[3].y = 0.4;   // frame 1: fallen only (its knee is the clip's)
  twoSolved.rotation = twoClip.rotation;
  const Metrics two = score(twoSolved, twoClip, s, 30.0);
  CHECK(two.kneeReverseFrames == 1);
  CHECK(two.collapsedFrames == 2);
  CHECK(two.perFrameFlags == std::vector<unsigned char>{kKneeReversed | kCollapsed, kCollapsed});
}

TEST_CASE("eval metrics: p95 is the nearest-rank 95th percentile", "[eval]") {
  std::vector<double> v;
  for (int i = 1; i <= 100; ++i) v.push_back(double(i));
  CHECK(percentile95(v) == 95.0);
  CHECK(percentile95({}) == 0.0);
  CHECK(percentile95({3.0}) == 3.0);
}

TEST_CASE("eval metrics: spine torsion changing sign inside a region, not between regions", "[eval]") {
  // Four joints up a vertical chain; joint 1 twisted +10 deg about the chain, joint 2 back to -5
  // in the world (local -15): a sign change when 0..3 is one region; none when the regions are
  // 0..1 and 1..3 (the +10 and the -15 fall in different regions).
  JointTrack t;
  t.joints = 4;
  const glm::dvec3 up(0, 1, 0);
  const glm::dquat q1 = glm::angleAxis(glm::radians(10.0), up), q2 = glm::angleAxis(glm::radians(-5.0), up);
  t.position = {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 3, 0}};
  t.rotation = {glm::dquat(1, 0, 0, 0), q1, q2, q2};
  ScoredSkeleton one;
  one.groups[kAll] = {0, 1, 2, 3};
  one.spineRegions = {{{0, 1, 2, 3}, {up, up, up, up}}};
  CHECK(score(t, t, one, 30.0).torsionSignChangeFrames == 1);
  ScoredSkeleton two = one;
  two.spineRegions = {{{0, 1}, {up, up}}, {{1, 2, 3}, {up, up, up}}};
  CHECK(score(t, t, two, 30.0).torsionSignChangeFrames == 0);
  JointTrack straight = t;
  straight.rotation = {glm::dquat(1, 0, 0, 0), q1, q1 * q1, q1 * q1};  // the same way all along
  CHECK(score(straight, straight, one, 30.0).torsionSignChangeFrames == 0);
}

TEST_CASE("eval metrics: per-joint bias in the clip's body frame (forward, left, up)", "[eval]") {
  // Root and two hips, the body turned 90° left (its left -Z, its forward +X). The solution sits
  // 5 cm ahead of the clip and 2 cm up: bias (0.05, 0, 0.02) for every joint, whatever the turn.
  JointTrack clip;
  clip.joints = 3;
  for (int f = 0; f < 4; ++f)
    for (const glm::dvec3& p : {glm::dvec3(0.0, 1.0, 0.0), glm::dvec3(0.0, 1.0, -0.1), glm::dvec3(0.0, 1.0, 0.1)}) {
      clip.position.push_back(p + glm::dvec3(0.3 * f, 0.0, 0.0));
      clip.rotation.emplace_back(1.0, 0.0, 0.0, 0.0);
    }
  JointTrack solved = clip;
  for (auto& p : solved.position) p += glm::dvec3(0.05, 0.02, 0.0);
  ScoredSkeleton s;
  s.groups[kAll] = {0, 1, 2};
  s.legs[0] = {1, -1, -1};
  s.legs[1] = {2, -1, -1};
  const Metrics m = score(solved, clip, s, 30.0);
  REQUIRE(m.perJointBias.size() == 3);
  for (const glm::dvec3& b : m.perJointBias) {
    CHECK(b.x == Approx(0.05));
    CHECK(b.y == Approx(0.0).margin(1e-12));
    CHECK(b.z == Approx(0.02));
  }
  // Without hips there is no body frame: no bias.
  s.legs[0][0] = -1;
  CHECK(score(solved, clip, s, 30.0).perJointBias.empty());
}
