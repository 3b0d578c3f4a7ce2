// The lock-free hand-offs: triple buffer semantics, and the IK thread between a tracking thread
// and a render thread (run under ThreadSanitizer by `make tsan`).
#include <catch2/catch.hpp>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include "fake_solver.h"
#include "runtime/ik_thread.h"
#include "tracking/synthetic_source.h"
#include "runtime/task_layout.h"

using namespace embody;
using namespace embody::runtime;

TEST_CASE("triple buffer: the reader gets the newest published value and keeps it") {
  TripleBuffer<int> tb(0);
  CHECK_FALSE(tb.acquire());
  CHECK(tb.front() == 0);
  tb.back() = 1;
  tb.publish();
  tb.back() = 2;
  tb.publish();  // overwrites 1, which was never taken
  CHECK(tb.acquire());
  CHECK(tb.front() == 2);
  CHECK_FALSE(tb.acquire());
  CHECK(tb.front() == 2);  // kept until something newer arrives
  tb.back() = 3;
  tb.publish();
  tb.back() = 4;  // being written, not published
  CHECK(tb.acquire());
  CHECK(tb.front() == 3);
}

TEST_CASE("triple buffer: concurrent writer and reader never see a torn or older value") {
  struct Payload {
    uint64_t seq = 0;
    std::array<uint64_t, 64> data{};
  };
  TripleBuffer<Payload> tb;
  constexpr uint64_t kCount = 20000;
  std::thread writer([&] {
    for (uint64_t s = 1; s <= kCount; ++s) {
      Payload& p = tb.back();
      p.seq = s;
      p.data.fill(s);
      tb.publish();
    }
  });
  uint64_t last = 0, torn = 0, backwards = 0, reads = 0;
  while (last < kCount) {
    if (!tb.acquire()) {
      std::this_thread::yield();
      continue;
    }
    const Payload& p = tb.front();
    ++reads;
    backwards += p.seq < last ? 1 : 0;
    for (uint64_t v : p.data) torn += v != p.seq ? 1 : 0;
    last = p.seq;
  }
  writer.join();
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(last == kCount);
  CHECK(reads > 0);
}

TEST_CASE("IK thread: each submitted sample is solved and published in order") {
  ManualClock clock;
  test::FakeSolver solver(&clock, [](int) { return 100e-6; }, 4);
  IkThread ik(solver, clock, {}, test::posedSkeleton(8));
  CHECK_FALSE(ik.acquire());
  ik.start();
  auto src = tracking::SyntheticSource::create("look").value();
  for (uint32_t i = 1; i <= 20; ++i) {
    const tracking::PoseSample s = src->sample(i / 90.0);
    ik.submit(s);
    REQUIRE(ik.waitForFrames(i, 10.0));
    REQUIRE(ik.acquire());
    const SolvedFrame& f = ik.frame();
    CHECK(f.stats.sequence == i);
    CHECK(f.stats.sampleTime == s.time);
    CHECK(f.stats.iterations == 4);
    CHECK_FALSE(f.stats.deadlineMiss);
    CHECK(f.pose.local.size() == 8);
    CHECK(f.targets.pose[tracking::TrackerId::Head].position.y > 1.0f);
  }
  CHECK(ik.samplesSkipped() == 0);
  ik.stop();
  ik.stop();  // idempotent
  CHECK(ik.framesSolved() == 20);
}

TEST_CASE("IK thread: a requested reset restarts filter and warm start before the next solve (a recenter)") {
  ManualClock clock;
  test::FakeSolver solver(&clock, [](int) { return 100e-6; }, 4);
  IkThread ik(solver, clock, {}, test::posedSkeleton(4));
  ik.start();
  auto src = tracking::SyntheticSource::create("idle").value();
  uint32_t n = 0;
  auto solveShifted = [&](double t, const glm::vec3& shift) {
    tracking::PoseSample s = src->sample(t);
    for (auto& p : s.trackers) p.position += shift;
    ik.submit(s);
    REQUIRE(ik.waitForFrames(++n, 10.0));
    REQUIRE(ik.acquire());
    return std::pair{s[tracking::TrackerId::Head].position, ik.frame().targets.pose[tracking::TrackerId::Head].position};
  };
  for (int i = 0; i < 10; ++i) solveShifted(i / 90.0, glm::vec3(0.0f));
  // Without a reset a 0.3 m jump of the whole space is smoothed: the filtered head lags behind.
  const auto [raw1, filtered1] = solveShifted(10 / 90.0, glm::vec3(0.3f, 0.0f, 0.0f));
  CHECK(glm::distance(raw1, filtered1) > 0.01f);
  CHECK(solver.solves - solver.warmSolves == 1);
  // After requestReset the next sample passes the fresh filter as it is, and the solve is cold.
  ik.requestReset();
  const auto [raw2, filtered2] = solveShifted(11 / 90.0, glm::vec3(0.6f, 0.0f, 0.0f));
  CHECK(glm::distance(raw2, filtered2) < 1e-6f);
  CHECK(solver.solves - solver.warmSolves == 2);
  // It happens once: the sample after that is warm and filtered again.
  solveShifted(12 / 90.0, glm::vec3(0.9f, 0.0f, 0.0f));
  CHECK(solver.solves - solver.warmSolves == 2);
  ik.stop();
}

