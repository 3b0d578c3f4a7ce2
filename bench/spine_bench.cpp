// Coupled vs uncoupled spine: the cost of one solver iteration (kinematics, Jacobians, priority
// passes, clamping) on the isolated-spine set-up, and of building the models. The paper's claim
// is that coupling costs no more per iteration than the uncoupled spine, despite the rows.
#include <benchmark/benchmark.h>

#include <algorithm>

#include "ik/solver.h"
#include "ik/spine/spine_model.h"

namespace {

using namespace embody;

// Solver state a few iterations into the isolated-spine experiment (neck pulled 12 cm left, head
// orientation kept), so the clamping loop has the rows it has in practice.
// whole = true: one full iteration (kinematics, Jacobians, every clamping pass, q += Δq);
// whole = false: kinematics + one priority pass with only the equality rows active, i.e. the
// cost of the solve itself without the clamping loop (how many passes that takes depends on
// how many bands and limits a pose touches).
// restore = true: a state further into the same solve (after `before` iterations, when the bands
// are already in contact), with or without the clamping loop's active set carried from the
// iteration before (`warm`, SolveOptions::warm_active_set, docs/ik.md). The solver's Data is
// restored outside the timed region before each timed iteration (all four variants alike; the
// pause costs each about the same few µs), so every one starts from that state.
void iteration(benchmark::State& state, const ik::spine::SpineDescription& d, bool coupled, bool whole = true,
               bool restore = false, bool warm = false, int before = 3) {
  ik::spine::SpineOptions o;
  o.coupled = coupled;
  auto s = ik::spine::buildIsolatedSpine(d, o);
  if (!s) {
    state.SkipWithError(s.error().c_str());
    return;
  }
  ik::Data data(s->model);
  ik::kinematics(s->model, data, false);
  const Eigen::Vector3d neck = data.taskPosition(s->neck_position);
  (void)data.setTarget(s->head_orientation, data.taskOrientation(s->head_orientation));
  (void)data.setTarget(s->neck_position, Eigen::Vector3d(neck + Eigen::Vector3d(0.12, 0, 0)));
  ik::SolveOptions so;
  so.warm_active_set = warm;
  for (int i = 0; i < before; ++i) ik::iterate(s->model, data, so);
  const Eigen::VectorXd q0 = data.q();
  const ik::Data snapshot = data;
  double passes = 0;
  for (auto _ : state) {
    if (restore) {
      state.PauseTiming();
      data = snapshot;
      state.ResumeTiming();
      ik::iterate(s->model, data, so);
      passes += data.report().clamp_passes;
      benchmark::DoNotOptimize(data.q().data());
    } else if (whole) {
      (void)data.setConfiguration(q0);
      ik::iterate(s->model, data, so);
      passes += data.report().clamp_passes;
      benchmark::DoNotOptimize(data.q().data());
    } else {
      ik::kinematics(s->model, data, true);
      benchmark::DoNotOptimize(ik::priorityPass(s->model, data, so).data());
    }
  }
  state.counters["dofs"] = s->model.dofs;
  state.counters["clamp_passes"] = passes / static_cast<double>(std::max<benchmark::IterationCount>(state.iterations(), 1));
}

void BM_IterationFullCoupled(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), true); }
void BM_IterationFullUncoupled(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), false); }
// Iteration 9 of the same solve (the bands in contact since iteration 4): cold and warm.
void BM_InContactFullCoupledCold(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), true, true, true, false, 8); }
void BM_InContactFullUncoupledCold(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), false, true, true, false, 8); }
void BM_InContactFullCoupledWarm(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), true, true, true, true, 8); }
void BM_InContactFullUncoupledWarm(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), false, true, true, true, 8); }
void BM_IterationSimplifiedCoupled(benchmark::State& s) { iteration(s, ik::spine::defaultSimplifiedSpine(), true); }
void BM_IterationSimplifiedUncoupled(benchmark::State& s) { iteration(s, ik::spine::defaultSimplifiedSpine(), false); }

void BM_PriorityPassFullCoupled(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), true, false); }
void BM_PriorityPassFullUncoupled(benchmark::State& s) { iteration(s, ik::spine::defaultFullSpine(), false, false); }

void BM_BuildFullCoupledModel(benchmark::State& state) {
  for (auto _ : state) {
    auto s = ik::spine::buildIsolatedSpine(ik::spine::defaultFullSpine());
    benchmark::DoNotOptimize(s.ok());
  }
}

}  // namespace

BENCHMARK(BM_IterationFullCoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IterationFullUncoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InContactFullCoupledCold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InContactFullUncoupledCold)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InContactFullCoupledWarm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_InContactFullUncoupledWarm)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IterationSimplifiedCoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_IterationSimplifiedUncoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PriorityPassFullCoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PriorityPassFullUncoupled)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_BuildFullCoupledModel)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
