#include "ik/solver.h"

#include <algorithm>
#include <cmath>

#include "core/enum_names.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik {

using detail::sameShape;
using detail::computeDq0;
using detail::resetActiveSet;
using detail::runPass;

namespace {

class SteadyClock final : public Clock {
 public:
  time_point now() const override { return std::chrono::steady_clock::now(); }
};

bool validOptions(const SolveOptions& o) {
  return o.max_iterations >= 0 && o.min_iterations >= 0 && std::isfinite(o.damping_max) && o.damping_max >= 0 &&
         std::isfinite(o.damping_eps) && o.damping_eps > 0 && std::isfinite(o.rank_tolerance) &&
         o.rank_tolerance > 0 && std::isfinite(o.inequality_tolerance) && o.inequality_tolerance >= 0 &&
         !(o.max_level_step < 0) && !std::isnan(o.max_level_step);
}

void fillResiduals(const Model& model, Workspace& w) {
  for (int t = 0; t < w.task_count; ++t) w.report.tasks[t] = w.residual[t];
  for (size_t k = 0; k < model.levels.size(); ++k) {
    double sum = 0.0;
    for (TaskId t : model.levels[k].tasks)
      if (w.enabled[t]) sum += w.residual[t].position * w.residual[t].position + w.residual[t].rotation * w.residual[t].rotation;
    w.report.levels[k] = std::sqrt(sum);
  }
}

bool allSatisfied(const Workspace& w) {
  for (const TaskResidual& r : w.residual)
    if (!r.satisfied) return false;
  return true;
}

}  // namespace

const Clock& steadyClock() {
  static const SteadyClock clock;
  return clock;
}

constexpr EnumName<StopReason> kStopReasonNames[] = {{StopReason::Converged, "converged"},
                                                     {StopReason::IterationCap, "iteration cap"},
                                                     {StopReason::Deadline, "deadline"},
                                                     {StopReason::Stalled, "stalled"},
                                                     {StopReason::InvalidState, "invalid state"}};

const char* toString(StopReason reason) {
  return enumName(kStopReasonNames, reason);
}

const Eigen::VectorXd& priorityPass(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  if (!sameShape(model, w)) return w.dq;
  resetActiveSet(w, options.path);
  computeDq0(w);
  runPass(model, w, options);
  return w.dq;
}

void iterate(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  if (!sameShape(model, w) || !validOptions(options)) return;
  kinematics(model, data, true);
  detail::step(model, w, options);
}

const SolveReport& solve(const Model& model, Data& data, const SolveOptions& options) {
  Workspace& w = data.workspace();
  SolveReport& report = w.report;
  const Clock& clock = options.clock ? *options.clock : steadyClock();
  const Clock::time_point start = clock.now();
  report.iterations = 0;
  report.clamp_passes = 0;
  report.active_clamps.clear();
  report.unsatisfiable.clear();
  if (!sameShape(model, w) || !validOptions(options)) {
    report.stop = StopReason::InvalidState;
    report.elapsed = std::chrono::nanoseconds(0);
    return report;
  }
  report.stop = StopReason::IterationCap;
  kinematics(model, data, true);
  for (;;) {
    if (report.iterations >= options.min_iterations && allSatisfied(w)) {
      report.stop = StopReason::Converged;
      break;
    }
    if (report.iterations >= options.max_iterations) break;
    if (options.deadline && clock.now() >= *options.deadline) {
      report.stop = StopReason::Deadline;
      break;
    }
    if (!detail::step(model, w, options)) {
      report.stop = StopReason::InvalidState;
      break;
    }
    ++report.iterations;
    kinematics(model, data, true);
    if (w.dq.norm() < options.min_step) {
      report.stop = allSatisfied(w) ? StopReason::Converged : StopReason::Stalled;
      break;
    }
  }
  fillResiduals(model, w);
  report.elapsed = std::chrono::duration_cast<std::chrono::nanoseconds>(clock.now() - start);
  return report;
}

}  // namespace embody::ik
