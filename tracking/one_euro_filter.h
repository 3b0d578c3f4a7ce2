#pragma once
// The One Euro filter (Casiez, Roussel & Vogel, CHI 2012): a low-pass filter whose cutoff rises
// with speed, so jitter at rest is removed while fast motion keeps little lag.
//   cutoff = minCutoff + beta * |filtered speed|,   alpha = 1 / (1 + tau / dt),  tau = 1 / (2 pi cutoff)
// With a reference noise the cutoff is raised by (reference / measured noise)^2 where that is
// above 1: a first-order low-pass leaves a residual noise variance of about s^2 pi cutoff dt, so
// this keeps a quieter source's residual at the reference source's, at rest and at speed, and a
// clean one is barely delayed.
// Positions use speed in m/s, orientations angular speed in rad/s (the quaternion is slerped).
#include "tracking/tracker.h"

namespace embody::tracking {

struct OneEuroParams {
  float minCutoff = 1.0f;         // Hz, the cutoff at rest: lower removes more jitter
  float beta = 0.0f;              // cutoff increase per unit of speed: higher cuts lag at speed
  float derivativeCutoff = 1.0f;  // Hz, for the speed estimate
  // The noise (standard deviation per axis, metres or radians) the cutoffs above are tuned for;
  // 0: they apply whatever the noise. Otherwise the filter measures the signal's own noise
  // (NoiseEstimate) and smooths no more than that noise needs: the cutoff times
  // max(1, (referenceNoise / measured)^2), which leaves a quieter source's residual jitter
  // where the tuned cutoffs leave a `referenceNoise` one's, with less lag. It never smooths less
  // than the plain filter would at referenceNoise and above.
  float referenceNoise = 0.0f;
};

struct TrackerFilterParams {
  // Defaults measured for 90 Hz tracking with ~1 mm / 0.3 deg noise (tests/tracking/filter_tests.cpp):
  // about 4x less jitter at rest, about 4 mm of lag at 1 m/s. Position beta 40 rather than 15:
  // 1 mm jitter 4.3x less instead of 4.8x (0.3 mm: 4.9x instead of 5.1x), for 3.9 mm of lag at
  // 1 m/s instead of 9.9 mm, which was most of a hand's error against motion capture (embody eval,
  // three trackers, eight clips: hands 1.45 -> 0.84 cm; docs/eval.md).
  // Both are tuned for that 1 mm / 0.3 deg and smooth a cleaner source (a headset runtime's own
  // filtered poses, motion capture) less: `embody eval --trackers 3`, eight clips, hands 0.55 ->
  // 0.42 cm (cmu_131_02 0.51 -> 0.05) for positions; the head 0.32 -> 0.17 cm for orientations,
  // with the body's heading eased by a filter of its own (runtime/body_heading.h; without it the
  // body turned as abruptly as a clean head and crossed its legs: docs/tracking.md, "One Euro
  // filter").
  OneEuroParams position{1.0f, 40.0f, 1.0f, 0.001f};
  OneEuroParams orientation{1.0f, 3.0f, 1.0f, 0.00524f};
};

// The white noise on a tracker's signal, from its third differences: per axis, white noise of
// standard deviation s gives E|d3|^2 = 20 s^2 (1 + 9 + 9 + 1), while smooth motion gives
// d3 = jerk * dt^3 (0.14 mm at 100 m/s^3 and 90 Hz). The mean of |d3|^2 / 60 (three axes) over
// the samples so far, exponential over `window` seconds once there are that many; the prior until
// the first one. A reset breaks the history, not the measured level (it is the device's).
class NoiseEstimate {
 public:
  explicit NoiseEstimate(float prior = 0.0f, float window = 1.0f) : variance_(prior * prior), window_(window) {}
  // `velocity`: this step's raw difference over dt. Returns the standard deviation per axis.
  float update(const glm::vec3& velocity, float dt);
  float deviation() const;
  void restart() { steps_ = 0; }  // a broken history (a gap, a glitch); the noise level stays

 private:
  glm::vec3 previous_[2]{glm::vec3(0.0f), glm::vec3(0.0f)};
  int steps_ = 0, samples_ = 0;
  float variance_;
  float window_;
};

// The One Euro cutoff for `speed`, raised where the noise `estimate` measures (updated with this
// step's raw `velocity`; only with a reference noise, the one case that reads it) is below the
// reference.
float oneEuroCutoff(const OneEuroParams& p, float speed, NoiseEstimate& estimate, const glm::vec3& velocity, float dt);

float oneEuroAlpha(float cutoffHz, float dt);

class OneEuroVec3 {
 public:
  explicit OneEuroVec3(OneEuroParams p = {}) : p_(p), noise_(p.referenceNoise) {}
  glm::vec3 filter(const glm::vec3& x, float dt);
  void reset() {
    primed_ = false;
    noise_.restart();
  }
  bool primed() const { return primed_; }

 private:
  OneEuroParams p_;
  NoiseEstimate noise_;
  glm::vec3 x_{0.0f}, raw_{0.0f};
  glm::vec3 velocity_{0.0f};  // low-passed per component, so zero-mean jitter averages out
  bool primed_ = false;
};

class OneEuroQuat {
 public:
  explicit OneEuroQuat(OneEuroParams p = {}) : p_(p), noise_(p.referenceNoise) {}
  glm::quat filter(const glm::quat& q, float dt);
  void reset() {
    primed_ = false;
    noise_.restart();
  }

 private:
  OneEuroParams p_;
  NoiseEstimate noise_;
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
