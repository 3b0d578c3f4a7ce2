#pragma once
// The one conversion between the render side's GLM (float) and the IK side's Eigen (double):
// vectors and unit quaternions, component for component (glm::quat is w, x, y, z as Eigen's).
#include <Eigen/Geometry>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace embody::avatar {

inline Eigen::Vector3d toEigen(const glm::vec3& v) { return {v.x, v.y, v.z}; }
inline Eigen::Quaterniond toEigen(const glm::quat& q) { return Eigen::Quaterniond(q.w, q.x, q.y, q.z); }
inline glm::vec3 toGlm(const Eigen::Vector3d& v) { return {float(v.x()), float(v.y()), float(v.z())}; }
inline glm::quat toGlm(const Eigen::Quaterniond& q) { return glm::quat(float(q.w()), float(q.x()), float(q.y()), float(q.z())); }

}  // namespace embody::avatar
