// Reading VRMC_springBone (VRM 1.0) and secondaryAnimation (VRM 0.x) into SpringBoneSetup.
#include <algorithm>

#include "avatar/avatar_asset.h"
#include "avatar/vrm/vrm_parsers.h"

namespace embody::avatar {

namespace {

using vrm::Json;
using vrm::member;

constexpr float kVrm0VirtualTail = 0.07f;  // UniVRM / three-vrm: a leaf's tail 7 cm along its own offset

int jointOfNode(const Json& node, const AvatarAsset& asset, const std::string& what, std::vector<std::string>& w) {
  const int n = vrm::indexBelow(node, asset.gltfNodeToJoint.size(), what, w);
  return n < 0 ? -1 : asset.gltfNodeToJoint[static_cast<size_t>(n)];
}

glm::vec3 unitOr(glm::vec3 v, glm::vec3 fallback) {
  const float len = glm::length(v);
  return len > 1e-6f ? v / len : fallback;
}

SpringJointSettings readSettings(const Json& j, const char* stiffnessKey, const std::string& what,
                                 std::vector<std::string>& w, bool flipGravityZ) {
  SpringJointSettings s;
  s.stiffness = vrm::numberIn(member(j, stiffnessKey), s.stiffness, 0.0f, 1e4f, what + " " + stiffnessKey, w);
  s.dragForce = vrm::numberIn(member(j, "dragForce"), s.dragForce, 0.0f, 1.0f, what + " dragForce", w);
  s.gravityPower = vrm::numberIn(member(j, "gravityPower"), s.gravityPower, 0.0f, 1e4f, what + " gravityPower", w);
  s.hitRadius = vrm::numberIn(member(j, "hitRadius"), s.hitRadius, 0.0f, 1e3f, what + " hitRadius", w);
  glm::vec3 g = vrm::vec3Of(member(j, "gravityDir"), s.gravityDir, what + " gravityDir", w);
  if (flipGravityZ) g.z = -g.z;
  s.gravityDir = unitOr(g, glm::vec3(0.0f, -1.0f, 0.0f));
  return s;
}

SpringCollider readCollider(const Json& c, const AvatarAsset& asset, const std::string& what, std::vector<std::string>& w) {
  SpringCollider col;
  col.joint = jointOfNode(member(c, "node"), asset, what + " node", w);
  const Json& shape = member(c, "shape");
  const Json& sphere = member(shape, "sphere");
  const Json& capsule = member(shape, "capsule");
  const Json& s = capsule.is_object() ? capsule : sphere;
  if (!s.is_object()) {
    w.push_back(what + ": shape is neither a sphere nor a capsule; dropped");
    col.joint = -1;
    return col;
  }
  col.shape = capsule.is_object() ? SpringCollider::Shape::Capsule : SpringCollider::Shape::Sphere;
  col.offset = vrm::vec3Of(member(s, "offset"), glm::vec3(0.0f), what + " offset", w);
  col.tail = vrm::vec3Of(member(s, "tail"), col.offset, what + " tail", w);
  col.radius = vrm::numberIn(member(s, "radius"), 0.0f, 0.0f, 1e3f, what + " radius", w);
  return col;
}

// Collider indices of the groups a spring lists (indices into the kept colliders).
std::vector<int> groupColliders(const Json& groups, const std::vector<std::vector<int>>& groupList,
                                const std::string& what, std::vector<std::string>& w) {
  std::vector<int> out;
  for (const Json& g : vrm::arrayOf(groups)) {
    const int gi = vrm::indexBelow(g, groupList.size(), what + " colliderGroup", w);
    if (gi >= 0) out.insert(out.end(), groupList[static_cast<size_t>(gi)].begin(), groupList[static_cast<size_t>(gi)].end());
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

void parseVrm1(const Json& sb, const AvatarAsset& asset, SpringBoneSetup& setup, std::vector<std::string>& w,
               std::vector<bool>& claimed) {
  std::vector<glm::mat4> restGlobals;
  computeGlobals(asset.skeleton, SkeletonPose::rest(asset.skeleton), restGlobals);
  std::vector<int> keptIndex;  // file collider -> setup collider, -1 when dropped
  size_t ci = 0;
  for (const Json& c : vrm::arrayOf(member(sb, "colliders"))) {
    SpringCollider col = readCollider(c, asset, "VRMC_springBone collider " + std::to_string(ci++), w);
    keptIndex.push_back(col.joint < 0 ? -1 : static_cast<int>(setup.colliders.size()));
    if (col.joint >= 0) setup.colliders.push_back(col);
  }
  std::vector<std::vector<int>> groups;
  for (const Json& g : vrm::arrayOf(member(sb, "colliderGroups"))) {
    groups.emplace_back();
    for (const Json& c : vrm::arrayOf(member(g, "colliders"))) {
      const int k = vrm::indexBelow(c, keptIndex.size(), "VRMC_springBone colliderGroup " + std::to_string(groups.size() - 1), w);
      if (k >= 0 && keptIndex[static_cast<size_t>(k)] >= 0) groups.back().push_back(keptIndex[static_cast<size_t>(k)]);
    }
  }
  size_t si = 0;
  for (const Json& spring : vrm::arrayOf(member(sb, "springs"))) {
    const std::string what = "VRMC_springBone spring " + std::to_string(si++);
    SpringChain chain;
    chain.name = vrm::stringOr(member(spring, "name"), what);
    chain.colliders = groupColliders(member(spring, "colliderGroups"), groups, what, w);
    chain.center = jointOfNode(member(spring, "center"), asset, what + " center", w);
    const Json& joints = vrm::arrayOf(member(spring, "joints"));
    std::vector<int> ids;
    for (const Json& j : joints) ids.push_back(jointOfNode(member(j, "node"), asset, what + " joint node", w));
    for (size_t k = 0; k + 1 < ids.size(); ++k) {
      const int a = ids[k], b = ids[k + 1];
      if (a < 0 || b < 0 || a == b || !asset.skeleton.isAncestor(a, b)) {
        w.push_back(what + ": joint " + std::to_string(k + 1) + " is not below joint " + std::to_string(k) +
                    "; the chain ends there");
        break;
      }
      if (claimed[static_cast<size_t>(a)]) {
        w.push_back(what + ": joint " + std::to_string(k) + " already swings in another spring; skipped");
        continue;
      }
      claimed[static_cast<size_t>(a)] = true;
      SpringJoint sj;
      sj.joint = a;
      sj.child = b;
      // b may sit deeper than a's child (the joints between are not simulated): its rest offset in a's frame.
      sj.tail = glm::vec3(glm::inverse(restGlobals[static_cast<size_t>(a)]) * restGlobals[static_cast<size_t>(b)][3]);
      sj.settings = readSettings(joints[k], "stiffness", what + " joint " + std::to_string(k), w, false);
      chain.joints.push_back(sj);
    }
    if (!chain.joints.empty()) setup.chains.push_back(std::move(chain));
  }
}

void parseVrm0(const Json& sa, const AvatarAsset& asset, SpringBoneSetup& setup, std::vector<std::string>& w,
               std::vector<bool>& claimed) {
  std::vector<std::vector<int>> groups;
  for (const Json& g : vrm::arrayOf(member(sa, "colliderGroups"))) {
    const std::string what = "secondaryAnimation colliderGroup " + std::to_string(groups.size());
    groups.emplace_back();
    const int joint = jointOfNode(member(g, "node"), asset, what + " node", w);
    if (joint < 0) continue;
    for (const Json& c : vrm::arrayOf(member(g, "colliders"))) {
      SpringCollider col;
      col.joint = joint;
      col.offset = vrm::vec3Of(member(c, "offset"), glm::vec3(0.0f), what + " offset", w);
      col.offset.z = -col.offset.z;  // VRM 0.x stores Unity's left-handed z
      col.tail = col.offset;
      col.radius = vrm::numberIn(member(c, "radius"), 0.0f, 0.0f, 1e3f, what + " radius", w);
      groups.back().push_back(static_cast<int>(setup.colliders.size()));
      setup.colliders.push_back(col);
    }
  }
  size_t bi = 0;
  for (const Json& bg : vrm::arrayOf(member(sa, "boneGroups"))) {
    const std::string what = "secondaryAnimation boneGroup " + std::to_string(bi++);
    // "stiffiness" is the 0.x schema's spelling; 0.x gravityDir is taken as written (three-vrm, UniVRM).
    const SpringJointSettings settings = readSettings(bg, "stiffiness", what, w, false);
    const std::vector<int> colliders = groupColliders(member(bg, "colliderGroups"), groups, what, w);
    const Json& centerNode = member(bg, "center");
    const int center = centerNode.is_number() && centerNode.get<double>() < 0 ? -1 : jointOfNode(centerNode, asset, what + " center", w);
    for (const Json& rootNode : vrm::arrayOf(member(bg, "bones"))) {
      const int root = jointOfNode(rootNode, asset, what + " bone", w);
      if (root < 0) continue;
      SpringChain chain;
      chain.name = vrm::stringOr(member(bg, "comment"), what) + " / " + asset.skeleton.joints[static_cast<size_t>(root)].name;
      chain.colliders = colliders;
      chain.center = center;
      // The whole subtree sways, each joint towards its first child (a leaf: a virtual tail).
      for (size_t j = static_cast<size_t>(root); j < asset.skeleton.joints.size(); ++j) {
        if (!asset.skeleton.isAncestor(root, static_cast<int>(j)) || claimed[j]) continue;
        claimed[j] = true;
        SpringJoint sj;
        sj.joint = static_cast<int>(j);
        sj.settings = settings;
        for (size_t c = j + 1; c < asset.skeleton.joints.size() && sj.child < 0; ++c)
          if (asset.skeleton.joints[c].parent == static_cast<int>(j)) sj.child = static_cast<int>(c);
        if (sj.child >= 0) sj.tail = asset.skeleton.joints[static_cast<size_t>(sj.child)].rest.translation;
        if (sj.child < 0)
          sj.tail = unitOr(asset.skeleton.joints[j].rest.translation, glm::vec3(0.0f, 1.0f, 0.0f)) * kVrm0VirtualTail;
        chain.joints.push_back(sj);
      }
      if (!chain.joints.empty()) setup.chains.push_back(std::move(chain));
    }
  }
}

}  // namespace

size_t SpringBoneSetup::jointCount() const {
  size_t n = 0;
  for (const auto& c : chains) n += c.joints.size();
  return n;
}

SpringBoneSetup parseSpringBones(const Json& doc, const AvatarAsset& asset, std::vector<std::string>& warnings) {
  SpringBoneSetup setup;
  std::vector<bool> claimed(asset.skeleton.joints.size(), false);
  const Json& ext = member(doc, "extensions");
  if (const Json& sb = member(ext, "VRMC_springBone"); sb.is_object())
    parseVrm1(sb, asset, setup, warnings, claimed);
  else if (const Json& sa = member(member(ext, "VRM"), "secondaryAnimation"); sa.is_object())
    parseVrm0(sa, asset, setup, warnings, claimed);
  // Parents before children across chains (the job also walks the skeleton in order).
  std::stable_sort(setup.chains.begin(), setup.chains.end(),
                   [](const SpringChain& a, const SpringChain& b) { return a.joints.front().joint < b.joints.front().joint; });
  return setup;
}

}  // namespace embody::avatar
