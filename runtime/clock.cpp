#include "runtime/clock.h"

#include <algorithm>

namespace embody::runtime {

void IterationCostModel::observe(Duration cost) {
  // Jump at once to a dearer iteration, decay by a quarter towards a cheaper one.
  predicted_ = std::max(cost, (3 * predicted_ + cost) / 4);
}

void IterationCostModel::observe(Duration elapsed, int iterations) {
  if (iterations > 0) observe(elapsed / iterations);
}

IterationBudget::IterationBudget(const Clock& clock, TimePoint deadline, IterationCostModel* model)
    : clock_(clock), deadline_(deadline), model_(model ? model : &local_) {}

bool IterationBudget::startIteration() {
  const TimePoint now = clock_.now();
  if (iterations_ > 0) model_->observe(now - lastStart_);
  // The first iteration always runs: progress every frame, an overshoot of at most one iteration.
  if (iterations_ > 0 && now + model_->predicted() > deadline_) return false;
  lastStart_ = now;
  ++iterations_;
  return true;
}

}  // namespace embody::runtime
