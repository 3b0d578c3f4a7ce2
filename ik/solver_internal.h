#pragma once
// The solver's internal steps, shared by its files (private to ik and its tests). Each file of
// the solver holds one idea:
//   data.cpp            Workspace and Data (buffers sized once, validating setters)
//   kinematics.cpp      forward kinematics, exact task Jacobians, clamped errors
//   active_set.cpp      the active set A: equality rows + pinned rows, basis, null space, Δq0
//   level_damping.cpp   one level's damping, truncated solve and trust region
//   fast_pass.cpp       the fast priority pass (reduced coordinates, sparsity)
//   reference_pass.cpp  the reference priority pass (n x n projectors, SVD)
//   clamping.cpp        the clamping loop's pieces (pin, exchange, report)
//   warm_active_set.cpp the active set carried from the previous iteration (docs/ik.md)
//   multipliers.cpp     the pinned rows' lexicographic multipliers (the warm set's release test)
//   iteration.cpp       one iteration: clamping loop, oscillation guard, q += Δq
//   solver.cpp          the public entry points: priorityPass, iterate, solve
#include <Eigen/Core>

#include <string>

#include "core/result.h"
#include "ik/model.h"
#include "ik/solver.h"
#include "ik/solver_detail.h"

namespace embody::ik::detail {

inline Error fail(const std::string& what) { return Error{"ik: " + what}; }

inline bool sameShape(const Model& model, const Workspace& w) {
  return w.n == model.dofs && w.task_count == static_cast<int>(model.tasks.size()) &&
         w.rows == model.task_rows;
}

// active_set.cpp
// [begin, end): the entries where x is non-zero ({0, 0} when none is).
Workspace::Range nonZeroSpan(const Eigen::Ref<const Eigen::VectorXd>& x);
// Back to the equality rows only (pinned rows dropped; the carried set is untouched).
void resetActiveSet(Workspace& w, Path path);
// Δq0 = A⁺ (b_A - A q) from the active rows' right-hand sides in w.active_rhs.
void computeDq0(Workspace& w);
// Adds row c (in w.tmp_n) pinned so that cᵀ (q + Δq) = cᵀ q + rhs_delta; false (nothing changed)
// when it depends on the active set. single_dof >= 0: the row is that one dof (mask mode).
bool addActiveRow(Workspace& w, double rhs_delta, int single_dof, Path path, double tolerance);

// level_damping.cpp
bool levelActive(const Model::Level& level, const Workspace& w);
struct LevelDamping {
  double lambda2 = 0.0;
  double sigma_min = 0.0;
  bool gram_pd = false;
};
LevelDamping levelDamping(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o);
void truncatedSolve(const Eigen::MatrixXd& gram, Workspace& w, size_t k, const SolveOptions& o, Eigen::VectorXd& y);
double levelStepScale(double norm, const SolveOptions& o);

// fast_pass.cpp, reference_pass.cpp: Δq (w.dq) from Δq0 and the active set.
void fastPass(const Model& model, Workspace& w, const SolveOptions& o);
void referencePass(const Model& model, Workspace& w, const SolveOptions& o);
void runPass(const Model& model, Workspace& w, const SolveOptions& o);

// clamping.cpp
double rowValue(const Workspace& w, size_t i, const Eigen::VectorXd& x);  // inequality row i at x
double nextRowValue(const Workspace& w, size_t i);                       // ... at q + Δq
bool pinRow(Workspace& w, size_t i, Path path);
void rebuildActiveSet(Workspace& w, Path path, int skip);
bool exchangePinnedRow(const Model& model, Workspace& w, const SolveOptions& o, size_t i);
bool pinViolations(const Model& model, Workspace& w, const SolveOptions& o);
void reportRemainingViolations(const Model& model, Workspace& w, const SolveOptions& o);

// warm_active_set.cpp (SolveOptions::warm_active_set)
// The iteration's first active set: the equality rows, plus (warm) the rows pinned in the last
// iteration that still hold at their bounds, their factorisation reused when all do. Returns how
// many rows were carried (they come first among the pinned rows: w.carried_count).
int startActiveSet(Workspace& w, const SolveOptions& o);
// After the first pass: releases the carried rows whose multiplier says the tasks pull them
// inside their bounds and rebuilds the active set without them. True when any was released.
bool releaseCarriedRows(const Model& model, Workspace& w, const SolveOptions& o);
// After the pass that follows a release: when the new step violates a released row again (a
// lower level pushes it back out, which the multipliers of a damped, trust-region step cannot
// always foresee), the released rows go back, the step from before the release is restored and
// the row is held (not released again for a while). True when the release stands.
bool confirmRelease(const Model& model, Workspace& w, const SolveOptions& o);
// multipliers.cpp: the carried rows' multipliers for level k (into w.warm_multiplier, carried
// order), with the active rows and the levels above k held (lexicographic), after a pass.
void carriedMultipliers(const Model& model, Workspace& w, size_t k, const SolveOptions& o);
// At the end of an iteration: the pinned rows become the next iteration's carried rows.
void keepActiveSet(Workspace& w, const SolveOptions& o);
void clearCarriedActiveSet(Workspace& w);

// iteration.cpp
// The iteration after kinematics(): clamping loop, oscillation guard, q += Δq. False (q
// unchanged) if the step came out non-finite.
bool step(const Model& model, Workspace& w, const SolveOptions& o);
// The last pass's level contributions (the oscillation guard's input), kept in joint space with
// the step they made (warm_saved_dq) and put back when that step is.
void saveLevelSteps(Workspace& w);
void restoreLevelSteps(Workspace& w);
// Forgets the oscillation guard's history (every level back to full steps): a new configuration.
void forgetSteps(Workspace& w);

}  // namespace embody::ik::detail
