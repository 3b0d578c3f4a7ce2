// Fingers from XR_EXT_hand_tracking: the headless runtime's hand joints (curled by the trace's
// trigger) fed to avatar::FingerRetargetJob in-process, and `embody xr` driving the finger bones
// of an avatar exported with `embody avatar export-default --fingers`.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>
#include <string>

#include "avatar/hand/finger_retarget.h"
#include "avatar/procedural/default_avatar.h"
#include "headless_session.h"
#include "xr_test_support.h"

using namespace embody::test;
using namespace embody::avatar;

namespace {

constexpr float kRad = 57.29578f;

// Both controllers at chest height; the right trigger held at `trigger`.
std::string triggerTrace(const std::string& name, float trigger) {
  const std::string t = std::to_string(trigger);
  return writeTraceFile(
      name,
      {R"({"t":0,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.1,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":)" +
           t + "}}",
       R"({"t":100,"head":{"p":[0,1.7,0],"q":[0,0,0,1]},"left":{"p":[-0.2,1.1,-0.3],"q":[0,0,0,1]},"right":{"p":[0.2,1.1,-0.3],"q":[0,0,0,1],"trigger":)" +
           t + "}}"});
}

TrackedHandJoints locate(HeadlessSession& h, XrHandEXT hand) {
  std::array<XrHandJointLocationEXT, XR_HAND_JOINT_COUNT_EXT> joints{};
  const bool active = h.locateHand(hand, h.lastDisplayTime, joints);
  TrackedHandJoints t;
  t.active = active;
  constexpr XrSpaceLocationFlags kValid =
      XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  for (size_t j = 0; j < joints.size(); ++j) {
    const auto& p = joints[j].pose;
    t.position[j] = {p.position.x, p.position.y, p.position.z};
    t.orientation[j] = glm::quat(p.orientation.w, p.orientation.x, p.orientation.y, p.orientation.z);
    t.valid[j] = (joints[j].locationFlags & kValid) == kValid;
  }
  return t;
}

}  // namespace

TEST_CASE("the headless runtime's curled hand bends the avatar's finger bones by the same angles", "[xr]") {
  const float trigger = GENERATE(0.0f, 0.75f);
  const float bend = 12.0f + 60.0f * trigger;  // the runtime's curl per finger joint (poses.cpp)
  HeadlessSession h({{"EMBODY_XR_POSES", triggerTrace("finger_curl", trigger)}});
  h.runUntilFocused();
  const TrackedHandJoints right = locate(h, XR_HAND_RIGHT_EXT);
  REQUIRE(right.active);
  // Every joint's +Y stays on the back of its finger, also past 90 degrees of curl: the twist the
  // retargeting reads from it is small.
  for (int f = 1; f < kFingerCount; ++f)
    for (int k = 0; k < 3; ++k) {
      const int j = static_cast<int>(HandJoint::IndexProximal) + (f - 1) * 5 + k;
      const glm::vec3 lateral = right.orientation[size_t(j)] * glm::vec3(1, 0, 0);
      const glm::vec3 palmLateral = right.orientation[size_t(HandJoint::Palm)] * glm::vec3(1, 0, 0);
      CHECK(glm::dot(lateral, palmLateral) > 0.95f);
    }

  static const AvatarAsset a = buildDefaultAvatar(DefaultAvatarOptions{.fingers = true});
  const FingerRig rig = buildFingerRig(a.skeleton, a.humanoid);
  REQUIRE(rig.mappedBones() == 30);
  FingerRetargetState state;
  FingerRetargetOutput out;
  SkeletonPose pose = SkeletonPose::rest(a.skeleton);
  FingerRetargetJob job;
  job.skeleton = &a.skeleton;
  job.rig = &rig;
  job.hands = {nullptr, &right};
  job.deltaTime = 1.0f;
  job.state = &state;
  job.pose = &pose;
  job.output = &out;
  REQUIRE(job.Validate());
  REQUIRE(job.Run());
  CHECK(out.handTracked[1]);
  for (int f = 1; f < kFingerCount; ++f)
    for (int s = 0; s < kFingerSegments; ++s) {
      INFO("finger " << f << " segment " << s);
      // The knuckle's angle also holds the small difference between the two hands' shapes (their
      // knuckle lines differ by about 0.3 degrees); the finger's own joints match exactly.
      CHECK(out.bend[1][size_t(f * 3 + s)] * kRad == Approx(bend).margin(s == 0 ? 0.5 : 0.05));
    }
  // The left hand is not driven (no joints given): its fingers stay at rest.
  for (float b : out.bend[0]) CHECK(b == 0.0f);
}

