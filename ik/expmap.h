#pragma once
// Exponential-map rotations (Grassia 1998, "Practical parameterization of rotations using the
// exponential map"): rotation, its exact derivative, and the re-parameterisation near |v| = π.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace embody::ik {

// R = exp([v]x), Rodrigues' formula with a Taylor series near 0.
Eigen::Matrix3d expMapRotation(const Eigen::Vector3d& v);

// The left (spatial) Jacobian of SO(3): for R(v) = exp(v), the angular velocity expressed in the
// frame R acts in is  ω = leftJacobian(v) * dv/dt. Exact (not the small-angle identity):
//   J(v) = I + (1 - cos θ)/θ² [v]x + (θ - sin θ)/θ³ [v]x²,  θ = |v|   (series near θ = 0).
Eigen::Matrix3d leftJacobian(const Eigen::Vector3d& v);

// log: the rotation vector of R with |v| <= π.
Eigen::Vector3d rotationLog(const Eigen::Matrix3d& rotation);

// Grassia's re-parameterisation: when |v| > π, v and (1 - 2π/|v|) v are the same rotation and
// the latter has |v'| = 2π - |v| < π, keeping away from the singular shell |v| = 2π.
// Returns true when it changed v.
bool reparameterizeExpMap(Eigen::Vector3d& v);

}  // namespace embody::ik
