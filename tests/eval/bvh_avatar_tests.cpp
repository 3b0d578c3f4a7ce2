// A BVH clip as an avatar, the clip's joints resampled, and solved motion written back onto the
// clip's hierarchy (tracking/bvh_avatar.h, tracking/bvh_export.h, avatar/bvh/bvh_writer.h).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>

#include "avatar/bvh/bvh_writer.h"
#include "test_paths.h"
#include "tracking/bvh_avatar.h"
#include "tracking/bvh_export.h"

using namespace embody;

namespace {

// A small humanoid in CMU-like names, Z-up-free conventions mixed: ZXY on most joints, XYZ and
// YZX on others, a position channel on a non-root joint. Frame 1 moves the root 10 units along X
// and bends the left knee and right elbow.
const char* kClip = R"(HIERARCHY
ROOT Hips
{
  OFFSET 0 100 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT LeftLeg
    {
      OFFSET 0 -45 0
      CHANNELS 3 Xrotation Yrotation Zrotation
      JOINT LeftFoot
      {
        OFFSET 0 -45 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -5 12
        }
      }
    }
  }
  JOINT RightUpLeg
  {
    OFFSET -10 0 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT RightLeg
    {
      OFFSET 0 -45 0
      CHANNELS 3 Zrotation Xrotation Yrotation
      JOINT RightFoot
      {
        OFFSET 0 -45 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        End Site
        {
          OFFSET 0 -5 12
        }
      }
    }
  }
  JOINT Spine
  {
    OFFSET 0 20 0
    CHANNELS 3 Yrotation Zrotation Xrotation
    JOINT Spine1
    {
      OFFSET 0 20 0
      CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
      JOINT Neck
      {
        OFFSET 0 15 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT Head
        {
          OFFSET 0 10 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          End Site
          {
            OFFSET 0 15 0
          }
        }
      }
      JOINT LeftArm
      {
        OFFSET 18 10 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT LeftForeArm
        {
          OFFSET 28 0 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT LeftHand
          {
            OFFSET 25 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            End Site
            {
              OFFSET 8 0 0
            }
          }
        }
      }
      JOINT RightArm
      {
        OFFSET -18 10 0
        CHANNELS 3 Zrotation Xrotation Yrotation
        JOINT RightForeArm
        {
          OFFSET -28 0 0
          CHANNELS 3 Zrotation Xrotation Yrotation
          JOINT RightHand
          {
            OFFSET -25 0 0
            CHANNELS 3 Zrotation Xrotation Yrotation
            End Site
            {
              OFFSET -8 0 0
            }
          }
        }
      }
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
)";

// Sets one channel of a frame by joint name and channel.
void set(avatar::BvhClip& c, size_t frame, const char* joint, avatar::BvhChannel channel, float value) {
  const avatar::BvhJoint& j = c.joints[size_t(c.find(joint))];
  for (size_t k = 0; k < j.channels.size(); ++k)
    if (j.channels[k] == channel) c.values[frame * size_t(c.channelCount) + size_t(j.firstChannel) + k] = value;
}

avatar::BvhClip clip() {
  std::string text = kClip;
  avatar::BvhClip c;
  // Three frames of zeros, then the motion set channel by channel.
  int channels = 0;
  for (size_t p = text.find("CHANNELS"); p != std::string::npos; p = text.find("CHANNELS", p + 1))
    channels += text[p + 9] - '0';
  for (int f = 0; f < 3; ++f) {
    for (int k = 0; k < channels; ++k) text += k ? " 0" : "0";
    text += "\n";
  }
  auto parsed = avatar::parseBvh(text, "test.bvh");
  REQUIRE(parsed);
  c = std::move(parsed).value();
  using C = avatar::BvhChannel;
  for (size_t f = 0; f < 3; ++f) {
    const float x = float(f);
    set(c, f, "Hips", C::Xposition, 10 * x);
    set(c, f, "Hips", C::Yposition, 95);
    set(c, f, "Hips", C::Zrotation, 5 * x), set(c, f, "Hips", C::Xrotation, 3 * x), set(c, f, "Hips", C::Yrotation, 20 * x);
    set(c, f, "LeftUpLeg", C::Xrotation, -10 * x);
    set(c, f, "LeftLeg", C::Xrotation, 40 * x), set(c, f, "LeftLeg", C::Yrotation, 5 * x), set(c, f, "LeftLeg", C::Zrotation, 3 * x);
    set(c, f, "RightUpLeg", C::Xrotation, 10 * x);
    set(c, f, "Spine", C::Yrotation, 10 * x), set(c, f, "Spine", C::Zrotation, 5 * x), set(c, f, "Spine", C::Xrotation, -7 * x);
    set(c, f, "Spine1", C::Xposition, 0.5f * x), set(c, f, "Spine1", C::Zrotation, 4 * x), set(c, f, "Spine1", C::Xrotation, -6 * x);
    set(c, f, "Neck", C::Yrotation, 10 * x);
    set(c, f, "LeftArm", C::Zrotation, 3 * x), set(c, f, "LeftArm", C::Yrotation, -12 * x);
    set(c, f, "RightForeArm", C::Yrotation, 30 * x);
  }
  return c;
}

void requireSameGlobals(const avatar::BvhClip& a, const avatar::BvhClip& b, double tolerance) {
  REQUIRE(a.frameCount == b.frameCount);
  std::vector<avatar::BvhGlobal> ga, gb;
  for (size_t f = 0; f < a.frameCount; ++f) {
    avatar::bvhGlobals(a, a.frame(f), ga);
    avatar::bvhGlobals(b, b.frame(f), gb);
    for (size_t j = 0; j < ga.size(); ++j) {
      INFO("frame " << f << " joint " << a.joints[j].name);
      CHECK(glm::length(ga[j].position - gb[j].position) < tolerance);
    }
  }
}

}  // namespace

