#include "runtime/pole_tasks.h"

#include <algorithm>
#include <cmath>
#include <Eigen/Geometry>

namespace embody::runtime {

Eigen::Vector3d poleTarget(const Eigen::Vector3d& root, const Eigen::Vector3d& end, const LimbGeometry& limb,
                           const Eigen::Vector3d& pole, const Eigen::Vector3d& fallback, double maxExtension) {
  const Eigen::Vector3d line = end - root;
  const double length = line.norm();
  const double reach = limb.upper + limb.lower;
  if (!(length > 1e-6) || !(reach > 1e-6)) return root + (pole.norm() > 1e-9 ? pole.normalized() : fallback) * limb.upper;
  const Eigen::Vector3d axis = line / length;
  Eigen::Vector3d side = pole - axis * axis.dot(pole);
  if (side.norm() < 1e-3 * std::max(1.0, pole.norm())) side = fallback - axis * axis.dot(fallback);
  if (side.norm() < 1e-9) side = axis.unitOrthogonal();
  side.normalize();
  // The circle of middle-joint places: centre at `a` along the line, radius r.
  const double d = std::clamp(length, std::abs(limb.upper - limb.lower) + 1e-6, maxExtension * reach);
  const double a = (limb.upper * limb.upper - limb.lower * limb.lower + d * d) / (2.0 * d);
  const double r = std::sqrt(std::max(0.0, limb.upper * limb.upper - a * a));
  return root + axis * a + side * r;
}

Eigen::Vector3d elbowPole(const Eigen::Vector3d& up, const Eigen::Vector3d& forward, const Eigen::Vector3d& outward,
                          const Eigen::Vector3d& palmNormal, const Eigen::Vector3d& shoulderToHand) {
  // Palm down (pronated): the elbow goes out; palm up or facing in: it hangs.
  const double palmDown = std::max(0.0, -palmNormal.normalized().dot(up));
  // A hand above the shoulder lifts the elbow sideways (the arm abducts rather than flexes).
  const double n = shoulderToHand.norm();
  const double raised = n > 1e-6 ? std::max(0.0, shoulderToHand.dot(up) / n) : 0.0;
  return -up + outward * (0.3 + 0.6 * palmDown + 0.7 * raised) - forward * 0.3;
}

}  // namespace embody::runtime
