// The runtime on real avatars, CPU only: pose source -> filter -> loss guard -> budgeted PIK on
// the avatar's body model -> retargeted skeleton. BVH walk with every tracker (default avatar and
// CesiumMan), three-point mode with procedural stepping, tracking loss, and the deadline with an
// injected clock.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>

#include "avatar/gltf/gltf_loader.h"
#include "runtime/avatar_body_solver.h"
#include "runtime/ik_stage.h"
#include "test_paths.h"
#include "tracking/pose_source.h"
#include "tracking/synthetic_source.h"
#include "runtime/runtime_test_support.h"

using namespace embody;
using namespace embody::runtime;
using tracking::TrackerId;

namespace {

// Per frame: far more than the solver needs here (tens of ms at worst on a loaded machine), so any
// deadline miss is a real one. Under ThreadSanitizer (`make tsan` runs this suite) one iteration
// took up to 40 ms on the loaded 2-core machine (ik p50 0.95 s for ~24 iterations): 10 s there.
#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
constexpr double kGenerousBudget = 10.0;
#else
constexpr double kGenerousBudget = 1.0;
#endif

using embody::test::defaultAvatar;
using embody::test::openSource;

struct FootTrace {
  std::vector<Eigen::Vector3d> position[2];  // the avatar's ankles, per frame
  std::vector<Eigen::Isometry3d> ankle[2];   // the avatar's ankle frames, per frame
  std::vector<Eigen::Vector3d> ball[2];      // the planner's ball of the foot, per frame
  std::vector<char> planted[2];              // the planner's state, per frame
};

struct Run {
  StatsSummary summary;
  FootTrace feet;
  size_t nonFinitePoses = 0;
  int steps = 0;
  double up = 0.0;
};

// Drives `frames` frames at `fps` from `source` through an IkStage on the real solver.
Run drive(const avatar::AvatarAsset& avatar, tracking::PoseSource& source, const AvatarBodyOptions& options, int frames,
          double fps, double budgetSeconds,
          const std::function<void(tracking::PoseSample&)>& edit = {},
          const std::function<void(const AvatarBodySolver&, const SolvedFrame&)>& check = {}) {
  auto solver = AvatarBodySolver::create(avatar, options);
  REQUIRE(solver.ok());
  const Clock& clock = steadyClock();
  IkStageConfig cfg;
  cfg.budgetSeconds = budgetSeconds;
  cfg.guard.userHeight = options.userHeight > 0.0f ? options.userHeight : 1.75f;
  IkStage stage(**solver, clock, cfg);
  SolvedFrame frame;
  frame.pose = avatar::SkeletonPose::rest(avatar.skeleton);
  StatsRecorder rec;
  Run run;
  const AvatarBodySolver& s = **solver;
  for (int i = 0; i < frames; ++i) {
    tracking::PoseSample sample = source.sample(i / fps);
    if (edit) edit(sample);
    rec.add(stage.process(sample, frame));
    for (const auto& t : frame.pose.local)
      if (!std::isfinite(t.translation.x + t.translation.y + t.translation.z + t.rotation.w + t.rotation.x + t.rotation.y +
                         t.rotation.z))
        ++run.nonFinitePoses;
    for (int f = 0; f < 2; ++f) {
      const TrackerId id = f == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot;
      run.feet.position[f].push_back(s.jointPosition(s.trackerJoint(id)));
      run.feet.ankle[f].push_back(s.jointFrame(s.trackerJoint(id)));
      run.feet.ball[f].push_back(s.feet().ballPoint(f));
      run.feet.planted[f].push_back(s.feet().feet()[size_t(f)].planted ? 1 : 0);
    }
    if (check) check(s, frame);
  }
  run.summary = rec.summary();
  run.steps = s.feet().steps();
  return run;
}

void checkFullBodyWalk(const avatar::AvatarAsset& avatar, double headLimit = 0.01) {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  auto src = openSource(bvh);
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  const int frames = int(src->duration() * 60.0);
  const Run r = drive(avatar, *src, o, frames, 60.0, kGenerousBudget);
  INFO("head p95 " << r.summary.headErrorP95 << " hand p95 " << r.summary.handErrorP95 << " misses "
                   << r.summary.deadlineMisses << " ik p50 " << r.summary.ikP50Ms << " ms, iterations "
                   << r.summary.iterationsMean);
  CHECK(r.summary.frames == size_t(frames));
  CHECK(r.nonFinitePoses == 0);
  CHECK(r.summary.nonFiniteFrames == 0);
  CHECK(r.summary.headErrorP95 >= 0.0);
  CHECK(r.summary.headErrorP95 <= headLimit);
  CHECK(r.summary.handErrorP95 >= 0.0);
  CHECK(r.summary.handErrorP95 <= 0.02);
  CHECK(r.summary.deadlineMisses == 0);
  // The first live solve settled outside the budget, and is reported as the start-up.
  CHECK(r.summary.startupMs > 0.0);
  CHECK(r.summary.startupIterations > 1);
}

}  // namespace