TEST_CASE("BVH writer: a parsed clip written and parsed again is the same clip", "[eval][bvh]") {
  const avatar::BvhClip a = clip();
  auto b = avatar::parseBvh(avatar::formatBvh(a), "again.bvh");
  REQUIRE(b);
  REQUIRE(b->joints.size() == a.joints.size());
  for (size_t j = 0; j < a.joints.size(); ++j) {
    CHECK(b->joints[j].name == a.joints[j].name);
    CHECK(b->joints[j].offset == a.joints[j].offset);
    CHECK(b->joints[j].channels == a.joints[j].channels);
  }
  CHECK(b->frameTime == a.frameTime);
  CHECK(b->values == a.values);
}

TEST_CASE("BVH writer: joints kept out of hierarchy order (an avatar's skeleton) are written as a reader reads them",
          "[eval][bvh]") {
  // An avatar's skeleton may list both hips before either knee (breadth first); the file lists
  // each chain depth first, and its MOTION columns must follow the file's order. Before this was
  // fixed, `render --export` of the default avatar gave the left arm the spine's angles.
  const avatar::BvhClip a = clip();
  std::vector<size_t> order;  // breadth first: every root, then their children, ...
  for (size_t j = 0; j < a.joints.size(); ++j)
    if (a.joints[j].parent < 0) order.push_back(j);
  for (size_t k = 0; k < order.size(); ++k)
    for (size_t c = 0; c < a.joints.size(); ++c)
      if (a.joints[c].parent == int(order[k])) order.push_back(c);
  REQUIRE(order.size() == a.joints.size());
  std::vector<int> newIndex(a.joints.size());
  for (size_t k = 0; k < order.size(); ++k) newIndex[order[k]] = int(k);
  avatar::BvhClip b = a;
  b.values.clear();
  int channel = 0;
  for (size_t k = 0; k < order.size(); ++k) {
    b.joints[k] = a.joints[order[k]];
    b.joints[k].parent = b.joints[k].parent < 0 ? -1 : newIndex[size_t(b.joints[k].parent)];
    b.joints[k].firstChannel = channel;
    channel += int(b.joints[k].channels.size());
  }
  bool reordered = false;
  for (size_t k = 0; k < order.size(); ++k) reordered = reordered || order[k] != k;
  REQUIRE(reordered);
  for (size_t f = 0; f < a.frameCount; ++f)
    for (size_t k = 0; k < order.size(); ++k)
      for (size_t c = 0; c < a.joints[order[k]].channels.size(); ++c)
        b.values.push_back(a.frame(f)[size_t(a.joints[order[k]].firstChannel) + c]);

  auto read = avatar::parseBvh(avatar::formatBvh(b), "reordered.bvh");
  REQUIRE(read);
  std::vector<avatar::BvhGlobal> want, got;
  for (size_t f = 0; f < a.frameCount; ++f) {
    avatar::bvhGlobals(a, a.frame(f), want);
    avatar::bvhGlobals(*read, read->frame(f), got);
    for (size_t j = 0; j < a.joints.size(); ++j) {
      if (a.joints[j].endSite) continue;
      const int r = read->find(a.joints[j].name);
      REQUIRE(r >= 0);
      INFO(a.joints[j].name << " frame " << f);
      CHECK(glm::distance(got[size_t(r)].position, want[j].position) < 1e-3);
    }
  }
}

