#include "tests/support/test_avatar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <numbers>
#include <numeric>

namespace embody::test {

namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr int kSpineJoints = 5;
constexpr float kSpineBase = 0.2f, kSpineStep = 0.3f;
constexpr int kHeadMaterial = 1;

struct Builder {
  avatar::AvatarAsset& a;
  uint32_t begin() const { return static_cast<uint32_t>(a.mesh.indices.size()); }
  void primitive(uint32_t first, int material) {
    a.mesh.primitives.push_back({first, begin() - first, material});
  }
  uint32_t vertex(const glm::vec3& p, const glm::vec3& n, const glm::vec2& uv, int joint) {
    avatar::SkinnedVertex v;
    v.position = p;
    v.normal = n;
    v.uv = uv;
    v.joints0 = glm::uvec4(uint32_t(joint), 0, 0, 0);
    v.weights0 = glm::vec4(1.0f, 0.0f, 0.0f, 0.0f);
    a.mesh.vertices.push_back(v);
    return static_cast<uint32_t>(a.mesh.vertices.size() - 1);
  }
  void tri(uint32_t i, uint32_t j, uint32_t k) { a.mesh.indices.insert(a.mesh.indices.end(), {i, j, k}); }
  // Axis-aligned box around `c` rigidly on `joint` (outward normals, counter-clockwise faces).
  void box(const glm::vec3& c, const glm::vec3& half, int joint) {
    for (int axis = 0; axis < 3; ++axis)
      for (int sign = -1; sign <= 1; sign += 2) {
        glm::vec3 n(0.0f);
        n[axis] = float(sign);
        const glm::vec3 u = glm::vec3(n.y, n.z, n.x) * float(sign), w = glm::cross(n, u);
        uint32_t base = 0;
        for (int k = 0; k < 4; ++k) {
          const float su = (k == 1 || k == 2) ? 1.0f : -1.0f, sw = (k >= 2) ? 1.0f : -1.0f;
          const uint32_t idx = vertex(c + half * (n + u * su + w * sw), n, glm::vec2(su, sw) * 0.5f + 0.5f, joint);
          if (k == 0) base = idx;
        }
        tri(base, base + 1, base + 2);
        tri(base, base + 2, base + 3);
      }
  }
};

avatar::Image checker(int size, int cells, glm::u8vec4 a, glm::u8vec4 b) {
  avatar::Image img;
  img.width = img.height = size;
  img.rgba.resize(size_t(size) * size * 4);
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const bool odd = ((x * cells / size) + (y * cells / size)) % 2;
      const glm::u8vec4 c = odd ? b : a;
      std::copy(&c.x, &c.x + 4, &img.rgba[(size_t(y) * size + x) * 4]);
    }
  return img;
}

// root, spine0..4 (up +Y), head on the top, hands on spine3. Returns {head, leftHand, rightHand}.
std::array<int, 3> addTestSkeleton(avatar::Skeleton& skeleton) {
  auto& joints = skeleton.joints;
  joints.push_back({"root", -1, {}});
  for (int i = 0; i < kSpineJoints; ++i) {
    avatar::Transform t;
    t.translation = glm::vec3(0.0f, i == 0 ? kSpineBase : kSpineStep, 0.0f);
    joints.push_back({"spine" + std::to_string(i), i, t});
  }
  const int spineTop = kSpineJoints;  // joint index of spine4
  avatar::Transform headT;
  headT.translation = glm::vec3(0.0f, 0.25f, 0.0f);
  joints.push_back({"head", spineTop, headT});
  const int head = int(joints.size()) - 1;
  avatar::Transform lh, rh;
  lh.translation = glm::vec3(0.35f, -0.1f, 0.0f);
  rh.translation = glm::vec3(-0.35f, -0.1f, 0.0f);
  joints.push_back({"leftHand", spineTop - 1, lh});
  joints.push_back({"rightHand", spineTop - 1, rh});
  return {head, int(joints.size()) - 2, int(joints.size()) - 1};
}

