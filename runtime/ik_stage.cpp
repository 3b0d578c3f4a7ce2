#include "runtime/ik_stage.h"

#include <algorithm>

namespace embody::runtime {

IkStage::IkStage(BodySolver& solver, const Clock& clock, const IkStageConfig& config)
    : solver_(solver), clock_(clock), config_(config), filter_(config.filterParams), guard_(config.guard) {}

void IkStage::reset() {
  filter_.reset();
  guard_.reset();
  solver_.resetWarmStart();
  sequence_ = 0;
}

const FrameStats& IkStage::process(const tracking::PoseSample& sample, SolvedFrame& out) {
  const TimePoint start = clock_.now();
  const TimePoint deadline = start + fromSeconds(config_.budgetSeconds);
  tracking::PoseSample clean = sample;
  tracking::sanitize(clean);
  if (config_.filter) clean = filter_.apply(clean);
  out.targets = guard_.update(clean);

  SolveRequest request;
  request.targets = &out.targets;
  request.clock = &clock_;
  request.deadline = deadline - fromSeconds(std::min(config_.reserveSeconds, 0.5 * config_.budgetSeconds));
  request.fixedIterations = config_.fixedIterations;
  const SolveResult r = solver_.solve(request, out.pose);
  const TimePoint end = clock_.now();

  FrameStats& s = out.stats;
  s.sequence = ++sequence_;
  s.sampleTime = sample.time;
  s.ikSeconds = toSeconds(end - start);
  s.budgetSeconds = config_.budgetSeconds;
  s.iterations = r.iterations;
  s.converged = r.converged;
  s.startup = r.settled;
  s.deadlineMiss = config_.fixedIterations == 0 && !r.settled && end > deadline;
  s.residual = r.residual;
  s.reachable = r.reachable;
  s.turnResidual = r.turnResidual;
  s.status = out.targets.status;
  s.renderSeconds = 0.0;
  return s;
}

}  // namespace embody::runtime
