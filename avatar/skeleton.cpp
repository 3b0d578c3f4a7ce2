#include "avatar/skeleton.h"

#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <unordered_map>
#include <unordered_set>

namespace embody::avatar {

glm::mat4 Transform::matrix() const {
  glm::mat4 m = glm::mat4_cast(rotation);
  m[0] *= scale.x;
  m[1] *= scale.y;
  m[2] *= scale.z;
  m[3] = glm::vec4(translation, 1.0f);
  return m;
}

int Skeleton::find(std::string_view name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  return -1;
}

glm::quat globalRotationOf(const glm::mat4& global, const glm::quat& ifDegenerate) {
  const glm::vec3 c0(global[0]), c1(global[1]), c2(global[2]);
  const glm::vec3 s(glm::length(c0), glm::length(c1), glm::length(c2));
  if (!(s.x > 1e-12f && s.y > 1e-12f && s.z > 1e-12f) || !std::isfinite(s.x + s.y + s.z)) return ifDegenerate;
  return glm::normalize(glm::quat_cast(glm::mat3(c0 / s.x, c1 / s.y, c2 / s.z)));
}

std::vector<std::string> uniqueJointNames(const Skeleton& skeleton) {
  std::unordered_map<std::string_view, int> uses;
  for (const Joint& j : skeleton.joints) ++uses[j.name];
  std::vector<std::string> names;
  names.reserve(skeleton.joints.size());
  std::unordered_set<std::string> taken;
  for (const Joint& j : skeleton.joints)
    if (!j.name.empty() && uses[j.name] == 1) taken.insert(j.name);
  for (size_t i = 0; i < skeleton.joints.size(); ++i) {
    const std::string& name = skeleton.joints[i].name;
    if (!name.empty() && uses[name] == 1) {
      names.push_back(name);
      continue;
    }
    std::string unique = (name.empty() ? std::string("joint") : name) + "_" + std::to_string(i);
    while (!taken.insert(unique).second) unique.insert(unique.rfind('_'), "_");
    names.push_back(std::move(unique));
  }
  return names;
}

std::vector<int> Skeleton::children(int joint) const {
  std::vector<int> out;
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].parent == joint) out.push_back(static_cast<int>(i));
  return out;
}

bool Skeleton::isAncestor(int ancestor, int joint) const {
  for (int j = joint; j >= 0; j = joints[j].parent)
    if (j == ancestor) return true;
  return false;
}

std::string Skeleton::validate() const {
  for (size_t i = 0; i < joints.size(); ++i) {
    const int p = joints[i].parent;
    if (p < -1 || p >= static_cast<int>(i))
      return "joint " + std::to_string(i) + " ('" + joints[i].name + "') has parent " + std::to_string(p) +
             ", which does not come before it";
  }
  return {};
}

SkeletonPose SkeletonPose::rest(const Skeleton& s) {
  SkeletonPose p;
  p.local.reserve(s.joints.size());
  for (const auto& j : s.joints) p.local.push_back(j.rest);
  return p;
}

void computeGlobals(const Skeleton& skeleton, const SkeletonPose& pose, std::vector<glm::mat4>& globals) {
  globals.resize(skeleton.joints.size());
  for (size_t i = 0; i < skeleton.joints.size(); ++i) {
    const glm::mat4 local = pose.local[i].matrix();
    const int p = skeleton.joints[i].parent;
    globals[i] = p < 0 ? local : globals[p] * local;
  }
}

}  // namespace embody::avatar
