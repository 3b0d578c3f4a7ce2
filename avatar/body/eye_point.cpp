#include "avatar/body/eye_point.h"

#include <algorithm>
#include <vector>

#include "avatar/body/anthropometry.h"
#include "avatar/skeleton.h"

namespace embody::avatar {
namespace {

struct RestShape {
  std::vector<glm::mat4> globals;
  std::vector<glm::vec3> positions;  // skinned rest mesh
};

RestShape restShape(const AvatarAsset& asset) {
  RestShape r;
  std::vector<glm::mat4> palette;
  std::vector<glm::vec3> normals;
  computeGlobals(asset.skeleton, SkeletonPose::rest(asset.skeleton), r.globals);
  computeSkinningPalette(asset, r.globals, palette);
  skinOnCpu(asset.mesh, palette, r.positions, normals);
  return r;
}

glm::dvec3 jointPosition(const RestShape& r, int joint) {
  return joint >= 0 && size_t(joint) < r.globals.size() ? glm::dvec3(r.globals[size_t(joint)][3]) : glm::dvec3(0.0);
}

RestStature statureOf(const AvatarAsset& asset, const RestShape& r, const glm::dvec3& up) {
  double lo = 1e30, hi = -1e30;
  for (const glm::vec3& p : r.positions) {
    const double h = glm::dot(up, glm::dvec3(p));
    lo = std::min(lo, h), hi = std::max(hi, h);
  }
  if (!(hi > lo + 0.3)) {
    const auto& h = asset.humanoid;
    lo = std::min(glm::dot(up, jointPosition(r, h.joint(HumanBone::leftFoot))),
                  glm::dot(up, jointPosition(r, h.joint(HumanBone::rightFoot)))) -
         0.07;
    hi = glm::dot(up, jointPosition(r, h.joint(HumanBone::head))) + 0.15;
  }
  return {lo, hi - lo};
}

}  // namespace

RestStature restStature(const AvatarAsset& asset, const glm::dvec3& up) {
  return statureOf(asset, restShape(asset), up);
}

EyePoint restEyePoint(const AvatarAsset& asset, int head, const glm::vec3& forward) {
  const RestShape r = restShape(asset);
  const glm::dvec3 up = glm::normalize(glm::dvec3(asset.humanoid.up));
  EyePoint eye;
  eye.stature = statureOf(asset, r, up);
  const RestStature& stature = eye.stature;
  glm::vec3 lo(1e30f), hi(-1e30f);
  if (head >= 0)
    for (size_t i = 0; i < asset.mesh.vertices.size() && i < r.positions.size(); ++i) {
      const SkinnedVertex& v = asset.mesh.vertices[i];
      int strongest = int(v.joints0[0]);
      float w = v.weights0[0];
      for (int k = 1; k < 4; ++k)
        if (v.weights0[k] > w) w = v.weights0[k], strongest = int(v.joints0[k]);
      if (!asset.skeleton.isAncestor(head, strongest)) continue;
      lo = glm::min(lo, r.positions[i]);
      hi = glm::max(hi, r.positions[i]);
    }
  if (lo.x <= hi.x) {
    // Halfway up: the renderer used 0.6, which puts the default avatar's eyes at 0.950 of its
    // stature, 3 cm above H-Anim's 0.933; the body solver then missed the synthetic seated
    // motion's head by 3 cm (docs/architecture.md, "Eye point").
    const glm::vec3 centre = (lo + hi) * 0.5f, extent = hi - lo;
    const glm::vec3 p = glm::vec3(centre.x, lo.y + 0.5f * extent.y, centre.z) +
                        forward * (0.25f * glm::dot(glm::abs(forward), extent));
    eye.position = glm::dvec3(p);
    eye.aboveFloor = glm::dot(up, eye.position) - stature.floor;
    eye.fromMesh = true;
    return eye;
  }
  // The proportion rule, in tracking::BodyDimensions' single precision.
  const float height = float(stature.height);
  const float eyeHeight = float(kEyeHeightRatio) * height, eyeForward = float(kEyeForwardRatio) * height;
  const glm::dvec3 headPos = jointPosition(r, head);
  eye.position = headPos + up * (stature.floor + eyeHeight - glm::dot(up, headPos)) + glm::dvec3(forward) * double(eyeForward);
  eye.aboveFloor = eyeHeight;
  return eye;
}

}  // namespace embody::avatar
