#include "runtime/tracked_avatar_body.h"

#include <algorithm>
#include <cmath>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "avatar/glm_eigen.h"

namespace embody::runtime {

Result<std::unique_ptr<TrackedAvatarBody>> TrackedAvatarBody::create(const avatar::AvatarAsset& avatar,
                                                                     const TrackedBodyOptions& options) {
  std::unique_ptr<TrackedAvatarBody> b(new TrackedAvatarBody());
  b->avatar_ = &avatar;
  b->options_ = options;
  auto solver = AvatarBodySolver::create(avatar, options.body);
  if (!solver) return Error{solver.error()};
  b->solver_ = std::move(solver).value();
  b->stage_ = std::make_unique<IkStage>(*b->solver_, *b->clock_, options.stage);
  b->frame_.pose = avatar::SkeletonPose::rest(avatar.skeleton);
  return b;
}

void TrackedAvatarBody::reset() {
  stage_->reset();
  solver_->resetWarmStart();
}

glm::mat4 TrackedAvatarBody::avatarToTracking() const {
  // toAvatar is x -> R (s x) + t: read R s and t off the images of the origin and the axes.
  const Eigen::Vector3d o = solver_->toAvatar(glm::vec3(0.0f));
  glm::mat4 forward(1.0f);
  for (int i = 0; i < 3; ++i) {
    glm::vec3 axis(0.0f);
    axis[i] = 1.0f;
    const Eigen::Vector3d c = solver_->toAvatar(axis) - o;
    forward[i] = glm::vec4(avatar::toGlm(c), 0.0f);
  }
  forward[3] = glm::vec4(avatar::toGlm(o), 1.0f);
  return glm::inverse(forward);
}

glm::vec3 TrackedAvatarBody::toTracking(const Eigen::Vector3d& p) const {
  return glm::vec3(avatarToTracking() * glm::vec4(avatar::toGlm(p), 1.0f));
}

bool TrackedAvatarBody::solve(const tracking::PoseSample& sample, avatar::SkeletonPose& pose) {
  const tracking::TrackerPose& head = sample[tracking::TrackerId::Head];
  const bool headUsable = head.valid && tracking::isUsable(head);
  // Nothing is solved before the first valid head: the solver would calibrate from a default
  // height instead of the user's eye height.
  if (!seenHead_ && !headUsable) return false;
  seenHead_ = true;
  stage_->process(sample, frame_);
  if (!(solver_->scale() > 0.0)) return false;
  const glm::mat4 m = avatarToTracking();
  const float s = glm::length(glm::vec3(m[0]));
  if (!std::isfinite(s) || s <= 0.0f) return false;
  const glm::quat r = glm::quat_cast(glm::mat3(m) / s);
  pose = frame_.pose;
  const auto& joints = avatar_->skeleton.joints;
  for (size_t j = 0; j < joints.size() && j < pose.local.size(); ++j) {
    if (joints[j].parent >= 0) continue;
    auto& t = pose.local[j];
    t.translation = glm::vec3(m * glm::vec4(t.translation, 1.0f));
    t.rotation = r * t.rotation;
    t.scale *= s;
  }
  return true;
}

void TrackedAvatarBody::solveInto(const tracking::PoseSample& sample, SolvedFrame& out) {
  if (!solve(sample, out.pose)) {
    out.stats = FrameStats{};  // sequence 0: no body yet
    return;
  }
  out.stats = frame_.stats;
  out.targets = frame_.targets;
}

}  // namespace embody::runtime
