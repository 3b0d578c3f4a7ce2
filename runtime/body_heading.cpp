#include "runtime/body_heading.h"

#include <algorithm>
#include <cmath>

#include "core/smoothstep.h"
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

double BodyHeading::facingTravel(double yaw, const Eigen::Vector3d& travel, double walking, const Eigen::Vector3d& up,
                                 const Eigen::Vector3d& forward, double scale) const {
  const double speed = std::hypot(travel.dot(forward), travel.dot(up.cross(forward))) / std::max(scale, 1e-9);
  if (!(walking > 0.0) || !(speed > config_.noSpeed) || !std::isfinite(yaw)) return yaw;
  const double off = wrapAngle(headingOfDirection(travel, up, forward) - yaw);
  const double bySpeed = smoothstep((speed - config_.noSpeed) / (config_.fullSpeed - config_.noSpeed));
  const double byDirection = 1.0 - smoothstep((std::abs(off) - config_.fullWithin) / (config_.noneBeyond - config_.fullWithin));
  return wrapAngle(yaw + std::min(walking, 1.0) * bySpeed * byDirection * off);
}

}  // namespace embody::runtime
