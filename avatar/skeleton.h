#pragma once
// Skeleton: every node of an avatar's scene as a joint, parents before children. Render-side
// runtime data (GLM); the IK body model is built from it (avatar/body) and writes back into a
// SkeletonPose through retargeting.
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace embody::avatar {

struct Transform {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // w, x, y, z
  glm::vec3 scale{1.0f};
  glm::mat4 matrix() const;
};

struct Joint {
  std::string name;
  int parent = -1;  // index into Skeleton::joints, always < this joint's index; -1 for roots
  Transform rest;   // local rest transform (glTF node TRS)
};

struct Skeleton {
  std::vector<Joint> joints;  // topologically sorted: parent index < child index

  int find(std::string_view name) const;  // -1 when absent
  std::vector<int> children(int joint) const;
  bool isAncestor(int ancestor, int joint) const;  // true when ancestor == joint too
  // Checks the ordering invariant and parent indices; "" when valid, else the reason.
  std::string validate() const;
};

// The rotation of a global (model-space) matrix: its columns normalised. A matrix with a zero (or
// non-finite) column, a bone hidden by a zero scale or one below it, has none: `ifDegenerate` is
// returned (the parent's global rotation times the joint's local one keeps the chain turning).
glm::quat globalRotationOf(const glm::mat4& global, const glm::quat& ifDegenerate);

// Every joint's name, unique: glTF allows two nodes the same name (or none), the IK model and the
// spine description do not. A name that two or more joints share gets "_<joint index>" on each
// (more underscores while that still collides); an empty one becomes "joint_<index>".
std::vector<std::string> uniqueJointNames(const Skeleton& skeleton);

// Local transforms for every joint of a skeleton (same order). Starts at the rest pose.
struct SkeletonPose {
  std::vector<Transform> local;
  static SkeletonPose rest(const Skeleton& s);
};

// Global (model-space) matrices, computed in hierarchy order (no parent walking per joint).
void computeGlobals(const Skeleton& skeleton, const SkeletonPose& pose, std::vector<glm::mat4>& globals);

}  // namespace embody::avatar
