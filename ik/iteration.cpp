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

// Level k's contribution to the last pass's Δq, in joint space.
void levelContribution(const Workspace& w, size_t k, Eigen::VectorXd& out) {
  if (!w.level_step_reduced) {
    out = w.level_step[k];
    return;
  }
  out.setZero();
  for (const Workspace::ColumnGroup& g : w.null_groups)
    out.segment(g.row_begin, g.row_end - g.row_begin).noalias() +=
        w.nullspace.block(g.row_begin, g.col_begin, g.row_end - g.row_begin, g.col_end - g.col_begin) *
        w.level_step[k].segment(g.col_begin, g.col_end - g.col_begin);
}

// The shortened step moves each row's value linearly from its value at q + Δq (the clamping
// loop's full step) to the one at q + Δq'. Δq' may break a row the full step keeps (a shortened
// level no longer compensates a pinned row's move to its bound, and a band past its slack is
// the result), so the step goes only as far toward Δq' as keeps every such row.
double fractionKeepingRows(const Model& model, const Workspace& w, const SolveOptions& o) {
  double fraction = 1.0;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    const double bound = w.ineq_rhs[i] + o.inequality_tolerance;
    double full = rowValue(w, i, w.q), shortened = full;
    for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) {
      full += w.ineq_coef[k] * w.guard_full(w.ineq_dof[k]);
      shortened += w.ineq_coef[k] * w.dq(w.ineq_dof[k]);
    }
    if (full > bound) continue;  // violated anyway (reported): shortening cannot help
    if (shortened > bound) fraction = std::min(fraction, (bound - full) / (shortened - full));
  }
  return std::max(fraction, 0.0);
}

constexpr double kNegligibleLevelStep = 1e-9;

// What the last pass's levels did, for the oscillation guard.
struct LevelSteps {
  size_t top;            // the first level whose contribution is not negligible
  size_t firstReversed;  // the first level whose contribution reverses its previous one (cos < -0.3)
};

// Records each level's contribution (joint space) as its previous step; the number of levels
// stands for "none" in the result.
LevelSteps recordLevelSteps(const Model& model, Workspace& w) {
  LevelSteps r{model.levels.size(), model.levels.size()};
  for (size_t k = 0; k < model.levels.size(); ++k) {
    if (!w.level_step_set[k]) {
      w.level_has_previous[k] = 0;  // off this iteration: its history says nothing any more
      continue;
    }
    Eigen::VectorXd& step = w.guard_full;  // scratch
    levelContribution(w, k, step);
    Eigen::VectorXd& previous = w.level_previous_step[k];
    if (!(step.norm() > kNegligibleLevelStep)) {
      // A level left no dofs by those above it, or already met (the fast path skips it; the
      // reference path's step is round-off): no direction to compare, nothing to shorten.
      previous.setZero();
      w.level_has_previous[k] = 0;
      continue;
    }
    r.top = std::min(r.top, k);
    const double norms = step.norm() * previous.norm();
    if (w.level_has_previous[k] && norms > 0 && step.dot(previous) < -0.3 * norms)
      r.firstReversed = std::min(r.firstReversed, k);
    previous = step;
    w.level_has_previous[k] = 1;
  }
  return r;
}

// The oscillation guard. Near unreachable or singular targets the Gauss-Newton map of damped
// least squares can settle into a period-2 cycle: when the task part of the step (Δq - Δq0)
// reverses the previous one (cos < -0.3) the step scale halves (>= 1/64), otherwise it grows
// back x1.25 up to 1. The scale shortens the contributions of every level below the top moving
// one (a level already met has no step to spare: counting it as the top left the seated head,
// one level lower, shortened with the rest); the top level is shortened too only when its own
// contribution reversed, or when no level's did on its own (then the cycle is between levels,
// the higher ones take part, and the whole task part is shortened).
// A cycle low down (knee poles and feet against clamped hips on a walk; a seated head at the
// sway's extremes) then no longer holds the top level back: shortening the whole task part
// left the eyes, alone on level 0, 1-2 cm off on the Mixamo walk, and the seated head 20 mm off.
// Shortening level k keeps every level above it exact (its contribution lies in their null
// space) and every pinned row (it lies in the active rows' null space); the levels below see a
// step they did not compensate and correct it next iteration.
void applyOscillationGuard(const Model& model, Workspace& w, const SolveOptions& o) {
  const LevelSteps levels = recordLevelSteps(model, w);
  Eigen::VectorXd& task = w.tmp_n;
  task = w.dq - w.dq0;
  const double norms = task.norm() * w.previous_task_step.norm();
  if (w.has_previous_step && norms > 0 && task.dot(w.previous_task_step) < -0.3 * norms)
    w.step_scale = std::max(w.step_scale * 0.5, 1.0 / 64);
  else
    w.step_scale = std::min(1.0, w.step_scale * 1.25);
  w.previous_task_step = task;
  w.has_previous_step = true;
  if (w.step_scale >= 1.0) return;
  w.guard_full = w.dq;
  const bool topKept = levels.firstReversed < model.levels.size() && levels.firstReversed > levels.top;
  for (size_t k = topKept ? levels.top + 1 : 0; k < model.levels.size(); ++k)
    if (w.level_step_set[k]) w.dq.noalias() -= (1.0 - w.step_scale) * w.level_previous_step[k];
  const double fraction = fractionKeepingRows(model, w, o);
  if (fraction < 1.0) w.dq = w.guard_full + fraction * (w.dq - w.guard_full);
}

}  // namespace

void saveLevelSteps(Workspace& w) {
  for (size_t k = 0; k < w.level_step.size(); ++k) {
    w.warm_saved_level_step_set[k] = w.level_step_set[k];
    if (w.level_step_set[k]) levelContribution(w, k, w.warm_saved_level_step[k]);
  }
}

void restoreLevelSteps(Workspace& w) {
  for (size_t k = 0; k < w.level_step.size(); ++k) {
    w.level_step_set[k] = w.warm_saved_level_step_set[k];
    if (w.level_step_set[k]) w.level_step[k] = w.warm_saved_level_step[k];
  }
  w.level_step_reduced = false;
}

void forgetSteps(Workspace& w) {
  std::fill(w.level_has_previous.begin(), w.level_has_previous.end(), 0);
  w.has_previous_step = false;
  w.step_scale = 1.0;
}

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
  startActiveSet(w, o);  // the equality rows, plus the rows carried from the last iteration
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
  if (o.oscillation_guard) applyOscillationGuard(model, w, o);
  w.q += w.dq;
  reparameterize(model, w);
  return true;
}

}  // namespace embody::ik::detail