TEST_CASE("BVH walk, every tracker, default avatar: head within 1 cm, hands within 2 cm (p95), no NaN, no misses") {
  checkFullBodyWalk(defaultAvatar());
}

// Was [!mayfail] (head p95 ~4.4 cm: the head could not be reached with the feet first); passes
// since the per-level trust region and the head orientation one level below the eye position.
TEST_CASE("BVH walk, every tracker, CesiumMan: head within 1.2 cm, hands within 2 cm (p95), no NaN, no misses") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "CesiumMan.glb");
  auto a = avatar::loadAvatarFile(path);
  REQUIRE(a.ok());
  // 1.2 cm: since knees may no longer bend backwards (body_model.h), the walk's longest strides
  // leave CesiumMan's head up to ~1 cm short (10.2-10.4 mm p95; it was just under 10 mm).
  checkFullBodyWalk(a.value(), 0.012);
}

TEST_CASE("three-point walk: the avatar steps foot by foot, planted feet do not slide, head within 1 cm") {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  auto src = openSource(bvh, tracking::TrackerMask::threePoint());
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  o.trackers = tracking::TrackerMask::threePoint();
  const int frames = int(src->duration() * 60.0);
  int recoveries = 0;
  const Run r = drive(defaultAvatar(), *src, o, frames, 60.0, kGenerousBudget, {},
                      [&](const AvatarBodySolver& s, const SolvedFrame&) { recoveries = s.collapseGuard().recoveries(); });
  INFO("head p95 " << r.summary.headErrorP95 << " hand p95 " << r.summary.handErrorP95 << " steps " << r.steps);
  CHECK(r.nonFinitePoses == 0);
  CHECK(r.summary.headErrorP95 <= 0.01);
  // A walk is no collapse: stepping feet pass each other along the stride, never across it.
  CHECK(recoveries == 0);
  // Lift-offs (planted -> swinging), in order, and the ankle's rise above its planted height.
  // A planted foot's heel rises as the body passes over it (foot_planner.h): what must not slide
  // is the ball of the foot, the point the planner turns it about, carried in the solved ankle's
  // frame from the first planted frame on.
  std::vector<int> liftOffs;
  double worstSlide = 0.0, maxRise[2] = {0.0, 0.0}, heelRise = 0.0;
  for (int f = 0; f < 2; ++f) {
    const auto& pos = r.feet.position[f];
    const auto& planted = r.feet.planted[f];
    size_t plantStart = 0;
    Eigen::Vector3d ballInAnkle = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < pos.size(); ++i) {
      if (i > 0 && planted[i - 1] && !planted[i]) liftOffs.push_back(int(i) * 2 + f);
      if (planted[i] && (i == 0 || !planted[i - 1])) plantStart = i;
      if (planted[i] && i == plantStart + 1) ballInAnkle = r.feet.ankle[f][i].inverse() * r.feet.ball[f][i];
      if (planted[i] && i > plantStart + 1) {
        worstSlide = std::max(worstSlide, (r.feet.ankle[f][i] * ballInAnkle - r.feet.ball[f][plantStart + 1]).norm());
        heelRise = std::max(heelRise, pos[i].y() - pos[plantStart + 1].y());
      }
      if (!planted[i] && plantStart < pos.size()) maxRise[f] = std::max(maxRise[f], pos[i].y() - pos[plantStart].y());
    }
  }
  std::sort(liftOffs.begin(), liftOffs.end());
  int left = 0, right = 0, repeats = 0;
  for (size_t k = 0; k < liftOffs.size(); ++k) {
    (liftOffs[k] % 2 == 0 ? left : right)++;
    if (k > 0 && liftOffs[k] % 2 == liftOffs[k - 1] % 2) ++repeats;
  }
  INFO("lift-offs: left " << left << ", right " << right << ", same foot twice in a row " << repeats << ", worst slide "
                          << worstSlide << " m (ball of the foot), rise " << maxRise[0] << " / " << maxRise[1]
                          << ", planted ankles up to " << heelRise << " m up");
  CHECK(left >= 2);
  CHECK(right >= 2);
  CHECK(repeats <= (left + right) / 4);  // mostly alternating
  CHECK(maxRise[0] > 0.02);              // the feet really leave the ground
  CHECK(maxRise[1] > 0.02);
  CHECK(worstSlide < 0.02);
}

