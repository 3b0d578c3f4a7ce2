// Runtime and tracking costs per frame: the hand-off, the filter, the loss guard, sources, and a
// full IkStage step on the sample humanoid with the real PIK solver.
#include <benchmark/benchmark.h>
#include <numbers>

#include "tests/support/sample_models.h"
#include "runtime/ik_stage.h"
#include "runtime/pik_body_solver.h"
#include "runtime/triple_buffer.h"
#include "test_paths.h"
#include "tracking/bvh_source.h"
#include "tracking/synthetic_source.h"

using namespace embody;

static void BM_TripleBufferPublishAcquire(benchmark::State& state) {
  runtime::TripleBuffer<runtime::SolvedFrame> tb;
  for (auto& s : tb.slots()) s.pose.local.resize(64);
  for (auto _ : state) {
    tb.back().stats.sequence++;
    tb.publish();
    benchmark::DoNotOptimize(tb.acquire());
    benchmark::DoNotOptimize(tb.front().stats.sequence);
  }
}
BENCHMARK(BM_TripleBufferPublishAcquire);

static void BM_SyntheticSample(benchmark::State& state) {
  auto src = tracking::SyntheticSource::create("figure8").value();
  double t = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(src->sample(t));
    t += 1.0 / 90.0;
  }
}
BENCHMARK(BM_SyntheticSample);

static void BM_FilterAndGuard(benchmark::State& state) {
  auto src = tracking::SyntheticSource::create("reach").value();
  std::vector<tracking::PoseSample> samples;
  for (int i = 0; i < 900; ++i) samples.push_back(src->sample(i / 90.0));
  tracking::PoseFilter filter;
  tracking::TrackingGuard guard;
  size_t i = 0;
  for (auto _ : state) {
    tracking::PoseSample s = samples[i % samples.size()];
    s.time = static_cast<double>(i) / 90.0;
    benchmark::DoNotOptimize(guard.update(filter.apply(s)));
    ++i;
  }
}
BENCHMARK(BM_FilterAndGuard);

static void BM_LoadCmuWalk(benchmark::State& state) {
  const std::string path = test::sharedAsset("cmu_12_01_walk.bvh");
  if (path.empty()) {
    state.SkipWithError("cmu_12_01_walk.bvh not found");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(tracking::openBvhSource(path, {}));
}
BENCHMARK(BM_LoadCmuWalk)->Unit(benchmark::kMillisecond);

// One runtime frame (filter, guard, PIK on the 61-dof sample humanoid, 6 tasks) with a 1 ms
// budget, the hands following synthetic:reach.
static void BM_IkStageSampleHumanoid(benchmark::State& state) {
  auto model = std::make_shared<const ik::Model>(test::sampleHumanoid().value());
  runtime::PikBinding binding = runtime::PikBinding::byTaskNames(*model);
  binding.modelFromTracking = Eigen::Isometry3d(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()));
  ik::SolveOptions opts;
  opts.max_iterations = static_cast<int>(state.range(0));
  runtime::PikBodySolver solver(model, binding, opts);
  runtime::IkStageConfig cfg;
  runtime::IkStage stage(solver, runtime::steadyClock(), cfg);
  runtime::SolvedFrame frame;
  auto src = tracking::SyntheticSource::create("reach").value();
  int i = 0;
  double misses = 0, iterations = 0;
  for (auto _ : state) {
    tracking::PoseSample s = src->sample(i / 90.0);
    s[tracking::TrackerId::LeftFoot].valid = s[tracking::TrackerId::RightFoot].valid = false;
    const auto& st = stage.process(s, frame);
    misses += st.deadlineMiss ? 1 : 0;
    iterations += st.iterations;
    ++i;
  }
  state.counters["deadline_miss_rate"] = benchmark::Counter(misses, benchmark::Counter::kAvgIterations);
  state.counters["iterations_mean"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_IkStageSampleHumanoid)->Arg(1)->Arg(10)->Arg(100)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