TEST_CASE("BVH writer: Euler angles in every channel order compose back to the rotation", "[eval][bvh]") {
  using C = avatar::BvhChannel;
  const C orders[6][3] = {{C::Xrotation, C::Yrotation, C::Zrotation}, {C::Xrotation, C::Zrotation, C::Yrotation},
                          {C::Yrotation, C::Xrotation, C::Zrotation}, {C::Yrotation, C::Zrotation, C::Xrotation},
                          {C::Zrotation, C::Xrotation, C::Yrotation}, {C::Zrotation, C::Yrotation, C::Xrotation}};
  const glm::dquat qs[] = {glm::normalize(glm::dquat(0.9, 0.2, -0.3, 0.25)), glm::angleAxis(glm::radians(90.0), glm::dvec3(0, 1, 0)),
                           glm::angleAxis(glm::radians(90.0), glm::dvec3(1, 0, 0)), glm::dquat(1, 0, 0, 0)};
  for (const auto& order : orders)
    for (const auto& q : qs) {
      double deg[3];
      avatar::eulerForChannels(q, order, deg);
      glm::dquat r(1, 0, 0, 0);
      for (int k = 0; k < 3; ++k) {
        glm::dvec3 axis(0.0);
        axis[int(order[k]) - int(C::Xrotation)] = 1.0;
        r = r * glm::angleAxis(glm::radians(deg[k]), axis);
      }
      CHECK(std::abs(glm::dot(r, q)) == Approx(1.0).margin(1e-9));
    }
}

TEST_CASE("BVH avatar: the clip's skeleton in tracking space, mapped, with a capsule mesh", "[eval][bvh]") {
  auto a = tracking::buildBvhAvatar(clip(), {});
  REQUIRE(a);
  CHECK(a->asset.skeleton.joints.size() == a->clip.joints.size());
  CHECK(a->asset.humanoid.usable());
  CHECK(a->asset.humanoid.joint(avatar::HumanBone::leftHand) == a->clip.find("LeftHand"));
  CHECK(a->asset.mesh.triangleCount() > 100);
  // Offsets scaled like the motion: the head joint 155 units above the ankle.
  std::vector<glm::mat4> g;
  avatar::computeGlobals(a->asset.skeleton, avatar::SkeletonPose::rest(a->asset.skeleton), g);
  const int head = a->clip.find("Head"), foot = a->clip.find("LeftFoot");
  CHECK(g[size_t(head)][3].y - g[size_t(foot)][3].y == Approx(155.0 * a->mapping.scale).margin(1e-4));
  // Tracking space faces -Z with +X to the right: the left hand lies at -X.
  CHECK(g[size_t(a->clip.find("LeftHand"))][3].x < g[size_t(a->clip.find("RightHand"))][3].x);
}