TEST_CASE("three-point standing still: the feet stay planted") {
  auto src = openSource("synthetic:idle", tracking::TrackerMask::threePoint());
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  o.trackers = tracking::TrackerMask::threePoint();
  const Run r = drive(defaultAvatar(), *src, o, 180, 60.0, kGenerousBudget);
  CHECK(r.steps == 0);
  CHECK(r.nonFinitePoses == 0);
  CHECK(r.summary.headErrorP95 <= 0.01);
}

TEST_CASE("three-point jump: a head above what straight legs reach lifts both feet, and they land again") {
  // Standing idle; between 1 and 2 s the head and hands rise 15 cm and come down (a smooth bump,
  // 0.3 m/s at most). Straight legs under the hips reach a few cm above the rest pose's eyes: the
  // rest must come from the feet leaving the floor, or the eyes stay below the HMD.
  auto src = openSource("synthetic:idle", tracking::TrackerMask::threePoint());
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  o.trackers = tracking::TrackerMask::threePoint();
  auto rise = [](double t) { return t > 1.0 && t < 2.0 ? 0.15 * std::pow(std::sin(M_PI * (t - 1.0)), 2.0) : 0.0; };
  int frame = 0;
  std::array<double, 2> standing{}, highest{}, landed{};
  double eyeErrorAtTop = 1.0;
  const Run r = drive(defaultAvatar(), *src, o, 240, 60.0, kGenerousBudget,
                      [&](tracking::PoseSample& s) {
                        const float dy = float(rise(frame++ / 60.0));
                        for (auto id : {TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand}) s[id].position.y += dy;
                      },
                      [&](const AvatarBodySolver& s, const SolvedFrame&) {
                        const int f = frame - 1;
                        for (int k = 0; k < 2; ++k) {
                          const double y = s.jointPosition(s.trackerJoint(k == 0 ? TrackerId::LeftFoot : TrackerId::RightFoot)).y();
                          if (f == 59) standing[size_t(k)] = y;
                          if (f == 90) highest[size_t(k)] = y;
                          if (f == 239) landed[size_t(k)] = y;
                        }
                        if (f == 90) eyeErrorAtTop = (s.eyePosition() - s.target(TrackerId::Head)).norm();
                      });
  CHECK(r.nonFinitePoses == 0);
  INFO("ankles standing " << standing[0] << ", " << standing[1] << " at the top " << highest[0] << ", " << highest[1]
                          << " landed " << landed[0] << ", " << landed[1] << " eye error at the top " << eyeErrorAtTop);
  for (size_t k = 0; k < 2; ++k) {
    CHECK(highest[k] - standing[k] > 0.08);             // 15 cm less the legs' straightening
    CHECK(std::abs(landed[k] - standing[k]) < 0.005);   // back on the floor
  }
  CHECK(eyeErrorAtTop < 0.02);
}

