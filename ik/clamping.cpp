// The clamping loop's pieces: inequality rows evaluated sparsely, violated rows pinned at their
// bounds, a dependent violated row exchanged for a pinned one, what stays violated reported.
#include <cstddef>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

double rowValue(const Workspace& w, size_t i, const Eigen::VectorXd& x) {
  double v = 0.0;
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) v += w.ineq_coef[k] * x(w.ineq_dof[k]);
  return v;
}

// Loads inequality row i into w.tmp_n and pins it at its bound (c^T (q + Δq) = rhs). Returns
// false when it depends on the active set (nothing changes then).
bool pinRow(Workspace& w, size_t i, Path path) {
  const double current = rowValue(w, i, w.q);
  w.tmp_n.setZero();
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) w.tmp_n(w.ineq_dof[k]) += w.ineq_coef[k];
  const int single = w.ineq_begin[i + 1] - w.ineq_begin[i] == 1 ? w.ineq_dof[w.ineq_begin[i]] : -1;
  return addActiveRow(w, w.ineq_rhs[i] - current, single, path, 1e-9);
}

// The active set again from the equality rows: the pinned rows (report.active_clamps, in the
// order they were added) except `skip`.
void rebuildActiveSet(Workspace& w, Path path, int skip) {
  resetActiveSet(w, path);
  for (int r : w.report.active_clamps)
    if (r != skip && pinRow(w, static_cast<size_t>(r), path)) w.ineq_active[r] = 1;
}

double nextRowValue(const Workspace& w, size_t i) {
  double next = rowValue(w, i, w.q);
  for (int k = w.ineq_begin[i]; k < w.ineq_begin[i + 1]; ++k) next += w.ineq_coef[k] * w.dq(w.ineq_dof[k]);
  return next;
}

// Row i is violated by q + Δq but depends on the pinned rows: held at their bounds, they fix its
// value. A pinned row only has to hold as an inequality, so one of them may be the wrong one to
// hold at its bound (two regions' opposite limits pinned in one sweep leave the band between
// them no room; pinning the band instead leaves one of those limits inactive). Tries each pinned
// row, latest first, replaced by row i, and keeps the first exchange whose step satisfies the
// released row; otherwise restores the active set and step. Only rows that were dependent and
// violated pay for this (a rebuild and a pass per try).
bool exchangePinnedRow(const Model& model, Workspace& w, const SolveOptions& o, size_t i) {
  std::vector<int>& pinned = w.report.active_clamps;
  for (size_t k = pinned.size(); k-- > 0;) {
    const int released = pinned[k];
    rebuildActiveSet(w, o.path, released);
    if (!pinRow(w, i, o.path)) continue;
    computeDq0(w);
    runPass(model, w, o);
    if (nextRowValue(w, static_cast<size_t>(released)) > w.ineq_rhs[released] + o.inequality_tolerance)
      continue;
    pinned.erase(pinned.begin() + static_cast<std::ptrdiff_t>(k));  // capacity reserved: no allocation
    pinned.push_back(static_cast<int>(i));
    w.ineq_active[i] = 1;
    return true;
  }
  rebuildActiveSet(w, o.path, -1);
  computeDq0(w);
  runPass(model, w, o);
  return false;
}

// Pins every inequality violated by q + Δq (user couplings first: the model keeps that order).
// Returns whether a row was added.
bool pinViolations(const Model& model, Workspace& w, const SolveOptions& o) {
  bool added = false;
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    if (w.ineq_active[i]) continue;
    if (!(nextRowValue(w, i) > w.ineq_rhs[i] + o.inequality_tolerance)) continue;
    // A row dependent on the active set is first offered in exchange for a pinned row; if none
    // can give way it is skipped (first added wins), and reported only if it is still violated
    // once the loop settles (pinning its partner often satisfies it).
    if (pinRow(w, i, o.path)) {
      w.ineq_active[i] = 1;
      w.report.active_clamps.push_back(static_cast<int>(i));
      added = true;
    } else if (exchangePinnedRow(model, w, o, i)) {
      added = true;
    }
  }
  return added;
}

void reportRemainingViolations(const Model& model, Workspace& w, const SolveOptions& o) {
  for (size_t i = 0; i < model.inequalities.size(); ++i) {
    if (w.ineq_active[i] || w.ineq_reported[i]) continue;
    if (nextRowValue(w, i) > w.ineq_rhs[i] + o.inequality_tolerance) {
      w.ineq_reported[i] = 1;
      w.report.unsatisfiable.push_back(static_cast<int>(i));
    }
  }
}

}  // namespace embody::ik::detail
