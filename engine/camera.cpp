#include "engine/camera.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>

namespace embody::engine {

FovAngles FovAngles::symmetric(float verticalFovRadians, float aspect) {
  const float halfV = verticalFovRadians * 0.5f;
  const float halfH = std::atan(std::tan(halfV) * aspect);
  return {-halfH, halfH, halfV, -halfV};
}

glm::vec3 Camera::position() const { return glm::vec3(glm::inverse(view)[3]); }

glm::mat4 projectionFromFov(const FovAngles& fov, float nearZ, float farZ) {
  const float l = std::tan(fov.angleLeft), r = std::tan(fov.angleRight);
  const float u = std::tan(fov.angleUp), d = std::tan(fov.angleDown);
  glm::mat4 m(0.0f);  // column-major: m[column][row]
  m[0][0] = 2.0f / (r - l);
  m[2][0] = (r + l) / (r - l);
  // Vulkan clip y points down: up (tan u) maps to -1.
  m[1][1] = -2.0f / (u - d);
  m[2][1] = -(u + d) / (u - d);
  m[2][2] = farZ / (nearZ - farZ);
  m[3][2] = nearZ * farZ / (nearZ - farZ);
  m[2][3] = -1.0f;
  return m;
}

Camera orbitCamera(const glm::vec3& target, float distance, float yawRadians, float pitchRadians,
                   const FovAngles& fov, float nearZ, float farZ) {
  const glm::vec3 offset(std::sin(yawRadians) * std::cos(pitchRadians), std::sin(pitchRadians),
                         std::cos(yawRadians) * std::cos(pitchRadians));
  Camera c;
  c.view = glm::lookAt(target + offset * distance, target, glm::vec3(0.0f, 1.0f, 0.0f));
  c.projection = projectionFromFov(fov, nearZ, farZ);
  return c;
}

Camera cameraFromPose(const glm::mat4& eyePose, const FovAngles& fov, float nearZ, float farZ) {
  Camera c;
  c.view = glm::inverse(eyePose);
  c.projection = projectionFromFov(fov, nearZ, farZ);
  return c;
}

std::array<Camera, 2> stereoCameras(const glm::mat4& headPose, float ipdMeters, const FovAngles& leftFov,
                                    const FovAngles& rightFov, float nearZ, float farZ) {
  const glm::mat4 left = glm::translate(headPose, glm::vec3(-0.5f * ipdMeters, 0.0f, 0.0f));
  const glm::mat4 right = glm::translate(headPose, glm::vec3(0.5f * ipdMeters, 0.0f, 0.0f));
  return {cameraFromPose(left, leftFov, nearZ, farZ), cameraFromPose(right, rightFov, nearZ, farZ)};
}

Bounds boundsOf(std::span<const glm::vec3> points) {
  Bounds b;
  for (const auto& p : points) b.add(p);
  return b;
}

float framingDistance(float radius, const FovAngles& fov, float margin) {
  const float halfAngle = std::min({-fov.angleLeft, fov.angleRight, fov.angleUp, -fov.angleDown});
  return margin * radius / std::sin(std::max(halfAngle, 0.05f));
}

}  // namespace embody::engine
