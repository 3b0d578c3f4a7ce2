#pragma once
// Residuals and reach after a solve (SolveResult's per-tracker figures), in avatar metres: each
// enabled tracker position task's target against the body part it drives (the head's eye point,
// the other trackers' joint pivots); for the hands, whether the target is within the arm's reach
// from the shoulder; the angle between each live tracker's orientation target and its joint's
// orientation. Trackers without an enabled position task keep -1. No allocation.
//
//   ResidualsJob job{&rig, &data, &targets, &result};
//   if (job.Run()) ... result.residual, result.reachable
#include "ik/solver.h"
#include "runtime/body_rig.h"
#include "runtime/body_solver.h"
#include "runtime/body_targets.h"

namespace embody::runtime {

struct ResidualsJob {
  const BodyRig* rig = nullptr;
  const ik::Data* data = nullptr;         // solved, kinematics current
  const BodyTargets* targets = nullptr;   // the targets the tasks were given
  SolveResult* result = nullptr;          // out: residual and reachable (the rest untouched)

  // Every pointer set, the data sized for the rig's model, the targets finite.
  bool Validate() const;
  bool Run() const;
};

}  // namespace embody::runtime
