#pragma once
// The budgeted solve: PIK iterations (ik::solve, one per call) on the body's ik::Data until
// converged, the iteration cap, or the deadline less the predicted cost of one more iteration:
// the runtime's one deadline policy (IterationBudget with the caller's IterationCostModel,
// runtime/clock.h). It returns before the deadline while iterations cost what they did, and by
// the deadline plus at most one iteration when one suddenly costs more. No allocation.
//
//   BudgetedSolveJob job;
//   job.model = &rig.body.model; job.data = &data; job.clock = &clock;
//   job.deadline = request.deadline - finishCost.predicted();   // leave time for the pose
//   job.iterationCost = &iterationCost; job.output = &out;
//   if (job.Run()) ... out.iterations, out.converged, out.broken
//
// A cold start (the first solve, after resetWarmStart or a re-seed) begins far from the targets:
// the small trust region (maxLevelStep) that keeps conflicting levels from pulling the feet would
// make it crawl, so it gets the library's default cap and four times the iterations (the budget
// still rules). `settleFirst`: the first live solve first settles outside the budget, once.
// Deterministic mode (fixedIterations > 0): that count (four times it cold), no clock.
#include "ik/solver.h"
#include "runtime/clock.h"

namespace embody::runtime {

// Iterations outside the budget, once, from a cold start (the seat's placement, the first live
// solve): until converged or `maxIterations`.
const ik::SolveReport& settle(const ik::Model& model, ik::Data& data, ik::SolveOptions options, int maxIterations);

struct BudgetedSolveOutput {
  int iterations = 0;
  bool converged = false;
  bool broken = false;  // the solver reported an invalid state (see also data.q()'s finiteness)
};

struct BudgetedSolveJob {
  const ik::Model* model = nullptr;
  const Clock* clock = nullptr;
  TimePoint deadline{};          // for the iterations (the caller keeps its own finish time off it)
  int fixedIterations = 0;       // > 0: deterministic mode, the deadline ignored
  int maxIterations = 40;        // the cap under a deadline (> 0)
  double maxLevelStep = 0.05;    // ik::SolveOptions::max_level_step warm (> 0)
  bool cold = false;             // a cold start (see above)
  bool settleFirst = false;      // settle outside the budget first (only without fixedIterations)
  IterationCostModel* iterationCost = nullptr;  // in-out: one PIK iteration's cost
  ik::Data* data = nullptr;      // in-out: the warm start and the solution
  BudgetedSolveOutput* output = nullptr;

  // Every pointer set, the data sized for the model, the caps > 0, maxLevelStep finite > 0.
  bool Validate() const;
  bool Run() const;
};

}  // namespace embody::runtime
