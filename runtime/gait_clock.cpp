#include "runtime/gait_clock.h"

#include <cmath>

namespace embody::runtime {

void GaitClock::configure(const GaitClockConfig& config, double scale) {
  config_ = config;
  scale_ = scale;
  reset();
}

void GaitClock::reset() {
  seekingMin_ = true;
  started_ = false;
  lastDip_ = -1e9;
  period_ = 0.0;
  steady_ = false;
  sway_ = 0.0;
  lastFoot_ = -1;
  alternating_ = false;
}

void GaitClock::update(double time, double height, double sway) {
  if (!std::isfinite(time) || !std::isfinite(height) || !std::isfinite(sway)) return;
  if (!started_) {
    started_ = true;
    seekingMin_ = true;
    extreme_ = height;
    extremeTime_ = time;
    sway_ = extremeSway_ = sway;
    lastTime_ = time;
    return;
  }
  const double dt = time - lastTime_;
  lastTime_ = time;
  if (dt > 0.0) sway_ += (1.0 - std::exp(-dt / config_.swaySmoothing)) * (sway - sway_);
  const double dip = config_.dip * scale_;
  if (seekingMin_) {
    if (height < extreme_) {
      extreme_ = height;
      extremeTime_ = time;
      extremeSway_ = sway_;
    } else if (height > extreme_ + dip) {
      // A dip: its time is the minimum's.
      const double interval = extremeTime_ - lastDip_;
      if (interval >= config_.minPeriod && interval <= config_.maxPeriod) {
        const bool agrees = period_ > 0.0 && std::abs(interval - period_) <= config_.regularity * period_;
        steady_ = period_ <= 0.0 || agrees;  // the first period since a start has nothing to disagree with
        period_ = period_ > 0.0 && agrees ? 0.5 * (period_ + interval) : interval;
      } else {
        steady_ = false;
        period_ = 0.0;
      }
      lastDip_ = extremeTime_;
      ++dips_;
      // The foot the head was moving towards at the dip's time.
      const double floor = config_.swayFloor * scale_;
      const int foot = extremeSway_ > floor ? 0 : extremeSway_ < -floor ? 1 : -1;
      alternating_ = foot >= 0 && lastFoot_ >= 0 && foot != lastFoot_;
      lastFoot_ = foot;
      seekingMin_ = false;
      extreme_ = height;
      extremeTime_ = time;
    }
  } else if (height > extreme_) {
    extreme_ = height;
    extremeTime_ = time;
  } else if (height < extreme_ - dip) {
    seekingMin_ = true;
    extreme_ = height;
    extremeTime_ = time;
    extremeSway_ = sway_;
  }
}

bool GaitClock::locked(double time) const {
  return steady_ && period_ > 0.0 && time - lastDip_ <= 1.5 * period_;
}

namespace {
// Whole periods from the last dip to the first one after `time`.
double periodsAfter(double lastDip, double period, double time) {
  return std::floor((time - lastDip) / period) + 1.0;
}
}  // namespace

double GaitClock::nextDip(double time) const {
  if (period_ <= 0.0) return time;
  return lastDip_ + periodsAfter(lastDip_, period_, time) * period_;
}

int GaitClock::nextFoot(double time) const {
  if (!alternating_ || period_ <= 0.0) return -1;
  const bool odd = static_cast<long long>(periodsAfter(lastDip_, period_, time)) % 2 != 0;
  return odd ? 1 - lastFoot_ : lastFoot_;
}

}  // namespace embody::runtime
