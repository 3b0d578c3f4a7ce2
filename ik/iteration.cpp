// One iteration after kinematics(): the clamping loop around the priority pass, the oscillation
// guard, q += Δq and the exp-map re-parameterisation.
#include <algorithm>
#include <cmath>

#include "ik/expmap.h"
#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

void reparameterize(const Model& model, Workspace& w) {
  for (const Model::Joint& j : model.joints) {
    if (!j.reparameterize) continue;
    if (j.desc.type == JointType::Swing) {
      Eigen::Vector3d v = j.swing_basis * w.q.segment<2>(j.first_dof);
      if (reparameterizeExpMap(v)) w.q.segment<2>(j.first_dof) = j.swing_basis.transpose() * v;
      continue;
    }
    const int f = j.first_dof + (j.desc.type == JointType::Free ? 3 : 0);
    Eigen::Vector3d v = w.q.segment<3>(f);
    if (reparameterizeExpMap(v)) w.q.segment<3>(f) = v;
  }
}

// The oscillation guard's scaled step Δq0 + s (Δq - Δq0) moves each row's value linearly from
// its value at q + Δq0 to the one at q + Δq. Δq0 alone (the pinned rows at their bounds) may
// break a row the full step keeps (a limit pinned pushes a band past its slack), so the scale
// may not go below what keeps every row the clamping loop left satisfied.
double smallestScaleKeepingRows(const Model& model, const Workspace& w, const SolveOptions& o) {
  double smallest = 0.0;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    const double bound = model.inequalities[i].rhs + o.inequality_tolerance;
    const double full = nextRowValue(w, i);
    if (full > bound) continue;  // violated anyway (reported): the scale cannot help
    double base = rowValue(w, i, w.q);
    for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) base += w.ineq_coef[k] * w.dq0(w.ineq_dof[k]);
    if (base > bound) smallest = std::max(smallest, (base - bound) / (base - full));
  }
  return std::min(smallest, 1.0);
}

}  // namespace

void runPass(const Model& model, Workspace& w, const SolveOptions& o) {
  if (o.path == Path::Fast)
    fastPass(model, w, o);
  else
    referencePass(model, w, o);
}

// The iteration after kinematics(): active set (reset, or carried), clamping loop, q += Δq.
// Returns false (q unchanged) if the step came out non-finite.
bool step(const Model& model, Workspace& w, const SolveOptions& o) {
  w.report.active_clamps.clear();
  w.report.unsatisfiable.clear();
  startActiveSet(model, w, o);  // the equality rows, plus the rows carried from the last iteration
  computeDq0(w);
  runPass(model, w, o);
  int passes = 1;
  if (releaseCarriedRows(model, w, o)) {  // a carried row the tasks now pull inside
    computeDq0(w);
    runPass(model, w, o);
    ++passes;
    confirmRelease(model, w, o);  // undone (no further pass) when the new step violates it again
  }
  while (o.clamping) {
    if (passes >= std::max(1, o.max_clamp_passes) || !pinViolations(model, w, o)) {
      reportRemainingViolations(model, w, o);
      break;
    }
    computeDq0(w);
    runPass(model, w, o);
    ++passes;
  }
  w.report.clamp_passes = passes;
  keepActiveSet(w, o);
  if (!w.dq.allFinite()) return false;
  if (o.oscillation_guard) {
    // The task part of the step (Δq - Δq0) lies in the null space of the active rows, so scaling
    // it keeps every pinned row and every priority relation exact. A step that reverses the
    // previous one (a period-2 cycle of the Gauss-Newton map near an unreachable or singular
    // target) halves the scale; consistent steps let it grow back to 1.
    Eigen::VectorXd& task = w.tmp_n;
    task = w.dq - w.dq0;
    const double norms = task.norm() * w.previous_task_step.norm();
    if (w.has_previous_step && norms > 0 && task.dot(w.previous_task_step) < -0.3 * norms)
      w.step_scale = std::max(w.step_scale * 0.5, 1.0 / 64);
    else
      w.step_scale = std::min(1.0, w.step_scale * 1.25);
    w.previous_task_step = task;
    w.has_previous_step = true;
    const double scale = w.step_scale < 1.0 ? std::max(w.step_scale, smallestScaleKeepingRows(model, w, o)) : 1.0;
    w.dq = w.dq0 + scale * task;
  }
  w.q += w.dq;
  reparameterize(model, w);
  return true;
}

}  // namespace embody::ik::detail
