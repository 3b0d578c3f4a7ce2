#pragma once
// The tracking-loss policy, as one reusable component between the (filtered) pose source and
// whatever consumes targets (the IK). Its output never contains NaN and never snaps:
//
// - A tracker is lost when it is flagged invalid, is not finite, or jumps implausibly
//   (faster than `jumpSpeed`; a jump that persists longer than `maxJumpRejectSeconds` is
//   accepted as real, e.g. a recentred play space, and blended in).
// - Hands and hips, when lost, hold their last target relative to the head (position and
//   orientation in the head's heading frame, so a nod does not swing them); after `holdSeconds`
//   the hands ease over `easeSeconds` to a relaxed pose hanging at the sides, the hips are
//   dropped (status Absent: the IK infers them). Feet hold in the world (they are planted), then
//   are dropped. The head holds its last pose.
// - Hands that were never tracked hang in the neutral pose; the head before its first valid
//   sample stands at eye height at the origin.
// - When tracking returns, the target moves from where it was towards the live pose no faster
//   than `recoverySpeed` (and `recoveryAngularSpeed`) until it has caught up.
// - While a hand is lost (held, easing, neutral) it stays within arm's reach of the shoulder
//   estimated from the head (BodyDimensions::shoulderFromHead).
#include "tracking/body_dimensions.h"

namespace embody::tracking {

enum class TrackerStatus : uint8_t {
  Tracked,     // live target
  Recovering,  // tracking is back, blending towards the live target
  Held,        // lost: holding the last target
  Easing,      // lost for longer: easing to the neutral pose
  Neutral,     // lost for good or never seen: neutral pose (hands, head)
  Absent,      // no target (optional trackers: hips, feet)
};
std::string_view statusName(TrackerStatus s);

struct TrackingGuardConfig {
  float userHeight = 1.75f;
  float holdSeconds = 0.5f;
  float easeSeconds = 1.0f;
  float recoverySpeed = 2.0f;          // m/s
  float recoveryAngularSpeed = 6.0f;   // rad/s
  float jumpSpeed = 10.0f;             // m/s; faster is a glitch
  float maxJumpRejectSeconds = 0.25f;
  float reachMargin = 0.98f;           // fraction of the arm's reach allowed while not tracked
};

struct GuardedSample {
  PoseSample pose;  // finite everywhere; valid == there is a target (false only for Absent)
  std::array<TrackerStatus, kTrackerCount> status{};
  TrackerStatus operator[](TrackerId id) const { return status[static_cast<size_t>(index(id))]; }
};

class TrackingGuard {
 public:
  explicit TrackingGuard(const TrackingGuardConfig& config = {});
  // Feed samples in time order; returns the guarded targets (valid until the next call).
  const GuardedSample& update(const PoseSample& input);
  void reset();
  const TrackingGuardConfig& config() const { return config_; }
  const BodyDimensions& body() const { return body_; }

 private:
  struct State {
    TrackerPose accepted;        // last accepted live pose
    double acceptedTime = -1.0;  // < 0: never
    double jumpSince = -1.0;     // first rejected jump of the current run, < 0 none
    TrackerPose anchoredLocal;   // held target in the anchor frame
    double lostSince = -1.0;
  };
  bool accept(State& st, const TrackerPose& in, double time);
  void updateHead(const TrackerPose& in, double time, float dt);
  void updateLimb(TrackerId id, const TrackerPose& in, double time, float dt);

  TrackingGuardConfig config_;
  BodyDimensions body_;
  std::array<State, kTrackerCount> state_{};
  GuardedSample out_;
  TrackerPose prevHead_;
  double lastTime_ = 0.0;
  bool primed_ = false;
};

}  // namespace embody::tracking
