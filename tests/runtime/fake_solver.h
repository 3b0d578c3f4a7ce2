#pragma once
// Test solvers for the runtime: their cost is simulated on a ManualClock (deterministic), or real
// busy work on the steady clock. They write the head target into every joint's translation, so a
// reader can tell a torn frame (joints disagreeing) from a whole one.
#include <functional>

#include "runtime/body_solver.h"

namespace embody::test {

class FakeSolver final : public runtime::BodySolver {
 public:
  // iterationCost(i) in seconds, advanced on `clock` for iteration i (0-based).
  FakeSolver(runtime::ManualClock* clock, std::function<double(int)> iterationCost, int maxIterations = 1000)
      : clock_(clock), cost_(std::move(iterationCost)), maxIterations_(maxIterations) {}

  runtime::SolveResult solve(const runtime::SolveRequest& req, avatar::SkeletonPose& pose) override {
    runtime::IterationBudget budget(*req.clock, req.deadline);
    runtime::SolveResult r;
    while (r.iterations < maxIterations_ && budget.startIteration()) {
      if (clock_) clock_->advance(cost_(r.iterations));
      ++r.iterations;
    }
    r.converged = r.iterations == maxIterations_;
    const glm::vec3 head = (*req.targets).pose[tracking::TrackerId::Head].position;
    for (auto& t : pose.local) t.translation = head;
    r.residual[0] = 0.001f * static_cast<float>(r.iterations);
    ++solves;
    if (warm) ++warmSolves;
    warm = true;
    return r;
  }
  void resetWarmStart() override { warm = false; }

  int solves = 0, warmSolves = 0;
  bool warm = false;

 private:
  runtime::ManualClock* clock_;
  std::function<double(int)> cost_;
  int maxIterations_;
};

// A solver that ignores the budget: its call n (0-based) fills in the result with `script(n, r)`
// and takes the seconds the script returns on `clock`.
class ScriptedSolver final : public runtime::BodySolver {
 public:
  using Script = std::function<double(int call, runtime::SolveResult& result)>;
  ScriptedSolver(runtime::ManualClock& clock, Script script) : clock_(clock), script_(std::move(script)) {}

  runtime::SolveResult solve(const runtime::SolveRequest&, avatar::SkeletonPose&) override {
    runtime::SolveResult r;
    clock_.advance(script_(calls_++, r));
    return r;
  }

 private:
  runtime::ManualClock& clock_;
  Script script_;
  int calls_ = 0;
};

inline avatar::SkeletonPose posedSkeleton(int joints) {
  avatar::SkeletonPose p;
  p.local.resize(static_cast<size_t>(joints));
  return p;
}

}  // namespace embody::test