TEST_CASE("three-point turning on the spot: the body steps round with the head, never re-seeded, head and hands on target") {
  // Standing idle, the head and hands turned about the vertical through the head: half a turn in
  // 0.6 s (looking behind), back, then a full turn the other way in 2 s. The feet must step round
  // (the legs would otherwise cross, or twist past the hips' range), the pelvis and trunk follow
  // the head. A pirouette (two turns in 1.2 s) still crosses the legs and is re-seeded once
  // (docs/eval.md, "Session 13").
  auto src = openSource("synthetic:idle", tracking::TrackerMask::threePoint());
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  o.trackers = tracking::TrackerMask::threePoint();
  auto smooth = [](double x) {
    x = std::clamp(x, 0.0, 1.0);
    return x * x * (3.0 - 2.0 * x);
  };
  auto yaw = [&](double t) {
    if (t < 2.6) return M_PI * smooth((t - 1.0) / 0.6);
    if (t < 4.0) return M_PI * (1.0 - smooth((t - 2.6) / 0.6));
    return -2.0 * M_PI * smooth((t - 4.0) / 2.0);
  };
  const double fps = 90.0;
  glm::vec3 pivot(0.0f);
  int recoveries = 0;
  const Run r = drive(
      defaultAvatar(), *src, o, int(7.0 * fps), fps, kGenerousBudget,
      [&](tracking::PoseSample& s) {
        if (s.time == 0.0) pivot = glm::vec3(s[TrackerId::Head].position.x, 0.0f, s[TrackerId::Head].position.z);
        const glm::quat turn = glm::angleAxis(float(yaw(s.time)), glm::vec3(0, 1, 0));
        for (auto id : {TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand}) {
          s[id].position = pivot + turn * (s[id].position - pivot);
          s[id].orientation = turn * s[id].orientation;
        }
      },
      [&](const AvatarBodySolver& s, const SolvedFrame&) { recoveries = s.collapseGuard().recoveries(); });
  const size_t head = size_t(tracking::index(TrackerId::Head));
  INFO("steps " << r.steps << ", re-seeds " << recoveries << ", head p95 " << r.summary.headErrorP95 << " m, hands p95 "
                << r.summary.handErrorP95 << " m, head turned off the headset's " << r.summary.turnResidualP95Deg[head]
                << " degrees p95, hand targets out of reach " << r.summary.handFramesOutOfReach << " frames");
  CHECK(r.nonFinitePoses == 0);
  CHECK(recoveries == 0);
  CHECK(r.steps >= 6);
  CHECK(r.summary.headErrorP95 <= 0.005);
  CHECK(r.summary.handErrorP95 <= 0.005);
  CHECK(r.summary.handFramesOutOfReach == 0);
  CHECK(r.summary.turnResidualP95Deg[head] < 5.0);
}

