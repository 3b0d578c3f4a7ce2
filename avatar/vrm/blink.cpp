#include "avatar/vrm/blink.h"

#include <algorithm>
#include <cmath>

namespace embody::avatar {

void BlinkSchedule::reset(uint64_t seed) {
  state_ = seed ? seed : 0x9E3779B97F4A7C15ull;
  time_ = 0.0;
  next_ = 0.5 + 3.0 * uniform();  // the first blink within the first few seconds
}

double BlinkSchedule::uniform() {  // xorshift64*: the same numbers on every platform
  state_ ^= state_ >> 12;
  state_ ^= state_ << 25;
  state_ ^= state_ >> 27;
  return double((state_ * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

double BlinkSchedule::waitAfterBlink() {
  if (uniform() < 1.0 / 6.0) return 0.25;  // a double blink
  return std::min(2.0 - 2.5 * std::log(1.0 - uniform()), 10.0);
}

float BlinkSchedule::advance(double dt) {
  if (std::isfinite(dt) && dt > 0.0) time_ += dt;
  constexpr double total = kClose + kHold + kOpen;
  if (time_ - next_ > 60.0) next_ = time_ - total;  // a long gap: no catching up blink by blink
  while (time_ >= next_ + total) next_ += total + waitAfterBlink();  // blinks over: schedule the next
  const double t = time_ - next_;
  if (t < 0.0) return 0.0f;
  auto ease = [](double x) { return x * x * (3.0 - 2.0 * x); };
  if (t < kClose) return float(ease(t / kClose));
  if (t < kClose + kHold) return 1.0f;
  if (t < kClose + kHold + kOpen) return float(1.0 - ease((t - kClose - kHold) / kOpen));
  return 0.0f;
}

}  // namespace embody::avatar