TEST_CASE("BVH avatar: the rest pose stands its ankles as high as the clip's stand", "[eval][bvh]") {
  // A clip standing still with both feet pitched 30 degrees toes-down: its end sites (0, -5, 12)
  // under the ankles drop to -5 cos 30 - 12 sin 30 = -10.33 units, so the clip's floor (its lowest
  // points) lies 10.33 units under the ankles, where the rest pose's lowest joints lie 5 under
  // them. Stood on its lowest joint, the rest would plant the ankles 5.33 units too low.
  avatar::BvhClip still = clip();
  const size_t n = size_t(still.channelCount);
  for (size_t f = 1; f < still.frameCount; ++f)
    std::copy_n(still.values.begin(), n, still.values.begin() + std::ptrdiff_t(f * n));
  using C = avatar::BvhChannel;
  for (size_t f = 0; f < still.frameCount; ++f)
    for (const char* foot : {"LeftFoot", "RightFoot"}) set(still, f, foot, C::Xrotation, 30.0f);
  auto a = tracking::buildBvhAvatar(still, {});
  REQUIRE(a);
  const double drop = 5.0 * std::cos(std::numbers::pi / 6) + 12.0 * std::sin(std::numbers::pi / 6) - 5.0;  // 5.33 units
  CHECK(a->restLift == Approx(drop * a->mapping.scale).margin(1e-5));
  std::vector<glm::mat4> g;
  avatar::computeGlobals(a->asset.skeleton, avatar::SkeletonPose::rest(a->asset.skeleton), g);
  const double restAnkle = g[size_t(a->clip.find("LeftFoot"))][3].y;
  const double clipAnkle = a->trace.samples[0][tracking::TrackerId::LeftFoot].position.y;
  CHECK(restAnkle == Approx(clipAnkle).margin(1e-5));
  CHECK(a->trace.samples[0][tracking::TrackerId::RightFoot].position.y == Approx(clipAnkle).margin(1e-5));
  CHECK(std::find_if(a->mapping.notes.begin(), a->mapping.notes.end(),
                     [](const std::string& s) { return s.rfind("rest pose lifted", 0) == 0; }) != a->mapping.notes.end());
  // Feet as at rest: the rest's lowest joints on the floor, as before.
  avatar::BvhClip flat = still;
  for (size_t f = 0; f < flat.frameCount; ++f)
    for (const char* foot : {"LeftFoot", "RightFoot"}) set(flat, f, foot, C::Xrotation, 0.0f);
  auto b = tracking::buildBvhAvatar(flat, {});
  REQUIRE(b);
  CHECK(b->restLift == Approx(0.0).margin(1e-6));
}

TEST_CASE("BVH avatar: a clip that is not a standing body is refused with one line", "[eval][bvh]") {
  auto c = avatar::parseBvh("HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 3 Xrotation Yrotation Zrotation\n JOINT B\n {\n"
                            "  OFFSET 0 1 0\n  CHANNELS 3 Xrotation Yrotation Zrotation\n  End Site\n  {\n   OFFSET 0 1 0\n  }\n }\n}\n"
                            "MOTION\nFrames: 2\nFrame Time: 0.1\n0 0 0 0 0 0\n0 0 0 0 0 0\n", "stick.bvh");
  REQUIRE(c);
  auto a = tracking::buildBvhAvatar(std::move(c).value(), {});
  REQUIRE_FALSE(a);
  CHECK(a.error().find('\n') == std::string::npos);
}