TEST_CASE("embody xr drives the finger bones of an avatar with fingers from hand tracking", "[xr]") {
  const std::string dir = freshTestDir("fingers");
  const std::string glb = dir + "/fingers.glb";
  const auto exported = runProcess({embodyBin(), "avatar", "export-default", "--fingers", glb}, {}, 60);
  INFO(exported.output);
  REQUIRE(exported.exitCode == 0);
  // Looping traces (the runtime replays a trace in a loop) whose triggers alternate between
  // released (a relaxed hand) and squeezed (a fist), so every phase comes round whenever the
  // session's first frame does (start-up time varies).
  // `steady`: a 1 s loop, released 0.4 s, squeezed within 0.1 s, held 0.4 s, released.
  // `lossy`: a 2 s loop whose first 0.5 s have both hands lost (invalid), then released 0.5 s,
  // squeezed within 0.1 s, held 0.8 s, released.
  auto writeLoop = [&](const std::string& name, double period, double lostUntil, double squeezeAt) {
    const std::string path = dir + "/" + name + ".jsonl";
    std::ofstream out(path);
    for (int i = 0; i <= int(std::lround(period / 0.05)); ++i) {
      const double t = 0.05 * i;
      const double squeeze = std::clamp(std::min((t - squeezeAt) / 0.1, (period - t) / 0.1), 0.0, 1.0);
      const bool valid = t >= lostUntil;
      auto hand = [&](double x) {
        return nlohmann::json{
            {"p", {x, 1.3, -0.38}}, {"q", {0, 0, 0, 1}}, {"trigger", squeeze}, {"valid", valid}};
      };
      out << nlohmann::json{{"t", t},
                            {"head", {{"p", {0, 1.6, 0}}, {"q", {0, 0, 0, 1}}}},
                            {"left", hand(-0.16)},
                            {"right", hand(0.16)}}
                 .dump()
          << "\n";
    }
    return path;
  };
  const std::string steady = writeLoop("steady", 1.0, 0.0, 0.4);
  const std::string lossy = writeLoop("lossy", 2.0, 0.5, 1.0);
  auto env = headlessRuntimeEnv();
  env["EMBODY_XR_VIEW_SIZE"] = "256x280";
  // As the other embody xr tests, with the capture on: without it, `embody xr --validate --frames 30`
  // crashes inside a lavapipe thread on this machine (on main too; not a finger matter).
  env["EMBODY_XR_CAPTURE"] = dir + "/capture";
  auto run = [&](const std::string& avatar, const std::string& trace, int frames, const std::string& name) {
    const std::string stats = dir + "/" + name + ".json";
    env["EMBODY_XR_POSES"] = trace;
    const auto p = runProcess({embodyBin(), "xr", "--validate", "--avatar", avatar, "--frames",
                               std::to_string(frames), "--ik-budget-ms", "5", "--stats", stats},
                              env, 90);
    INFO(p.output.substr(p.output.size() > 3000 ? p.output.size() - 3000 : 0));
    REQUIRE_FALSE(p.timedOut);
    REQUIRE(p.exitCode == 0);
    std::ifstream in(stats);
    return nlohmann::json::parse(in, nullptr, false);
  };
  const auto s = run(glb, steady, 150, "with_fingers");
  REQUIRE(s.is_object());
  CHECK(s["hand_tracking"] == true);
  CHECK(s["vulkan_validation_messages"] == 0);
  CHECK(s["tracking"]["non_finite_frames"] == 0);
  const auto& f = s["fingers"];
  CHECK(f["driven_bones"] == 30);
  CHECK(f["frames"].get<int>() >= 145);  // every rendered frame after the first
  CHECK(f["full_frames"].get<int>() >= 130);
  // The runtime's relaxed hand bends each finger joint 12 degrees, its fist 72: the avatar's
  // finger bones follow to within a few degrees (the mean over index..little, both hands).
  CHECK(f["curl_min_deg"].get<double>() == Approx(12.0).margin(3.0));
  CHECK(f["curl_max_deg"].get<double>() == Approx(72.0).margin(3.0));

  // Hands lost for a quarter of each loop: the fingers blend back to rest (0.15 s) and stay there
  // while the hands are gone, then follow the relaxed hand and the fist again; nothing turns NaN.
  const auto l = run(glb, lossy, 250, "with_loss");
  REQUIRE(l.is_object());
  CHECK(l["vulkan_validation_messages"] == 0);
  CHECK(l["tracking"]["non_finite_frames"] == 0);
  CHECK(l["hand_lost_frames"][1].get<int>() >= 30);
  const auto& lf = l["fingers"];
  CHECK(lf["frames"].get<int>() <= 250 - 15);  // at rest (weight 0) for part of every loss
  CHECK(lf["full_frames"].get<int>() >= 100);
  CHECK(lf["curl_min_deg"].get<double>() == Approx(12.0).margin(3.0));
  CHECK(lf["curl_max_deg"].get<double>() == Approx(72.0).margin(3.0));

  // The control: the default mannequin has no finger bones, nothing is driven.
  const auto d = run("default", steady, 30, "default");
  REQUIRE(d.is_object());
  CHECK(d["fingers"]["driven_bones"] == 0);
  CHECK(d["fingers"]["frames"] == 0);
}