TEST_CASE("hands lost for 1 s: within arm's reach of the shoulder every frame, at most 3 m/s when tracking returns") {
  auto src = openSource("synthetic:figure8");
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  const double fps = 90.0;
  std::vector<Eigen::Vector3d> hands[2];
  double worstReach = 0.0;
  const Run r = drive(
      defaultAvatar(), *src, o, int(4.0 * fps), fps, kGenerousBudget,
      [](tracking::PoseSample& s) {
        if (s.time >= 1.5 && s.time < 2.5) {
          s[TrackerId::LeftHand].valid = false;
          s[TrackerId::RightHand].position = glm::vec3(NAN);  // broken data counts as lost too
        }
      },
      [&](const AvatarBodySolver& s, const SolvedFrame&) {
        for (int f = 0; f < 2; ++f) {
          const auto side = f == 0 ? tracking::Side::Left : tracking::Side::Right;
          const TrackerId id = f == 0 ? TrackerId::LeftHand : TrackerId::RightHand;
          const Eigen::Vector3d hand = s.jointPosition(s.trackerJoint(id));
          hands[f].push_back(hand);
          worstReach = std::max(worstReach, (hand - s.jointPosition(s.shoulderJoint(side))).norm() / s.armReach());
          // The target itself stays within reach of the solved shoulder too (a margin for the
          // shoulder the guard estimates from the head).
          CHECK((s.target(id) - s.jointPosition(s.shoulderJoint(side))).norm() <= 1.1 * s.armReach());
        }
      });
  CHECK(r.nonFinitePoses == 0);
  CHECK(worstReach <= 1.0 + 1e-6);
  // Speed of each hand from the moment tracking returns (t = 2.5 s) for one second.
  double worstSpeed = 0.0;
  for (int f = 0; f < 2; ++f)
    for (size_t i = size_t(2.5 * fps) + 1; i < size_t(3.5 * fps); ++i)
      worstSpeed = std::max(worstSpeed, (hands[f][i] - hands[f][i - 1]).norm() * fps);
  INFO("worst hand speed after recovery " << worstSpeed << " m/s");
  CHECK(worstSpeed <= 3.0);
}

namespace {
// A clock that moves forward by `tick` seconds every time it is read: a solver's every step costs
// time, deterministically.
class TickingClock final : public Clock {
 public:
  explicit TickingClock(double tick) : tick_(fromSeconds(tick)) {}
  time_point now() const override { return t_ += tick_; }

 private:
  Duration tick_;
  mutable time_point t_{};
};
}  // namespace

TEST_CASE("the avatar solver given a deadline returns by the deadline plus at most one iteration") {
  auto src = openSource("synthetic:reach");
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  auto solver = AvatarBodySolver::create(defaultAvatar(), o);
  REQUIRE(solver.ok());
  tracking::TrackingGuard guard;
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(defaultAvatar().skeleton);
  TickingClock clock(50e-6);
  int iterations = 0;
  for (int i = 0; i < 20; ++i) {
    const tracking::GuardedSample& g = guard.update(src->sample(i / 90.0));
    const TimePoint start = clock.now();
    SolveRequest req;
    req.targets = &g;
    req.clock = &clock;
    req.deadline = start + fromSeconds(1e-3);
    const SolveResult r = (*solver)->solve(req, pose);
    const TimePoint end = clock.now();
    // One solver iteration reads this clock four times (twice in AvatarBodySolver's loop, twice
    // in ik::solve), so it costs four ticks: the solve may end past the deadline by at most that
    // plus the test's own read. (Before the pelvis row, every solve here converged well before
    // the deadline, so this bound was never reached.)
    iterations += r.iterations;
    CHECK(end <= req.deadline + fromSeconds(5 * 50e-6));
  }
  CHECK(iterations > 0);
}

// Figures for docs/runtime.md (hidden: `embody_tests_runtime "[.figures]" -s`): the CMU walk on
// the default avatar, spine and rows switched one at a time.
TEST_CASE("figures: CMU walk, coupled and uncoupled spine, pelvis and balance rows", "[.figures]") {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  for (int mode = 0; mode < 6; ++mode) {
    const bool three = mode >= 4;
    auto src = openSource(bvh, three ? tracking::TrackerMask::threePoint() : tracking::TrackerMask::all());
    AvatarBodyOptions o;
    o.userHeight = 1.75f;
    o.coupledSpine = mode % 2 == 0;
    o.pelvisRow = mode < 2;
    o.balanceRow = true;
    const int frames = int(src->duration() * 60.0);
    const Run r = drive(defaultAvatar(), *src, o, frames, 60.0, kGenerousBudget);
    WARN((three ? "three-point, balance row" : "all trackers") << (o.coupledSpine ? ", coupled" : ", uncoupled")
                                                  << (three ? "" : o.pelvisRow ? ", pelvis row" : ", no pelvis row") << ": head p95 "
                                                  << r.summary.headErrorP95 * 1000 << " mm, hand p95 "
                                                  << r.summary.handErrorP95 * 1000 << " mm, iterations "
                                                  << r.summary.iterationsMean << ", ik p50 " << r.summary.ikP50Ms
                                                  << " ms, p99 " << r.summary.ikP99Ms << " ms, non-finite "
                                                  << r.nonFinitePoses);
  }
}

