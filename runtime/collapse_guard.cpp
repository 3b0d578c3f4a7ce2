#include "runtime/collapse_guard.h"

#include <algorithm>
#include <cmath>

#include "core/enum_names.h"

namespace embody::runtime {

constexpr EnumName<CollapseReason> kCollapseReasonNames[] = {{CollapseReason::None, "none"},
                                                             {CollapseReason::NonFinite, "non_finite"},
                                                             {CollapseReason::Stalled, "stalled"},
                                                             {CollapseReason::PelvisLow, "pelvis_low"},
                                                             {CollapseReason::Folded, "folded"},
                                                             {CollapseReason::ThroughFloor, "through_floor"},
                                                             {CollapseReason::CrossedLegs, "crossed_legs"},
                                                             {CollapseReason::Diverged, "diverged"}};

std::string_view collapseReasonName(CollapseReason reason) {
  return enumName(kCollapseReasonNames, reason);
}

double fixableHeadError(double error, double headTargetHeight, double standingEyeHeight) {
  return std::max(0.0, error - std::max(0.0, headTargetHeight - 1.02 * standingEyeHeight));
}

CollapseReason CollapseGuard::assess(const BodySignals& s) const {
  if (!s.finite) return CollapseReason::NonFinite;
  if (diverged(s)) return CollapseReason::Diverged;
  const bool headHigh = s.headTargetHeight > config_.crouchHeadFraction * s.standingEyeHeight;
  if (s.lowestTrunkOrKnee < -config_.floorPenetration * s.scale) return CollapseReason::ThroughFloor;
  if (headHigh && s.pelvisHeight < config_.pelvisLowFraction * s.standingPelvisHeight) return CollapseReason::PelvisLow;
  if (headHigh && s.pelvisTilt > config_.foldedRadians) return CollapseReason::Folded;
  if (s.inferredLegs && s.legSeparation < -config_.crossMargin * s.scale) return CollapseReason::CrossedLegs;
  return CollapseReason::None;
}

bool CollapseGuard::diverged(const BodySignals& s) const {
  return onTargets_ && s.residual > config_.divergedResidual * s.scale;
}

bool CollapseGuard::stalled(const BodySignals& s) {
  if (!(s.residual > config_.stallResidual * s.scale)) {
    stallSince_ = -1.0;
    return false;
  }
  if (stallSince_ < 0.0 || s.residual < (1.0 - config_.stallImprovement) * stallReference_) {
    stallSince_ = s.time;  // a new window: the error is falling (or just rose above the threshold)
    stallReference_ = s.residual;
    stallIterations_ = 0;
    return false;
  }
  stallIterations_ += s.iterations;
  return s.time - stallSince_ >= config_.stallSeconds && stallIterations_ >= config_.stallIterations;
}

CollapseReason CollapseGuard::update(const BodySignals& s) {
  if (s.residual <= config_.divergedResidual * s.scale) onTargets_ = true;
  CollapseReason reason = assess(s);
  if (reason != CollapseReason::None) ++collapsedFrames_;
  const bool isStalled = stalled(s);
  if (!config_.enabled) return CollapseReason::None;
  if (reason == CollapseReason::NonFinite) {
    conditionSince_ = -1.0;
  } else {
    if (reason == CollapseReason::None && isStalled) reason = CollapseReason::Stalled;
    if (reason == CollapseReason::None) {
      conditionSince_ = -1.0;
      return reason;
    }
    if (conditionSince_ < 0.0) conditionSince_ = s.time;
    const bool confirmed = reason == CollapseReason::Stalled || s.time - conditionSince_ >= config_.confirmSeconds;
    const double cooldown = reason == CollapseReason::Diverged ? config_.divergedCooldownSeconds : config_.cooldownSeconds;
    if (!confirmed || s.time - lastRecovery_ < cooldown) return CollapseReason::None;
  }
  lastRecovery_ = s.time;
  conditionSince_ = -1.0;
  stallSince_ = -1.0;
  onTargets_ = false;
  ++recoveries_;
  lastReason_ = reason;
  return reason;
}

void CollapseGuard::reset() {
  onTargets_ = false;
  conditionSince_ = -1.0;
  stallSince_ = -1.0;
  lastRecovery_ = -1e9;
}

}  // namespace embody::runtime
