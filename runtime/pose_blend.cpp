#include "runtime/pose_blend.h"

#include <algorithm>
#include <glm/gtc/quaternion.hpp>

#include "core/smoothstep.h"

namespace embody::runtime {

void blendPoses(const avatar::SkeletonPose& from, const avatar::SkeletonPose& to, float t, avatar::SkeletonPose& out) {
  const size_t n = std::min(from.local.size(), to.local.size());
  out.local.resize(to.local.size());
  t = std::clamp(t, 0.0f, 1.0f);
  for (size_t j = 0; j < n; ++j) {
    const avatar::Transform& a = from.local[j];
    const avatar::Transform& b = to.local[j];
    avatar::Transform& o = out.local[j];
    o.translation = glm::mix(a.translation, b.translation, t);
    o.scale = glm::mix(a.scale, b.scale, t);
    glm::quat qb = b.rotation;
    if (glm::dot(a.rotation, qb) < 0.0f) qb = -qb;
    o.rotation = glm::normalize(glm::slerp(a.rotation, qb, t));
  }
}

void PoseFade::start(const avatar::SkeletonPose& shown, double time, double seconds) {
  from_.local.assign(shown.local.begin(), shown.local.end());
  start_ = time;
  seconds_ = seconds;
  active_ = !shown.local.empty() && seconds > 0.0;
}

void PoseFade::apply(double time, avatar::SkeletonPose& pose) {
  if (!active_) return;
  const double u = std::clamp((time - start_) / seconds_, 0.0, 1.0);
  if (u >= 1.0 || from_.local.size() != pose.local.size()) {
    active_ = false;
    return;
  }
  const double w = smoothstep(u);
  blendPoses(from_, pose, float(w), pose);
}

}  // namespace embody::runtime