TEST_CASE("IK thread between a tracking thread and a render thread: newest whole frames, no waiting") {
  const Clock& clock = steadyClock();
  // Real work on the IK thread: a few microseconds per iteration, up to the 1 ms budget.
  struct Busy final : BodySolver {
    SolveResult solve(const SolveRequest& req, avatar::SkeletonPose& pose) override {
      IterationBudget budget(*req.clock, req.deadline);
      SolveResult r;
      volatile double x = 0;
      while (r.iterations < 20 && budget.startIteration()) {
        for (int k = 0; k < 200; ++k) x = x + std::sqrt(static_cast<double>(k));
        ++r.iterations;
      }
      const glm::vec3 head = req.targets->pose[tracking::TrackerId::Head].position;
      for (auto& t : pose.local) t.translation = head;
      return r;
    }
  } solver;
  IkThread ik(solver, clock, {}, test::posedSkeleton(32));
  ik.start();
  constexpr int kSamples = 1500;
  std::atomic<bool> done{false};
  std::thread tracking([&] {
    auto src = tracking::SyntheticSource::create("figure8").value();
    for (int i = 0; i < kSamples; ++i) {
      tracking::PoseSample s = src->sample(i / 90.0);
      ik.submit(s);
      if (i % 8 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    done = true;
  });
  uint64_t lastSeq = 0, frames = 0, torn = 0, backwards = 0;
  double maxAcquire = 0.0;
  while (!done || ik.framesSolved() + ik.samplesSkipped() < static_cast<uint32_t>(kSamples)) {
    const TimePoint t0 = clock.now();
    const bool fresh = ik.acquire();
    maxAcquire = std::max(maxAcquire, toSeconds(clock.now() - t0));
    if (!fresh) {
      std::this_thread::yield();
      continue;
    }
    const SolvedFrame& f = ik.frame();
    ++frames;
    backwards += f.stats.sequence < lastSeq ? 1 : 0;
    lastSeq = f.stats.sequence;
    const glm::vec3 head = f.targets.pose[tracking::TrackerId::Head].position;
    for (const auto& t : f.pose.local) torn += t.translation != head ? 1 : 0;
  }
  tracking.join();
  ik.stop();
  CHECK(frames > 0);
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(ik.framesSolved() + ik.samplesSkipped() == static_cast<uint32_t>(kSamples));
  // The render side never waits on the solver (generous: scheduling noise on a loaded machine).
  CHECK(maxAcquire < 0.05);
}

TEST_CASE("task layout: balance first, head, then hands, lower body inferred without feet") {
  const TaskLayout three = taskLayoutFor(tracking::TrackerMask::threePoint());
  CHECK(three.inferLowerBody);
  // feet, head, hands, orientations, the pelvis inferred from the head, knee and elbow directions,
  // then the clavicles at rest
  CHECK(three.levels() == 7);
  int balance = 0, plants = 0, poles = 0, inferredHips = 0, clavicles = 0;
  for (const auto& t : three.tasks) {
    if (t.kind == TaskKind::LimbPole) {
      CHECK(t.priority == three.levels() - 1);
      ++poles;
      continue;
    }
    if (t.kind == TaskKind::ClavicleRest) {
      CHECK(t.priority == three.levels());  // below everything: it takes only what the rest leave
      ++clavicles;
      continue;
    }
    if (t.kind == TaskKind::Balance) balance = t.priority;
    if (t.kind == TaskKind::FootPlant) ++plants;
    if (t.kind == TaskKind::InferredHips) {
      inferredHips = t.priority;
      CHECK(t.weight == 0.1f);  // as soft as a tracked pelvis
    }
    if (t.kind == TaskKind::TrackerPosition && t.tracker == tracking::TrackerId::Head) CHECK(t.priority == 2);
    if (t.kind == TaskKind::TrackerPosition && t.tracker == tracking::TrackerId::LeftHand) CHECK(t.priority == 3);
    CHECK((t.tracker != tracking::TrackerId::Hips || t.kind == TaskKind::Balance || t.kind == TaskKind::InferredHips));
  }
  CHECK(balance == 1);
  CHECK(plants == 2);
  CHECK(inferredHips == 5);  // under the orientations, over the poles
  CHECK(poles == 4);  // both knees, both elbows
  CHECK(clavicles == 2);
  CHECK(three.describe().find("7  clavicle_rest left") != std::string::npos);
  const TaskLayout full = taskLayoutFor(tracking::TrackerMask::all());
  CHECK_FALSE(full.inferLowerBody);
  for (const auto& t : full.tasks) CHECK((t.kind != TaskKind::FootPlant && t.kind != TaskKind::InferredHips));
  CHECK(full.describe().find("2  position left_foot") != std::string::npos);
  // All trackers: the eyes first, the tracked feet next (they yield to the eyes when the avatar's
  // legs cannot reach both), hands next, orientations below positions; the tracked pelvis's
  // position with the hands' orientations (it yields to head and hands when proportions differ),
  // its orientation one level lower, on one level with the head's (they share what the coupled
  // spine cannot twist), the poles below everything.
  int headPos = 0, headRot = 0, handPos = 0, handRot = 0, hipsPos = 0, hipsRot = 0;
  for (const auto& t : full.tasks) {
    if (t.kind == TaskKind::LimbPole || t.kind == TaskKind::ClavicleRest) {
      CHECK(t.priority >= full.levels() - 1);  // below everything a tracker drives
      continue;
    }
    const bool position = t.kind == TaskKind::TrackerPosition;
    if (t.tracker == tracking::TrackerId::Head) (position ? headPos : headRot) = t.priority;
    if (t.tracker == tracking::TrackerId::LeftHand) (position ? handPos : handRot) = t.priority;
    if (t.tracker == tracking::TrackerId::Hips) (position ? hipsPos : hipsRot) = t.priority;
  }
  int footPos = 0;
  for (const auto& t : full.tasks)
    if (t.tracker == tracking::TrackerId::LeftFoot && t.kind == TaskKind::TrackerPosition) footPos = t.priority;
  CHECK(headPos == 1);
  CHECK(footPos == 2);
  CHECK(handPos == 3);
  CHECK(handRot == 4);
  CHECK(hipsPos == handRot);
  CHECK(hipsRot == hipsPos + 1);
  CHECK(headRot == hipsRot);
  CHECK(hipsRot == full.levels() - 2);
  // Without a tracked pelvis the head's orientation stays with the hands'.
  const TaskLayout noPelvis = taskLayoutFor(tracking::TrackerMask::threePoint());
  for (const auto& t : noPelvis.tasks)
    if (t.kind == TaskKind::TrackerOrientation) CHECK(t.priority == 4);
  CHECK(statusWeight(tracking::TrackerStatus::Absent) == 0.0f);
  CHECK(statusWeight(tracking::TrackerStatus::Held) == 1.0f);
}

TEST_CASE("IK thread join: waits while this sample is solved, never past the deadline") {
  // A process function (IkThread(Process)) that takes 200 ms per sample, as a slow solve would.
  std::atomic<int> solves{0};
  runtime::IkThread ik(
      [&](const tracking::PoseSample& s, runtime::SolvedFrame& out) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        out.stats.sequence = uint64_t(++solves);
        out.stats.sampleTime = s.time;
      },
      avatar::SkeletonPose{});
  ik.start();
  tracking::PoseSample sample;
  sample.time = 1.0;
  ik.submit(sample);
  // A 5 ms deadline: the join gives up at it (not caught up) and the newest frame is the initial one.
  auto start = std::chrono::steady_clock::now();
  CHECK_FALSE(ik.waitUntilCaughtUp(start + std::chrono::milliseconds(5)));
  const double waitedMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  CHECK(waitedMs >= 4.9);
  CHECK(waitedMs < 150.0);  // well before the solve ends (a loaded scheduler's wake-up at most)
  CHECK_FALSE(ik.acquire());
  // A generous deadline: the join returns as soon as the solve is published, with that frame.
  start = std::chrono::steady_clock::now();
  CHECK(ik.waitUntilCaughtUp(start + std::chrono::seconds(5)));
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(1));
  REQUIRE(ik.acquire());
  CHECK(ik.frame().stats.sampleTime == 1.0);
  // Nothing submitted since: caught up at once.
  CHECK(ik.waitUntilCaughtUp(std::chrono::steady_clock::now()));
  ik.stop();
}
