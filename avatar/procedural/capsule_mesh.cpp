#include "avatar/procedural/capsule_mesh.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/constants.hpp>

namespace embody::avatar {

namespace {

constexpr int kSlices = 10, kHalfRings = 4;

// A capsule from a to b (model space), all vertices on `joint`.
void addCapsule(SkinnedMesh& mesh, const glm::vec3& a, const glm::vec3& b, float radius, uint32_t joint) {
  const glm::vec3 axis = b - a;
  const float length = glm::length(axis);
  const glm::vec3 w = axis / length;
  const glm::vec3 helper = std::abs(w.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
  const glm::vec3 u = glm::normalize(glm::cross(helper, w)), v = glm::cross(w, u);
  const auto first = uint32_t(mesh.vertices.size());
  const int rings = 2 * kHalfRings + 2;  // south cap, two equator rings (one per end), north cap
  for (int r = 0; r < rings; ++r) {
    const bool north = r > kHalfRings;
    const int k = north ? r - 1 : r;  // latitude step 0 .. 2*kHalfRings
    const float lat = -glm::half_pi<float>() + glm::pi<float>() * float(k) / float(2 * kHalfRings);
    const glm::vec3 centre = north ? b : a;
    for (int s = 0; s <= kSlices; ++s) {
      const float lon = glm::two_pi<float>() * float(s) / float(kSlices);
      const glm::vec3 n = std::cos(lat) * (std::cos(lon) * u + std::sin(lon) * v) + std::sin(lat) * w;
      SkinnedVertex vert;
      vert.position = centre + radius * n;
      vert.normal = n;
      vert.uv = glm::vec2(float(s) / float(kSlices), float(r) / float(rings - 1));
      vert.joints0 = glm::uvec4(joint, 0, 0, 0);
      vert.weights0 = glm::vec4(1, 0, 0, 0);
      mesh.vertices.push_back(vert);
    }
  }
  for (int r = 0; r + 1 < rings; ++r)
    for (int s = 0; s < kSlices; ++s) {
      const uint32_t i0 = first + uint32_t(r * (kSlices + 1) + s), i1 = i0 + 1;
      const uint32_t j0 = i0 + uint32_t(kSlices + 1), j1 = j0 + 1;
      mesh.indices.insert(mesh.indices.end(), {i0, i1, j1, i0, j1, j0});
    }
}

}  // namespace

void buildCapsuleMesh(AvatarAsset& asset, float stature, int bodyRoot) {
  const Skeleton& sk = asset.skeleton;
  std::vector<glm::mat4> globals;
  computeGlobals(sk, SkeletonPose::rest(sk), globals);
  std::vector<bool> aboveBody(sk.joints.size(), false);
  if (bodyRoot >= 0 && size_t(bodyRoot) < sk.joints.size())
    for (int a = sk.joints[size_t(bodyRoot)].parent; a >= 0; a = sk.joints[size_t(a)].parent) aboveBody[size_t(a)] = true;
  SkinnedMesh& mesh = asset.mesh;
  mesh = {};
  for (size_t j = 0; j < sk.joints.size(); ++j) {
    const int parent = sk.joints[j].parent;
    if (parent < 0 || aboveBody[size_t(parent)]) continue;
    const glm::vec3 a(globals[size_t(parent)][3]), b(globals[j][3]);
    const float length = glm::length(b - a);
    if (length < 1e-3f) continue;
    const float radius = std::clamp(0.25f * length, 0.006f * stature, 0.035f * stature);
    addCapsule(mesh, a, b, radius, uint32_t(parent));
  }
  mesh.inverseBind.resize(sk.joints.size());
  for (size_t j = 0; j < sk.joints.size(); ++j) mesh.inverseBind[j] = glm::inverse(globals[j]);
  mesh.primitives = {Primitive{0, uint32_t(mesh.indices.size()), 0, -1, -1}};
  asset.materials = {Material{"capsules", glm::vec4(0.72f, 0.74f, 0.78f, 1.0f)}};
  asset.skinJointCount = int(sk.joints.size());
}

}  // namespace embody::avatar
