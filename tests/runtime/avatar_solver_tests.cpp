// The runtime on the real avatar body model: the default avatar calibrated to 1.75 m, trackers
// bound to its tasks on the rest pose, synthetic motions and the CMU walk through IkStage.
#include <catch2/catch.hpp>

#include "avatar/body/calibration.h"
#include "avatar/procedural/default_avatar.h"
#include "runtime/avatar_solver.h"
#include "runtime/ik_stage.h"
#include "test_paths.h"
#include "xr/tracking/bvh_source.h"
#include "xr/tracking/synthetic_source.h"

using namespace embody;
using namespace embody::runtime;
using tracking::TrackerId;

namespace {

struct Avatar {
  std::shared_ptr<const avatar::AvatarAsset> asset;
  std::shared_ptr<const avatar::BodyModel> body;

  Avatar() {
    auto a = std::make_shared<avatar::AvatarAsset>(avatar::buildDefaultAvatar());
    avatar::CalibrationInput in;
    in.userHeight = 1.75;
    auto profile = avatar::calibrate(*a, in);
    REQUIRE(profile.ok());
    avatar::BodyModelOptions opts;
    opts.scale = profile->scale;
    auto b = avatar::buildBodyModel(*a, opts);
    REQUIRE(b.ok());
    asset = a;
    body = std::make_shared<const avatar::BodyModel>(std::move(*b));
  }
};

size_t at(TrackerId id) { return static_cast<size_t>(tracking::index(id)); }

// Runs a source through the stage at `fps` for `seconds`; returns the per-frame stats.
std::vector<FrameStats> run(IkStage& stage, tracking::PoseSource& src, double fps, double seconds,
                            avatar::SkeletonPose& lastPose) {
  SolvedFrame frame;
  std::vector<FrameStats> out;
  for (int i = 0; i < static_cast<int>(seconds * fps); ++i) {
    out.push_back(stage.process(src.sample(i / fps), frame));
    for (const auto& t : frame.pose.local) {
      REQUIRE(std::isfinite(t.translation.x));
      REQUIRE(std::isfinite(t.rotation.w));
    }
  }
  lastPose = frame.pose;
  return out;
}

double p95(const std::vector<FrameStats>& frames, TrackerId id) {
  std::vector<double> v;
  for (const auto& f : frames)
    if (f.residual[at(id)] >= 0.0f) v.push_back(f.residual[at(id)]);
  return percentile(v, 95);
}

}  // namespace

TEST_CASE("the avatar binding reproduces the rest pose from the rest trackers") {
  Avatar av;
  auto binding = bindBodyModel(*av.body, *av.asset);
  REQUIRE(binding.ok());
  CHECK(binding->height == Approx(1.75).margin(0.01));
  const auto& rest = binding->rest;
  CHECK(rest[TrackerId::Head].position.y == Approx(tracking::kEyeHeightRatio * 1.75f).margin(1e-3));
  CHECK(rest[TrackerId::LeftHand].position.x < -0.1f);  // the avatar's left is OpenXR's -X
  CHECK(rest[TrackerId::LeftFoot].position.y < 0.15f);
  auto solver = makeAvatarSolver(av.body, av.asset);
  REQUIRE(solver.ok());
  ManualClock clock;
  IkStageConfig cfg;
  cfg.filter = false;
  IkStage stage(**solver, clock, cfg);
  SolvedFrame frame;
  frame.pose = avatar::SkeletonPose::rest(av.asset->skeleton);
  tracking::PoseSample s = rest;
  stage.process(s, frame);
  for (auto id : {TrackerId::Head, TrackerId::LeftHand, TrackerId::RightHand, TrackerId::LeftFoot, TrackerId::RightFoot})
    CHECK(frame.stats.residual[at(id)] < 1e-4f);
  CHECK((*solver)->data().q().cwiseAbs().maxCoeff() < 1e-6);  // nothing moved
  CHECK(frame.pose.local.size() == av.asset->skeleton.joints.size());
}

TEST_CASE("synthetic motions drive the default avatar: head and hands on target") {
  Avatar av;
  ik::SolveOptions opts;
  opts.max_iterations = 30;
  // squat is not asserted: at the deepest point the straight-legged rest pose leaves the solver
  // stalled (head 0.2 m off; docs/runtime.md).
  for (const char* motion : {"idle", "reach", "look", "bow", "figure8"}) {
    INFO(motion);
    auto solver = makeAvatarSolver(av.body, av.asset, opts);
    REQUIRE(solver.ok());
    ManualClock clock;  // deterministic: the iteration cap, not the wall clock, ends each solve
    IkStage stage(**solver, clock, {});
    auto src = tracking::SyntheticSource::create(motion, 1.75f).value();
    avatar::SkeletonPose pose;
    const auto frames = run(stage, *src, 30.0, src->duration(), pose);
    const double head = p95(frames, TrackerId::Head), left = p95(frames, TrackerId::LeftHand),
                 right = p95(frames, TrackerId::RightHand), foot = p95(frames, TrackerId::LeftFoot);
    INFO(motion << ": residual p95 head " << head * 1e3 << " mm, hands " << left * 1e3 << " / " << right * 1e3
                << " mm, left foot " << foot * 1e3 << " mm");
    CHECK(head < 0.01);
    CHECK(left < 0.03);
    CHECK(right < 0.03);
    CHECK(foot < 0.005);
  }
}

TEST_CASE("the CMU walk drives the default avatar with every tracker") {
  EMBODY_REQUIRE_SHARED_ASSET(path, "cmu_12_01_walk.bvh");
  Avatar av;
  auto src = tracking::openBvhSource(path, {});
  REQUIRE(src.ok());
  ik::SolveOptions opts;
  opts.max_iterations = 30;
  auto solver = makeAvatarSolver(av.body, av.asset, opts);
  REQUIRE(solver.ok());
  ManualClock clock;
  IkStage stage(**solver, clock, {});
  avatar::SkeletonPose pose;
  const auto frames = run(stage, **src, 30.0, (*src)->duration(), pose);
  const double head = p95(frames, TrackerId::Head), left = p95(frames, TrackerId::LeftHand),
               right = p95(frames, TrackerId::RightHand), foot = p95(frames, TrackerId::LeftFoot);
  INFO("CMU walk: residual p95 head " << head * 1e3 << " mm, hands " << left * 1e3 << " / " << right * 1e3
                                      << " mm, left foot " << foot * 1e3 << " mm");
  CHECK(head < 0.05);
  CHECK(left < 0.01);
  CHECK(right < 0.01);
  CHECK(foot < 0.01);
}
