#include "runtime/body_heading.h"

#include <algorithm>
#include <cmath>

#include "runtime/foot_planner.h"

namespace embody::runtime {

double BodyHeading::update(double headYaw, double neckTurn) {
  if (!initialised_ || !std::isfinite(yaw_)) {
    yaw_ = headYaw;
    initialised_ = true;
    return yaw_;
  }
  const double slack = std::max(0.0, neckTurn);
  yaw_ = wrapAngle(headYaw - std::clamp(wrapAngle(headYaw - yaw_), -slack, slack));
  return yaw_;
}

}  // namespace embody::runtime
