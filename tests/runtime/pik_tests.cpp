// The runtime driving the real prioritized IK solver (ik's sample humanoid): targets
// reached, warm starts, deadlines kept with an injected clock.
#include <catch2/catch.hpp>
#include <numbers>

#include "tests/support/sample_models.h"
#include "runtime/ik_stage.h"
#include "runtime/pik_body_solver.h"

using namespace embody;
using namespace embody::runtime;
using tracking::TrackerId;

namespace {

// Every call to now() moves time on by `tick`: the solver's own clock reads make time pass, so
// each iteration "costs" a tick, deterministically.
class TickingClock final : public Clock {
 public:
  explicit TickingClock(std::chrono::nanoseconds tick) : tick_(tick.count()) {}
  time_point now() const override { return time_point(std::chrono::nanoseconds(ns_.fetch_add(tick_))); }

 private:
  int64_t tick_;
  mutable std::atomic<int64_t> ns_{0};
};

struct Fixture {
  std::shared_ptr<const ik::Model> model;
  PikBinding binding;
  tracking::PoseSample rest;  // the model's own rest targets, in tracking space

  Fixture() {
    auto m = test::sampleHumanoid();
    REQUIRE(m.ok());
    model = std::make_shared<const ik::Model>(std::move(*m));
    binding = PikBinding::byTaskNames(*model);
    // The sample humanoid faces +Z with +X to its left: OpenXR's frame turned 180 deg about Y.
    binding.modelFromTracking = Eigen::Isometry3d(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()));
    ik::Data d(*model);
    ik::kinematics(*model, d, false);
    const Eigen::Isometry3d trackingFromModel = binding.modelFromTracking.inverse();
    for (auto id : tracking::kAllTrackers) {
      const ik::TaskId t = binding.targets[static_cast<size_t>(tracking::index(id))].task;
      if (t < 0) continue;
      const Eigen::Vector3d p = trackingFromModel * d.taskPosition(t);
      const Eigen::Quaterniond q(trackingFromModel.linear() * d.taskOrientation(t).toRotationMatrix());
      rest[id] = {glm::vec3(p.x(), p.y(), p.z()), glm::quat(static_cast<float>(q.w()), static_cast<float>(q.x()),
                                                           static_cast<float>(q.y()), static_cast<float>(q.z())), true};
    }
  }
};

}  // namespace

TEST_CASE("PIK through the runtime reaches moved hand targets with head and feet kept") {
  Fixture fx;
  REQUIRE(fx.binding.targets[0].task >= 0);
  REQUIRE(fx.binding.targets[1].task >= 0);
  REQUIRE(fx.binding.targets[3].task < 0);  // the sample humanoid has no hips task
  ik::SolveOptions opts;
  opts.max_iterations = 200;
  PikBodySolver solver(fx.model, fx.binding, opts);
  IkStageConfig cfg;
  cfg.filter = false;
  ManualClock clock;  // time stands still: this test is about reaching, not timing
  IkStage stage(solver, clock, cfg);
  SolvedFrame frame;
  tracking::PoseSample s = fx.rest;
  // From the T-pose, hands 20 cm in, 10 cm up and 15 cm forward (tracking space: -Z forward,
  // the left hand on -X): reachable by bending the elbows.
  s[TrackerId::LeftHand].position += glm::vec3(0.2f, 0.1f, -0.15f);
  s[TrackerId::RightHand].position += glm::vec3(-0.2f, 0.1f, -0.15f);
  for (int i = 0; i < 3; ++i) {
    s.time = i / 90.0;
    CHECK_FALSE(stage.process(s, frame).deadlineMiss);
  }
  CHECK(frame.stats.residual[static_cast<size_t>(tracking::index(TrackerId::LeftHand))] < 1e-3f);
  CHECK(frame.stats.residual[static_cast<size_t>(tracking::index(TrackerId::RightHand))] < 1e-3f);
  CHECK(frame.stats.residual[static_cast<size_t>(tracking::index(TrackerId::Head))] < 1e-3f);
  CHECK(frame.stats.residual[static_cast<size_t>(tracking::index(TrackerId::LeftFoot))] < 1e-3f);
  CHECK(frame.stats.residual[static_cast<size_t>(tracking::index(TrackerId::Hips))] < 0.0f);  // no task
  CHECK(solver.data().q().allFinite());

  // Warm starts: with two iterations per frame, each frame continues where the last one stopped.
  opts.max_iterations = 2;
  PikBodySolver few(fx.model, fx.binding, opts);
  IkStage warm(few, clock, cfg);
  std::vector<float> residuals;
  for (int i = 0; i < 4; ++i) {
    s.time = i / 90.0;
    residuals.push_back(warm.process(s, frame).residual[1]);
  }
  // Each frame's two iterations make progress from where the last frame stopped (at least 1 cm
  // here: the solver's per-level trust region, ik::SolveOptions::max_level_step, bounds how far
  // one iteration moves from a far-off warm start).
  for (size_t i = 1; i < residuals.size(); ++i) CHECK(residuals[i] < residuals[i - 1] - 0.01f);
  warm.reset();  // forgets the warm start: back to the first frame's error
  CHECK(warm.process(s, frame).residual[1] == Approx(residuals[0]).epsilon(1e-3));
}

TEST_CASE("PIK through the runtime keeps the deadline with an injected clock") {
  Fixture fx;
  ik::SolveOptions opts;
  opts.max_iterations = 1000;
  PikBodySolver solver(fx.model, fx.binding, opts);
  TickingClock clock(std::chrono::microseconds(40));
  IkStageConfig cfg;
  cfg.budgetSeconds = 1e-3;
  cfg.reserveSeconds = 80e-6;  // the two clock reads after the solver's last check
  cfg.filter = false;
  IkStage stage(solver, clock, cfg);
  SolvedFrame frame;
  tracking::PoseSample s = fx.rest;
  for (int i = 0; i < 30; ++i) {
    // Targets that keep moving, so the solver never converges and always runs into the deadline.
    const float a = 0.2f * static_cast<float>(i);
    s[TrackerId::LeftHand].position = fx.rest[TrackerId::LeftHand].position + glm::vec3(0.0f, 0.2f * std::sin(a), -0.3f);
    s[TrackerId::RightHand].position = fx.rest[TrackerId::RightHand].position + glm::vec3(0.0f, 0.2f * std::cos(a), -0.3f);
    s.time = i / 90.0;
    const FrameStats& st = stage.process(s, frame);
    INFO("frame " << i << " took " << st.ikSeconds * 1e3 << " ms, " << st.iterations << " iterations");
    CHECK(st.iterations > 0);
    // By the deadline plus at most one iteration (one tick per clock read), always...
    CHECK(st.ikSeconds <= 1e-3 + 2 * 40e-6 + 1e-9);
    // ...and once the cost of an iteration is known, before the deadline.
    if (i > 0) CHECK_FALSE(st.deadlineMiss);
  }
  CHECK(solver.costModel().predicted() > Duration(0));
  CHECK(solver.data().q().allFinite());
}
