// Which BVH joints are the humanoid's: the avatar name table, the topology mapper on the clip's
// posed skeleton where names fail, the user's bone map on top.
#include <glm/gtx/quaternion.hpp>

#include "avatar/bvh/bvh_body_internal.h"

namespace embody::avatar {

Skeleton bvhSkeleton(const BvhClip& clip) {
  Skeleton s;
  s.joints.reserve(clip.joints.size());
  for (const auto& j : clip.joints) {
    Joint joint;
    joint.name = j.name;
    joint.parent = j.parent;
    joint.rest.translation = glm::vec3(j.offset);
    s.joints.push_back(std::move(joint));
  }
  return s;
}

namespace {

// The skeleton as it stands in one frame, turned so that `up` becomes +Y: pure translations, so
// the topology mapper (which reads +Y up rest poses) sees a person, whatever the rest pose.
Skeleton posedSkeleton(const BvhClip& clip, const std::vector<BvhGlobal>& g, const glm::dvec3& up) {
  Skeleton s = bvhSkeleton(clip);
  const glm::dquat turn = glm::rotation(up, glm::dvec3(0, 1, 0));
  for (size_t j = 0; j < s.joints.size(); ++j) {
    const int p = clip.joints[j].parent;
    const glm::dvec3 local = p < 0 ? g[j].position : g[j].position - g[static_cast<size_t>(p)].position;
    s.joints[j].rest.translation = glm::vec3(turn * local);
  }
  return s;
}

int countMapped(const HumanoidMap& m) {
  int n = 0;
  for (HumanBone b : bvhBodyBones()) n += m.has(b) ? 1 : 0;
  return n;
}

}  // namespace

const std::vector<HumanBone>& bvhBodyBones() {
  static const std::vector<HumanBone> b = {HumanBone::hips,     HumanBone::head,      HumanBone::leftHand,
                                           HumanBone::rightHand, HumanBone::leftFoot, HumanBone::rightFoot};
  return b;
}

Result<HumanoidMap> mapBvhJoints(const BvhClip& clip, const Skeleton& skeleton, size_t frame,
                                 const std::string& boneMapJson) {
  HumanoidMap map = mapByNames(skeleton);
  const int byNames = countMapped(map);
  if (byNames < static_cast<int>(bvhBodyBones().size()) && clip.frameCount > frame) {
    std::vector<BvhGlobal> g;
    bvhGlobals(clip, clip.frame(frame), g);
    HumanoidMap best;
    int bestCount = -1;
    for (glm::dvec3 up : {glm::dvec3(0, 1, 0), glm::dvec3(0, 0, 1), glm::dvec3(1, 0, 0), glm::dvec3(0, -1, 0),
                          glm::dvec3(0, 0, -1), glm::dvec3(-1, 0, 0)}) {
      HumanoidMap t = mapByTopology(posedSkeleton(clip, g, up), {});
      const int c = countMapped(t);
      if (c > bestCount) {
        best = std::move(t);
        bestCount = c;
      }
    }
    // End Sites carry no rotation: a bone the topology put on one (the head's top) is its parent.
    for (int& j : best.bones)
      if (j >= 0 && clip.joints[static_cast<size_t>(j)].endSite) j = clip.joints[static_cast<size_t>(j)].parent;
    if (bestCount > byNames) {
      best.notes.push_back("names mapped " + std::to_string(byNames) + " of the 6 body joints; mapped by topology");
      map = std::move(best);
      finishHumanoidMap(skeleton, map);
    }
  }
  if (!boneMapJson.empty()) {
    // Joint names only: a number is no joint of a BVH file (the probe's {"leftHand": 5} went to
    // whatever joint had that index).
    if (auto s = applyBoneMap(boneMapJson, skeleton, {}, map); !s.ok()) return Error{s.error()};
    map.method = MappingMethod::BoneMap;
    finishHumanoidMap(skeleton, map);
  }
  return map;
}

}  // namespace embody::avatar
