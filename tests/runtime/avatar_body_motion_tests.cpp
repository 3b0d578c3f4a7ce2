// AvatarBodySolver on the default avatar over the synthetic motions and the CMU walk, per
// tracker (ported from the former runtime/avatar_solver binding's tests, which it replaces):
// rest trackers keep the rest pose, head and hands on target, feet never slide off theirs.
#include <catch2/catch.hpp>
#include <cmath>

#include "runtime/avatar_body_solver.h"
#include "runtime/ik_stage.h"
#include "test_paths.h"
#include "tracking/pose_source.h"
#include "runtime/runtime_test_support.h"

using namespace embody;
using namespace embody::runtime;
using tracking::TrackerId;

namespace {

using embody::test::defaultAvatar;

struct Figures {
  StatsSummary summary;
  size_t nonFinite = 0;
  int refusedCalls = 0;  // ik::Data setter calls the solver made that were refused
  double p95(TrackerId id) const { return summary.residualP95[size_t(tracking::index(id))]; }
  double turnP95Deg(TrackerId id) const { return summary.turnResidualP95Deg[size_t(tracking::index(id))]; }
};

// `spec` through an IkStage on AvatarBodySolver at 30 Hz; the clock never moves, so the
// iteration cap (not the machine's load) ends each solve and runs are repeatable.
Figures drive(const std::string& spec, AvatarBodyOptions o = {}, double seconds = -1.0) {
  tracking::SourceOptions so;
  so.userHeight = 1.75f;
  auto src = tracking::openPoseSource(spec, so);
  REQUIRE(src.ok());
  o.userHeight = 1.75f;
  auto solver = AvatarBodySolver::create(defaultAvatar(), o);
  REQUIRE(solver.ok());
  ManualClock clock;
  IkStageConfig cfg;
  cfg.budgetSeconds = 1.0;
  cfg.guard.userHeight = 1.75f;
  IkStage stage(**solver, clock, cfg);
  SolvedFrame frame;
  frame.pose = avatar::SkeletonPose::rest(defaultAvatar().skeleton);
  StatsRecorder rec;
  Figures f;
  const double duration = seconds > 0 ? seconds : (*src)->duration();
  for (int i = 0; i < int(duration * 30.0); ++i) {
    rec.add(stage.process((*src)->sample(i / 30.0), frame));
    for (const auto& t : frame.pose.local)
      if (!std::isfinite(t.translation.x + t.translation.y + t.translation.z + t.rotation.w + t.rotation.x +
                         t.rotation.y + t.rotation.z))
        ++f.nonFinite;
  }
  f.summary = rec.summary();
  f.refusedCalls = (*solver)->refusedCalls();
  return f;
}

}  // namespace

TEST_CASE("synthetic motions drive the default avatar: head and hands on target, feet planted") {
  // squat is not asserted: at the deepest point the straight-legged rest pose leaves the head
  // above its target (docs/runtime.md "Known limits").
  for (const char* motion : {"idle", "reach", "look", "bow", "figure8"}) {
    const Figures f = drive(std::string("synthetic:") + motion);
    INFO(motion << ": residual p95 head " << f.p95(TrackerId::Head) * 1e3 << " mm, hands "
                << f.p95(TrackerId::LeftHand) * 1e3 << " / " << f.p95(TrackerId::RightHand) * 1e3 << " mm, feet "
                << f.p95(TrackerId::LeftFoot) * 1e3 << " / " << f.p95(TrackerId::RightFoot) * 1e3 << " mm");
    CHECK(f.nonFinite == 0);
    CHECK(f.refusedCalls == 0);
    CHECK(f.p95(TrackerId::Head) >= 0.0);
    CHECK(f.p95(TrackerId::Head) < 0.01);
    CHECK(f.p95(TrackerId::LeftHand) < 0.03);
    CHECK(f.p95(TrackerId::RightHand) < 0.03);
    CHECK(f.p95(TrackerId::LeftFoot) >= 0.0);
    CHECK(f.p95(TrackerId::LeftFoot) < 0.005);
    CHECK(f.p95(TrackerId::RightFoot) < 0.005);
  }
}

TEST_CASE("the CMU walk at 30 Hz with every tracker: head and hands within 1 cm, feet within 1 cm (uncoupled) / 2 cm (coupled), the pelvis turned with its tracker") {
  EMBODY_REQUIRE_SHARED_ASSET(bvh, "cmu_12_01_walk.bvh");
  for (const bool coupled : {true, false}) {
    AvatarBodyOptions o;
    o.coupledSpine = coupled;
    const Figures f = drive(bvh, o);
    INFO((coupled ? "coupled" : "uncoupled") << " spine, CMU walk: residual p95 head " << f.p95(TrackerId::Head) * 1e3
                                             << " mm, hands " << f.p95(TrackerId::LeftHand) * 1e3 << " / "
                                             << f.p95(TrackerId::RightHand) * 1e3 << " mm, feet "
                                             << f.p95(TrackerId::LeftFoot) * 1e3 << " / "
                                             << f.p95(TrackerId::RightFoot) * 1e3 << " mm, pelvis turned "
                                             << f.turnP95Deg(TrackerId::Hips) << " degrees off its tracker");
    CHECK(f.nonFinite == 0);
    CHECK(f.p95(TrackerId::Head) < 0.01);
    CHECK(f.p95(TrackerId::LeftHand) < 0.01);
    CHECK(f.p95(TrackerId::RightHand) < 0.01);
    // The removed binding asserted feet < 1 cm with its head 44 mm off. With the coupled spine
    // the feet (the top level) end 1.0-1.6 cm off in the double-support frames at 30 Hz (the
    // levels below pull them to second order; docs/runtime.md "Known limits"): weaker here.
    const double feet = coupled ? 0.02 : 0.01;
    CHECK(f.p95(TrackerId::LeftFoot) < feet);
    CHECK(f.p95(TrackerId::RightFoot) < feet);
    // The pelvis turns with its tracker: 10.5 / 7.6 degrees p95 (coupled / uncoupled), where
    // without its orientation task it drifted 62 / 55 degrees off (docs/runtime.md).
    CHECK(f.turnP95Deg(TrackerId::Hips) >= 0.0);
    CHECK(f.turnP95Deg(TrackerId::Hips) < 15.0);
  }
}

TEST_CASE("six trackers: a solve whose head and pelvis share their turn stops once both are met, not at the cap") {
  // The head's and the pelvis's orientations share a level (task_layout.cpp) and meet at their
  // least-squares compromise (0.7 degrees each on synthetic:figure8). At the head's own tolerance
  // (0.01 rad) no solve counted as converged while the two disagreed: 5.7 iterations a frame at
  // 30 Hz (cap 10) for the same final turns, 3.8 with the shared level's 0.02 rad.
  AvatarBodyOptions o;
  o.maxIterations = 10;
  const Figures f = drive("synthetic:figure8", o);
  INFO("iterations a frame " << f.summary.iterationsMean << ", pelvis turned " << f.turnP95Deg(TrackerId::Hips)
                             << " degrees, head " << f.turnP95Deg(TrackerId::Head) << " degrees off their trackers");
  CHECK(f.summary.iterationsMean < 4.5);
  CHECK(f.turnP95Deg(TrackerId::Hips) < 2.0);
  CHECK(f.turnP95Deg(TrackerId::Head) < 2.0);
}
