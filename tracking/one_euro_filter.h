#pragma once
// The One Euro filter (Casiez, Roussel & Vogel, CHI 2012): a low-pass filter whose cutoff rises
// with speed, so jitter at rest is removed while fast motion keeps little lag.
//   cutoff = minCutoff + beta * |filtered speed|,   alpha = 1 / (1 + tau / dt),  tau = 1 / (2 pi cutoff)
// Positions use speed in m/s, orientations angular speed in rad/s (the quaternion is slerped).
#include "tracking/tracker.h"

namespace embody::tracking {

struct OneEuroParams {
  float minCutoff = 1.0f;         // Hz, the cutoff at rest: lower removes more jitter
  float beta = 0.0f;              // cutoff increase per unit of speed: higher cuts lag at speed
  float derivativeCutoff = 1.0f;  // Hz, for the speed estimate
};

struct TrackerFilterParams {
  // Defaults measured for 90 Hz tracking with ~1 mm / 0.3 deg noise (tests/tracking/filter_tests.cpp):
  // about 4x less jitter at rest, about 4 mm of lag at 1 m/s. Position beta 40 rather than 15:
  // 1 mm jitter 4.3x less instead of 4.8x (0.3 mm: 4.9x instead of 5.1x), for 3.9 mm of lag at
  // 1 m/s instead of 9.9 mm, which was most of a hand's error against motion capture (embody eval,
  // three trackers, eight clips: hands 1.45 -> 0.84 cm; docs/eval.md).
  OneEuroParams position{1.0f, 40.0f, 1.0f};
  OneEuroParams orientation{1.0f, 3.0f, 1.0f};
};

float oneEuroAlpha(float cutoffHz, float dt);

class OneEuroVec3 {
 public:
  explicit OneEuroVec3(OneEuroParams p = {}) : p_(p) {}
  glm::vec3 filter(const glm::vec3& x, float dt);
  void reset() { primed_ = false; }
  bool primed() const { return primed_; }

 private:
  OneEuroParams p_;
  glm::vec3 x_{0.0f}, raw_{0.0f};
  glm::vec3 velocity_{0.0f};  // low-passed per component, so zero-mean jitter averages out
  bool primed_ = false;
};

class OneEuroQuat {
 public:
  explicit OneEuroQuat(OneEuroParams p = {}) : p_(p) {}
  glm::quat filter(const glm::quat& q, float dt);
  void reset() { primed_ = false; }

 private:
  OneEuroParams p_;
  glm::quat q_{1, 0, 0, 0}, raw_{1, 0, 0, 0};
  glm::vec3 velocity_{0.0f};  // angular velocity, low-passed per component
  bool primed_ = false;
};

// One position and one orientation filter per tracker. Invalid trackers pass through and reset
// their filter (the tracking-loss guard blends them back in); so does a gap longer than
// `maxGapSeconds` between samples, and a jump faster than `jumpSpeed` (an outlier is passed on
// as it is, for the guard to reject, instead of being smeared over the following samples).
class PoseFilter {
 public:
  explicit PoseFilter(const TrackerFilterParams& params = {});
  void setParams(TrackerId id, const TrackerFilterParams& params);
  PoseSample apply(const PoseSample& input);
  void reset();

  static constexpr double maxGapSeconds = 0.25;
  static constexpr float jumpSpeed = 10.0f;  // m/s, as TrackingGuardConfig::jumpSpeed

 private:
  std::array<glm::vec3, kTrackerCount> lastRaw_{};
  std::array<bool, kTrackerCount> haveRaw_{};
  std::array<OneEuroVec3, kTrackerCount> position_;
  std::array<OneEuroQuat, kTrackerCount> orientation_;
  double lastTime_ = 0.0;
  bool primed_ = false;
};

}  // namespace embody::tracking
