#pragma once
// Automatic blinking: a natural, random-interval schedule that is deterministic for a seed.
// Blinks come 2 to ~10 s apart (2 s plus an exponential wait of mean 2.5 s, so about 15 a
// minute), one in six is followed by a second blink; each closes in 70 ms, stays shut 30 ms and
// opens in 120 ms (eased), the shape of a spontaneous human blink.
#include <cstdint>

namespace embody::avatar {

class BlinkSchedule {
 public:
  explicit BlinkSchedule(uint64_t seed = 1) { reset(seed); }
  void reset(uint64_t seed);
  // Advances the clock by dt seconds and returns the blink weight (0 open .. 1 closed) at the new time.
  float advance(double dt);
  double time() const { return time_; }
  double nextBlinkStart() const { return next_; }

  static constexpr double kClose = 0.07, kHold = 0.03, kOpen = 0.12;

 private:
  double uniform();  // [0, 1)
  double waitAfterBlink();
  uint64_t state_ = 1;
  double time_ = 0.0, next_ = 0.0;
};

}  // namespace embody::avatar
