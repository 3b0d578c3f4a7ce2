// Seated mode (AvatarBodyOptions::seat, seated_pose.h): the lower body sits on a seat placed under
// the first tracked head, the spine and arms follow the head and hands. Measured on the built-in
// mannequin through TrackedAvatarBody (what `embody xr --seated` runs), in tracking metres.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <vector>

#include "avatar/avatar_asset.h"
#include "avatar/procedural/default_avatar.h"
#include "runtime/frame_stats.h"
#include "runtime/tracked_avatar_body.h"

using namespace embody;
using tracking::TrackerId;

namespace {

const avatar::AvatarAsset& mannequin() {
  static const avatar::AvatarAsset a = avatar::buildDefaultAvatar();
  return a;
}

constexpr float kSeatedEye = 1.20f;  // a 1.75 m user on a chair about 45 cm high
constexpr double kRad = 3.14159265358979323846 / 180.0;

// A seated user: eyes at `head` looking 15 degrees down, the hands in front of the chest
// (forearms forward, palms facing each other), moving with the head.
tracking::PoseSample seatedSample(const glm::vec3& head, double t, const glm::vec3& handShift = glm::vec3(0.0f)) {
  tracking::PoseSample s;
  s.time = t;
  const glm::quat left = tracking::gripOrientation(tracking::Side::Left, {0, 0, -1}, {1, 0, 0});
  const glm::quat right = tracking::gripOrientation(tracking::Side::Right, {0, 0, -1}, {-1, 0, 0});
  s[TrackerId::Head] = {head, glm::angleAxis(glm::radians(-15.0f), glm::vec3(1, 0, 0)), true};
  s[TrackerId::LeftHand] = {head + glm::vec3(-0.18f, -0.40f, -0.30f) + handShift, left, true};
  s[TrackerId::RightHand] = {head + glm::vec3(0.18f, -0.40f, -0.30f) + handShift, right, true};
  return s;
}

runtime::TrackedBodyOptions seatedOptions(float seatHeight = 0.0f) {
  runtime::TrackedBodyOptions o;
  o.body.trackers = tracking::TrackerMask::threePoint();
  o.body.seat.enabled = true;
  o.body.seat.seatHeight = seatHeight;
  o.body.userHeight = 1.75f;
  o.stage.budgetSeconds = 0.2;  // generous: the pose, not the timing, is under test
  o.stage.filter = false;
  return o;
}

struct Body {
  std::unique_ptr<runtime::TrackedAvatarBody> body;
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(mannequin().skeleton);
  bool solve(const tracking::PoseSample& s) { return body->solve(s, pose); }
  const runtime::AvatarBodySolver& solver() const { return body->solver(); }
  runtime::LowerBodyPosture posture() const { return solver().posture(); }
  glm::vec3 at(const Eigen::Vector3d& p) const { return body->toTracking(p); }
  double metres(float avatarMetres) const { return avatarMetres / solver().scale(); }
};

Body seatedBody(float seatHeight = 0.0f) {
  Body b;
  auto created = runtime::TrackedAvatarBody::create(mannequin(), seatedOptions(seatHeight));
  REQUIRE(created.ok());
  b.body = std::move(created).value();
  return b;
}

// The skinned mesh of the posed avatar (tracking space): its lowest point, and the lowest point
// of the vertices below the knees' height (the shins and feet).
struct MeshHeights {
  float lowest = 1e9f;
};
MeshHeights skinnedHeights(const Body& b) {
  std::vector<glm::mat4> globals, palette;
  avatar::computeGlobals(mannequin().skeleton, b.pose, globals);
  avatar::computeSkinningPalette(mannequin(), globals, palette);
  std::vector<glm::vec3> positions, normals;
  avatar::skinOnCpu(mannequin().mesh, palette, positions, normals);
  MeshHeights h;
  for (const auto& p : positions) h.lowest = std::min(h.lowest, p.y);
  return h;
}

double p95(std::vector<double> v) { return runtime::percentile(v, 95.0); }

}  // namespace

