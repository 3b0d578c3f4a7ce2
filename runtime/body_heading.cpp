#include "runtime/body_heading.h"

#include <algorithm>
#include <cmath>

#include "runtime/foot_planner.h"

namespace embody::runtime {

double BodyHeading::smoothedHeadYaw(double headYaw, double time) {
  const double dt = time - lastTime_;
  if (config_.smoothed && dt == 0.0) return smoothYaw_;  // the same instant again
  lastTime_ = time;
  if (!config_.smoothed || !(dt > 0.0) || dt >= 0.5) {
    // Off, time running backwards, or a gap: the head's as it is.
    smoothYaw_ = rawYaw_ = headYaw;
    rate_ = 0.0;
    return smoothYaw_;
  }
  const auto& p = config_.smoothing;
  const double rawRate = wrapAngle(headYaw - rawYaw_) / dt;
  rawYaw_ = headYaw;
  rate_ += tracking::oneEuroAlpha(p.derivativeCutoff, float(dt)) * (rawRate - rate_);
  const double cutoff = p.minCutoff + p.beta * std::abs(rate_);
  smoothYaw_ = wrapAngle(smoothYaw_ + tracking::oneEuroAlpha(float(cutoff), float(dt)) * wrapAngle(headYaw - smoothYaw_));
  return smoothYaw_;
}

double BodyHeading::update(double headYaw, double neckTurn, double time) {
  if (!initialised_ || !std::isfinite(yaw_) || !std::isfinite(smoothYaw_)) {
    yaw_ = smoothYaw_ = rawYaw_ = headYaw;
    rate_ = 0.0;
    lastTime_ = time;
    initialised_ = true;
    return yaw_;
  }
  const double head = smoothedHeadYaw(headYaw, time);
  const double slack = std::max(0.0, neckTurn);
  yaw_ = wrapAngle(head - std::clamp(wrapAngle(head - yaw_), -slack, slack));
  return yaw_;
}

}  // namespace embody::runtime
