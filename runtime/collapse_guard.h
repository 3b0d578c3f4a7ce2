#pragma once
// Notices a body the solver has left in a heap, so the solver can stand it up again.
//
// A warm-started local solver keeps whatever configuration it reached: after a bad frame (a
// tracking glitch, a target it could not follow, a cold start far away) it can settle folded
// over, sitting on the floor or with its legs crossed, and stay there although the targets stop
// moving. Each frame the solver measures its body (BodySignals) and this guard says whether to
// re-seed it from a standing pose under the head (body_seed.h):
//
//   NonFinite     the configuration is not finite                      (at once)
//   Stalled       the head or a reachable hand is far off its target and its error has not
//                 fallen by `stallImprovement` for `stallSeconds` and `stallIterations`
//   PelvisLow     the pelvis is below `pelvisLowFraction` of its standing height while the head
//                 target is high (no crouch signal)
//   Folded        the pelvis is tilted more than `foldedRadians` from upright while the head
//                 target is high (no bow deep enough to ask for it)
//   ThroughFloor  a knee, the pelvis or the head is below the floor by `floorPenetration`
//   CrossedLegs   with inferred legs, a knee or an ankle is on the other leg's side
//   Diverged      the head or a reachable hand is more than `divergedResidual` off its target,
//                 having been within it since the last recovery: the body is being dragged away
//                 (in three-point mode by planted feet it cannot reach from the head), which the
//                 stall window would leave for half a second while the error grows. A target the
//                 body never reached (a head on the floor, one far out of reach) is a stall.
// A condition other than NonFinite must hold for `confirmSeconds`; after a recovery the guard
// waits `cooldownSeconds` (the re-seeded body needs a few frames to reach its targets), but only
// `divergedCooldownSeconds` for Diverged: a re-seeded body is on its targets within the fade, and
// one dragged off them again is a new failure that the full wait would leave growing.
// Distances are at the avatar's scale (`BodySignals::scale` = avatar height / 1.75 m).
#include <cstdint>
#include <string_view>

namespace embody::runtime {

struct CollapseGuardConfig {
  double confirmSeconds = 0.1;
  double stallSeconds = 0.5;
  double stallResidual = 0.10;    // m: errors below this never count as a stall
  double stallImprovement = 0.2;  // the error must fall by this fraction per stallSeconds ...
  int stallIterations = 60;       // ... and per this many solver iterations (a slow frame rate or
                                  // a tight budget gives the solver fewer: that is no stall)
  double pelvisLowFraction = 0.5;
  double crouchHeadFraction = 0.75;  // a head target above this fraction of the eye height: no crouch
  double foldedRadians = 1.3;        // ~75 degrees
  double floorPenetration = 0.05;    // m
  double crossMargin = 0.02;         // m
  double divergedResidual = 0.2;     // m
  double cooldownSeconds = 1.0;
  double divergedCooldownSeconds = 0.3;
  bool enabled = true;
};

// One frame's measures of the solved body (avatar space, heights above the floor).
struct BodySignals {
  double time = 0.0;
  bool finite = true;
  double scale = 1.0;
  double pelvisHeight = 0.0, standingPelvisHeight = 0.0;
  double headTargetHeight = 0.0, standingEyeHeight = 0.0;
  double pelvisTilt = 0.0;           // radians from upright
  double lowestTrunkOrKnee = 0.0;    // the lowest of the knees, the pelvis and the head
  double legSeparation = 0.0;        // min over knees and ankles of (left - right), across the feet's heading
  bool inferredLegs = false;         // crossing counts only for legs the runtime places
  double residual = 0.0;             // the worst of the head's and the reachable hands' errors (the
                                     // head's less what a target above standing height explains)
  int iterations = 0;                // solver iterations this frame
};

// The part of the head's error a body could fix: all of it while the head target is no higher
// than standing allows (2 % over the standing eye height), less the excess above that otherwise
// (a taller user, the top of a jump).
double fixableHeadError(double error, double headTargetHeight, double standingEyeHeight);

enum class CollapseReason : uint8_t { None, NonFinite, Stalled, PelvisLow, Folded, ThroughFloor, CrossedLegs, Diverged };
std::string_view collapseReasonName(CollapseReason reason);

class CollapseGuard {
 public:
  explicit CollapseGuard(const CollapseGuardConfig& config = {}) : config_(config) {}
  // The body's condition this frame (None when it looks like a body).
  CollapseReason assess(const BodySignals& s) const;
  // Feeds one frame; returns the reason to re-seed now (None: keep solving). Counts a recovery
  // when it returns one.
  CollapseReason update(const BodySignals& s);
  void reset();  // forgets timers (not the counters)
  int recoveries() const { return recoveries_; }
  int collapsedFrames() const { return collapsedFrames_; }  // frames assessed as collapsed
  CollapseReason lastReason() const { return lastReason_; }
  const CollapseGuardConfig& config() const { return config_; }

 private:
  bool stalled(const BodySignals& s);
  bool diverged(const BodySignals& s) const;
  CollapseGuardConfig config_;
  bool onTargets_ = false;  // the error has been within divergedResidual since the last recovery
  double conditionSince_ = -1.0, stallSince_ = -1.0, stallReference_ = 0.0, lastRecovery_ = -1e9;
  int stallIterations_ = 0;
  int recoveries_ = 0, collapsedFrames_ = 0;
  CollapseReason lastReason_ = CollapseReason::None;
};

}  // namespace embody::runtime
