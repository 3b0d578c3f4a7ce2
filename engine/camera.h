#pragma once
// Cameras for the three views: third-person orbit, first-person at the eyes, and stereo eyes
// with asymmetric frusta given the way OpenXR gives them (XrFovf angles, radians). Projections
// are Vulkan clip space directly: right-handed view looking down -Z, clip y pointing down, depth
// 0 (near) .. 1 (far).
#include <array>
#include <glm/glm.hpp>
#include <span>

namespace embody::engine {

// Same meaning and signs as XrFovf: angleLeft and angleDown are usually negative.
struct FovAngles {
  float angleLeft = -0.785398f;
  float angleRight = 0.785398f;
  float angleUp = 0.785398f;
  float angleDown = -0.785398f;
  static FovAngles symmetric(float verticalFovRadians, float aspect);
};

struct Camera {
  glm::mat4 view{1.0f};        // world -> eye
  glm::mat4 projection{1.0f};  // eye -> Vulkan clip
  glm::vec3 position() const;  // world-space eye position
  glm::mat4 viewProjection() const { return projection * view; }
};

glm::mat4 projectionFromFov(const FovAngles& fov, float nearZ, float farZ);

// Looks at `target` from `distance` away; yaw 0 looks along -Z from +Z (the glTF front),
// positive pitch looks down on the target.
Camera orbitCamera(const glm::vec3& target, float distance, float yawRadians, float pitchRadians,
                   const FovAngles& fov, float nearZ = 0.05f, float farZ = 100.0f);

// A camera whose world pose (rotation + translation, no scale) is `eyePose`; it looks down the
// pose's -Z, like an OpenXR view pose.
Camera cameraFromPose(const glm::mat4& eyePose, const FovAngles& fov, float nearZ = 0.05f, float farZ = 100.0f);

// Two eyes of a head pose: each eye sits ipd/2 along the head's local X and gets its own fov.
std::array<Camera, 2> stereoCameras(const glm::mat4& headPose, float ipdMeters, const FovAngles& leftFov,
                                    const FovAngles& rightFov, float nearZ = 0.05f, float farZ = 100.0f);

struct Bounds {
  glm::vec3 min{1e30f}, max{-1e30f};
  void add(const glm::vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  bool empty() const { return min.x > max.x; }
  glm::vec3 center() const { return (min + max) * 0.5f; }
  float radius() const { return empty() ? 0.0f : glm::length(max - min) * 0.5f; }
};
Bounds boundsOf(std::span<const glm::vec3> points);

// Distance at which a sphere of `radius` fills a view of fov `fov` (the narrower axis), with margin.
float framingDistance(float radius, const FovAngles& fov, float margin = 1.1f);

}  // namespace embody::engine
