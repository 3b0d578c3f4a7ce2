// The warm active set (SolveOptions::warm_active_set): the clamping loop starts from the rows it
// pinned in the previous iteration instead of rediscovering them pass by pass. docs/ik.md
// ("The warm active set") says what is carried, when a row is released, and why it is correct.
#include <cmath>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

// A carried row still holds at its bound when q moved only by the solver's own steps (the step
// keeps every pinned row exactly, up to round-off); a configuration set from outside, or a row
// the solver no longer held, leaves it inside or past its bound and it is not carried.
bool atBound(const Model& model, const Workspace& w, int row, double tolerance) {
  return std::abs(model.inequalities[static_cast<size_t>(row)].rhs - rowValue(w, static_cast<size_t>(row), w.q)) <=
         tolerance;
}

// b - A q for the equality rows over their few non-zero terms (the structure is unchanged).
void refreshEqualityRhs(Workspace& w) {
  for (int i = 0; i < w.eq_rank; ++i) {
    double v = w.eq_rhs(i);
    for (int t = w.eq_begin[i]; t < w.eq_begin[i + 1]; ++t) v -= w.eq_coef[t] * w.q(w.eq_dof[t]);
    w.active_rhs(i) = v;
  }
}

// The active set rebuilt from the equality rows and the carried rows that `keep` accepts, in
// their carried order (the same order gives the same basis, so both paths stay comparable).
template <typename Keep>
void rebuildFromCarried(const Model& model, Workspace& w, Path path, Keep&& keep) {
  resetActiveSet(w, path);
  std::vector<int>& pinned = w.report.active_clamps;
  pinned.clear();
  for (size_t j = 0; j < w.carried.size(); ++j) {
    const int row = w.carried[j];
    if (!keep(j, row)) continue;
    if (pinRow(model, w, static_cast<size_t>(row), path)) {
      w.ineq_active[static_cast<size_t>(row)] = 1;
      pinned.push_back(row);  // capacity reserved: no allocation
    }
  }
}

}  // namespace

void clearCarriedActiveSet(Workspace& w) {
  w.carried.clear();
  w.carried_structure = false;
  w.carried_count = 0;
}

int startActiveSet(const Model& model, Workspace& w, const SolveOptions& o) {
  w.carried_count = 0;
  if (!o.warm_active_set || !o.clamping || w.carried.empty()) {
    resetActiveSet(w, o.path);
    return 0;
  }
  const double tolerance = std::max(o.inequality_tolerance, 1e-12);
  bool allAtBound = true;
  for (int row : w.carried) allAtBound = allAtBound && atBound(model, w, row, tolerance);
  const bool reuse = allAtBound && w.carried_structure && w.carried_path == o.path &&
                     w.rank == w.eq_rank + static_cast<int>(w.carried.size());
  if (reuse) {
    // The basis, factor and null space depend on the rows only, not on q: keep them and renew
    // the right-hand sides (b - A q) of the equality and carried rows.
    refreshEqualityRhs(w);
    for (size_t j = 0; j < w.carried.size(); ++j) {
      const size_t row = static_cast<size_t>(w.carried[j]);
      w.active_rhs(w.eq_rank + static_cast<Eigen::Index>(j)) = model.inequalities[row].rhs - rowValue(w, row, w.q);
    }
    w.report.active_clamps = w.carried;  // capacity reserved: no allocation
    std::fill(w.ineq_active.begin(), w.ineq_active.end(), 0);
    std::fill(w.ineq_reported.begin(), w.ineq_reported.end(), 0);
    for (int row : w.carried) w.ineq_active[static_cast<size_t>(row)] = 1;
  } else {
    rebuildFromCarried(model, w, o.path, [&](size_t, int row) { return atBound(model, w, row, tolerance); });
  }
  w.carried_count = static_cast<int>(w.report.active_clamps.size());
  return w.carried_count;
}