TEST_CASE("BVH avatar: a clip whose zero-channel pose lies down stands in its first frame (CC_Base)", "[eval][bvh]") {
  // The project's CC_Base fixture points the legs up at zero channels, as Reallusion's exports do.
  auto a = tracking::loadBvhAvatar(std::string(test::kSourceDir) + "/tests/tracking/fixtures/ccbase.bvh", {});
  REQUIRE(a);
  CHECK(a->restFromFirstFrame);
  const avatar::Skeleton& sk = a->asset.skeleton;
  std::vector<glm::mat4> rest, posed;
  avatar::computeGlobals(sk, avatar::SkeletonPose::rest(sk), rest);
  const int head = a->asset.humanoid.joint(avatar::HumanBone::head), hips = a->asset.humanoid.joint(avatar::HumanBone::hips);
  REQUIRE(head >= 0);
  REQUIRE(hips >= 0);
  CHECK(rest[size_t(head)][3].y > rest[size_t(hips)][3].y + 0.3f);
  // The trackers' references follow that rest pose: at every time, the head tracker's orientation
  // is the head joint's turn from the rest pose applied to the reference, and the clip replayed on
  // the avatar puts the head joint where the clip has it.
  const size_t h = size_t(tracking::index(tracking::TrackerId::Head));
  const glm::dquat restHead = glm::quat_cast(glm::dmat3(glm::mat3(rest[size_t(head)])));
  std::vector<avatar::BvhGlobal> clipJoints;
  for (const auto& sample : a->trace.samples) {
    avatar::SkeletonPose pose;
    tracking::bvhPoseAt(*a, sample.time, pose);
    avatar::computeGlobals(sk, pose, posed);
    tracking::bvhJointsAt(a->clip, a->mapping, sample.time, clipJoints);
    CHECK(glm::distance(glm::dvec3(posed[size_t(head)][3]), clipJoints[size_t(head)].position) < 1e-4);
    const glm::dquat turn = glm::quat_cast(glm::dmat3(glm::mat3(posed[size_t(head)]))) * glm::conjugate(restHead);
    const glm::dquat expected = glm::normalize(turn * a->mapping.reference[h]);
    const glm::dquat tracker(sample[tracking::TrackerId::Head].orientation);
    CHECK(std::abs(glm::dot(expected, tracker)) > 1.0 - 1e-6);
  }
}

namespace {

// The clip with a world turn in its root's channels: positions and rotations turned by `w` every
// frame, the offsets (the zero-channel pose) left as they were, as a Z-up tool writes a Y-up
// skeleton into a Z-up world.
avatar::BvhClip turnWorld(const avatar::BvhClip& in, const glm::dquat& w) {
  avatar::BvhClip c = in;
  const avatar::BvhJoint& root = c.joints[0];
  std::vector<avatar::BvhChannel> rotations;
  for (auto ch : root.channels)
    if (ch == avatar::BvhChannel::Xrotation || ch == avatar::BvhChannel::Yrotation || ch == avatar::BvhChannel::Zrotation)
      rotations.push_back(ch);
  REQUIRE(rotations.size() == 3);
  std::vector<avatar::BvhGlobal> g;
  for (size_t f = 0; f < c.frameCount; ++f) {
    avatar::bvhGlobals(in, in.frame(f), g);
    const glm::dvec3 p = w * g[0].position - root.offset;
    double degrees[3];
    avatar::eulerForChannels(w * g[0].rotation, rotations.data(), degrees);
    const char* name = root.name.c_str();
    set(c, f, name, avatar::BvhChannel::Xposition, float(p.x));
    set(c, f, name, avatar::BvhChannel::Yposition, float(p.y));
    set(c, f, name, avatar::BvhChannel::Zposition, float(p.z));
    for (int k = 0; k < 3; ++k) set(c, f, name, rotations[size_t(k)], float(degrees[k]));
  }
  return c;
}

}  // namespace

