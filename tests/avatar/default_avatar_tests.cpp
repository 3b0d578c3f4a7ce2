#include <catch2/catch.hpp>

#include "avatar/humanoid/first_person.h"
#include "avatar/procedural/default_avatar.h"

using namespace embody::avatar;

TEST_CASE("the default avatar is a 1.75 m H-Anim mannequin facing +Z with 10k-30k triangles", "[default]") {
  const AvatarAsset a = buildDefaultAvatar();
  CHECK(a.skeleton.validate().empty());
  CHECK(a.format == AvatarFormat::Procedural);
  const auto tris = a.mesh.triangleCount();
  INFO("triangles " << tris << ", vertices " << a.mesh.vertices.size());
  CHECK(tris >= 10000);
  CHECK(tris <= 30000);
  glm::vec3 lo(1e9f), hi(-1e9f);
  for (const auto& v : a.mesh.vertices) {
    lo = glm::min(lo, v.position);
    hi = glm::max(hi, v.position);
    const float sum = v.weights0.x + v.weights0.y + v.weights0.z + v.weights0.w + v.weights1.x +
                      v.weights1.y + v.weights1.z + v.weights1.w;
    REQUIRE(sum == Approx(1.0f).margin(1e-6));
    REQUIRE(glm::length(v.normal) == Approx(1.0f).margin(1e-4));
  }
  INFO("bounds " << lo.x << " " << lo.y << " " << lo.z << " .. " << hi.x << " " << hi.y << " " << hi.z);
  CHECK(hi.y - lo.y == Approx(1.75f).margin(0.02f));
  CHECK(lo.y == Approx(0.0f).margin(0.005f));
  // Every one of the 24 vertebrae and skullbase is a joint and stands for itself.
  for (int level = 0; level < kVertebralJointCount; ++level)
    CHECK(a.skeleton.find(vertebralJointName(level)) >= 0);
  const auto& h = a.humanoid;
  CHECK(h.method == MappingMethod::Names);
  CHECK(h.missingRequired.empty());
  REQUIRE(h.spine.size() == 25);
  for (int level = 0; level < kVertebralJointCount; ++level) {
    CHECK(a.skeleton.joints[h.spine[level].joint].name == vertebralJointName(level));
    CHECK(h.spine[level].firstLevel == level);
    CHECK(h.spine[level].levelCount() == 1);
  }
  CHECK(h.forward.z > 0.99f);
  CHECK(a.skeleton.joints[h.joint(HumanBone::leftHand)].name == "l_wrist");
  std::vector<glm::mat4> g;
  computeGlobals(a.skeleton, SkeletonPose::rest(a.skeleton), g);
  CHECK(g[h.joint(HumanBone::leftHand)][3].x > 0.2f);  // left is +X when facing +Z
  // Every vertebra moves some skin, so bending the spine shows.
  std::vector<bool> used(a.skeleton.joints.size(), false);
  for (const auto& v : a.mesh.vertices)
    for (int k = 0; k < 4; ++k)
      if (v.weights0[k] > 0.0f) used[v.joints0[k]] = true;
  for (int level = 0; level < kVertebralJointCount; ++level)
    CHECK(used[a.skeleton.find(vertebralJointName(level))]);
  // First person: the head's triangles are gone, the hands remain.
  CHECK(a.firstPerson.mode == "auto");
  CHECK(a.firstPerson.removedTriangles > 1000);
  std::vector<bool> head(a.skeleton.joints.size());
  for (size_t j = 0; j < head.size(); ++j)
    head[j] = a.skeleton.isAncestor(h.joint(HumanBone::head), static_cast<int>(j));
  for (size_t t = 0; t < a.mesh.firstPersonIndices.size() / 3; ++t)
    REQUIRE_FALSE(triangleTouches(a.mesh, a.mesh.firstPersonIndices, t, head));
}