// Checker textures and the five materials: body, head, fin (BLEND), flag (MASK), hands.
void addTestMaterials(avatar::AvatarAsset& a) {
  a.images.push_back(checker(64, 8, {220, 120, 60, 255}, {240, 220, 190, 255}));  // body
  a.images.push_back(checker(32, 4, {60, 170, 90, 255}, {0, 0, 0, 0}));           // flag: holes
  a.materials.push_back({.name = "body", .baseColorFactor = glm::vec4(1.0f), .baseColorImage = 0});
  a.materials.push_back({.name = "head", .baseColorFactor = glm::vec4(0.85f, 0.7f, 0.6f, 1.0f)});
  a.materials.push_back({.name = "fin",
                         .baseColorFactor = glm::vec4(0.2f, 0.5f, 1.0f, 0.45f),
                         .alphaMode = avatar::AlphaMode::Blend,
                         .doubleSided = true});
  a.materials.push_back({.name = "flag",
                         .baseColorFactor = glm::vec4(1.0f),
                         .baseColorImage = 1,
                         .alphaMode = avatar::AlphaMode::Mask,
                         .doubleSided = true});
  a.materials.push_back({.name = "hands", .baseColorFactor = glm::vec4(0.3f, 0.3f, 0.35f, 1.0f)});
}

constexpr float kTubeTop = kSpineBase + kSpineStep * (kSpineJoints - 1) + 0.25f;

// Tube: rings along y, each vertex weighted by a Gaussian of its distance to the spine joints.
void addTestTube(Builder& b, const TestAvatarOptions& o) {
  avatar::AvatarAsset& a = b.a;
  const float radius = 0.12f, y0 = kSpineBase, y1 = kTubeTop;
  const uint32_t first = b.begin();
  const uint32_t tubeBase = static_cast<uint32_t>(a.mesh.vertices.size());
  for (int r = 0; r <= o.rings; ++r) {
    const float t = float(r) / float(o.rings), y = y0 + (y1 - y0) * t;
    std::array<float, kSpineJoints> w{};
    for (int j = 0; j < kSpineJoints; ++j) {
      const float d = (y - (kSpineBase + kSpineStep * float(j))) / 0.22f;
      w[j] = std::exp(-0.5f * d * d);
    }
    const float sum = std::accumulate(w.begin(), w.end(), 0.0f);
    for (int s = 0; s <= o.segments; ++s) {
      const float phi = 2.0f * kPi * float(s) / float(o.segments);
      const glm::vec3 n(std::sin(phi), 0.0f, std::cos(phi));
      avatar::SkinnedVertex v;
      v.position = glm::vec3(0.0f, y, 0.0f) + radius * n;
      v.normal = n;
      v.uv = glm::vec2(float(s) / float(o.segments) * 2.0f, t * 4.0f);
      // Spine joints 0..4 are skeleton joints 1..5: four in JOINTS_0, the fifth in JOINTS_1.
      v.joints0 = glm::uvec4(1, 2, 3, 4);
      v.joints1 = glm::uvec4(5, 0, 0, 0);
      v.weights0 = glm::vec4(w[0], w[1], w[2], w[3]) / sum;
      v.weights1 = glm::vec4(w[4] / sum, 0.0f, 0.0f, 0.0f);
      a.mesh.vertices.push_back(v);
    }
  }
  const uint32_t stride = uint32_t(o.segments) + 1;
  for (int r = 0; r < o.rings; ++r)
    for (int s = 0; s < o.segments; ++s) {
      const uint32_t i0 = tubeBase + uint32_t(r) * stride + uint32_t(s), i1 = i0 + 1, i2 = i0 + stride, i3 = i2 + 1;
      b.tri(i0, i1, i3);  // counter-clockwise seen from outside
      b.tri(i0, i3, i2);
    }
  b.primitive(first, 0);
}

// Head: a UV sphere rigidly on the head joint, with a nose so that the facing direction (+Z, the
// glTF front) is visible.
void addTestHead(Builder& b, int head) {
  const uint32_t first = b.begin();
  const glm::vec3 headCenter(0.0f, kTubeTop + 0.16f, 0.0f);
  const float headRadius = 0.17f;
  const int lat = 12, lon = 18;
  const uint32_t headBase = static_cast<uint32_t>(b.a.mesh.vertices.size());
  for (int i = 0; i <= lat; ++i) {
    const float theta = kPi * float(i) / float(lat);
    for (int j = 0; j <= lon; ++j) {
      const float phi = 2.0f * kPi * float(j) / float(lon);
      const glm::vec3 n(std::sin(theta) * std::sin(phi), std::cos(theta), std::sin(theta) * std::cos(phi));
      b.vertex(headCenter + headRadius * n, n, glm::vec2(float(j) / lon, float(i) / lat), head);
    }
  }
  for (int i = 0; i < lat; ++i)
    for (int j = 0; j < lon; ++j) {
      const uint32_t i0 = headBase + uint32_t(i * (lon + 1) + j), i1 = i0 + 1, i2 = i0 + uint32_t(lon + 1), i3 = i2 + 1;
      b.tri(i0, i2, i3);
      b.tri(i0, i3, i1);
    }
  b.box(headCenter + glm::vec3(0.0f, 0.0f, headRadius), glm::vec3(0.03f, 0.03f, 0.05f), head);
  b.primitive(first, kHeadMaterial);
}

