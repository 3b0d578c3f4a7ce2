#pragma once
// The seam between the runtime and an IK solver. The runtime owns timing (budget, deadline,
// clock), the tracking-loss policy and the hand-off; a BodySolver turns guarded tracker targets
// into a skeleton pose before a deadline. The PIK solver with the avatar's body model
// (ik, avatar/body) is adapted to this interface where they are integrated; tests use
// fakes whose cost is simulated on a ManualClock.
#include <array>

#include "avatar/skeleton.h"
#include "runtime/clock.h"
#include "tracking/tracking_guard.h"

namespace embody::runtime {

struct SolveRequest {
  const tracking::GuardedSample* targets = nullptr;  // never null in a request from the runtime
  const Clock* clock = nullptr;
  TimePoint deadline{};  // by which solve() must have returned (IterationBudget, IterationCostModel)
  // > 0: deterministic mode (--ik-iterations): exactly this many solver iterations (fewer only
  // when converged), the deadline ignored, so the same samples give the same poses to the bit.
  int fixedIterations = 0;
};

struct SolveResult {
  int iterations = 0;
  bool converged = false;
  // Distance in metres between each tracker's target and the body part it drives after the
  // solve; negative where the tracker drives no task.
  std::array<float, tracking::kTrackerCount> residual{-1, -1, -1, -1, -1, -1};
  // Angle in radians between each tracked tracker's orientation (as the joint's target) and the
  // joint's, whether or not an orientation task drives it: a pelvis free to turn shows here;
  // negative where the tracker drives no task.
  std::array<float, tracking::kTrackerCount> turnResidual{-1, -1, -1, -1, -1, -1};
  // Per tracker: whether its target is within the avatar's reach (hands: the arm's reach from
  // the shoulder). Hand errors count only where it is: an out-of-reach target cannot be met.
  std::array<bool, tracking::kTrackerCount> reachable{true, true, true, true, true, true};
  // This budgeted solve first settled outside the budget, once by design: the body's start (the
  // first live solve from the rest pose, a new seat). Its time is the start-up's, not a frame's.
  bool settled = false;
};

class BodySolver {
 public:
  virtual ~BodySolver() = default;
  // Warm-started: a solver continues from its previous solution. Writes every joint's local
  // transform into `pose` (already sized for the skeleton; must not allocate).
  virtual SolveResult solve(const SolveRequest& request, avatar::SkeletonPose& pose) = 0;
  // Forget the warm start (e.g. after a long tracking gap or a new avatar).
  virtual void resetWarmStart() {}
};

}  // namespace embody::runtime
