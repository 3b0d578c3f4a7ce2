#pragma once
// Time for the runtime: an injectable monotonic clock (seconds), so budgets and deadlines can be
// tested deterministically, and IterationBudget, which lets an iterative solver stop *before*
// its deadline instead of after it.
#include <atomic>
#include <cstdint>

namespace embody::runtime {

class Clock {
 public:
  virtual ~Clock() = default;
  virtual double now() const = 0;  // seconds, monotonic, arbitrary origin
};

// std::chrono::steady_clock.
class SteadyClock final : public Clock {
 public:
  double now() const override;
};

// A clock that only moves when told to; safe to advance from one thread and read from another.
class ManualClock final : public Clock {
 public:
  explicit ManualClock(double start = 0.0) { set(start); }
  double now() const override { return static_cast<double>(ns_.load(std::memory_order_acquire)) * 1e-9; }
  void set(double seconds) { ns_.store(static_cast<int64_t>(seconds * 1e9 + 0.5), std::memory_order_release); }
  void advance(double seconds) { ns_.fetch_add(static_cast<int64_t>(seconds * 1e9 + 0.5), std::memory_order_acq_rel); }

 private:
  std::atomic<int64_t> ns_{0};
};

// Decides, before each iteration, whether one more fits before the deadline: it predicts the
// next iteration's cost from the ones measured so far (the largest recent one, so a slow
// iteration is not forgotten at once). An iteration starts only when now + predicted <= deadline,
// so the solve ends before the deadline while iterations cost what they did, and overshoots by at
// most one iteration when one suddenly costs more.
class IterationBudget {
 public:
  IterationBudget(const Clock& clock, double deadline, double firstIterationGuess = 0.0);
  bool startIteration();      // true: run one more iteration; records the previous one's cost
  int iterations() const { return iterations_; }
  double deadline() const { return deadline_; }
  double predictedCost() const { return predicted_; }

 private:
  const Clock& clock_;
  double deadline_;
  double predicted_;
  double lastStart_ = 0.0;
  int iterations_ = 0;
};

}  // namespace embody::runtime
