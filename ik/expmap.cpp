#include "ik/expmap.h"

#include <cmath>
#include <numbers>

namespace embody::ik {
namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace

Eigen::Matrix3d expMapRotation(const Eigen::Vector3d& v) {
  const double t2 = v.squaredNorm();
  const Eigen::Matrix3d k = skew(v);
  double a, b;  // sin θ / θ and (1 - cos θ) / θ²
  if (t2 < 1e-8) {
    a = 1.0 - t2 / 6.0 + t2 * t2 / 120.0;
    b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
  } else {
    const double t = std::sqrt(t2);
    a = std::sin(t) / t;
    b = (1.0 - std::cos(t)) / t2;
  }
  return Eigen::Matrix3d::Identity() + a * k + b * k * k;
}

Eigen::Matrix3d leftJacobian(const Eigen::Vector3d& v) {
  const double t2 = v.squaredNorm();
  const Eigen::Matrix3d k = skew(v);
  double b, c;  // (1 - cos θ)/θ² and (θ - sin θ)/θ³
  if (t2 < 1e-6) {
    b = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
    c = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0;
  } else {
    const double t = std::sqrt(t2);
    b = (1.0 - std::cos(t)) / t2;
    c = (t - std::sin(t)) / (t2 * t);
  }
  return Eigen::Matrix3d::Identity() + b * k + c * k * k;
}

Eigen::Vector3d rotationLog(const Eigen::Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

bool reparameterizeExpMap(Eigen::Vector3d& v) {
  const double t = v.norm();
  if (!(t > std::numbers::pi)) return false;
  v *= 1.0 - 2.0 * std::numbers::pi / t;
  return true;
}

}  // namespace embody::ik