TEST_CASE("BVH avatar: a skeleton authored in other axes than its motion stands as if authored in them", "[eval][bvh]") {
  // A Y-up skeleton turned into a Z-up (or X-up, or backwards) world by its root's channels lies
  // on its back or side at zero channels. Its rest pose is stood up by the turn between axes that
  // does it, so the avatar, the trackers and the clip's joints are the untouched clip's; before,
  // the lying rest was taken as is (27-41 cm in eval where the clip scores 6.3) or refused.
  const avatar::BvhClip plain = clip();
  auto a = tracking::buildBvhAvatar(plain, {});
  REQUIRE(a);
  CHECK(glm::abs(a->restTurn.w) == Approx(1.0));
  const double quarter = std::numbers::pi / 2;
  const glm::dquat turns[] = {glm::angleAxis(-quarter, glm::dvec3(1, 0, 0)),                                        // Z up
                              glm::angleAxis(quarter, glm::dvec3(0, 0, 1)) * glm::angleAxis(quarter, glm::dvec3(1, 0, 0)),  // X up
                              glm::angleAxis(std::numbers::pi, glm::dvec3(0, 1, 0))};                                 // facing back
  for (const glm::dquat& w : turns) {
    const avatar::BvhClip turned = turnWorld(plain, w);
    std::vector<avatar::BvhGlobal> g0, g1;
    avatar::bvhGlobals(plain, plain.frame(2), g0);
    avatar::bvhGlobals(turned, turned.frame(2), g1);
    REQUIRE(glm::distance(w * g0[5].position, g1[5].position) < 1e-3);  // the helper turned the world
    auto b = tracking::buildBvhAvatar(turned, {});
    REQUIRE(b);
    CHECK(glm::abs(b->restTurn.w) < 0.99);
    CHECK(std::any_of(b->mapping.notes.begin(), b->mapping.notes.end(),
                      [](const std::string& s) { return s.rfind("rest pose turned", 0) == 0; }));
    // The same rest skeleton, and the same clip replayed on it.
    std::vector<glm::mat4> ra, rb, pa, pb;
    avatar::computeGlobals(a->asset.skeleton, avatar::SkeletonPose::rest(a->asset.skeleton), ra);
    avatar::computeGlobals(b->asset.skeleton, avatar::SkeletonPose::rest(b->asset.skeleton), rb);
    REQUIRE(ra.size() == rb.size());
    for (size_t j = 0; j < ra.size(); ++j) {
      INFO("joint " << plain.joints[j].name);
      CHECK(glm::distance(glm::vec3(ra[j][3]), glm::vec3(rb[j][3])) < 1e-5f);
    }
    for (size_t t = 0; t < a->trace.samples.size(); ++t) {
      const double time = a->trace.samples[t].time;
      avatar::SkeletonPose poseA, poseB;
      tracking::bvhPoseAt(*a, time, poseA);
      tracking::bvhPoseAt(*b, time, poseB);
      avatar::computeGlobals(a->asset.skeleton, poseA, pa);
      avatar::computeGlobals(b->asset.skeleton, poseB, pb);
      for (size_t j = 0; j < pa.size(); ++j) CHECK(glm::distance(glm::vec3(pa[j][3]), glm::vec3(pb[j][3])) < 1e-4f);
      for (auto id : tracking::kAllTrackers) {
        const auto &sa = a->trace.samples[t][id], &sb = b->trace.samples[t][id];
        CHECK(glm::distance(sa.position, sb.position) < 1e-4f);
        CHECK(std::abs(glm::dot(sa.orientation, sb.orientation)) > 1.0f - 1e-5f);
      }
    }
    for (size_t i = 0; i < a->mapping.reference.size(); ++i)
      CHECK(std::abs(glm::dot(a->mapping.reference[i], b->mapping.reference[i])) > 1.0 - 1e-6);
  }
}

