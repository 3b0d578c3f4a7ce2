#include "runtime/body_heading.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace embody::runtime {

double BodyHeading::update(double headYaw, double band) {
  if (!initialised_ || !std::isfinite(yaw_)) {
    yaw_ = headYaw;
    initialised_ = true;
    return yaw_;
  }
  const double away = std::remainder(headYaw - yaw_, 2.0 * std::numbers::pi);
  const double kept = std::clamp(away, -std::max(0.0, band), std::max(0.0, band));
  yaw_ = std::remainder(headYaw - kept, 2.0 * std::numbers::pi);
  return yaw_;
}

}  // namespace embody::runtime
