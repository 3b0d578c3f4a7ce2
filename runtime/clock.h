#pragma once
// Time for the runtime. One clock abstraction for the runtime and the IK solver: ik::Clock
// (ik/solver.h, std::chrono::steady_clock time points), injectable so budgets and
// deadlines are tested deterministically. Adds a thread-safe manual clock for tests and
// IterationBudget, which lets an iterative solver stop *before* its deadline instead of after it.
#include <atomic>
#include <chrono>
#include <cstdint>

#include "ik/solver.h"

namespace embody::runtime {

using Clock = ik::Clock;
using TimePoint = Clock::time_point;
using Duration = std::chrono::steady_clock::duration;

inline const Clock& steadyClock() { return ik::steadyClock(); }
inline double toSeconds(Duration d) { return std::chrono::duration<double>(d).count(); }
inline Duration fromSeconds(double s) {
  return std::chrono::duration_cast<Duration>(std::chrono::duration<double>(s));
}

// A clock that only moves when told to; safe to advance from one thread and read from another.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(double startSeconds = 0.0) { set(startSeconds); }
  time_point now() const override { return time_point(std::chrono::nanoseconds(ns_.load(std::memory_order_acquire))); }
  void set(double seconds) { ns_.store(static_cast<int64_t>(seconds * 1e9 + 0.5), std::memory_order_release); }
  void advance(double seconds) { ns_.fetch_add(static_cast<int64_t>(seconds * 1e9 + 0.5), std::memory_order_acq_rel); }
  double seconds() const { return static_cast<double>(ns_.load(std::memory_order_acquire)) * 1e-9; }

 private:
  std::atomic<int64_t> ns_{0};
};

// Predicts the cost of the next iteration from those measured so far: the largest recent one,
// decaying slowly towards cheaper ones (a slow iteration is not forgotten at once).
class IterationCostModel {
 public:
  void observe(Duration iterationCost);
  // Total over `iterations` iterations (e.g. from ik::SolveReport::elapsed).
  void observe(Duration elapsed, int iterations);
  Duration predicted() const { return predicted_; }
  // The deadline to hand a solver that only checks "now >= deadline" before each iteration, so
  // that its last iteration still ends before `deadline` (when costs stay as predicted).
  TimePoint safeDeadline(TimePoint deadline) const { return deadline - predicted_; }

 private:
  Duration predicted_{0};
};

// Decides, before each iteration, whether one more fits before the deadline. An iteration starts
// only when now + predicted cost <= deadline, so the solve ends before the deadline while
// iterations cost what they did, and overshoots by at most one iteration when one suddenly costs
// more than predicted. The first iteration always runs (a budget smaller than one iteration
// still makes progress, late by that one iteration).
class IterationBudget {
 public:
  IterationBudget(const Clock& clock, TimePoint deadline, IterationCostModel* model = nullptr);
  bool startIteration();  // true: run one more iteration; records the previous one's cost
  int iterations() const { return iterations_; }

 private:
  const Clock& clock_;
  TimePoint deadline_;
  IterationCostModel local_;
  IterationCostModel* model_;  // shared across solves when given, so the first guess is informed
  TimePoint lastStart_{};
  int iterations_ = 0;
};

}  // namespace embody::runtime