TEST_CASE("BVH avatar: bones above the pelvis (a root-motion bone on the floor) get no capsule", "[eval][bvh]") {
  // The test clip under a root on the floor that carries the position, as CC_Base's RL_BoneRoot
  // and Unreal's root do: its bone up to the hips would stand where the clip began, like a pole.
  std::string text = kClip;
  const size_t hips = text.find("ROOT Hips");
  text.replace(hips, 9, "ROOT BoneRoot\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
                        "Yrotation\n  JOINT Hips");
  text.replace(text.find("MOTION"), 6, "}\nMOTION");
  const avatar::BvhClip plain = clip();
  for (size_t f = 0; f < 3; ++f) {
    text += "0 0 0 0 0 0";
    for (float v : plain.frame(f)) text += " " + std::to_string(v);
    text += "\n";
  }
  auto parsed = avatar::parseBvh(text, "rooted.bvh");
  REQUIRE(parsed);
  auto a = tracking::buildBvhAvatar(std::move(parsed).value(), {});
  REQUIRE(a);
  const int root = a->asset.skeleton.find("BoneRoot");
  REQUIRE(root >= 0);
  size_t onRoot = 0;
  for (const auto& v : a->asset.mesh.vertices) onRoot += (v.joints0.x == uint32_t(root) && v.weights0.x > 0.5f) ? 1 : 0;
  CHECK(onRoot == 0);
  CHECK(a->asset.mesh.vertices.size() > 100);  // the body's capsules are there
}

TEST_CASE("BVH avatar: the clip's joints resampled between frames", "[eval][bvh]") {
  auto a = tracking::buildBvhAvatar(clip(), {});
  REQUIRE(a);
  std::vector<avatar::BvhGlobal> g0, g1, gh;
  const double dt = a->clip.frameTime;
  tracking::bvhJointsAt(a->clip, a->mapping, 0.0, g0);
  tracking::bvhJointsAt(a->clip, a->mapping, dt, g1);
  tracking::bvhJointsAt(a->clip, a->mapping, 0.5 * dt, gh);
  // The root moves 10 units along file X between frames 0 and 1: half way at half a frame, and
  // the trace's hips tracker sits on the same point.
  CHECK(glm::length(gh[0].position - 0.5 * (g0[0].position + g1[0].position)) < 1e-9);
  CHECK(glm::length(g1[0].position - g0[0].position) == Approx(10.0 * a->mapping.scale));
  const auto& hips = a->trace.samples[1][tracking::TrackerId::Hips];
  CHECK(glm::length(glm::dvec3(hips.position) - g1[0].position) < 1e-5);
}

TEST_CASE("BVH export: the clip's own poses written on its hierarchy give back the clip", "[eval][bvh]") {
  auto a = tracking::buildBvhAvatar(clip(), {});
  REQUIRE(a);
  auto out = tracking::SolvedMotionBvh::forBvhAvatar(*a);
  avatar::SkeletonPose pose;
  for (size_t f = 0; f < a->clip.frameCount; ++f) {
    tracking::bvhPoseAt(*a, double(f) * a->clip.frameTime, pose);
    out.add(pose);
  }
  const avatar::BvhClip& e = out.clip();
  for (size_t j = 0; j < e.joints.size(); ++j) {
    CHECK(e.joints[j].name == a->clip.joints[j].name);
    CHECK(e.joints[j].offset == a->clip.joints[j].offset);
    CHECK(e.joints[j].channels == a->clip.joints[j].channels);
  }
  CHECK(e.frameTime == a->clip.frameTime);
  auto reparsed = avatar::parseBvh(avatar::formatBvh(e), "exported.bvh");
  REQUIRE(reparsed);
  requireSameGlobals(*reparsed, a->clip, 1e-3);  // file units (cm here)
}

TEST_CASE("BVH export: the CMU walk's own poses round-trip through the avatar", "[eval][bvh]") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "cmu_12_01_walk.bvh");
  auto a = tracking::loadBvhAvatar(path, {});
  REQUIRE(a);
  auto out = tracking::SolvedMotionBvh::forBvhAvatar(*a);
  avatar::SkeletonPose pose;
  const size_t frames = std::min<size_t>(a->clip.frameCount - a->mapping.firstFrame, 40);
  for (size_t f = 0; f < frames; ++f) {
    tracking::bvhPoseAt(*a, double(f) * a->clip.frameTime, pose);
    out.add(pose);
  }
  avatar::BvhClip expected = a->clip;
  expected.frameCount = frames;
  expected.values.assign(a->clip.values.begin() + std::ptrdiff_t(a->mapping.firstFrame * size_t(a->clip.channelCount)),
                         a->clip.values.begin() + std::ptrdiff_t((a->mapping.firstFrame + frames) * size_t(a->clip.channelCount)));
  requireSameGlobals(out.clip(), expected, 1e-2);
}