// A quad of one material on one joint (both faces drawn by the material).
void addQuad(Builder& b, glm::vec3 c, glm::vec3 u, glm::vec3 v, int joint, int material) {
  const uint32_t f = b.begin();
  const glm::vec3 n = glm::normalize(glm::cross(u, v));
  const uint32_t q0 = b.vertex(c - u - v, n, {0, 0}, joint), q1 = b.vertex(c + u - v, n, {1, 0}, joint);
  const uint32_t q2 = b.vertex(c + u + v, n, {1, 1}, joint), q3 = b.vertex(c - u + v, n, {0, 1}, joint);
  b.tri(q0, q1, q2);
  b.tri(q0, q2, q3);
  b.primitive(f, material);
}

// First person: every primitive but the head's.
void addFirstPersonList(avatar::SkinnedMesh& mesh) {
  for (const auto& p : mesh.primitives) {
    if (p.material == kHeadMaterial) continue;
    avatar::Primitive fp = p;
    fp.firstIndex = static_cast<uint32_t>(mesh.firstPersonIndices.size());
    mesh.firstPersonIndices.insert(mesh.firstPersonIndices.end(), mesh.indices.begin() + p.firstIndex,
                                   mesh.indices.begin() + p.firstIndex + p.indexCount);
    mesh.firstPersonPrimitives.push_back(fp);
  }
}

}  // namespace

avatar::AvatarAsset makeTestAvatar(const TestAvatarOptions& o) {
  avatar::AvatarAsset a;
  a.format = avatar::AvatarFormat::Procedural;
  const auto [head, leftHand, rightHand] = addTestSkeleton(a.skeleton);
  addTestMaterials(a);
  Builder b{a};
  addTestTube(b, o);
  addTestHead(b, head);
  // Hands: small blocks.
  const uint32_t first = b.begin();
  b.box(glm::vec3(0.35f, kSpineBase + kSpineStep * 3 - 0.1f, 0.0f), glm::vec3(0.05f, 0.08f, 0.03f), leftHand);
  b.box(glm::vec3(-0.35f, kSpineBase + kSpineStep * 3 - 0.1f, 0.0f), glm::vec3(0.05f, 0.08f, 0.03f), rightHand);
  b.primitive(first, 4);
  // Fin (BLEND) on the back and flag (MASK) on the side, both skinned to a mid-spine joint.
  addQuad(b, glm::vec3(0.0f, 0.8f, -0.25f), glm::vec3(0.0f, 0.0f, 0.13f), glm::vec3(0.0f, 0.3f, 0.0f), 3, 2);
  addQuad(b, glm::vec3(0.0f, 1.25f, 0.14f), glm::vec3(0.2f, 0.0f, 0.0f), glm::vec3(0.0f, 0.12f, 0.0f), 4, 3);
  addFirstPersonList(a.mesh);
  // Inverse bind matrices from the rest pose.
  std::vector<glm::mat4> globals;
  avatar::computeGlobals(a.skeleton, avatar::SkeletonPose::rest(a.skeleton), globals);
  for (const auto& g : globals) a.mesh.inverseBind.push_back(glm::inverse(g));
  a.skinJointCount = static_cast<int>(a.skeleton.joints.size());
  return a;
}

avatar::SkeletonPose bentTestPose(const avatar::Skeleton& skeleton, float bend) {
  avatar::SkeletonPose pose = avatar::SkeletonPose::rest(skeleton);
  for (size_t j = 0; j < skeleton.joints.size(); ++j) {
    const std::string& name = skeleton.joints[j].name;
    glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
    if (name.rfind("spine", 0) == 0) q = glm::angleAxis(bend, glm::vec3(0.0f, 0.0f, 1.0f));
    if (name == "head") q = glm::angleAxis(-bend, glm::vec3(0.0f, 0.0f, 1.0f)) * glm::angleAxis(0.6f, glm::vec3(0, 1, 0));
    if (name == "root") q = glm::angleAxis(0.4f, glm::vec3(0.0f, 1.0f, 0.0f));
    pose.local[j].rotation = q * pose.local[j].rotation;
  }
  return pose;
}

}  // namespace embody::test