// The multipliers of the carried rows, from the step just computed with them pinned. Let
// r_k = e_k - J_k Δq be level k's remaining error (weighted, clamped: what the priority loop
// tracks) and A = F Bᵀ the active rows (F lower triangular, B orthonormal: active_set.cpp). The
// direction that moves pinned row p outward by one and keeps every other active row where it is
// is d_p = B F⁻ᵀ e_p: the row's own direction projected off all the others (its dual vector).
// Along it level k's error changes at the rate -(J_k d_p)ᵀ r_k = -μ_kp, with
//   μ_k = F⁻¹ Bᵀ (J_kᵀ r_k)      (every row's multiplier at once: two products, one solve).
// μ_kp > 0: level k pushes the row outward and the bound holds it; μ_kp < 0: level k pulls it
// inside. A row is released as soon as one level (above round-off: |μ| > kDecisive) pulls it
// inside, and stays when the levels that care all push it outward, or when none cares (every task
// is met as well with it as without). Releasing on any pull errs on the safe side: a wrong
// release costs a pass (the loop pins the row again if the new step violates it), a wrong keep
// would hold a row the tasks want to leave. Projecting is what makes the multiplier right: with
// the raw row c_p instead of d_p, a limit and a band pinned on the same dof would each be
// credited with the force that holds the other. Known weakness: d_p keeps the other active rows
// fixed, not the higher levels (docs/ik.md).
bool releaseCarriedRows(const Model& model, Workspace& w, const SolveOptions& o) {
  if (w.carried_count == 0) return false;
  constexpr double kDecisive = 1e-12;
  const int rank = w.rank;
  std::vector<char>& decision = w.warm_released;  // per carried row: 0 undecided, 1 keep, 2 release
  std::fill(decision.begin(), decision.begin() + w.carried_count, 0);
  int undecided = w.carried_count;
  for (size_t k = 0; k < model.levels.size() && undecided > 0; ++k) {
    const Model::Level& level = model.levels[k];
    if (!levelActive(level, w)) continue;
    const auto j = w.jacobian.middleRows(level.first_row, level.rows);
    auto residual = w.warm_residual.head(level.rows);
    residual = w.error.segment(level.first_row, level.rows);
    residual.noalias() -= j * w.dq;
    w.warm_gradient.noalias() = j.transpose() * residual;
    auto mu = w.warm_multiplier.head(rank);
    mu.noalias() = w.basis.leftCols(rank).transpose() * w.warm_gradient;
    w.factor.topLeftCorner(rank, rank).triangularView<Eigen::Lower>().solveInPlace(mu);
    for (int p = 0; p < w.carried_count; ++p) {  // carried row p sits at basis index eq_rank + p
      const double m = mu(w.eq_rank + p);
      if (decision[static_cast<size_t>(p)] == 2 || !(std::abs(m) > kDecisive)) continue;
      if (m < 0.0) --undecided;
      decision[static_cast<size_t>(p)] = m < 0.0 ? 2 : 1;
    }
  }
  bool release = false;
  for (int p = 0; p < w.carried_count; ++p) release = release || decision[static_cast<size_t>(p)] == 2;
  if (!release) return false;
  std::vector<int>& carried = w.carried;
  carried = w.report.active_clamps;  // the carried rows in basis order (no allocation)
  rebuildFromCarried(model, w, o.path, [&](size_t p, int) { return decision[p] != 2; });
  w.carried_count = static_cast<int>(w.report.active_clamps.size());
  return true;
}

void keepActiveSet(Workspace& w, const SolveOptions& o) {
  if (!o.warm_active_set || !o.clamping) {
    clearCarriedActiveSet(w);
    return;
  }
  w.carried = w.report.active_clamps;  // capacity reserved: no allocation
  w.carried_structure = w.rank == w.eq_rank + static_cast<int>(w.carried.size());
  w.carried_path = o.path;
}

}  // namespace embody::ik::detail
