#include "runtime/clock.h"

#include <algorithm>
#include <chrono>

namespace embody::runtime {

double SteadyClock::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

IterationBudget::IterationBudget(const Clock& clock, double deadline, double firstIterationGuess)
    : clock_(clock), deadline_(deadline), predicted_(std::max(0.0, firstIterationGuess)) {}

bool IterationBudget::startIteration() {
  const double now = clock_.now();
  if (iterations_ > 0) {
    const double last = now - lastStart_;
    // Decay slowly towards cheaper iterations, jump at once to a dearer one.
    predicted_ = std::max(last, 0.75 * predicted_ + 0.25 * last);
  }
  if (now + predicted_ > deadline_) return false;
  lastStart_ = now;
  ++iterations_;
  return true;
}

}  // namespace embody::runtime
