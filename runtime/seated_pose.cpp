#include "runtime/seated_pose.h"

#include <algorithm>
#include <cmath>

namespace embody::runtime {

SeatedPose placeSeat(const SeatedLegs& legs, const Eigen::Vector3d& eye, double yaw, double seatHeight) {
  SeatedPose s;
  const Eigen::Vector3d& up = legs.up;
  const Eigen::Quaterniond heading(Eigen::AngleAxisd(yaw, up));
  const Eigen::Vector3d forward = heading * legs.forward;
  const Eigen::Vector3d restMid = 0.5 * (legs.hip[0] + legs.hip[1]);
  s.yaw = yaw;
  // The hips sit under the eyes as the upright rest trunk has them (a little behind).
  Eigen::Vector3d mid = eye + heading * (restMid - legs.eye);
  const double wanted = seatHeight >= 0.0 ? seatHeight : up.dot(eye) - legs.floor - legs.sittingEyeHeight();
  s.seatHeight = std::clamp(wanted, legs.minSeatHeight(), legs.maxSeatHeight());
  mid += up * (legs.floor + s.seatHeight + legs.hipAboveSeat - up.dot(mid));
  s.seat = mid - up * legs.hipAboveSeat;
  s.pelvisRotation = heading * legs.pelvisRotation;
  for (size_t i = 0; i < 2; ++i) {
    const int side = int(i);
    s.hip[i] = mid + heading * (legs.hip[i] - restMid);
    // The shin vertical, the ankle at its rest height; the thigh slopes from the hip joint down
    // (high seat) or up (low seat) to the knee, at most 30 degrees (|drop| <= thigh / 2).
    const double thigh = legs.thigh(side), shin = legs.shin(side);
    const double kneeHeight = legs.ankleHeight(side) + shin;
    const double drop = std::clamp(up.dot(s.hip[i]) - legs.floor - kneeHeight, -0.5 * thigh, 0.5 * thigh);
    s.knee[i] = s.hip[i] + forward * std::sqrt(thigh * thigh - drop * drop) - up * drop;
    s.ankle[i] = s.knee[i] - up * shin;
    s.footRotation[i] = heading * legs.footRotation[i];
  }
  return s;
}

}  // namespace embody::runtime
