#pragma once
// The avatar's body solved from trackers and placed back in the tracking space: what a headset
// (first person) needs, where the avatar's hands must be where the user's are. Synchronous (one
// IkStage call per frame: filter -> tracking-loss guard -> budgeted AvatarBodySolver), so the
// pose rendered this frame is solved from this frame's predicted trackers; or, through
// solveInto, the step a runtime::IkThread runs on its own thread (embody xr).
//
//   auto body = TrackedAvatarBody::create(avatar, options);
//   each frame: body->solve(sample, pose);   // pose: model space = the tracking space
//
// AvatarBodySolver works in the avatar's model space (tracking metres scaled by avatar eye
// height / user eye height, turned onto the avatar's forward); the inverse of that map is applied
// to the skeleton's roots, which scales the avatar to the user.
//
// Seated mode (options.body.seat, AvatarBodySolver): the avatar sits on a seat placed under the
// first valid head (reset() places it again), feet on the tracking floor; the spine and arms
// follow the head and hands (docs/runtime.md, "Seated mode").
#include <memory>

#include "runtime/avatar_body_solver.h"
#include "runtime/clock.h"
#include "runtime/ik_stage.h"

namespace embody::runtime {

struct TrackedBodyOptions {
  AvatarBodyOptions body;  // trackers: threePoint() for an HMD with two controllers
  IkStageConfig stage;
};

class TrackedAvatarBody {
 public:
  static Result<std::unique_ptr<TrackedAvatarBody>> create(const avatar::AvatarAsset& avatar,
                                                           const TrackedBodyOptions& options);
  // Solves `sample` (tracking space) into `pose` (resized to the skeleton). False, with `pose`
  // left alone, until the first valid head sample (it calibrates the solver when no user height
  // was given). Afterwards a lost head is the tracking-loss guard's business.
  bool solve(const tracking::PoseSample& sample, avatar::SkeletonPose& pose);
  // The same as one runtime::IkThread step: `out` gets the placed pose, the targets and the
  // statistics of this solve; before the first valid head out.stats.sequence is 0 (no body yet)
  // and out.pose is left alone. For IkThread(Process): everything it touches stays on that thread.
  void solveInto(const tracking::PoseSample& sample, SolvedFrame& out);
  // Forgets the warm start and the seat (after a recenter or recalibration): the next valid head
  // places the seat again.
  void reset();

  const AvatarBodySolver& solver() const { return *solver_; }
  const SolvedFrame& frame() const { return frame_; }
  // Avatar model space -> tracking space (a similarity: rotation, uniform scale, translation).
  glm::mat4 avatarToTracking() const;
  glm::vec3 toTracking(const Eigen::Vector3d& avatarPoint) const;

 private:
  TrackedAvatarBody() = default;
  const avatar::AvatarAsset* avatar_ = nullptr;
  TrackedBodyOptions options_;
  std::unique_ptr<AvatarBodySolver> solver_;
  const Clock* clock_ = &steadyClock();
  std::unique_ptr<IkStage> stage_;
  SolvedFrame frame_;
  bool seenHead_ = false;
};

}  // namespace embody::runtime
