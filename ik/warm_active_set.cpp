// The warm active set (SolveOptions::warm_active_set): the clamping loop starts from the rows it
// pinned in the previous iteration instead of rediscovering them pass by pass. docs/ik.md
// ("The warm active set") says what is carried, when a row is released, and why it is correct.
#include <algorithm>
#include <cmath>
#include <limits>

#include "ik/solver_detail.h"
#include "ik/solver_internal.h"

namespace embody::ik::detail {

namespace {

// A carried row still holds at its bound when q moved only by the solver's own steps (the step
// keeps every pinned row exactly, up to round-off); a configuration set from outside, or a row
// the solver no longer held, leaves it inside or past its bound and it is not carried.
bool atBound(const Workspace& w, int row, double tolerance) {
  return std::abs(w.ineq_rhs[static_cast<size_t>(row)] - rowValue(w, static_cast<size_t>(row), w.q)) <=
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
void rebuildFromCarried(Workspace& w, Path path, Keep&& keep) {
  resetActiveSet(w, path);
  std::vector<int>& pinned = w.report.active_clamps;
  pinned.clear();
  for (size_t j = 0; j < w.carried.size(); ++j) {
    const int row = w.carried[j];
    if (!keep(j, row)) continue;
    if (pinRow(w, static_cast<size_t>(row), path)) {
      w.ineq_active[static_cast<size_t>(row)] = 1;
      pinned.push_back(row);  // capacity reserved: no allocation
    }
  }
}

// A level decides about a row when |μ| is above round-off: kDecisive, or kDecisiveRelative of
// its gradient |J_kᵀ r_k|; a level whose gradient is below kMetGradient is met (decides nothing).
constexpr double kDecisive = 1e-12;
constexpr double kDecisiveRelative = 1e-9;
constexpr double kMetGradient = 1e-10;
// A held row (its last release was undone) is tried again after this many iterations, or at
// once when its deciding multiplier has doubled (the tasks pull it inside harder than then).
constexpr long kRetryAfter = 8;

bool held(const Workspace& w, size_t row, double multiplier) {
  const double then = w.warm_hold_multiplier[row];
  return then < 0.0 && multiplier > 2.0 * then && w.warm_iteration - w.warm_hold_since[row] < kRetryAfter;
}

}  // namespace

void clearCarriedActiveSet(Workspace& w) {
  w.carried.clear();
  std::fill(w.warm_hold_multiplier.begin(), w.warm_hold_multiplier.end(), 0.0);
  w.warm_one_at_a_time = false;
  w.carried_structure = false;
  w.carried_count = 0;
}

int startActiveSet(Workspace& w, const SolveOptions& o) {
  w.carried_count = 0;
  if (!o.warm_active_set || !o.clamping || w.carried.empty()) {
    resetActiveSet(w, o.path);
    return 0;
  }
  const double tolerance = std::max(o.inequality_tolerance, 1e-12);
  bool allAtBound = true;
  for (int row : w.carried) allAtBound = allAtBound && atBound(w, row, tolerance);
  const bool reuse = allAtBound && w.carried_structure && w.carried_path == o.path &&
                     w.rank == w.eq_rank + static_cast<int>(w.carried.size());
  if (reuse) {
    // The basis, factor and null space depend on the rows only, not on q: keep them and renew
    // the right-hand sides (b - A q) of the equality and carried rows.
    refreshEqualityRhs(w);
    for (size_t j = 0; j < w.carried.size(); ++j) {
      const size_t row = static_cast<size_t>(w.carried[j]);
      w.active_rhs(w.eq_rank + static_cast<Eigen::Index>(j)) = w.ineq_rhs[row] - rowValue(w, row, w.q);
    }
    w.report.active_clamps = w.carried;  // capacity reserved: no allocation
    std::fill(w.ineq_active.begin(), w.ineq_active.end(), 0);
    std::fill(w.ineq_reported.begin(), w.ineq_reported.end(), 0);
    for (int row : w.carried) w.ineq_active[static_cast<size_t>(row)] = 1;
  } else {
    rebuildFromCarried(w, o.path, [&](size_t, int row) { return atBound(w, row, tolerance); });
  }
  w.carried_count = static_cast<int>(w.report.active_clamps.size());
  return w.carried_count;
}

namespace {

// The carried rows' multipliers, from the step just computed with them pinned, level by level
// (carriedMultipliers, multipliers.cpp: lexicographic, each level's with the active rows and the
// levels above it held). The highest level that cares about a row decides (|μ| above round-off):
// μ < 0, it pulls the row inside (release); μ > 0, it pushes the row outward and the row stays,
// whatever the levels below want (they may not trade a higher level's error). A row no level
// cares about stays (every task is met as well with it as without). Into w.warm_released (per
// carried row: 1 keep, 2 release) and w.warm_deciding (the deciding multiplier).
void decideCarriedRows(const Model& model, Workspace& w, const SolveOptions& o) {
  std::vector<char>& decision = w.warm_released;
  std::fill(decision.begin(), decision.begin() + w.carried_count, 1);
  std::fill(w.warm_deciding.begin(), w.warm_deciding.begin() + w.carried_count, 0.0);
  int undecided = w.carried_count;
  std::vector<char>& open = w.warm_undecided;
  std::fill(open.begin(), open.begin() + w.carried_count, 1);
  for (size_t k = 0; k < model.levels.size() && undecided > 0; ++k) {
    if (!levelActive(model.levels[k], w)) continue;
    carriedMultipliers(model, w, k, o);
    // A level met to round-off pushes nothing (the two paths' round-off differs there).
    if (!(w.warm_gradient_norm > kMetGradient)) continue;
    const double decisive = std::max(kDecisive, kDecisiveRelative * w.warm_gradient_norm);
    for (int p = 0; p < w.carried_count; ++p) {
      const auto pi = static_cast<size_t>(p);
      const double m = w.warm_multiplier(p);
      if (!open[pi] || !(std::abs(m) > decisive)) continue;
      open[pi] = 0;
      decision[pi] = m < 0.0 ? 2 : 1;
      w.warm_deciding[pi] = m;
      --undecided;
    }
  }
}

}  // namespace

// The release test. For the exact lexicographic problem a row whose deciding level pulls it
// inside is one the next step leaves inside when it is released alone; damping, the trust
// region and lower levels that push it back out (within the deciding level's null space) can
// still undo that, and releasing several rows at once can too. confirmRelease handles both.
bool releaseCarriedRows(const Model& model, Workspace& w, const SolveOptions& o) {
  if (w.carried_count == 0) return false;
  decideCarriedRows(model, w, o);
  std::vector<char>& decision = w.warm_released;
  int candidates = 0, mostNegative = -1;
  for (int p = 0; p < w.carried_count; ++p) {
    const auto pi = static_cast<size_t>(p);
    const auto row = static_cast<size_t>(w.report.active_clamps[pi]);
    if (decision[pi] == 1 && w.warm_deciding[pi] > 0.0) w.warm_hold_multiplier[row] = 0.0;  // pushed out: moot
    if (decision[pi] == 2 && held(w, row, w.warm_deciding[pi])) decision[pi] = 1;
    if (decision[pi] != 2) continue;
    ++candidates;
    if (mostNegative < 0 || w.warm_deciding[pi] < w.warm_deciding[static_cast<size_t>(mostNegative)]) mostNegative = p;
  }
  if (candidates == 0) return false;
  if (candidates > 1 && w.warm_one_at_a_time)  // the last joint release was undone: one row only
    for (int p = 0; p < w.carried_count; ++p)
      if (p != mostNegative) decision[static_cast<size_t>(p)] = 1;
  w.warm_one_at_a_time = false;
  w.warm_saved_dq = w.dq;  // the step with every carried row kept, should the release be undone
  w.warm_saved_dq0 = w.dq0;
  saveLevelSteps(w);
  w.warm_released_rows.clear();
  std::vector<int>& carried = w.carried;
  carried = w.report.active_clamps;  // the carried rows in basis order (no allocation)
  for (int p = 0; p < w.carried_count; ++p)
    if (decision[static_cast<size_t>(p)] == 2) {
      w.warm_released_rows.push_back(carried[static_cast<size_t>(p)]);
      w.warm_deciding[w.warm_released_rows.size() - 1] = w.warm_deciding[static_cast<size_t>(p)];  // p >= index
    }
  rebuildFromCarried(w, o.path, [&](size_t p, int) { return decision[p] != 2; });
  w.carried_count = static_cast<int>(w.report.active_clamps.size());
  return true;
}

// After the pass that follows a release, every row the new step violates is held (not released
// again for a while, kRetryAfter): a released row violated again (a lower level pushes it back
// out), or another row the release let go past its bound. Both would otherwise repeat in a
// steady state, a pass or two every iteration (the release churn), or cycle between two active
// sets (release one, pin the other; release that, pin the first). The clamping loop pins them.
// When the violated rows are exactly the released ones, the loop would rebuild the carried set
// and its step: that is restored instead, without a pass. Several rows undone together say
// nothing about each alone: they are not held, and the next release takes one row at a time.
bool confirmRelease(const Model& model, Workspace& w, const SolveOptions& o) {
  const auto violatedAt = [&](size_t row) {
    return nextRowValue(w, row) > w.ineq_rhs[row] + o.inequality_tolerance;
  };
  size_t releasedViolated = 0, othersViolated = 0;
  for (size_t row = 0; row < model.inequalities.size(); ++row)
    if (!w.ineq_active[row] && violatedAt(row)) ++othersViolated;  // released rows included
  for (int row : w.warm_released_rows) releasedViolated += violatedAt(static_cast<size_t>(row)) ? 1 : 0;
  othersViolated -= releasedViolated;
  const size_t released = w.warm_released_rows.size();
  if (releasedViolated == 0 && othersViolated == 0) {
    w.warm_one_at_a_time = false;
    return true;
  }
  if (othersViolated == 0 && releasedViolated == released) {
    if (released == 1) {
      const auto row = static_cast<size_t>(w.warm_released_rows[0]);
      w.warm_hold_multiplier[row] = w.warm_deciding[0];
      w.warm_hold_since[row] = w.warm_iteration;
    } else {
      w.warm_one_at_a_time = true;
    }
    for (int row : w.warm_released_rows)
      if (pinRow(w, static_cast<size_t>(row), o.path)) {
        w.ineq_active[static_cast<size_t>(row)] = 1;
        w.report.active_clamps.push_back(row);
      }
    w.carried_count = static_cast<int>(w.report.active_clamps.size());
    w.dq = w.warm_saved_dq;
    w.dq0 = w.warm_saved_dq0;
    restoreLevelSteps(w);
    return false;
  }
  w.warm_one_at_a_time = false;
  for (size_t row = 0; row < model.inequalities.size(); ++row) {
    if (w.ineq_active[row] || !violatedAt(row)) continue;
    // A released row keeps its deciding multiplier (a doubled pull retries it at once); another
    // row waits out kRetryAfter.
    w.warm_hold_multiplier[row] = -std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < released; ++i)
      if (w.warm_released_rows[i] == static_cast<int>(row)) w.warm_hold_multiplier[row] = w.warm_deciding[i];
    w.warm_hold_since[row] = w.warm_iteration;
  }
  return false;
}

void keepActiveSet(Workspace& w, const SolveOptions& o) {
  ++w.warm_iteration;
  if (!o.warm_active_set || !o.clamping) {
    clearCarriedActiveSet(w);
    return;
  }
  w.carried = w.report.active_clamps;  // capacity reserved: no allocation
  w.carried_structure = w.rank == w.eq_rank + static_cast<int>(w.carried.size());
  w.carried_path = o.path;
}

}  // namespace embody::ik::detail
