#pragma once
// One tracking sample through the runtime, synchronously: One Euro filter -> tracking-loss
// guard -> budgeted, warm-started solve -> a SolvedFrame with statistics. IkThread runs this on
// its own thread; offline rendering (`embody render`) calls it directly so runs are repeatable.
#include "avatar/skeleton.h"
#include "runtime/body_solver.h"
#include "runtime/frame_stats.h"
#include "tracking/one_euro_filter.h"

namespace embody::runtime {

struct IkStageConfig {
  double budgetSeconds = 0.001;  // per sample (--ik-budget-ms), filter and guard included
  // Kept back from the solver's deadline for the work after it returns (writing the pose,
  // publishing), so the whole stage ends within the budget.
  double reserveSeconds = 0.05e-3;
  // > 0 (--ik-iterations): a fixed iteration count per sample instead of the budget, so offline
  // runs (render, eval) are reproducible to the bit. 0: the budget (live use).
  int fixedIterations = 0;
  bool filter = true;            // One Euro filter on (off for exact replays)
  tracking::TrackerFilterParams filterParams;
  tracking::TrackingGuardConfig guard;
};

// What the render side consumes: the solved pose, the targets it was solved for, the stats.
struct SolvedFrame {
  FrameStats stats;
  tracking::GuardedSample targets;
  avatar::SkeletonPose pose;
};

class IkStage {
 public:
  IkStage(BodySolver& solver, const Clock& clock, const IkStageConfig& config = {});
  // Processes one sample into `out` (out.pose keeps its size; nothing is allocated when it
  // already has the skeleton's joint count). Returns out.stats.
  const FrameStats& process(const tracking::PoseSample& sample, SolvedFrame& out);
  void reset();
  const IkStageConfig& config() const { return config_; }

 private:
  BodySolver& solver_;
  const Clock& clock_;
  IkStageConfig config_;
  tracking::PoseFilter filter_;
  tracking::TrackingGuard guard_;
  uint64_t sequence_ = 0;
};

}  // namespace embody::runtime