TEST_CASE("BVH export: hips moved under a root that carries the motion (CC_Base) move the root", "[eval][bvh]") {
  // As RL_BoneRoot over CC_Base_Hip: the root has the position channels, the hips only rotation
  // ones. The solver moves the hips; written as they were, the file kept the root where the clip
  // began and the body walked on the spot.
  std::string text = kClip;
  text.replace(text.find("ROOT Hips"), 9, "ROOT BoneRoot\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation "
                                          "Xrotation Yrotation\n  JOINT Hips");
  const size_t hipsChannels = text.find("CHANNELS 6", text.find("JOINT Hips"));
  text.replace(hipsChannels, 10 + std::string(" Xposition Yposition Zposition").size(), "CHANNELS 3");
  text.replace(text.find("MOTION"), 6, "}\nMOTION");
  int channels = 0;
  for (size_t p = text.find("CHANNELS"); p != std::string::npos; p = text.find("CHANNELS", p + 1)) channels += text[p + 9] - '0';
  for (int f = 0; f < 3; ++f) {
    for (int k = 0; k < channels; ++k) text += k ? " 0" : "0";
    text += "\n";
  }
  auto parsed = avatar::parseBvh(text, "rooted.bvh");
  REQUIRE(parsed);
  auto a = tracking::buildBvhAvatar(std::move(parsed).value(), {});
  REQUIRE(a);
  const avatar::Skeleton& sk = a->asset.skeleton;
  const int hips = sk.find("Hips");
  REQUIRE(hips >= 0);
  auto out = tracking::SolvedMotionBvh::forBvhAvatar(*a);
  std::vector<avatar::SkeletonPose> poses;
  for (int f = 0; f < 3; ++f) {
    avatar::SkeletonPose pose = avatar::SkeletonPose::rest(sk);
    // Walked 0.4 m a frame along the avatar's forward and sunk 5 cm, turned and bent a little.
    pose.local[size_t(hips)].translation += glm::vec3(0.05f * float(f), -0.05f, 0.4f * float(f));
    pose.local[size_t(hips)].rotation = glm::angleAxis(0.3f * float(f), glm::vec3(0, 1, 0)) * pose.local[size_t(hips)].rotation;
    poses.push_back(pose);
    out.add(pose);
  }
  auto reparsed = avatar::parseBvh(avatar::formatBvh(out.clip()), "exported.bvh");
  REQUIRE(reparsed);
  std::vector<glm::mat4> g;
  std::vector<avatar::BvhGlobal> read;
  const glm::dmat3 toFile = glm::transpose(a->mapping.toXr);
  for (int f = 0; f < 3; ++f) {
    avatar::computeGlobals(sk, poses[size_t(f)], g);
    avatar::bvhGlobals(*reparsed, reparsed->frame(size_t(f)), read);
    for (size_t j = 0; j < reparsed->joints.size(); ++j) {
      // The root is where the motion went (it carries the hips, as the clip's does).
      if (reparsed->joints[j].endSite || reparsed->joints[j].parent < 0) continue;
      const int s = sk.find(reparsed->joints[j].name);
      REQUIRE(s >= 0);
      const glm::dvec3 want = toFile * (glm::dvec3(g[size_t(s)][3]) - a->mapping.shift) / a->mapping.scale;
      INFO("frame " << f << " joint " << reparsed->joints[j].name);
      CHECK(glm::distance(read[j].position, want) < 1e-3);
    }
  }
}