#include "avatar/avatar_loader.h"
#include "avatar/humanoid_test_files.h"

namespace {

// Solves `frames` frames of synthetic:reach on `avatar`; every solved pose's globals finite.
void solveFinite(const avatar::AvatarAsset& avatar, int frames) {
  AvatarBodyOptions o;
  o.userHeight = 1.75f;
  auto solver = AvatarBodySolver::create(avatar, o);
  REQUIRE(solver.ok());
  auto src = openSource("synthetic:reach");
  tracking::TrackingGuard guard;
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(avatar.skeleton);
  std::vector<glm::mat4> globals;
  ManualClock clock;
  for (int i = 0; i < frames; ++i) {
    SolveRequest req;
    req.targets = &guard.update(src->sample(i / 10.0));
    req.clock = &clock;
    (*solver)->solve(req, pose);
    REQUIRE(std::isfinite((*solver)->scale()));
    REQUIRE((*solver)->scale() > 0.0);
    avatar::computeGlobals(avatar.skeleton, pose, globals);
    for (const auto& m : globals)
      for (int c = 0; c < 4; ++c)
        for (int k = 0; k < 4; ++k) REQUIRE(std::isfinite(m[c][k]));
  }
}

}  // namespace

TEST_CASE("the body solver refuses an avatar in the wrong units or of no size and drives 0.3x to 3x ones",
          "[runtime][avatar-size]") {
  auto scaled = [](float s) {
    avatar::AvatarAsset a = defaultAvatar();
    a.skeleton.joints[0].rest.scale *= s;
    return a;
  };
  for (float s : {0.3f, 3.0f}) {
    INFO("scale " << s);
    solveFinite(scaled(s), 5);
  }
  auto cm = AvatarBodySolver::create(scaled(100.0f));
  REQUIRE_FALSE(cm.ok());
  CHECK_THAT(cm.error(), Catch::Contains("the avatar is 175.5 m tall") && Catch::Contains("centimetres"));
  auto tiny = AvatarBodySolver::create(scaled(0.01f));
  REQUIRE_FALSE(tiny.ok());
  CHECK_THAT(tiny.error(), Catch::Contains("0.01755 m tall") && Catch::Contains("100 times too small"));
  avatar::AvatarAsset flat = defaultAvatar();  // every vertex at the origin: once a negative scale
  for (auto& v : flat.mesh.vertices) v.position = glm::vec3(0.0f);
  auto none = AvatarBodySolver::create(flat);
  REQUIRE_FALSE(none.ok());
  CHECK_THAT(none.error(), Catch::Contains("cannot measure the avatar's height"));
}

TEST_CASE("the body solver drives a glTF avatar whose left forearm is hidden by a zero scale", "[runtime][gltf]") {
  test::HumanoidFile f;
  f.doc["nodes"][size_t(f.nodeOfBone["leftLowerArm"])]["scale"] = {0, 0, 0};
  auto a = test::loadPrepared(f);
  REQUIRE(a.ok());
  solveFinite(*a, 5);
}

TEST_CASE("the body solver drives a glTF avatar whose bones are all named Bone", "[runtime][gltf]") {
  // The spine sites, IK joints and marker tasks take the joint index (avatar::uniqueJointNames).
  std::map<std::string, std::string> names;
  for (const auto& s : test::humanoidJointSpecs()) names[s.bone] = "Bone";
  test::HumanoidFile f(names);
  auto a = test::loadPrepared(f);
  REQUIRE(a.ok());
  solveFinite(*a, 5);
}