TEST_CASE("seated: the pelvis stays on the seat and the legs stay seated while the head moves ±20 cm",
          "[runtime]") {
  Body b = seatedBody();
  const glm::vec3 home(0.0f, kSeatedEye, 0.0f);
  double t = 0.0;
  for (int i = 0; i < 60; ++i, t += 1.0 / 90.0) REQUIRE(b.solve(seatedSample(home, t)));
  REQUIRE(b.solver().seat() != nullptr);
  const runtime::LowerBodyPosture start = b.posture();
  const glm::vec3 pelvis0 = b.at(start.pelvis);
  const glm::vec3 ankle0[2] = {b.at(start.ankle[0]), b.at(start.ankle[1])};
  const double seatHeight = b.metres(float(b.solver().seat()->seatHeight));
  INFO("seat height " << seatHeight << " m, pelvis " << pelvis0.x << " " << pelvis0.y << " " << pelvis0.z);
  // Upright on the seat: thighs level, shins down, the trunk over the pelvis.
  for (int s = 0; s < 2; ++s) {
    CHECK(start.kneeFlexion[size_t(s)] / kRad == Approx(90.0).margin(20.0));
    CHECK(start.hipFlexion[size_t(s)] / kRad == Approx(90.0).margin(20.0));
  }
  CHECK(seatHeight > 0.35);
  CHECK(seatHeight < 0.6);
  const MeshHeights rest = skinnedHeights(b);
  CHECK(rest.lowest == Approx(0.0).margin(0.01));  // the soles on the floor

  // 4 s at 90 Hz: the head sways ±20 cm sideways and leans up to 20 cm forward and back again.
  double pelvisDrift = 0.0, ankleDrift = 0.0, lowest = 1e9;
  double kneeMin = 1e9, kneeMax = -1e9, hipMin = 1e9, hipMax = -1e9;
  std::vector<double> head, hands;
  for (int i = 0; i < 360; ++i, t += 1.0 / 90.0) {
    const double phase = i / 360.0 * 2.0 * 3.14159265358979323846;
    const glm::vec3 h = home + glm::vec3(0.2f * float(std::sin(phase)), 0.0f, -0.1f * float(1.0 - std::cos(2.0 * phase)));
    REQUIRE(b.solve(seatedSample(h, t)));
    const runtime::LowerBodyPosture p = b.posture();
    pelvisDrift = std::max(pelvisDrift, double(glm::distance(b.at(p.pelvis), pelvis0)));
    for (int s = 0; s < 2; ++s) {
      ankleDrift = std::max(ankleDrift, double(glm::distance(b.at(p.ankle[size_t(s)]), ankle0[s])));
      kneeMin = std::min(kneeMin, p.kneeFlexion[size_t(s)] / kRad), kneeMax = std::max(kneeMax, p.kneeFlexion[size_t(s)] / kRad);
      hipMin = std::min(hipMin, p.hipFlexion[size_t(s)] / kRad), hipMax = std::max(hipMax, p.hipFlexion[size_t(s)] / kRad);
    }
    const auto& r = b.body->frame().stats.residual;
    head.push_back(b.metres(r[size_t(tracking::index(TrackerId::Head))]));
    hands.push_back(b.metres(std::max(r[size_t(tracking::index(TrackerId::LeftHand))], r[size_t(tracking::index(TrackerId::RightHand))])));
    if (i % 30 == 0) {
      const auto* seat = b.solver().seat();
      WARN("i " << i << " pitch " << p.pelvisPitch / kRad << " spine " << p.spineFlexion / kRad << " hipL drift "
                << (p.hip[0] - seat->hip[0]).norm() << " knee drift " << (p.knee[0] - seat->knee[0]).norm() << " ankle "
                << (p.ankle[0] - seat->ankle[0]).norm() << " head " << head.back() << " it " << b.body->frame().stats.iterations);
    }
    if (i % 45 == 0) lowest = std::min(lowest, double(skinnedHeights(b).lowest));
  }
  INFO("pelvis drift " << pelvisDrift << " ankle drift " << ankleDrift << " knee " << kneeMin << ".." << kneeMax
                       << " hip " << hipMin << ".." << hipMax << " head p95 " << p95(head) << " hands p95 "
                       << p95(hands) << " lowest " << lowest);
  CHECK(pelvisDrift < 0.01);
  CHECK(ankleDrift < 0.005);
  CHECK(kneeMin > 70.0);
  CHECK(kneeMax < 110.0);
  CHECK(hipMin > 70.0);
  CHECK(hipMax < 130.0);
  CHECK(lowest > -0.01);
  CHECK(p95(head) < 0.02);
  CHECK(p95(hands) < 0.02);
  CHECK(false);
}
